"""Base placement of seven-axis arms (iiwa14, panda): exact at the map's K values."""

from __future__ import annotations

import json
import math
from typing import ClassVar

import numpy as np
import pinocchio as pin
import pytest

from tests.test_workspace_placement import _write_task_csv
from workbench import ik, load_robot
from workbench.cli import main
from workbench.collision import CollisionChecker, Obstacle, Scene
from workbench.errors import InputError
from workbench.trajectory.csv_io import JointTrajectorySamples, write_trajectory_csv
from workbench.workspace.placement import (
    PlacementInfeasibleError,
    base_transform,
    place_base,
)
from workbench.workspace.placement_check import PlacementEvaluator
from workbench.workspace.redundant import redundancy_values
from workbench.workspace.store import open_map
from workbench.workspace.task_map import build_task_map
from workbench.workspace.task_poses import TaskPoses

#: Agreement of the exact verification with the independent computation.
RTOL_DEXTERITY = 1e-9
#: K of the test maps.
K = 4
#: The known base pose the tasks are reached from (on the test lattice).
BASE = (0.3, -0.2, 0.0, math.radians(40.0))
#: Coarse lattice around BASE: 0.1 m, 20° yaw steps (40° is on it).
REGION = (0.1, 0.5, -0.4, 0.0)
RESOLUTION = 0.1
YAW_STEP = math.radians(20.0)
ROBOTS = ("iiwa14", "panda")
TAU = 2.0 * math.pi


@pytest.fixture(scope="module", params=ROBOTS)
def arm(request, tmp_path_factory):
    """(robot, map path, the map's K values): a coarse map built by the CLI."""
    name = request.param
    path = tmp_path_factory.mktemp(name) / "map.zarr"
    code = main([
        "workspace", "map", "--robot", name, "--resolution", "0.2",
        "--orientations", "32", "--redundancy-samples", str(K),
        "--out", str(path), "--json",
    ])  # fmt: skip
    assert code == 0
    values = np.array(open_map(path).attrs["redundancy"]["values"])
    return load_robot(name), path, values


def _solutions(robot, pose, values):
    """Every (value, q) of ``pose`` (base frame) within the limits, q its
    representative nearest the middle of the limits (computed here)."""
    middle = 0.5 * (robot.lower + robot.upper)
    out = []
    for value in values:
        try:
            solutions = ik.analytic(robot, pose, redundancy=float(value))
        except ik.UnreachableError:
            continue
        for solution in solutions:
            q = np.asarray(solution.q)
            q = q + TAU * np.round((middle - q) / TAU)
            if np.all((robot.lower <= q) & (q <= robot.upper)):
                out.append((float(value), q))
    return out


def _manipulability(robot, q):
    jac = ik.compute_jacobians_local(robot, q[None])[0]
    return math.sqrt(np.linalg.det(jac @ jac.T))


def _task(robot, values, rng, count=4, base=BASE):
    """Poses of random configurations that ``base`` reaches at ``values``."""
    world = base_transform(*base)
    poses = []
    while len(poses) < count:
        pose = robot.fk(rng.uniform(robot.lower, robot.upper)).homogeneous
        if _solutions(robot, pose, values):
            poses.append(world @ pose)
    return np.array(poses)


def _check_independently(robot, placement, task, values, checker=None):
    """Every pose reached at ``values`` within the limits (and free), and the
    worst best manipulability and each pose's kept value, recomputed."""
    inverse = np.linalg.inv(placement.base_pose)
    best = []
    for i, pose in enumerate(task):
        found = _solutions(robot, inverse @ pose, values)
        if checker is not None:
            found = [
                (v, q) for v, q in found if np.min(checker.compute_raw_distances(q)) > 0
            ]
        assert found, f"pose {i} not reached"
        dexterity = [(_manipulability(robot, q), v) for v, q in found]
        top = max(d for d, _ in dexterity)
        at_kept = max(d for d, v in dexterity if v == placement.redundancy[i])
        assert at_kept == pytest.approx(top, rel=RTOL_DEXTERITY)
        best.append(top)
    assert placement.min_dexterity == pytest.approx(min(best), rel=RTOL_DEXTERITY)


def test_placement_found_and_verified_at_the_map_values(arm, rng):
    robot, path, values = arm
    task = _task(robot, values, rng)
    found = place_base(
        robot, task, region=REGION, resolution=RESOLUTION, yaw_step=YAW_STEP,
        map=path, top=3,
    )  # fmt: skip
    assert 1 <= len(found) <= 3
    for placement in found:
        assert placement.all_reachable and placement.missed == 0
        assert math.isnan(placement.min_singularity_margin)
        assert set(placement.redundancy) <= set(values.tolist())
        assert placement.branch in ik.get_solver(robot).branches
        _check_independently(robot, placement, task, values)
    keys = [p.rank_key() for p in found]
    assert keys == sorted(keys)


