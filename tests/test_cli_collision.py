"""``--scene`` / ``--no-collision`` of ``plan pick-place`` and ``fishcut``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import run_cli as run
from workbench import paper_data
from workbench.cli import EXIT_BAD_INPUT, EXIT_INFEASIBLE
from workbench.json_numbers import to_json_ready

PICK = [str(x) for x in paper_data.ANGELES_PICK_Q_DEG]
PLACE = [str(x) for x in paper_data.ANGELES_PLACE_Q_DEG]
PLAN = (
    "plan",
    "pick-place",
    "--robot",
    "puma560",
    "--pick-deg",
    *PICK,
    "--place-deg",
    *PLACE,
    "--duration",
    "10",
)


def test_paper_scene_reports_the_pedestal_and_exits_3(capsys) -> None:
    code, out, err = run(capsys, *PLAN, "--json")
    assert code == EXIT_INFEASIBLE
    result = json.loads(out)
    assert result["scene"] == "angeles-pick-and-place"
    first = result["collisions"][0]
    assert (first["body_a"], first["body_b"], first["t_start"]) == (
        "link2",
        "pedestal",
        0.0,
    )
    assert set(first) >= {"t", "body_a", "body_b", "distance"}
    assert result["min_clearance"] < 0.0 and result["first_contact"] == first
    assert err.count("\n") == 1 and "collision of link2 with pedestal" in err


def test_plan_default_scene_is_the_python_default(capsys) -> None:
    """The command's default check is JointTrajectory.check_collisions()."""
    from workbench import load_robot
    from workbench.collision import get_pick_and_place_scene
    from workbench.trajectory import pick_and_place

    code, out, _ = run(capsys, *PLAN, "--json")
    assert code == EXIT_INFEASIBLE
    result = json.loads(out)
    robot = load_robot("puma560")
    traj = pick_and_place(
        robot,
        np.deg2rad(paper_data.ANGELES_PICK_Q_DEG),
        np.deg2rad(paper_data.ANGELES_PLACE_Q_DEG),
        10.0,
    )
    python = json.loads(json.dumps(to_json_ready(traj.check_collisions().as_dict())))
    assert {key: result[key] for key in python} == python
    assert result["scene"] == get_pick_and_place_scene(robot).name


@pytest.mark.parametrize(
    ("name", "scene", "obstacles"),
    [
        ("puma560", "angeles-pick-and-place", ("pedestal", "pick_table")),
        ("puma560-kang", "pedestal", ("pedestal",)),
        ("ur5", "empty", ()),
    ],
)
def test_pick_and_place_scene_of_each_kind_of_arm(name, scene, obstacles) -> None:
    from workbench import load_robot
    from workbench.collision import get_pick_and_place_scene

    found = get_pick_and_place_scene(load_robot(name))
    assert found.name == scene
    assert tuple(o.name for o in found.obstacles) == obstacles


def test_human_output_lists_the_contacts(capsys) -> None:
    code, out, _ = run(capsys, *PLAN)
    assert code == EXIT_INFEASIBLE
    assert "contact link2 - pedestal" in out and "proven lower bound" in out


def test_free_scene_file(capsys, tmp_path: Path) -> None:
    scene = tmp_path / "far.json"
    far = {"name": "far", "shape": "sphere", "radius": 0.1, "position": [3, 0, 0]}
    scene.write_text(json.dumps({"objects": [far]}), encoding="utf-8")
    code, out, err = run(capsys, *PLAN, "--scene", str(scene), "--json")
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert result["collisions"] == [] and result["min_clearance"] > 0.05
    assert 0.0 < result["clearance_lower_bound"] <= result["min_clearance"]


def test_no_collision_keys(capsys) -> None:
    code, out, _ = run(capsys, *PLAN, "--no-collision", "--json")
    result = json.loads(out)
    assert code == 0
    assert (result["min_clearance"], result["collisions"]) == (None, [])


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ('{"objects": [{"name": "a", "shape": "cone"}]}', "unknown shape"),
        (
            '{"objects": [{"name": "a", "shape": "box", "size": [1, -1, 1]}]}',
            "must be > 0",
        ),
        (
            '{"objects": [{"name": "a", "shape": "sphere", "radius": 1, '
            '"position": [NaN, 0, 0]}]}',
            "must be finite",
        ),
        (
            '{"objects": [{"name": "a", "shape": "mesh", "file": "gone.stl"}]}',
            "mesh file not found",
        ),
    ],
)
def test_bad_scene_exits_2_and_writes_nothing(
    capsys, tmp_path: Path, text, fragment
) -> None:
    scene = tmp_path / "scene.json"
    scene.write_text(text, encoding="utf-8")
    csv = tmp_path / "out.csv"
    for argv in (
        (*PLAN, "--csv", str(csv)),
        ("fishcut", "--csv", str(csv), "--html", str(tmp_path / "f.html")),
    ):
        code, out, err = run(capsys, *argv, "--scene", str(scene))
        assert code == EXIT_BAD_INPUT
        assert err.count("\n") == 1 and fragment in err and out == ""
        assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.json"]


