"""Per-pose measures of a block of the workspace grid: compiled, NumPy, Pinocchio."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from conftest import random_configurations

from benchmarks.bench_ik_agreement import rounded_urdf
from workbench import Robot, load_robot
from workbench.collision import CollisionChecker
from workbench.collision.scene import Obstacle, Scene
from workbench.collision.scene_file import read_scene, write_scene
from workbench.errors import DimensionError, InputError
from workbench.ik import (
    UnreachableError,
    UnsupportedRobotError,
    analytic,
    get_solver,
)
from workbench.ik._refine_kernel import refinement_chain
from workbench.singularities.conditions import (
    ELBOW_TOL,
    SHOULDER_TOL,
    WRIST_TOL,
    get_factorisation,
)
from workbench.workspace import (
    POSE_KEYS,
    VOXEL_KEYS,
    PoseGrid,
    evaluate_block,
    make_pose_grid,
    singularity_margin,
)
from workbench.workspace import _measure_kernel as kernel
from workbench.workspace._reference import (
    block_poses,
    evaluate_block_reference,
    limit_representatives,
)
from workbench.workspace.measures import _constants
from workbench.workspace.orientations import rotations_from_quat_xyzw

ROBOTS = ("puma560", "puma560-kang", "ur5", "kuka-kr6-r700")
#: Relative agreement of the compiled and NumPy float measures.
RTOL_KERNEL = 1e-6
#: Relative agreement of |det J| with Pinocchio's √det(J Jᵀ).
RTOL_DET = 1e-9
#: Absolute agreement [m³] at a singularity (|det J| of rounding size).
ATOL_DET = 1e-15
#: |det J| [m³] above which √det(J Jᵀ) itself is compared to RTOL_DET.
WELL_CONDITIONED = 1e-3
#: Pose error of an in-limit closed-form solution [m, rad].
ATOL_POSE = 1e-9
#: Poses checked one by one against ik.analytic and Pinocchio per robot.
CHECKED_POSES = 400


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request: pytest.FixtureRequest) -> Robot:
    """Each closed-form robot in turn."""
    return load_robot(request.param)


def _special_grid(robot: Robot, rng: np.random.Generator) -> PoseGrid:
    """Positions × orientations of singular, boundary and random configurations.

    Every pose (v, v) is the FK of one configuration: wrist-singular (θ5 = 0),
    elbow-singular (stretched arm, at the reach boundary) or random; the
    off-diagonal pairs mix positions and orientations, many unreachable.
    """
    fac = get_factorisation(robot)
    q = random_configurations(robot, rng, 36)
    wrist_zero = (0.0 - fac.theta_offset[4]) / fac.joint_sign[4]
    q[:12, 4] = wrist_zero
    if fac.family == "ur":
        t3 = 0.0
    else:
        t3 = math.atan2(fac.sigma3 * fac.d4, fac.a3)
    q[12:24, 2] = (t3 - fac.theta_offset[2]) / fac.joint_sign[2]
    poses = [robot.fk(x) for x in q]
    positions = np.array([p.translation for p in poses])
    quat = np.array([pin.Quaternion(p.rotation).coeffs() for p in poses])
    quat[quat[:, 3] < 0] *= -1.0
    base = make_pose_grid(robot, resolution=1.0, orientations=1)
    return dataclasses.replace(
        base,
        positions=positions,
        orientations=quat,
        rotations=rotations_from_quat_xyzw(quat),
    )


def _coarse_grid(robot: Robot) -> PoseGrid:
    return make_pose_grid(robot, resolution=0.15, orientations=48)


def _compare(fast: dict[str, np.ndarray], ref: dict[str, np.ndarray]) -> None:
    assert set(fast) == set(ref)
    for key in ("reached", "branches"):
        assert fast[key].dtype == np.uint8
        np.testing.assert_array_equal(fast[key], ref[key], err_msg=key)
    for key in set(ref) - {"reached", "branches"}:
        assert fast[key].dtype == np.float32
        np.testing.assert_array_equal(np.isnan(fast[key]), np.isnan(ref[key]))
        np.testing.assert_allclose(
            fast[key], ref[key], rtol=RTOL_KERNEL, atol=0, err_msg=key
        )


@pytest.mark.slow
def test_kernel_equals_the_reference_on_a_real_block(robot: Robot) -> None:
    grid = _coarse_grid(robot)
    fast = evaluate_block(robot, grid, 0, grid.voxel_count)
    ref = evaluate_block_reference(robot, grid, 0, grid.voxel_count)
    _compare(fast, ref)
    reach = fast["reachability"]
    assert np.any(reach == 0.0) and np.any(reach > 0.5)  # unreachable voxels too
    assert fast["reached"].shape == (grid.voxel_count, grid.orientation_count)


def test_kernel_equals_the_reference_at_singular_and_boundary_poses(
    robot: Robot,
) -> None:
    grid = _special_grid(robot, np.random.default_rng(1))
    fast = evaluate_block(robot, grid, 0, grid.voxel_count)
    _compare(fast, evaluate_block_reference(robot, grid, 0, grid.voxel_count))
    diagonal = np.arange(grid.voxel_count)
    assert np.all(fast["reached"][diagonal, diagonal] > 0)  # FK poses are reached


def _in_limits(q: np.ndarray, robot: Robot) -> np.ndarray | None:
    """A representative of ``q`` within the limits, found by trying turns."""
    out = q.copy()
    for j in range(len(q)):
        found = [
            q[j] + 2 * math.pi * k
            for k in range(-3, 4)
            if robot.lower[j] <= q[j] + 2 * math.pi * k <= robot.upper[j]
        ]
        if not found:
            return None
        out[j] = found[0]
    return out


def _pose_error(robot: Robot, q: np.ndarray, pose: np.ndarray) -> float:
    reached = robot.fk(q)
    position = np.linalg.norm(reached.translation - pose[:3, 3])
    rotation = np.linalg.norm(pin.log3(reached.rotation.T @ pose[:3, :3]))
    return float(max(position, rotation))


def _manipulability(robot: Robot, q: np.ndarray) -> float:
    """Yoshikawa's √det(J Jᵀ) from Pinocchio's Jacobian, as |det J| (J is 6×6).

    The determinant by LU keeps its accuracy near a singularity, where
    det(J Jᵀ) loses it to rounding; :func:`_yoshikawa` is the literal form.
    """
    return abs(float(np.linalg.det(robot.jacobian(q))))


def _yoshikawa(robot: Robot, q: np.ndarray) -> float:
    jac = robot.jacobian(q)
    return math.sqrt(max(float(np.linalg.det(jac @ jac.T)), 0.0))


def _checked_poses(robot: Robot) -> tuple[PoseGrid, np.ndarray]:
    grid = _special_grid(robot, np.random.default_rng(2))
    rng = np.random.default_rng(3)
    flat = rng.choice(grid.pose_count, size=CHECKED_POSES, replace=False)
    return grid, np.sort(flat)


def test_counts_and_dexterity_against_analytic_and_pinocchio(robot: Robot) -> None:
    grid, flat = _checked_poses(robot)
    out = evaluate_block(robot, grid, 0, grid.voxel_count)
    poses = block_poses(grid, 0, grid.voxel_count)
    factors, joints = _constants(robot)
    q_all, valid = get_solver(robot).solve_batch(poses[flat])
    counts = np.zeros((2, len(flat)), dtype=np.uint8)
    measures = np.zeros((5, len(flat)), dtype=np.float32)
    dexterity = np.zeros((2, len(flat)))
    kernel.measure_poses(factors, joints, q_all, valid, 0, counts, measures, dexterity)
    usable_poses = 0
    for row, index in enumerate(flat):
        v, o = divmod(int(index), grid.orientation_count)
        try:
            solutions = analytic(robot, poses[index])
        except UnreachableError:
            solutions = []
        assert out["reached"][v, o] == len(solutions)
        inside = [rep for s in solutions if (rep := _in_limits(s.q, robot)) is not None]
        for rep in inside:
            assert _pose_error(robot, rep, poses[index]) < ATOL_POSE
        assert out["branches"][v, o] == len(inside)
        if not inside:
            assert np.isnan(out["dexterity"][v, o]) and np.isnan(dexterity[0, row])
            continue
        usable_poses += 1
        expected = max(_manipulability(robot, rep) for rep in inside)
        np.testing.assert_allclose(
            dexterity[0, row], expected, rtol=RTOL_DET, atol=ATOL_DET
        )
        if expected > WELL_CONDITIONED:
            literal = max(_yoshikawa(robot, rep) for rep in inside)
            np.testing.assert_allclose(dexterity[0, row], literal, rtol=RTOL_DET)
        assert out["dexterity"][v, o] == np.float32(dexterity[0, row])
    assert usable_poses > CHECKED_POSES // 10


def test_limit_representatives_have_the_largest_margin() -> None:
    lower, upper = np.array([-1.0, -4.0, -np.inf]), np.array([2.0, 1.0, np.inf])
    q = np.array([[2.0 * math.pi + 0.5, 3.0, 100.0]])
    shifted, margin, within = limit_representatives(q, lower, upper)
    np.testing.assert_allclose(shifted[0], [0.5, 3.0 - 2 * math.pi, 100.0], atol=1e-12)
    assert within[0]
    assert margin[0] == pytest.approx(min(1.5, 1.5, 3.0 - 2 * math.pi + 4.0))
    _, _, outside = limit_representatives(np.array([[3.0, 0.0, 0.0]]), lower, upper)
    assert not outside[0]


def test_singularity_margin() -> None:
    got = singularity_margin([0.02, -0.001, np.nan], [0.5, 0.5, 0.1], [0.9, 0.9, 1.0])
    np.testing.assert_allclose(got[:2], [2.0, 0.1], rtol=1e-15)
    assert np.isnan(got[2])
    assert singularity_margin(SHOULDER_TOL, ELBOW_TOL, WRIST_TOL) == pytest.approx(1.0)


def test_blocks_are_deterministic_and_independent_of_the_split() -> None:
    robot = load_robot("puma560")
    grid = make_pose_grid(robot, resolution=0.1, orientations=64)
    start = grid.voxel_count // 2
    whole = evaluate_block(robot, grid, start, start + 30)
    again = evaluate_block(robot, grid, start, start + 30)
    first = evaluate_block(robot, grid, start, start + 11)
    second = evaluate_block(robot, grid, start + 11, start + 30)
    for key in whole:
        assert np.array_equal(whole[key], again[key], equal_nan=True)
        joined = np.concatenate([first[key], second[key]])
        assert np.array_equal(whole[key], joined, equal_nan=True), key
    assert set(whole) == (set(POSE_KEYS) - {"collision_free"}) | set(VOXEL_KEYS)


def test_reused_buffers_give_the_same_bits_and_are_the_threads() -> None:
    """``reuse=True``: the same arrays, in this thread's buffers (next call's)."""
    robot = load_robot("puma560")
    grid = make_pose_grid(robot, resolution=0.1, orientations=64)
    start = grid.voxel_count // 2
    fresh = evaluate_block(robot, grid, start, start + 30)
    reused = evaluate_block(robot, grid, start, start + 30, reuse=True)
    for key in fresh:
        assert np.array_equal(fresh[key], reused[key], equal_nan=True), key
    kept = {key: values.copy() for key, values in reused.items()}
    smaller = evaluate_block(robot, grid, start + 30, start + 41, reuse=True)
    for key in ("reached", "dexterity"):  # first rows of the buffers: written over
        assert np.shares_memory(smaller[key], reused[key]), key
        assert not np.shares_memory(smaller[key], fresh[key]), key
    again = evaluate_block(robot, grid, start, start + 30, reuse=True)
    for key in kept:
        assert np.array_equal(kept[key], again[key], equal_nan=True), key


def test_voxel_summaries() -> None:
    robot = load_robot("ur5")
    grid = make_pose_grid(robot, resolution=0.1, orientations=32)
    start = grid.voxel_count // 2 - 40
    out = evaluate_block(robot, grid, start, start + 80)
    usable = ~np.isnan(out["dexterity"])
    np.testing.assert_array_equal(
        out["reachability"], usable.mean(axis=1, dtype=np.float32)
    )
    for v in np.nonzero(usable.any(axis=1))[0][:20]:
        values = out["dexterity"][v][usable[v]]
        assert out["dexterity_best"][v] == values.max()
        assert out["dexterity_median"][v] == pytest.approx(np.median(values), rel=1e-6)
        margin = singularity_margin(
            out["shoulder"][v][usable[v]],
            out["elbow"][v][usable[v]],
            out["wrist"][v][usable[v]],
        )
        assert out["near_singular_fraction"][v] == pytest.approx(np.mean(margin < 1.0))
    none = ~usable.any(axis=1)
    assert np.all(np.isnan(out["dexterity_best"][none]))
    assert np.all(np.isnan(out["near_singular_fraction"][none]))


def test_with_a_scene_the_best_branch_is_collision_free(tmp_path: Path) -> None:
    robot = load_robot("puma560")
    placement = pin.SE3(np.eye(3), np.array([0.55, 0.0, 0.0]))
    wall = Obstacle("wall", "box", (0.05, 2.0, 2.0), placement)
    path = write_scene(Scene("wall", (wall,)), tmp_path / "wall.json")
    checker = CollisionChecker(robot, read_scene(path))
    grid = make_pose_grid(robot, resolution=0.1, orientations=8)
    free_poses = blocked_poses = 0
    for x in (0.4, 0.5):  # clear of the wall; the hand reaches into it
        start = int(grid.voxel_index(np.array([[x, 0.0, 0.0]]))[0]) - 3
        out = evaluate_block(robot, grid, start, start + 6, checker=checker)
        for v, o in np.ndindex(6, grid.orientation_count):
            pose = grid.pose(start + v, o)
            try:
                solutions = analytic(robot, pose)
            except UnreachableError:
                solutions = []
            inside = [r for s in solutions if (r := _in_limits(s.q, robot)) is not None]
            free = [r for r in inside if np.all(checker.compute_distances(r) > 0.0)]
            assert out["branches"][v, o] == len(inside)
            assert out["collision_free"][v, o] == len(free)
            if free:
                free_poses += 1
                expected = max(_manipulability(robot, r) for r in free)
                assert out["dexterity"][v, o] == pytest.approx(expected, rel=1e-6)
            else:
                blocked_poses += len(inside) > 0
                assert np.isnan(out["dexterity"][v, o])
    assert free_poses > 0 and blocked_poses > 0


@pytest.mark.slow
def test_bad_requests() -> None:
    robot = load_robot("puma560")
    grid = make_pose_grid(robot, resolution=0.2, orientations=4)
    for start, stop in ((5, 5), (-1, 3), (0, grid.voxel_count + 1)):
        with pytest.raises(InputError, match="voxel range"):
            evaluate_block(robot, grid, start, stop)
    with pytest.raises(InputError, match="integer"):
        evaluate_block(robot, grid, 0.0, 3)  # type: ignore[arg-type]
    solver = get_solver(robot)
    poses = np.tile(np.eye(4), (3, 1, 1))
    with pytest.raises(DimensionError, match="valid"):
        solver.solve_batch_into(poses, np.empty((3, 8, 6)), np.empty((2, 8), bool))
    panda = load_robot("panda")
    with pytest.raises(UnsupportedRobotError):
        evaluate_block(
            panda, make_pose_grid(panda, resolution=0.3, orientations=2), 0, 2
        )


@pytest.mark.parametrize(("name", "zeros"), [("kuka-kr6-r700", False), ("ur5", True)])
def test_near_model_urdf_is_refined_and_equals_the_reference(
    name: str, zeros: bool, tmp_path: Path
) -> None:
    robot = rounded_urdf(name, tmp_path, zeros=zeros)
    assert refinement_chain(robot) is not None  # the solver refines its branches
    grid = make_pose_grid(robot, resolution=0.2, orientations=16)
    fast = evaluate_block(robot, grid, 0, grid.voxel_count)
    _compare(fast, evaluate_block_reference(robot, grid, 0, grid.voxel_count))
    assert np.nanmax(fast["reachability"]) > 0.5
