"""Sampled workspace maps: determinism, binning and manipulability of every hit."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from workbench import Robot, load_robot
from workbench.errors import DimensionError, InputError
from workbench.ik import compute_tool_poses
from workbench.workspace import PoseGrid, make_pose_grid
from workbench.workspace.orientations import (
    quat_xyzw_from_rotations,
    rotations_from_quat_xyzw,
)
from workbench.workspace.sampled import accumulate, sample_block, sample_configurations

#: Relative agreement of the compiled manipulability with Pinocchio's.
RTOL_MANIPULABILITY = 1e-9
#: Absolute agreement [m³] where J Jᵀ is near singular.
ATOL_MANIPULABILITY = 1e-12
#: Slack [m, rad] on the binning bounds (rounding of the voxel arithmetic).
BINNING_SLACK = 1e-12
SAMPLES = 3000


@pytest.fixture(scope="module")
def panda() -> Robot:
    """Franka Panda, seven joints: no closed form."""
    return load_robot("panda")


@pytest.fixture(scope="module")
def panda_grid(panda: Robot) -> PoseGrid:
    """Panda at 10 cm and 64 orientations."""
    return make_pose_grid(panda, resolution=0.1, orientations=64)


def test_blocks_are_deterministic(panda: Robot, panda_grid: PoseGrid) -> None:
    cells, values = sample_block(panda, panda_grid, 3, SAMPLES, 11)
    again = sample_block(panda, panda_grid, 3, SAMPLES, 11)
    assert np.array_equal(cells, again[0]) and np.array_equal(values, again[1])
    other = sample_block(panda, panda_grid, 4, SAMPLES, 11)
    assert not np.array_equal(cells, other[0])
    assert cells.dtype == np.int64 and values.dtype == np.float64


def test_every_hit_is_reachable(panda: Robot, panda_grid: PoseGrid) -> None:
    grid = panda_grid
    cells, values = sample_block(panda, grid, 0, SAMPLES, 5)
    q = sample_configurations(panda, 0, SAMPLES, 5)
    assert np.all((q >= panda.lower) & (q <= panda.upper))
    poses = [panda.fk(x) for x in q]
    positions = np.array([p.translation for p in poses])
    inside = grid.voxel_index(positions) >= 0
    assert inside.sum() == len(cells) > SAMPLES // 2
    radius = grid.orientation_set["covering_radius"]
    kept = [pose for pose, keep in zip(poses, inside, strict=True) if keep]
    for cell, value, x, pose in zip(cells, values, q[inside], kept, strict=True):
        v, o = divmod(int(cell), grid.orientation_count)
        offset = np.abs(pose.translation - grid.positions[v])
        assert np.all(offset <= grid.resolution / 2 + BINNING_SLACK)
        target = rotations_from_quat_xyzw(grid.orientations[o][None])[0]
        angle = np.linalg.norm(pin.log3(target.T @ pose.rotation))
        assert angle <= radius + BINNING_SLACK
        jac = panda.jacobian(x)
        expected = math.sqrt(max(float(np.linalg.det(jac @ jac.T)), 0.0))
        np.testing.assert_allclose(
            value, expected, rtol=RTOL_MANIPULABILITY, atol=ATOL_MANIPULABILITY
        )


def test_six_axis_manipulability_is_det_j() -> None:
    robot = load_robot("ur5")
    grid = make_pose_grid(robot, resolution=0.2, orientations=8)
    cells, values = sample_block(robot, grid, 0, 200, 1)
    q = sample_configurations(robot, 0, 200, 1)
    dets = np.array([abs(np.linalg.det(robot.jacobian(x))) for x in q])
    inside = grid.voxel_index(np.array([robot.fk(x).translation for x in q])) >= 0
    np.testing.assert_allclose(values, dets[inside], rtol=1e-9, atol=1e-13)
    assert len(cells) == inside.sum()


def test_accumulate_is_an_order_free_maximum(
    panda: Robot, panda_grid: PoseGrid
) -> None:
    shape = (panda_grid.voxel_count, panda_grid.orientation_count)
    blocks = [sample_block(panda, panda_grid, b, 800, 2) for b in range(3)]

    def fold(order: list[int]) -> tuple[np.ndarray, np.ndarray]:
        hit, dexterity = np.zeros(shape, np.uint8), np.full(shape, np.nan, np.float32)
        for b in order:
            accumulate(*blocks[b], hit, dexterity)
        return hit, dexterity

    hit, dexterity = fold([0, 1, 2])
    other = fold([2, 0, 1])
    assert np.array_equal(hit, other[0])
    assert np.array_equal(dexterity, other[1], equal_nan=True)
    cells = np.concatenate([c for c, _ in blocks])
    values = np.concatenate([v for _, v in blocks])
    assert hit.sum() == len(np.unique(cells))
    best = {}
    for cell, value in zip(cells.tolist(), values.tolist(), strict=True):
        best[cell] = max(best.get(cell, -1.0), value)
    flat = dexterity.reshape(-1)
    for cell, value in best.items():
        assert flat[cell] == np.float32(value)
    assert np.isnan(flat[hit.reshape(-1) == 0]).all()


def test_quaternions_of_rotations_round_trip() -> None:
    rng = np.random.default_rng(9)
    quat = rng.standard_normal((500, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    quat[quat[:, 3] < 0] *= -1
    half_turns = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, 0]])
    quat = np.vstack([quat, half_turns])
    back = quat_xyzw_from_rotations(rotations_from_quat_xyzw(quat))
    np.testing.assert_allclose(np.abs(np.sum(back * quat, axis=1)), 1.0, atol=1e-15)
    for r, q in zip(rotations_from_quat_xyzw(quat[:20]), back[:20], strict=True):
        expected = pin.Quaternion(r).coeffs()
        np.testing.assert_allclose(abs(expected @ q), 1.0, atol=1e-15)


def test_bad_input(panda: Robot, panda_grid: PoseGrid) -> None:
    with pytest.raises(InputError, match="samples_per_block must be positive"):
        sample_block(panda, panda_grid, 0, 0, 1)
    with pytest.raises(InputError, match="block must be non-negative"):
        sample_block(panda, panda_grid, -1, 10, 1)
    with pytest.raises(InputError, match="seed must be an integer"):
        sample_block(panda, panda_grid, 0, 10, 1.5)  # type: ignore[arg-type]
    hit, dexterity = np.zeros(10, np.uint8), np.full(10, np.nan)
    with pytest.raises(InputError, match=r"cells must lie in \[0, 10\)"):
        accumulate(np.array([10]), np.array([1.0]), hit, dexterity)
    with pytest.raises(InputError, match="one length"):
        accumulate(np.array([1, 2]), np.array([1.0]), hit, dexterity)
    with pytest.raises(InputError, match="C-contiguous"):
        accumulate(np.array([1]), np.array([1.0]), hit, np.full((10, 2), np.nan)[:, 0])
    with pytest.raises(InputError, match="differ"):
        accumulate(np.array([1]), np.array([1.0]), hit, np.full(11, np.nan))


@pytest.mark.parametrize("name", ["panda", "ur5", "puma560"])
def test_tool_poses_match_pinocchio(name: str) -> None:
    robot = load_robot(name)
    rng = np.random.default_rng(12)
    q = rng.uniform(robot.lower, robot.upper, size=(50, robot.nq))
    rotations, positions, _ = compute_tool_poses(robot, q)
    for x, rotation, position in zip(q, rotations, positions, strict=True):
        pose = robot.fk(x)
        np.testing.assert_allclose(rotation, pose.rotation, rtol=0, atol=1e-12)
        np.testing.assert_allclose(position, pose.translation, rtol=0, atol=1e-12)
    with pytest.raises(DimensionError):
        compute_tool_poses(robot, q[:, :-1])
