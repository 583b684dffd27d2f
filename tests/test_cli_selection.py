"""The command line and Python choose the same configurations, to the bit.

One request per command (``ik``, ``plan pick-place`` from tool poses,
``workspace place``), made through :func:`workbench.cli.main` with its JSON
output and through the library call the command documents. JSON floats are
written with ``repr`` (17 significant digits, read back exactly); the writer
prints a vector entry below its largest entry's rounding step as 0
(:func:`workbench.json_numbers.to_json_ready`), so the Python values are
passed through the same function before the exact comparison.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from tests.conftest import run_cli as run
from workbench import ik, load_robot, trajectory
from workbench.json_numbers import to_json_ready
from workbench.poses import parse_target, quat_wxyz_from_rotation
from workbench.workspace.placement import place_base
from workbench.workspace.task_poses import read_task_poses

SEED = 29


def _exact(printed: list[float], computed: np.ndarray) -> bool:
    """``printed`` (from JSON) is ``computed`` as the JSON writer writes it."""
    written = np.array(to_json_ready(computed), dtype=np.float64)
    got = np.array(printed, dtype=np.float64)
    return got.shape == written.shape and bool(
        np.array_equal(got.view(np.int64), written.view(np.int64))
    )


def _configuration(robot, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform(robot.lower, robot.upper)


def _xyz_quat_wxyz(pose: pin.SE3) -> list[str]:
    values = [*pose.translation, *quat_wxyz_from_rotation(pose.rotation)]
    return [repr(float(v)) for v in values]


@pytest.mark.parametrize("name", ["ur5", "puma560", "iiwa14", "panda"])
def test_ik_cli_is_ik_select(capsys, name) -> None:
    robot = load_robot(name)
    target = robot.fk(_configuration(robot, SEED))
    matrix = [repr(float(x)) for x in target.homogeneous.ravel()]
    code, out, err = run(capsys, "ik", "--robot", name, "--matrix", *matrix, "--json")
    assert (code, err) == (0, "")
    (row,) = json.loads(out)["solutions"]
    choice = ik.select(robot, target)
    assert row["branch"] == choice.branch and row["within_limits"]
    assert _exact(row["q"], choice.q)
    # the same numbers typed as position and quaternion: parse_target's pose
    typed = _xyz_quat_wxyz(target)
    code, out, _ = run(
        capsys, "ik", "--robot", name, "--xyz-quat-wxyz", *typed, "--json"
    )
    (row,) = json.loads(out)["solutions"]
    choice = ik.select(robot, parse_target([float(x) for x in typed], "xyz_quat_wxyz"))
    assert code == 0 and _exact(row["q"], choice.q)


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_plan_pick_place_cli_is_pick_and_place_from_poses(capsys, name) -> None:
    robot = load_robot(name)
    pick = _xyz_quat_wxyz(robot.fk(_configuration(robot, SEED)))
    place = _xyz_quat_wxyz(robot.fk(_configuration(robot, SEED + 1)))
    code, out, err = run(
        capsys, "plan", "pick-place", "--robot", name,
        "--pick-xyz-quat-wxyz", *pick, "--place-xyz-quat-wxyz", *place,
        "--duration", "8", "--no-collision", "--json",
    )  # fmt: skip
    assert code == 0, err
    result = json.loads(out)
    poses = [
        parse_target([float(x) for x in p], "xyz_quat_wxyz") for p in (pick, place)
    ]
    planned = trajectory.pick_and_place_from_poses(robot, *poses, 8.0)
    assert _exact(result["q_pick"], planned.pick.q)
    assert _exact(result["q_place"], planned.place.q)
    assert result["branch"] == planned.pick.branch == planned.place.branch
    first, second = ik.pick_place_configurations(robot, *poses)
    assert np.array_equal(first.q, planned.pick.q)
    assert np.array_equal(second.q, planned.place.q)


def _task_csv(path: Path, robot, base: np.ndarray, count: int) -> Path:
    rng = np.random.default_rng(SEED)
    lines = ["x,y,z,qx,qy,qz,qw"]
    for q in rng.uniform(robot.lower, robot.upper, size=(count, robot.nq)):
        pose = base @ robot.fk(q).homogeneous
        quat = pin.Quaternion(pose[:3, :3]).coeffs()
        lines.append(",".join(repr(float(v)) for v in [*pose[:3, 3], *quat]))
    path.write_text("\n".join(lines) + "\n")
    return path


def test_workspace_place_cli_is_place_base(capsys, tmp_path) -> None:
    robot = load_robot("puma560")
    base = np.eye(4)
    base[:3, 3] = 0.2, 0.2, 0.0
    path = _task_csv(tmp_path / "task.csv", robot, base, 5)
    zarr = tmp_path / "map.zarr"
    code, _, err = run(
        capsys, "workspace", "map", "--robot", "puma560", "--resolution", "0.4",
        "--orientations", "8", "--workers", "1", "--out", str(zarr),
    )  # fmt: skip
    assert code == 0, err
    region = (0.0, 0.4, 0.0, 0.4)
    code, out, err = run(
        capsys, "workspace", "place", "--robot", "puma560", "--targets", str(path),
        "--map", str(zarr), "--region", *map(str, region), "--resolution", "0.2",
        "--yaw-step", "90", "--top", "2", "--json",
    )  # fmt: skip
    assert code == 0, err
    printed = json.loads(out)["placements"]
    placements = place_base(
        robot,
        read_task_poses(path),
        region=region,
        resolution=0.2,
        yaw_step=math.radians(90.0),
        map=zarr,
        top=2,
    )
    assert printed and printed == [to_json_ready(p.as_dict()) for p in placements]
