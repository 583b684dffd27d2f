"""``workbench motion plan``: JSON, CSV, page, exit codes."""

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
from workbench.collision.scene import Obstacle, Scene
from workbench.trajectory.csv_io import read_trajectory_csv

PICK = [str(x) for x in paper_data.ANGELES_PICK_Q_DEG]
PLACE = [str(x) for x in paper_data.ANGELES_PLACE_Q_DEG]
BASE = ("motion", "plan", "--robot", "puma560", "--acceleration-limit", "4")
MBM = Path(__file__).parent / "data" / "motionbenchmaker" / "panda"


def _wall_scene(tmp_path: Path, *, on_start: bool = False) -> Path:
    robot = wb.load_robot("puma560")
    q = np.radians(paper_data.ANGELES_PICK_Q_DEG)
    if not on_start:
        q = 0.5 * (q + np.radians(paper_data.ANGELES_PLACE_Q_DEG))
    wall = Obstacle(
        "wall", "box", (0.1, 0.1, 0.1), pin.SE3(np.eye(3), robot.fk(q).translation)
    )
    path = tmp_path / "wall.json"
    path.write_text(json.dumps(Scene("wall", (wall,)).to_dict()))
    return path


def test_plans_around_a_wall_and_writes_csv_and_page(capsys, tmp_path: Path) -> None:
    csv, html = tmp_path / "m.csv", tmp_path / "m.html"
    code, out, err = run(
        capsys,
        *BASE,
        "--scene",
        str(_wall_scene(tmp_path)),
        "--start-deg",
        *PICK,
        "--goal-deg",
        *PLACE,
        "--csv",
        str(csv),
        "--html",
        str(html),
        "--json",
    )
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert result["solved"] and result["reason"] is None
    assert result["planner"] == "rrtconnect"
    assert result["min_clearance"] > 0 and result["duration"] > 0
    waypoints = np.array(result["waypoints"])
    np.testing.assert_allclose(waypoints[0], np.radians(paper_data.ANGELES_PICK_Q_DEG))
    samples = read_trajectory_csv(csv)
    assert samples.t[-1] == pytest.approx(result["duration"], abs=1e-2)
    np.testing.assert_allclose(samples.qd[[0, -1]], 0.0, atol=1e-12)
    page = html.read_text()
    assert "<html" in page.lower() and "wall" in page


def test_the_sphere_cover_is_counted_on_stderr(capsys, tmp_path, monkeypatch) -> None:
    """A first plan builds the robot's spheres (seconds on a real arm): its
    count goes to stderr with the other progress lines, and none with -q."""
    from workbench import progress

    monkeypatch.setenv("WORKBENCH_PROGRESS", "1")
    monkeypatch.setattr(progress, "PROGRESS_DELAY", 0.0)
    monkeypatch.setattr(progress, "COUNT_INTERVAL", 0.0)
    n = len(wb.load_robot("puma560").collision_model.geometryObjects)
    argv = [*BASE, "--start-deg", *PICK, "--goal-deg", *PLACE, "--json"]
    code, out, err = run(capsys, *argv)
    assert code == 0 and json.loads(out)["solved"]
    assert f"workbench: motion plan: sphere cover: {n}/{n} steps (100%)" in err
    code, _, err = run(capsys, "-q", *argv)
    assert code == 0 and "sphere cover" not in err


@pytest.mark.slow  # the Panda's spheres take seconds to build
def test_a_motion_request_and_a_moveit_scene(capsys) -> None:
    code, out, err = run(
        capsys,
        "motion",
        "plan",
        "--robot",
        str(MBM / "panda.urdf"),
        "--acceleration-limit",
        "15",
        "7.5",
        "10",
        "12.5",
        "15",
        "20",
        "20",
        "--scene",
        str(MBM / "table_pick_scene0001.yaml"),
        "--request",
        str(MBM / "table_pick_request0001.yaml"),
        "--json",
    )
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert result["solved"] and result["min_clearance"] > 0
    # Links 5 and 7 are 22 mm apart at the start; their spheres (within 17 mm
    # of the meshes) no longer overlap there, so no allowance is needed.
    assert not any(
        {a, b} == {"panda_link5", "panda_link7"} for a, b, _ in result["allowances"]
    )


def test_an_ompl_planner_with_the_same_checker(capsys, tmp_path: Path) -> None:
    pytest.importorskip("ompl")
    code, out, err = run(
        capsys,
        *BASE,
        "--scene",
        str(_wall_scene(tmp_path)),
        "--start-deg",
        *PICK,
        "--goal-deg",
        *PLACE,
        "--planner",
        "ompl:RRTConnect",
        "--json",
    )
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert result["planner"] == "ompl:RRTConnect"
    assert result["solved"] and result["min_clearance"] > 0


def test_no_motion_is_exit_3_with_the_reason(capsys, tmp_path: Path) -> None:
    code, out, err = run(
        capsys,
        *BASE,
        "--scene",
        str(_wall_scene(tmp_path, on_start=True)),
        "--start-deg",
        *PICK,
        "--goal-deg",
        *PLACE,
        "--json",
    )
    assert code == EXIT_INFEASIBLE
    result = json.loads(out)
    assert not result["solved"] and result["reason"] == "start in collision"
    assert err.count("\n") == 1 and "start in collision" in err


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (("--start-deg", *PICK), "give the goal"),
        (("--goal-deg", *PLACE), "give the start"),
        (("--start-deg", "1", "2", "--goal-deg", *PLACE), "--start-deg takes 6"),
        (
            ("--start-deg", *PICK, "--goal-pose", "0", "0", "0", "0", "0", "0", "0"),
            "--goal-pose: quat_wxyz must have unit norm",
        ),
        (
            ("--start-deg", *PICK, "--goal-deg", *PLACE, "--planner", "ompl:Nope"),
            "unknown planner 'ompl:Nope'; one of rrtconnect, ompl:BFMT",
        ),
    ],
)
def test_bad_input_is_exit_2_in_one_line(capsys, extra, message) -> None:
    code, out, err = run(capsys, *BASE, *extra)
    assert code == EXIT_BAD_INPUT and out == ""
    assert err.count("\n") == 1 and message in err


def test_a_robot_without_acceleration_limits_is_told_what_to_give(capsys) -> None:
    code, _, err = run(
        capsys,
        "motion",
        "plan",
        "--robot",
        "puma560",
        "--start-deg",
        *PICK,
        "--goal-deg",
        *PLACE,
    )
    assert code == EXIT_BAD_INPUT and "--acceleration-limit" in err