def test_missing_scene_file(capsys, tmp_path: Path) -> None:
    code, _, err = run(capsys, *PLAN, "--scene", str(tmp_path / "none.json"))
    assert code == EXIT_BAD_INPUT and "cannot read scene" in err


def test_fishcut_default_scene_is_clear(capsys) -> None:
    code, out, err = run(capsys, "fishcut", "--json")
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert result["scene"] == "kang-fish-cutting"
    assert result["collisions"] == []
    assert 0.0 < result["clearance_lower_bound"] <= result["min_clearance"] < 0.05


def test_fishcut_default_check_is_the_python_default(capsys) -> None:
    """The command's default check is compute_fish_cutting_clearance()."""
    from workbench import load_robot
    from workbench.tasks import compute_fish_cutting_clearance, run_fish_cutting

    code, out, _ = run(capsys, "fishcut", "--json")
    assert code == 0
    result = json.loads(out)
    robot = load_robot("puma560-kang")
    clearance = compute_fish_cutting_clearance(robot, run_fish_cutting(robot))
    python = json.loads(json.dumps(to_json_ready(clearance.as_dict())))
    assert {key: result[key] for key in python} == python


@pytest.mark.slow
def test_fishcut_obstacle_in_the_way_exits_3(capsys, tmp_path: Path) -> None:
    scene = tmp_path / "post.json"  # a post through the fish's middle
    post = {
        "name": "post",
        "shape": "cylinder",
        "radius": 0.03,
        "length": 0.6,
        "position": [0.0, 0.41, -0.3],
    }
    scene.write_text(json.dumps({"objects": [post]}), encoding="utf-8")
    csv = tmp_path / "fish.csv"
    code, out, err = run(
        capsys, "fishcut", "--scene", str(scene), "--csv", str(csv), "--json"
    )
    assert code == EXIT_INFEASIBLE
    result = json.loads(out)
    assert {c["body_b"] for c in result["collisions"]} == {"post"}
    assert err.count("\n") == 1 and "with post" in err
    assert csv.exists()  # the run completed: its outputs are written


def test_robot_without_geometry_skips_the_default_check(capsys, tmp_path) -> None:
    from workbench import load_robot

    text = load_robot("puma560").urdf_path.read_text()
    while "<collision>" in text:
        start = text.index("<collision>")
        text = text[:start] + text[text.index("</collision>") + 12 :]
    urdf = tmp_path / "bare.urdf"
    urdf.write_text(text)
    argv = ["plan", "pick-place", "--robot", str(urdf), *PLAN[4:]]
    code, out, _ = run(capsys, *argv, "--json")
    assert code == 0 and json.loads(out)["min_clearance"] is None
    scene = tmp_path / "s.json"
    scene.write_text('{"objects": []}')
    code, _, err = run(capsys, *argv, "--scene", str(scene))
    assert code == EXIT_BAD_INPUT and "no collision geometry" in err


def test_view_draws_a_scene(capsys, tmp_path: Path) -> None:
    scene = tmp_path / "s.json"
    post = {"name": "post", "shape": "box", "size": [0.1, 0.1, 0.5]}
    scene.write_text(json.dumps({"objects": [{**post, "position": [0.4, 0, -0.3]}]}))
    page = tmp_path / "v.html"
    code, _, _ = run(capsys, "view", "--robot", "puma560", "--deg", *PICK,
                     "--scene", str(scene), "--html", str(page))  # fmt: skip
    assert code == 0 and page.stat().st_size > 0
    code, _, err = run(capsys, "view", "--robot", "puma560", "--scene",
                       str(tmp_path / "none.json"), "--html", str(page))  # fmt: skip
    assert code == EXIT_BAD_INPUT and "cannot read scene" in err


def test_urdf_srdf(capsys, tmp_path: Path) -> None:
    code, out, _ = run(capsys, "urdf", "srdf", "--robot", "puma560")
    assert code == 0 and out.count("<disable_collisions") == 9
    assert 'link1="link4" link2="link6" reason="Default"' in out
    path = tmp_path / "ur5.srdf"
    code, _, _ = run(capsys, "urdf", "srdf", "--robot", "ur5", "--out", str(path))
    assert code == 0 and 'reason="Adjacent"' in path.read_text()
    code, _, err = run(capsys, "urdf", "srdf", "--robot", "ur5", "--out",
                       str(tmp_path / "no" / "x.srdf"))  # fmt: skip
    assert code == EXIT_BAD_INPUT and err.count("\n") == 1


def test_urdf_srdf_json_is_the_library_filter(capsys) -> None:
    from workbench import load_robot
    from workbench.collision import compute_self_collision_filter

    code, out, _ = run(capsys, "urdf", "srdf", "--robot", "puma560", "--json")
    assert code == 0
    found = compute_self_collision_filter(load_robot("puma560"))
    result = json.loads(out)
    assert result["disabled"] == [d.as_dict() for d in found.disabled]
    assert result["srdf"] == found.to_srdf() and result["out"] is None
