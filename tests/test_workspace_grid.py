"""The workspace pose grid: orientation sets, covering radii, voxel and pose indices."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import random_configurations
from hypothesis import given
from hypothesis import strategies as st

from workbench import load_robot
from workbench.errors import DimensionError, InputError, NonFiniteError
from workbench.poses.rotations import rotation_from_quat_xyzw
from workbench.workspace import (
    PoseGrid,
    cone_orientations,
    default_bounds,
    make_pose_grid,
    uniform_orientations,
)
from workbench.workspace.orientations import (
    quat_multiply_xyzw,
    rotation_angle_between,
    rotations_from_quat_xyzw,
)

ATOL_EXACT = 1e-12
#: Rotations checked against the covering radius in a test.
CHECKED_ROTATIONS = 20_000
ROBOTS = (
    "puma560", "puma560-kang", "ur5", "kuka-kr6-r700", "abb-irb2400", "panda",
    "generic6r",
)  # fmt: skip


@pytest.fixture(scope="module")
def puma_grid() -> PoseGrid:
    """PUMA 560 at 10 cm and 64 orientations."""
    return make_pose_grid(load_robot("puma560"), resolution=0.1, orientations=64)


def _angles_by_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation angles (N, M) between quaternion sets, from their matrices."""
    ra, rb = rotations_from_quat_xyzw(a), rotations_from_quat_xyzw(b)
    trace = np.einsum("nij,mij->nm", ra, rb)
    return np.arccos(np.clip((trace - 1.0) / 2.0, -1.0, 1.0))