def test_mounts_with_a_map_use_its_values(arm, rng):
    """Explicit bases: the known one reaches all; the values are the map's."""
    robot, path, values = arm
    task = _task(robot, values, rng, count=3)
    (placement,) = place_base(robot, task, mounts=[BASE], map=path)
    assert placement.all_reachable
    _check_independently(robot, placement, task, values)
    with pytest.raises(InputError, match="the map fixes the values"):
        place_base(robot, task, mounts=[BASE], map=path, redundancy_samples=8)


def test_map_built_in_memory_at_redundancy_samples(rng):
    robot = load_robot("iiwa14")
    count = 2
    values = redundancy_values(ik.get_solver(robot).parameter_range, count)
    task = _task(robot, values, rng, count=3)
    heights = task[:, 2, 3]
    small = build_task_map(
        robot, heights, resolution=0.2, orientations=16, redundancy_samples=count
    )
    np.testing.assert_array_equal(small.redundancy, values)
    assert set(small.arrays) == {"branches", "dexterity"}
    found = place_base(
        robot, task, region=REGION, resolution=RESOLUTION, yaw_step=YAW_STEP,
        map=small, top=1,
    )  # fmt: skip
    _check_independently(robot, found[0], task, values)
    (mounted,) = place_base(robot, task, mounts=[BASE], redundancy_samples=count)
    _check_independently(robot, mounted, task, values)


def test_scene_in_the_world_frame(rng):
    """A box beside the arm: the placement's solutions are collision-free
    (checked with a checker of the scene in the base frame); a cage around
    the arm blocks every pose."""
    robot = load_robot("iiwa14")
    values = redundancy_values(ik.get_solver(robot).parameter_range, K)
    task = _task(robot, values, rng, count=3)
    near = pin.SE3(np.eye(3), np.array([BASE[0] + 0.35, BASE[1], 0.3]))
    scene = Scene("near", (Obstacle("near", "box", (0.2, 0.2, 0.6), near),))
    (placement,) = place_base(
        robot, task, mounts=[BASE], scene=scene, redundancy_samples=K
    )
    assert placement.all_reachable
    world_to_base = pin.SE3(np.linalg.inv(placement.base_pose))
    moved = Obstacle("near", "box", (0.2, 0.2, 0.6), world_to_base * near)
    checker = CollisionChecker(robot, Scene("near", (moved,)))
    _check_independently(robot, placement, task, values, checker)
    world = pin.SE3(np.eye(3), np.array([BASE[0], BASE[1], 0.3]))
    cage = Scene("cage", (Obstacle("cage", "box", (3.0, 3.0, 3.0), world),))
    with pytest.raises(PlacementInfeasibleError, match="misses 3 of 3"):
        place_base(robot, task, mounts=[BASE], scene=cage, redundancy_samples=K)


def test_path_followed_by_a_chain_over_values_and_branches():
    """A straight 10 cm line at fixed orientation, solved by one (value,
    branch) from BASE: a chain follows it; reversed in time, too."""
    robot = load_robot("iiwa14")
    values = redundancy_values(ik.get_solver(robot).parameter_range, K)
    start = robot.fk(np.array([0.2, 0.6, 0.1, -1.2, 0.2, 0.9, 0.3])).homogeneous
    line = np.repeat(start[None], 11, axis=0)
    line[:, 0, 3] += np.linspace(0.0, 0.1, 11)
    task = base_transform(*BASE) @ line
    for poses in (task, task[::-1]):
        path = TaskPoses(poses=poses, ordered=True)
        (placement,) = place_base(robot, path, mounts=[BASE], redundancy_samples=K)
        assert placement.all_reachable and placement.branch
        assert set(placement.redundancy) <= set(values.tolist())
    # two far apart poses: reached one by one, but no chain without a jump
    far = task[[0, -1]].copy()
    far[1, :3, :3] = far[1, :3, :3] @ pin.rpy.rpyToMatrix(0.0, 0.0, math.pi)
    loose = place_base(robot, far, mounts=[BASE], redundancy_samples=K)
    assert loose[0].all_reachable
    with pytest.raises(PlacementInfeasibleError, match="no branch follows"):
        place_base(robot, far, mounts=[BASE], redundancy_samples=K, path=True)


def test_evaluator_needs_the_values_of_seven_axis_arms_only(puma):
    robot = load_robot("panda")
    task = robot.fk(np.zeros(7)).homogeneous[None]
    with pytest.raises(InputError, match="needs the values"):
        PlacementEvaluator(robot, task, None, False)
    with pytest.raises(InputError, match="needs the values"):
        PlacementEvaluator(puma, task, None, False, redundancy=[0.0])
    with pytest.raises(InputError, match="redundancy samples are for seven-axis"):
        place_base(puma, task, mounts=[BASE], redundancy_samples=4)


