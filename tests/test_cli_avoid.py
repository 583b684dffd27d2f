"""``workbench plan pick-place --avoid``: the colliding spline planned around."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import workbench as wb
from tests.conftest import run_cli as run
from workbench import paper_data
from workbench.cli import EXIT_BAD_INPUT, EXIT_INFEASIBLE
from workbench.collision import (
    CollisionChecker,
    Obstacle,
    Scene,
    get_angeles_obstacle_scene,
    write_scene,
)
from workbench.motion import DEFAULT_MAX_STEP, plan_around, verify_trajectory
from workbench.trajectory import pick_and_place
from workbench.trajectory.csv_io import read_trajectory_csv

PICK = [str(x) for x in paper_data.ANGELES_PICK_Q_DEG]
PLACE = [str(x) for x in paper_data.ANGELES_PLACE_Q_DEG]
#: Acceleration limit [rad/s²] of every joint (the URDF gives none).
ACCELERATION = 4.0
BASE = (
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
#: Position rounding of the CSV against the trajectory [rad].
ATOL_CSV = 1e-9
#: Pick and place reached by the planned motion [rad].
ATOL_ENDS = 1e-12


@pytest.fixture(scope="module")
def limited() -> wb.Robot:
    return wb.load_robot("puma560").with_limits(acceleration_limit=ACCELERATION)


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory: pytest.TempPathFactory, limited) -> Path:
    path = tmp_path_factory.mktemp("avoid") / "angeles-obstacle.json"
    write_scene(get_angeles_obstacle_scene(limited), path)
    return path


def _avoid(capsys, scene: Path, *extra: str) -> tuple[int, str, str]:
    return run(
        capsys,
        *BASE,
        "--scene",
        str(scene),
        "--acceleration-limit",
        str(ACCELERATION),
        "--avoid",
        *extra,
    )


def test_obstacle_scene_blocks_the_paper_path(limited) -> None:
    """The cube sits on Table III's path; pick and place stay free."""
    scene = get_angeles_obstacle_scene(limited)
    assert [o.name for o in scene.obstacles] == ["pedestal", "pick_table", "obstacle"]
    assert set(scene.obstacles[0].allow) == {"link1", "link2"}
    checker = CollisionChecker(limited, scene)
    for q_deg in (paper_data.ANGELES_PICK_Q_DEG, paper_data.ANGELES_PLACE_Q_DEG):
        assert checker.compute_distances(np.radians(q_deg)).min() > 0.0
    direct = pick_and_place(
        limited,
        np.radians(paper_data.ANGELES_PICK_Q_DEG),
        np.radians(paper_data.ANGELES_PLACE_Q_DEG),
        paper_data.ANGELES_DURATION,
    )
    report = direct.check_collisions(checker)
    assert {"obstacle", "pick_table"} <= {c.body_b for c in report.contacts}
    # The tool frame passes through the cube's centre: deeper than half an edge.
    deepest = -min(c.distance for c in report.contacts if c.body_b == "obstacle")
    assert deepest > 0.05


def test_collides_without_avoid(capsys, scene_file: Path) -> None:
    code, out, err = run(capsys, *BASE, "--scene", str(scene_file), "--json")
    assert code == EXIT_INFEASIBLE
    assert "collision of" in err and "obstacle" in out
    result = json.loads(out)
    assert result["avoided"] is None
    assert any(c["body_b"] == "obstacle" for c in result["collisions"])


def test_avoided_writes_the_planned_motion(
    capsys, tmp_path: Path, scene_file: Path, limited
) -> None:
    csv = tmp_path / "around.csv"
    code, out, err = _avoid(capsys, scene_file, "--csv", str(csv), "--json")
    assert (code, err) == (0, "")
    result = json.loads(out)
    avoided = result["avoided"]
    assert avoided["needed"] and avoided["solved"] and avoided["reason"] is None
    assert avoided["seed"] == 0 and avoided["time_limit"] == 1.0
    # The spline's contacts are still reported, with the depth they reach.
    assert result["min_clearance"] < 0
    assert avoided["direct_penetration"] == pytest.approx(
        -result["min_clearance"], abs=0.0
    )
    assert avoided["min_clearance"] > 0 and avoided["clearance_lower_bound"] > 0
    waypoints = np.array(avoided["waypoints"])
    np.testing.assert_allclose(
        waypoints[[0, -1]],
        np.radians([paper_data.ANGELES_PICK_Q_DEG, paper_data.ANGELES_PLACE_Q_DEG]),
        rtol=0,
        atol=ATOL_ENDS,
    )
    # The CSV is the planned motion, and the same as in Python (same seed).
    samples = read_trajectory_csv(csv, limited.nq)
    assert result["samples"] == samples.t.size
    np.testing.assert_allclose(samples.t[-1], avoided["duration"], rtol=0, atol=1e-12)
    scene = wb.collision.read_scene(scene_file)
    direct = pick_and_place(
        limited, waypoints[0], waypoints[-1], paper_data.ANGELES_DURATION
    )
    again = plan_around(limited, scene, direct)
    np.testing.assert_array_equal(again.waypoints, waypoints)
    q = again.trajectory.sample(samples.t)[0]
    np.testing.assert_allclose(samples.q, q, rtol=0, atol=ATOL_CSV)
    # The judge: the exact meshes, proven between samples at 0.25° steps.
    report = verify_trajectory(
        CollisionChecker(limited, scene), again.trajectory, max_step=DEFAULT_MAX_STEP
    )
    assert report.collision_free and not report.contacts
    assert report.min_clearance == pytest.approx(avoided["min_clearance"], abs=0.0)


