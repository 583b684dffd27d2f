"""The pose grid of a workspace map: voxel positions × a set of tool orientations.

A :class:`PoseGrid` is a box of voxels (centres on multiples of the
resolution, in the robot's base frame) times a set of orientations of the
tool frame (:mod:`workbench.workspace.orientations`). Pose ``(v, o)`` is the
tool frame at ``positions[v]`` with rotation ``orientations[o]``; the flat
pose index of a map is ``v·O + o``. :func:`make_pose_grid` builds one around
the arm's reach (:func:`default_bounds`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.validation import as_finite_array, check_positive
from workbench.workspace.orientations import (
    cone_orientations,
    rotations_from_quat_xyzw,
    uniform_orientations,
)

if TYPE_CHECKING:
    from scipy.spatial import cKDTree

FloatArray = npt.NDArray[np.float64]
IndexArray = npt.NDArray[np.int64]

#: Voxels per block (one task, one chunk of every array): 1024 voxels × 512
#: orientations is 524,288 poses, 2 MiB per float32 chunk; smaller blocks pay
#: Zarr's fixed cost per chunk written more often (docs/workspace.md, "Speed").
DEFAULT_BLOCK_VOXELS = 1024

#: Default voxel size [m].
DEFAULT_RESOLUTION = 0.05
#: Default number of orientations per voxel.
DEFAULT_ORIENTATIONS = 512
#: Widening [m] of :func:`default_bounds` for the rounding of the model's numbers.
BOUNDS_SLACK = 1e-9
#: |cos| within this of 1 (or |component| below it): axes taken as parallel
#: (perpendicular) in :func:`default_bounds`.
_AXIS_TOL = 1e-12


def _read_only(array: npt.ArrayLike) -> Any:
    out: FloatArray = np.array(array, dtype=np.float64)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class PoseGrid:
    """Voxel positions × tool orientations (immutable; arrays read-only).

    Attributes:
        positions: (V, 3) voxel centres [m] in the base frame, C order over
            ``shape``: flat index ``(ix·ny + iy)·nz + iz``.
        origin: (3,) centre of voxel (0, 0, 0) [m].
        resolution: Voxel edge [m].
        shape: ``(nx, ny, nz)`` voxels per axis.
        bounds: (2, 3) the box the grid was built to cover, rows min and max
            [m] (every point of it lies in a voxel).
        orientations: (O, 4) unit quaternions x y z w, w >= 0: rotation of
            the tool frame in the base frame.
        orientation_set: The set's description (``construction``, ``count``,
            ``covering_radius`` [rad], and for a cone ``axis``, ``half_angle``
            [rad]).
        rotations: (O, 3, 3) rotation matrices of ``orientations``.
    """

    positions: FloatArray
    origin: FloatArray
    resolution: float
    shape: tuple[int, int, int]
    bounds: FloatArray
    orientations: FloatArray
    orientation_set: dict[str, Any]
    rotations: FloatArray = field(repr=False)

    @property
    def voxel_count(self) -> int:
        """V, the number of voxels."""
        return len(self.positions)

    @property
    def orientation_count(self) -> int:
        """O, the number of orientations per voxel."""
        return len(self.orientations)

    @property
    def pose_count(self) -> int:
        """V · O."""
        return self.voxel_count * self.orientation_count

    def voxel_index(self, points: npt.ArrayLike) -> IndexArray:
        """Flat index of the voxel containing each point, -1 outside the grid.

        Args:
            points: (N, 3) positions [m] in the base frame.

        Returns:
            (N,) int64.

        Raises:
            DimensionError, NonFiniteError: If ``points`` is not finite (N, 3).
        """
        p = np.asarray(points, dtype=np.float64)
        p = as_finite_array(p, (p.shape[0] if p.ndim == 2 else -1, 3), "points")
        cell = np.rint((p - self.origin) / self.resolution)
        size = np.asarray(self.shape)
        inside = np.all((cell >= 0) & (cell < size), axis=1)
        ix, iy, iz = np.where(inside[:, None], cell, 0).astype(np.int64).T
        flat = (ix * size[1] + iy) * size[2] + iz
        return np.where(inside, flat, -1)

    def orientation_index(self, quat_xyzw: npt.ArrayLike) -> IndexArray:
        """Index of the orientation nearest (by rotation angle) each quaternion.

        Args:
            quat_xyzw: (N, 4) quaternions x y z w (either sign; normalised here).

        Returns:
            (N,) int64: argmax over the set of ``|q · orientation|`` (found
            as the nearest of ± the set in R⁴, by a KD-tree).

        Raises:
            DimensionError, NonFiniteError: If not finite (N, 4).
            InputError: If a quaternion is zero.
        """
        q = np.asarray(quat_xyzw, dtype=np.float64)
        q = as_finite_array(q, (q.shape[0] if q.ndim == 2 else -1, 4), "quat_xyzw")
        norm = np.linalg.norm(q, axis=1)
        if np.any(norm == 0.0):
            raise InputError("quat_xyzw: a quaternion is zero")
        _, index = self._orientation_tree.query(q / norm[:, None])
        return np.asarray(index, dtype=np.int64) % self.orientation_count

    @functools.cached_property
    def _orientation_tree(self) -> cKDTree:
        """KD-tree of ± the orientations (nearest by chord = nearest by angle)."""
        from scipy.spatial import cKDTree  # (SciPy: imported when first used)

        return cKDTree(np.concatenate([self.orientations, -self.orientations]))

    def pose(self, voxel: int, orientation: int) -> FloatArray:
        """(4, 4) pose of the tool frame in the base frame [m] of grid pose ``(v, o)``.

        Raises:
            InputError: If an index is out of range.
        """
        for name, index, count in (
            ("voxel", voxel, self.voxel_count),
            ("orientation", orientation, self.orientation_count),
        ):
            if not 0 <= int(index) < count:
                raise InputError(f"{name} index {index} outside [0, {count})")
        out = np.eye(4)
        out[:3, :3] = self.rotations[int(orientation)]
        out[:3, 3] = self.positions[int(voxel)]
        return out


def _path_joints(robot: Robot) -> list[int]:
    model = robot.model
    frame = model.frames[robot.tool_frame_id]
    return [j for j in model.supports[frame.parentJoint] if j > 0]


def default_bounds(robot: Robot) -> FloatArray:
    """A box (2, 3) [m] in the base frame that holds every reachable tool position.

    From the model, for any serial arm, at the neutral configuration (whose
    values do not matter: every joint turns through a full circle here). The
    tool positions reachable by moving joints ``k..n`` lie in a ball ``(c,
    r)`` and within ``t`` of ``c`` along a direction ``u`` (a disc when ``t =
    0``). From the tool point (``r = t = 0``), each joint from the last to the
    second turns that set about its axis ``a``: it stays in the ball centred
    on the projection ``c'`` of ``c`` onto the axis, of radius ``r + |c −
    c'|``, and keeps its extent along ``a`` (``t`` if ``u`` is ``a``, else
    ``r``), so ``u`` becomes ``a`` (a prismatic joint adds its largest travel
    to ``r`` and ``t``). The first joint turns the set about its axis: when
    that axis is the base z axis, the set's distance from it is at most
    ``√((|d_u| + t)² + (|d_⊥| + r)²)`` for a horizontal ``u`` (``d`` the
    horizontal offset of ``c`` from the axis, along ``u`` and across it),
    else ``|d| + r``, and its height ``c_z ± r``; for another first axis the
    box is the cube of half-edge ``|c − c'| + r`` around ``c'``. The box is
    widened by :data:`BOUNDS_SLACK` for rounding. For the closed-form
    families this is the shoulder offset, the axis height and the longest arm
    (tool point included).

    Raises:
        InputError: If the tool frame has no joint on its path.
    """
    model = robot.model
    path = _path_joints(robot)
    if not path:
        raise InputError(f"{robot.name}: no joint between the base and the tool frame")
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    centre = data.oMf[robot.tool_frame_id].translation.copy()
    radius = thickness = 0.0
    normal = np.zeros(3)  # u: no direction yet (t = r)
    for j in reversed(path[1:]):
        point, axis = data.oMi[j].translation, _joint_axis(model, j, data.oMi[j])
        if axis is None:  # prismatic (or any other joint): its travel
            k = model.joints[j].idx_q
            travel = float(max(abs(robot.lower[k]), abs(robot.upper[k])))
            radius, thickness = radius + travel, thickness + travel
            continue
        foot = point + axis * float(np.dot(centre - point, axis))
        along = (
            thickness
            if abs(abs(float(np.dot(normal, axis))) - 1.0) < _AXIS_TOL
            else radius
        )
        centre, radius = foot, radius + float(np.linalg.norm(centre - foot))
        normal, thickness = axis, min(along, radius)
    return _first_joint_box(robot, path[0], data, centre, radius, normal, thickness)


def _first_joint_box(
    robot: Robot,
    joint: int,
    data: pin.Data,
    centre: FloatArray,
    radius: float,
    normal: FloatArray,
    thickness: float,
) -> FloatArray:
    """The box of :func:`default_bounds` from the set of the joints after the first."""
    model = robot.model
    placement = data.oMi[joint]
    axis = _joint_axis(model, joint, placement)
    if axis is None:  # a prismatic first joint: its travel, any direction
        k = model.joints[joint].idx_q
        reach = radius + float(max(abs(robot.lower[k]), abs(robot.upper[k])))
        low, high = centre - reach, centre + reach
    else:
        point = placement.translation
        foot = point + axis * float(np.dot(centre - point, axis))
        offset = centre - foot
        rho = float(np.linalg.norm(offset))
        if abs(abs(axis[2]) - 1.0) < _AXIS_TOL:
            radial = rho + radius
            if abs(normal[2]) < _AXIS_TOL and np.any(normal):
                d_u = abs(float(np.dot(offset, normal)))
                d_across = math.sqrt(max(rho * rho - d_u * d_u, 0.0))
                radial = min(radial, math.hypot(d_u + thickness, d_across + radius))
            extent = np.array([radial, radial, radius])
        else:
            extent = np.full(3, rho + radius)
        low, high = foot - extent, foot + extent
    return np.stack([low - BOUNDS_SLACK, high + BOUNDS_SLACK])


def _joint_axis(model: pin.Model, joint: int, placement: pin.SE3) -> FloatArray | None:
    """Unit axis in the base frame of a revolute joint, None for other joints."""
    name = model.joints[joint].shortname()
    if not name.startswith("JointModelR"):
        return None
    if "Unaligned" in name:
        return placement.rotation @ np.asarray(model.joints[joint].extract().axis)
    return placement.rotation @ np.eye(3)["XYZ".index(name[-1])]


def _as_bounds(bounds: npt.ArrayLike) -> FloatArray:
    box = as_finite_array(bounds, (2, 3), "bounds")
    if np.any(box[1] < box[0]):
        raise InputError(
            f"bounds: max below min ({box[1].tolist()} < {box[0].tolist()})"
        )
    return box


def grid_positions(
    origin: npt.ArrayLike, resolution: float, shape: tuple[int, ...]
) -> FloatArray:
    """The voxel centres (V, 3) [m] of a grid, in C order over ``shape``.

    ``positions[(ix·ny + iy)·nz + iz] = origin + resolution · (ix, iy, iz)``,
    bitwise as a map stores them.

    Args:
        origin: (3,) centre of voxel (0, 0, 0) [m].
        resolution: Voxel edge [m].
        shape: (nx, ny, nz).
    """
    start = np.asarray(origin, dtype=np.float64)
    axes = [start[k] + resolution * np.arange(shape[k]) for k in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def make_pose_grid(
    robot: Robot,
    *,
    resolution: float = DEFAULT_RESOLUTION,
    orientations: int = DEFAULT_ORIENTATIONS,
    cone: tuple[npt.ArrayLike, float] | None = None,
    bounds: npt.ArrayLike | None = None,
) -> PoseGrid:
    """The pose grid of a robot: voxels over ``bounds`` × an orientation set.

    Voxel centres lie on multiples of ``resolution`` (in the base frame),
    from the one containing ``bounds[0]`` to the one containing ``bounds[1]``.

    Args:
        robot: The arm (its base frame is the grid's frame).
        resolution: Voxel edge [m], > 0.
        orientations: Orientations per voxel (>= 1).
        cone: ``(axis (3,), half_angle [rad])`` for :func:`cone_orientations`;
            None for :func:`uniform_orientations`.
        bounds: (2, 3) box [m], rows min and max; default
            :func:`default_bounds` of the robot.

    Raises:
        InputError: On a non-positive resolution or count, a bad cone or box.
    """
    check_positive(resolution, "resolution", strict=True)
    res = float(resolution)
    box = default_bounds(robot) if bounds is None else _as_bounds(bounds)
    if cone is None:
        quat, description = uniform_orientations(orientations)
    else:
        quat, description = cone_orientations(cone[0], cone[1], orientations)
    low, high = np.rint(box[0] / res), np.rint(box[1] / res)
    shape = tuple(int(n) for n in high - low + 1)
    if math.prod(shape) > 2**31:
        raise InputError(f"grid of {shape} voxels is too large; raise the resolution")
    origin = low * res
    return PoseGrid(
        positions=_read_only(grid_positions(origin, res, shape)),
        origin=_read_only(origin),
        resolution=res,
        shape=(shape[0], shape[1], shape[2]),
        bounds=_read_only(box),
        orientations=quat,
        orientation_set=dict(description),
        rotations=_read_only(rotations_from_quat_xyzw(quat)),
    )


__all__ = [
    "BOUNDS_SLACK",
    "DEFAULT_ORIENTATIONS",
    "DEFAULT_RESOLUTION",
    "PoseGrid",
    "cone_orientations",
    "default_bounds",
    "grid_positions",
    "make_pose_grid",
    "uniform_orientations",
]