def test_a_map_without_redundancy_values_is_refused(arm):
    """A map of the arm whose attributes lack the values (damaged or foreign)."""
    robot, path, _ = arm
    stored = open_map(path)

    class Stripped:
        grid = stored.grid
        attrs: ClassVar = {**stored.attrs, "redundancy": None}

        def __getitem__(self, name):
            return stored[name]

    task = robot.fk(np.zeros(7)).homogeneous[None]
    with pytest.raises(InputError, match=r"holds no values of .* redundancy"):
        place_base(robot, task, region=REGION, map=Stripped())


# -- CLI ----------------------------------------------------------------------
def test_cli_place_with_a_seven_axis_map(arm, rng, tmp_path, capsys):
    robot, path, values = arm
    task = _task(robot, values, rng, count=3)
    targets = _write_task_csv(tmp_path / "task.csv", task)
    common = [
        "workspace", "place", "--robot", robot.name, "--targets", str(targets),
        "--map", str(path), "--region", *map(str, REGION), "--resolution",
        str(RESOLUTION), "--yaw-step", "20",
    ]  # fmt: skip
    assert main([*common, "--top", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["feasible"] and 1 <= len(out["placements"]) <= 2
    for p in out["placements"]:
        assert p["all_reachable"] and p["min_singularity_margin"] is None
        assert len(p["redundancy"]) == 3 and set(p["redundancy"]) <= set(values)
    assert main([*common, "--top", "1"]) == 0
    assert "√det(JJᵀ)" in capsys.readouterr().out
    # 5 m above the base: no candidate reaches any pose
    far = task.copy()
    far[:, 2, 3] += 5.0
    far_csv = _write_task_csv(tmp_path / "far.csv", far)
    assert main([*common[:5], str(far_csv), *common[6:]]) == 3
    assert "no base placement reaches all 3" in capsys.readouterr().err
    assert main([*common, "--redundancy-samples", "8"]) == 2
    assert "the map fixes the values" in capsys.readouterr().err


def _line_trajectory(robot, values, rng):
    """Joint samples along a 5 cm line of the tool, one (value, branch) throughout.

    Every sample within the limits, each joint stepping by less than 0.2 rad;
    the configurations solve the line at one of ``values``.
    """
    middle = 0.5 * (robot.lower + robot.upper)
    for _ in range(100):
        start = robot.fk(rng.uniform(robot.lower, robot.upper)).homogeneous
        line = np.repeat(start[None], 11, axis=0)
        line[:, 0, 3] += np.linspace(0.0, 0.05, 11)
        for value in values:
            q, valid = ik.analytic_batch(robot, line, redundancy=float(value))
            for b in range(q.shape[1]):
                if not valid[:, b].all():
                    continue
                path = q[:, b] + TAU * np.round((middle - q[:, b]) / TAU)
                inside = np.all((robot.lower <= path) & (path <= robot.upper))
                if inside and np.max(np.abs(np.diff(path, axis=0))) < 0.2:
                    zeros = np.zeros_like(path)
                    times = np.linspace(0.0, 1.0, len(path))
                    return JointTrajectorySamples(times, path, zeros, zeros)
    raise AssertionError("no line found")


def test_cli_place_a_trajectory_of_a_seven_axis_arm(arm, rng, tmp_path, capsys):
    """A joint trajectory (world frame = its base frame): a base at the origin
    follows it with a chain over the map's (value, branch) solutions."""
    robot, path, values = arm
    samples = _line_trajectory(robot, values, rng)
    csv = tmp_path / "path.csv"
    write_trajectory_csv(csv, samples)
    code = main([
        "workspace", "place", "--robot", robot.name, "--trajectory", str(csv),
        "--map", str(path), "--region", "-0.1", "0.1", "-0.1", "0.1",
        "--resolution", "0.1", "--yaw-step", "90", "--top", "3", "--json",
    ])  # fmt: skip
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    assert out["path"] is True and out["feasible"]
    at_origin = [
        p for p in out["placements"] if (p["x"], p["y"], p["yaw"]) == (0.0, 0.0, 0.0)
    ]
    for p in out["placements"]:
        assert p["all_reachable"] and p["branch"]
        assert len(p["redundancy"]) == len(samples.q)
        assert set(p["redundancy"]) <= set(values.tolist())
    # the origin is a candidate; the chain it has kept is at least as good as
    # the constant one the trajectory was made of
    (origin,) = place_base(
        robot,
        TaskPoses(
            poses=np.array([robot.fk(q).homogeneous for q in samples.q]), ordered=True
        ),
        mounts=[(0.0, 0.0, 0.0, 0.0)],
        map=path,
    )
    worst = min(_manipulability(robot, q) for q in samples.q)
    assert origin.all_reachable and origin.min_dexterity >= worst * (1 - RTOL_DEXTERITY)
    assert not at_origin or at_origin[0]["min_dexterity"] == pytest.approx(
        origin.min_dexterity, rel=RTOL_DEXTERITY
    )
