"""Look up tool poses in a workspace map: nearest grid pose and its measures, in bulk.

:func:`query_map` snaps each pose to the voxel containing its position and to
the nearest orientation of the set (smallest rotation angle), then reads the
stored measures there (only the chunks those poses touch). The snapping
errors are returned too: a pose is as reachable as the grid pose it snaps to
only up to them.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.poses import RIGIDITY_TOL, compute_rigidity_errors
from workbench.validation import as_finite_array
from workbench.workspace.grid import PoseGrid
from workbench.workspace.measures import singularity_margin
from workbench.workspace.orientations import (
    quat_xyzw_from_rotations,
    rotation_angle_between,
)

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class MapQuery:
    """The map at N query poses (every field has shape (N,)).

    Attributes:
        voxel: Flat voxel index containing the position, -1 outside the grid.
        orientation: Index of the nearest orientation of the set.
        inside: Whether the position lies in the grid.
        branches: Closed-form branches within the joint limits (uint8; 0
            outside; of a sampled map: 1 where a sample landed, else 0).
        reached: Branches reaching the pose, limits aside (uint8; 0 outside).
        dexterity: Manipulability of the best branch [m³] (NaN: none).
        singularity_margin: ``min(|s|/SHOULDER_TOL, |e|/ELBOW_TOL,
            |w|/WRIST_TOL)`` of the best branch [1] (< 1: near-singular;
            NaN where none, and in a sampled map).
        limit_margin: Smallest distance of the best branch's joints to their
            limits [rad] (NaN: none, and in a sampled map).
        position_error: Distance from the position to the voxel centre [m]
            (NaN outside).
        orientation_error: Rotation angle from the orientation to the
            nearest one of the set [rad].
        redundancy: Of a seven-axis map, the arm angle or q7 of the best
            candidate [rad] (NaN: none, outside, and in other maps).
    """

    voxel: npt.NDArray[np.int64]
    orientation: npt.NDArray[np.int64]
    inside: npt.NDArray[np.bool_]
    branches: npt.NDArray[np.uint8]
    reached: npt.NDArray[np.uint8]
    dexterity: FloatArray
    singularity_margin: FloatArray
    limit_margin: FloatArray
    position_error: FloatArray
    orientation_error: FloatArray
    redundancy: FloatArray


def split_poses(poses: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Positions (N, 3) [m] and unit quaternions (N, 4) x y z w of N poses.

    Args:
        poses: (N, 4, 4) homogeneous matrices, or (N, 7) rows ``x y z qx qy
            qz qw`` [m, unit quaternion].

    Raises:
        NonFiniteError: If a value is not finite.
        InputError: If the shape is neither, or a rotation is not orthonormal
            (or a quaternion not of unit norm) within
            :data:`~workbench.poses.rigid.RIGIDITY_TOL`.
    """
    array = np.asarray(poses, dtype=np.float64)
    if array.ndim == 3 and array.shape[1:] == (4, 4):
        array = as_finite_array(array, array.shape, "poses")
        error, det = compute_rigidity_errors(np.ascontiguousarray(array))
        bad = np.flatnonzero((error > RIGIDITY_TOL) | (det <= 0.0))
        if bad.size:
            raise InputError(
                f"poses[{bad[0]}] is not a rigid transform (max |R^T R - I| or "
                f"bottom-row error {error[bad[0]]:.3g}, det R = {det[bad[0]]:.6g})"
            )
        return array[:, :3, 3].copy(), quat_xyzw_from_rotations(array[:, :3, :3])
    if array.ndim == 2 and array.shape[1] == 7:
        array = as_finite_array(array, array.shape, "poses")
        norm = np.linalg.norm(array[:, 3:], axis=1)
        bad = np.flatnonzero(np.abs(norm - 1.0) > RIGIDITY_TOL)
        if bad.size:
            raise InputError(
                f"poses[{bad[0]}]: the quaternion qx qy qz qw must have unit "
                f"norm, got {norm[bad[0]]:.9g}"
            )
        return array[:, :3].copy(), array[:, 3:] / norm[:, None]
    raise InputError(
        f"poses must have shape (N, 4, 4) or (N, 7), got shape {array.shape}"
    )


#: ``gather(name, rows, cols)``: ``array[rows, cols]`` of a per-pose data
#: array, ``array[rows]`` of a per-voxel one (``cols`` None), read from the map.
Gather = Callable[[str, npt.NDArray[np.int64], npt.NDArray[np.int64] | None], Any]


def query_map(
    gather: Gather, names: Collection[str], grid: PoseGrid, poses: npt.ArrayLike
) -> MapQuery:
    """The map's measures at the grid poses nearest to ``poses`` (:class:`MapQuery`).

    Args:
        gather: Reads the values of a data array at voxels and orientations
            (:meth:`~workbench.workspace.manifest.Manifest.gather`: only the
            chunks they lie in, checked).
        names: The data arrays the map holds.
        grid: Its pose grid.
        poses: (N, 4, 4) or (N, 7) tool poses in the base frame (see
            :func:`split_poses`).

    Raises:
        InputError: As :func:`split_poses`, or if a chunk read is damaged.
    """
    names = set(names)
    positions, quats = split_poses(poses)
    voxel = grid.voxel_index(positions)
    orientation = grid.orientation_index(quats)
    inside = voxel >= 0
    rows, cols = voxel[inside], orientation[inside]

    def read(name: str, fill: Any, dtype: type) -> Any:
        out: npt.NDArray[Any] = np.full(len(voxel), fill, dtype=dtype)
        if name in names and rows.size:
            out[inside] = gather(name, rows, cols)
        return out

    nan = float("nan")
    margin = np.full(len(voxel), nan)
    if {"shoulder", "elbow", "wrist"} <= names:
        margin = singularity_margin(
            read("shoulder", nan, np.float64),
            read("elbow", nan, np.float64),
            read("wrist", nan, np.float64),
        ).astype(np.float64)
    position_error = np.full(len(voxel), nan)
    position_error[inside] = np.linalg.norm(
        positions[inside] - grid.positions[rows], axis=1
    )
    return MapQuery(
        voxel=voxel,
        orientation=orientation,
        inside=inside,
        branches=read("branches" if "branches" in names else "reached", 0, np.uint8),
        reached=read("reached", 0, np.uint8),
        dexterity=read("dexterity", nan, np.float64),
        singularity_margin=margin,
        limit_margin=read("limit_margin", nan, np.float64),
        position_error=position_error,
        orientation_error=rotation_angle_between(quats, grid.orientations[orientation]),
        redundancy=read("redundancy", nan, np.float64),
    )