def _random_quats(rng: np.random.Generator, count: int) -> np.ndarray:
    q = rng.standard_normal((count, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


@pytest.mark.slow
@pytest.mark.parametrize("n", [1, 7, 64, 512])
def test_uniform_set_is_unit_canonical_and_deterministic(n: int) -> None:
    quat, info = uniform_orientations(n)
    assert quat.shape == (n, 4)
    assert not quat.flags.writeable
    np.testing.assert_allclose(np.linalg.norm(quat, axis=1), 1.0, rtol=0, atol=1e-15)
    assert np.all(quat[:, 3] >= 0.0)
    assert info["construction"] == "super-fibonacci"
    assert info["count"] == n
    assert np.array_equal(quat, uniform_orientations(n)[0])


def test_uniform_set_follows_the_super_fibonacci_formula() -> None:
    n = 100
    quat, _ = uniform_orientations(n)
    i = 37
    s = i + 0.5
    r, big_r = math.sqrt(s / n), math.sqrt(1.0 - s / n)
    alpha, beta = 2 * math.pi * s / math.sqrt(2.0), 2 * math.pi * s / 1.533751168755204
    x, y = r * math.sin(alpha), r * math.cos(alpha)
    expected = np.array([x, y, big_r * math.sin(beta), big_r * math.cos(beta)])
    expected *= 1.0 if expected[3] >= 0 else -1.0
    np.testing.assert_allclose(quat[i], expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("n", [64, 512])
def test_covering_radius_bounds_random_rotations(n: int) -> None:
    quat, info = uniform_orientations(n)
    radius = info["covering_radius"]
    samples = _random_quats(np.random.default_rng(7), CHECKED_ROTATIONS)
    nearest = np.min(_angles_by_matrix(samples[:2000], quat), axis=1)
    assert nearest.max() <= radius
    dots = np.abs(samples @ quat.T).max(axis=1)
    assert np.max(2 * np.arccos(np.minimum(dots, 1.0))) <= radius
    # a fair estimate: about the radius of a ball of the mean cell volume
    cell = math.pi**2 / n  # volume of SO(3) in quaternion-sphere measure / n
    ball = (3 * cell / (4 * math.pi)) ** (1 / 3) * 2  # rotation angle
    assert ball < radius < 2.5 * ball


@pytest.mark.slow
def test_covering_radius_shrinks_with_the_count() -> None:
    radii = [uniform_orientations(n)[1]["covering_radius"] for n in (64, 512, 4096)]
    assert radii[0] > radii[1] > radii[2]
    assert radii[0] / radii[1] == pytest.approx(2.0, rel=0.25)  # n^(1/3)


@given(raw=st.lists(st.floats(-1, 1), min_size=4, max_size=4))
def test_nearest_orientation_is_nearest(puma_grid: PoseGrid, raw: list[float]) -> None:
    q = np.array(raw)
    if np.linalg.norm(q) < 1e-3:
        return
    q = q / np.linalg.norm(q)
    grid = puma_grid
    index = grid.orientation_index(q[None])[0]
    angles = _angles_by_matrix(q[None], grid.orientations)[0]
    assert angles[index] <= angles.min() + 1e-12
    assert grid.orientation_index(-q[None])[0] == index


def test_orientation_and_voxel_index_round_trip(puma_grid: PoseGrid) -> None:
    np.testing.assert_array_equal(
        puma_grid.orientation_index(puma_grid.orientations),
        np.arange(puma_grid.orientation_count),
    )
    np.testing.assert_array_equal(
        puma_grid.voxel_index(puma_grid.positions), np.arange(puma_grid.voxel_count)
    )


@given(
    offset=st.lists(st.floats(-0.4999, 0.4999), min_size=3, max_size=3),
    seed=st.integers(0),
)
def test_voxel_index_of_points_in_a_voxel(
    puma_grid: PoseGrid, offset: list[float], seed: int
) -> None:
    grid = puma_grid
    v = seed % grid.voxel_count
    point = grid.positions[v] + np.array(offset) * grid.resolution
    assert grid.voxel_index(point[None])[0] == v


def test_voxel_layout_is_c_order(puma_grid: PoseGrid) -> None:
    nx, ny, nz = puma_grid.shape
    ix, iy, iz = 3, 5, 7
    flat = (ix * ny + iy) * nz + iz
    expected = puma_grid.origin + puma_grid.resolution * np.array([ix, iy, iz])
    np.testing.assert_allclose(puma_grid.positions[flat], expected, rtol=0, atol=1e-12)
    assert puma_grid.voxel_count == nx * ny * nz
    ratios = puma_grid.origin / puma_grid.resolution
    np.testing.assert_allclose(ratios, np.rint(ratios), rtol=0, atol=1e-9)


def test_points_outside_the_grid_have_no_voxel(puma_grid: PoseGrid) -> None:
    far = puma_grid.bounds[1] + puma_grid.resolution
    below = puma_grid.bounds[0] - puma_grid.resolution
    assert puma_grid.voxel_index(np.stack([far, below])).tolist() == [-1, -1]


def test_pose_of_a_grid_index(puma_grid: PoseGrid) -> None:
    pose = puma_grid.pose(10, 3)
    np.testing.assert_allclose(pose[:3, 3], puma_grid.positions[10], rtol=0, atol=0)
    expected = rotation_from_quat_xyzw(puma_grid.orientations[3])
    np.testing.assert_allclose(pose[:3, :3], expected, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_array_equal(pose[3], [0, 0, 0, 1])


def test_rotations_match_the_single_quaternion_conversion() -> None:
    quat = _random_quats(np.random.default_rng(3), 50)
    batch = rotations_from_quat_xyzw(quat)
    for q, matrix in zip(quat, batch, strict=True):
        np.testing.assert_allclose(
            matrix, rotation_from_quat_xyzw(q), rtol=0, atol=ATOL_EXACT
        )


def test_quaternion_product_composes_rotations() -> None:
    a, b = _random_quats(np.random.default_rng(4), 2)
    product = rotations_from_quat_xyzw(quat_multiply_xyzw(a, b)[None])[0]
    expected = (
        rotations_from_quat_xyzw(a[None])[0] @ rotations_from_quat_xyzw(b[None])[0]
    )
    np.testing.assert_allclose(product, expected, rtol=0, atol=ATOL_EXACT)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("axis", "half_deg"), [((0, 0, -1), 30.0), ((1, 1, 0), 10.0), ((0, 0, 1), 180.0)]
)
def test_cone_set_stays_in_its_cone(axis: tuple[float, ...], half_deg: float) -> None:
    half = math.radians(half_deg)
    quat, info = cone_orientations(axis, half, 200)
    direction = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    tool_z = rotations_from_quat_xyzw(quat)[:, :, 2]
    angles = np.arccos(np.clip(tool_z @ direction, -1.0, 1.0))
    assert angles.max() <= half + 1e-12
    assert np.all(quat[:, 3] >= 0.0) and quat.shape == (200, 4)
    assert info["construction"] == "super-fibonacci-cone"
    assert info["half_angle"] == half
    np.testing.assert_allclose(info["axis"], direction, rtol=0, atol=1e-15)


@pytest.mark.slow
def test_cone_covering_radius_bounds_rotations_in_the_cone() -> None:
    half = math.radians(30.0)
    quat, info = cone_orientations((0, 0, -1), half, 256)
    rng = np.random.default_rng(11)
    samples = _random_quats(rng, 400_000)
    tool_z = rotations_from_quat_xyzw(samples)[:, :, 2]
    inside = samples[np.arccos(np.clip(-tool_z[:, 2], -1.0, 1.0)) <= half]
    assert len(inside) > 10_000
    nearest = np.min(rotation_angle_between(inside[:, None], quat[None]), axis=1)
    assert nearest.max() <= info["covering_radius"]
    uniform_radius = uniform_orientations(256)[1]["covering_radius"]
    assert info["covering_radius"] < uniform_radius  # a smaller region, denser


@pytest.mark.parametrize("name", ROBOTS)
def test_default_bounds_hold_the_reach(name: str) -> None:
    robot = load_robot(name)
    box = default_bounds(robot)
    q = random_configurations(robot, np.random.default_rng(5), 3000)
    stretched = q.copy()
    stretched[:, 1:] = 0.0  # straightened arms, at the reach where the model is
    points = np.array([robot.fk(x).translation for x in np.vstack([q, stretched])])
    assert np.all(points >= box[0]) and np.all(points <= box[1])
    grid = make_pose_grid(robot, resolution=0.05, orientations=1)
    assert np.all(grid.voxel_index(points) >= 0)


def test_grid_bounds_given() -> None:
    grid = make_pose_grid(
        load_robot("puma560"),
        resolution=0.1,
        orientations=8,
        bounds=[[0, 0, 0], [0.3, 0.2, 0.1]],
    )
    assert grid.shape == (4, 3, 2)
    np.testing.assert_allclose(grid.origin, 0.0, rtol=0, atol=0)


@pytest.mark.parametrize(
    ("call", "fragment"),
    [
        (lambda: uniform_orientations(0), "positive integer"),
        (lambda: uniform_orientations(2.5), "positive integer"),  # type: ignore[arg-type]
        (lambda: cone_orientations((0, 0, 0), 0.3, 8), "nonzero"),
        (lambda: cone_orientations((0, 0, 1), 0.0, 8), "half_angle"),
        (lambda: cone_orientations((0, 0, 1), 4.0, 8), "half_angle"),
    ],
)
def test_bad_orientation_sets(call: object, fragment: str) -> None:
    with pytest.raises(InputError, match=fragment):
        call()  # type: ignore[operator]


def test_bad_grid_input(puma_grid: PoseGrid) -> None:
    robot = load_robot("puma560")
    with pytest.raises(InputError, match="resolution"):
        make_pose_grid(robot, resolution=0.0)
    with pytest.raises(InputError, match="max below min"):
        make_pose_grid(robot, bounds=[[0, 0, 0], [-1, 1, 1]])
    with pytest.raises(DimensionError):
        make_pose_grid(robot, bounds=[0, 1])
    with pytest.raises(NonFiniteError):
        puma_grid.voxel_index([[np.nan, 0, 0]])
    with pytest.raises(DimensionError):
        puma_grid.voxel_index([0.0, 0.0])
    with pytest.raises(InputError, match="zero"):
        puma_grid.orientation_index([[0, 0, 0, 0]])
    with pytest.raises(InputError, match="orientation index"):
        puma_grid.pose(0, puma_grid.orientation_count)
    with pytest.raises(InputError, match="voxel index"):
        puma_grid.pose(-1, 0)


@pytest.mark.parametrize("name", ["puma560", "puma560-kang"])
def test_puma_bounds_are_its_reach(name: str) -> None:
    """The box is the PUMA's reach: √(D² + (a2 + L3)²) about the axis, ± (a2 + L3)."""
    robot = load_robot(name)
    joints = robot.dh_table.joints
    offset = joints[1].d + joints[2].d
    arm = abs(joints[1].a) + math.hypot(joints[2].a, joints[3].d)
    radial = math.hypot(offset, arm)
    expected = np.array([[-radial, -radial, -arm], [radial, radial, arm]])
    np.testing.assert_allclose(default_bounds(robot), expected, rtol=0, atol=2e-9)


@given(raw=st.lists(st.floats(-1, 1), min_size=4, max_size=4))
def test_covering_radius_bounds_any_rotation(
    puma_grid: PoseGrid, raw: list[float]
) -> None:
    q = np.array(raw)
    if np.linalg.norm(q) < 1e-3:
        return
    q = q / np.linalg.norm(q)
    nearest = _angles_by_matrix(q[None], puma_grid.orientations)[0].min()
    assert nearest <= puma_grid.orientation_set["covering_radius"]


@given(
    resolution=st.floats(0.02, 0.5),
    low=st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
    size=st.lists(st.floats(0.0, 0.6), min_size=3, max_size=3),
    count=st.sampled_from([1, 8, 64]),
)
def test_grid_round_trips(
    resolution: float, low: list[float], size: list[float], count: int
) -> None:
    robot = load_robot("puma560")
    box = np.array([low, np.add(low, size)])
    grid = make_pose_grid(robot, resolution=resolution, orientations=count, bounds=box)
    np.testing.assert_array_equal(
        grid.voxel_index(grid.positions), np.arange(grid.voxel_count)
    )
    np.testing.assert_array_equal(
        grid.orientation_index(grid.orientations), np.arange(count)
    )
    corners = np.array(
        [[x, y, z] for x in box[:, 0] for y in box[:, 1] for z in box[:, 2]]
    )
    assert np.all(grid.voxel_index(corners) >= 0)  # the box lies in the grid