def test_text_output_names_the_plan(capsys, scene_file: Path) -> None:
    code, out, err = _avoid(capsys, scene_file, "--seed", "2")
    assert (code, err) == (0, "")
    assert "planned around the scene:" in out and "mm deep" in out


def test_free_spline_needs_no_plan(capsys) -> None:
    """A free spline with --avoid: the spline itself, ``avoided`` null."""
    empty = run(
        capsys,
        "plan",
        "pick-place",
        "--robot",
        "ur5",
        "--pick-deg",
        "0",
        "-90",
        "90",
        "0",
        "90",
        "0",
        "--place-deg",
        "30",
        "-90",
        "90",
        "0",
        "90",
        "0",
        "--duration",
        "5",
        "--acceleration-limit",
        "4",
        "--avoid",
        "--json",
    )
    assert empty[0] == 0, empty[2]
    result = json.loads(empty[1])
    assert result["collisions"] == [] and result["avoided"] is None


def test_no_motion_is_exit_3_and_writes_nothing(
    capsys, tmp_path: Path, limited
) -> None:
    """A box around the place pose: the goal is in collision."""
    place = limited.fk(np.radians(paper_data.ANGELES_PLACE_Q_DEG)).translation
    box = Obstacle("crate", "box", (0.2, 0.2, 0.2), pin.SE3(np.eye(3), place))
    scene = tmp_path / "crate.json"
    write_scene(Scene("crate", (box,)), scene)
    csv = tmp_path / "none.csv"
    code, out, err = _avoid(capsys, scene, "--csv", str(csv), "--json")
    assert code == EXIT_INFEASIBLE
    assert err.startswith("workbench: error: no motion around the scene: goal in ")
    assert "(the spline: collision of" in err and err.count("\n") == 1
    avoided = json.loads(out)["avoided"]
    assert not avoided["solved"] and avoided["reason"] == "goal in collision"
    assert avoided["duration"] is None and avoided["min_clearance"] is None
    assert json.loads(out)["csv"] is None and not csv.exists()


def test_default_cell_start_touches_the_pedestal(capsys) -> None:
    """In Angeles' own cell the pick has link2 in the pedestal: no motion."""
    code, out, err = run(
        capsys, *BASE, "--acceleration-limit", "4", "--avoid", "--json"
    )
    assert code == EXIT_INFEASIBLE
    assert json.loads(out)["avoided"]["reason"] == "start in collision"
    assert "link2 touches pedestal" in err


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (("--seed", "1"), "--seed is an option of --avoid"),
        (("--time-limit", "1"), "--time-limit is an option of --avoid"),
        (("--avoid", "--no-collision"), "--avoid and --no-collision contradict"),
        (("--avoid",), "planning around needs acceleration limits"),
        (("--avoid", "--time-limit", "0"), "--time-limit"),
        (("--avoid", "--seed", "-1"), "--seed"),
    ],
)
def test_bad_input_is_exit_2(
    capsys, scene_file: Path, extra: tuple[str, ...], message: str
) -> None:
    code, _out, err = run(capsys, *BASE, "--scene", str(scene_file), *extra)
    assert code == EXIT_BAD_INPUT
    assert message in err and err.count("\n") == 1


def test_plan_around_refuses_bad_arguments(limited) -> None:
    direct = pick_and_place(
        limited,
        np.radians(paper_data.ANGELES_PICK_Q_DEG),
        np.radians(paper_data.ANGELES_PLACE_Q_DEG),
        paper_data.ANGELES_DURATION,
    )
    scene = get_angeles_obstacle_scene(limited)
    with pytest.raises(wb.InputError, match="pick-and-place JointTrajectory"):
        plan_around(limited, scene, "spline")  # type: ignore[arg-type]
    with pytest.raises(wb.InputError, match="rate_hz must be"):
        plan_around(limited, scene, direct, rate_hz=0.0)
    with pytest.raises(wb.InputError, match="the robot has"):
        plan_around(wb.load_robot("ur5"), scene, direct)
    with pytest.raises(wb.InputError, match="acceleration limits"):
        plan_around(wb.load_robot("puma560"), scene, direct)
    with pytest.raises(wb.InputError, match="clearance must be"):
        plan_around(limited, scene, direct, clearance=0.1)  # type: ignore[arg-type]
