"""Where the base may go by default: the task's extent widened by the arm's reach.

:func:`default_region` is the region :func:`~workbench.workspace.placement.place_base`
searches when none is given (and the one ``workbench workspace place`` prints
without ``--region``): every base position from which the arm could reach some
task pose lies within its horizontal reach of that pose, so the task's x, y
bounding box widened by the reach holds every useful candidate.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.validation import as_finite_array, check_positive
from workbench.workspace.grid import default_bounds
from workbench.workspace.task_poses import TaskPoses, matrices_from_xyz_quat_xyzw

FloatArray = npt.NDArray[np.float64]


def default_region(
    robot: Robot, targets: TaskPoses | npt.ArrayLike, *, resolution: float
) -> tuple[float, float, float, float]:
    """``(xmin, xmax, ymin, ymax)`` [m], world frame: the task's extent and the reach.

    The arm's horizontal reach is half the width of its
    :func:`~workbench.workspace.grid.default_bounds` in x or y (the larger);
    the task's x, y bounding box is widened by it on every side and its edges
    are rounded outwards to multiples of ``resolution``, so the candidate
    lattice holds the world origin's multiples (a base at the origin is a
    candidate).

    Args:
        robot: The arm to place.
        targets: The task: :class:`~workbench.workspace.task_poses.TaskPoses`,
            or tool poses in the world frame, (N, 4, 4) [m] or (N, 7) rows
            ``x y z qx qy qz qw``.
        resolution: Spacing of the candidate positions [m], finite and > 0.

    Returns:
        The region, edges on multiples of ``resolution`` [m].

    Raises:
        InputError: If ``targets`` is malformed or ``resolution`` is not a
            finite number > 0.
    """
    check_positive(resolution, "resolution", strict=True)
    step = float(resolution)
    xy = task_matrices(targets)[:, :2, 3]
    box = default_bounds(robot)
    reach = 0.5 * float(np.max(box[1, :2] - box[0, :2]))
    low = np.floor((xy.min(axis=0) - reach) / step) * step
    high = np.ceil((xy.max(axis=0) + reach) / step) * step
    return (float(low[0]), float(high[0]), float(low[1]), float(high[1]))


def task_matrices(targets: TaskPoses | npt.ArrayLike) -> FloatArray:
    """The task poses as an (N, 4, 4) array, world frame [m].

    Args:
        targets: :class:`~workbench.workspace.task_poses.TaskPoses`, (N, 4, 4)
            [m] or (N, 7) rows ``x y z qx qy qz qw``.

    Raises:
        InputError: If the shape is neither, N is 0 or a value is not finite.
    """
    if isinstance(targets, TaskPoses):
        return np.asarray(targets.poses)
    poses = np.asarray(targets, dtype=np.float64)
    if poses.ndim == 2 and poses.shape[1] == 7:
        rows = as_finite_array(poses, poses.shape, "targets")
        poses = matrices_from_xyz_quat_xyzw(rows)
    if poses.ndim != 3 or poses.shape[1:] != (4, 4) or len(poses) == 0:
        raise InputError(
            f"targets must have shape (N, 4, 4) or (N, 7), N >= 1, got {poses.shape}"
        )
    return as_finite_array(poses, poses.shape, "targets")


__all__ = ["default_region", "task_matrices"]
