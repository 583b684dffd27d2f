r"""Per-pose reachability, dexterity and singularity measures of a block of the grid.

:func:`evaluate_block` solves every pose of voxels ``start:stop`` × every
orientation of a :class:`~workbench.workspace.grid.PoseGrid` in closed form
and returns, per pose (arrays (B, O), B = stop − start):

* ``reached`` (uint8): closed-form branches that reach the pose (0..8);
* ``branches`` (uint8): of those, branches within the joint limits (some
  representative :math:`q_i + 2\pi k` of every angle within its limits);
* ``collision_free`` (uint8, only with a ``checker``): of the in-limit ones,
  those whose configuration touches nothing (every distance > 0);
* of the **best branch** (the usable branch — in limits, and collision-free
  with a checker — of largest :math:`|\det J|`; ties: the larger limit
  margin, then the first label), NaN where no branch is usable (float32):
  ``dexterity`` Yoshikawa's :math:`\sqrt{\det(J J^T)} = |\det J| = |K s e w|`
  [m³] from the analytic factors (:mod:`workbench.singularities.conditions`),
  ``shoulder`` :math:`|s|` [m], ``elbow`` :math:`|e|` [1], ``wrist``
  :math:`|w|` [1], ``limit_margin`` [rad]: the smallest distance of a joint
  (its representative nearest the middle of its limits) to its limits;

and per voxel (arrays (B,), float32): ``reachability`` (fraction of the
orientations with a usable branch), ``dexterity_best`` (max),
``dexterity_median`` (median over the orientations with a usable branch) and
``near_singular_fraction`` (fraction of those whose best branch has
:func:`singularity_margin` < 1); NaN where the voxel has none.

The function is pure: the same inputs give the same bits on any worker.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from workbench.errors import InputError
from workbench.ik import get_closed_form
from workbench.model.robot import Robot
from workbench.workspace._reference import (
    evaluate_block_reference,
    singularity_margin,
)

if TYPE_CHECKING:
    from workbench.collision.checker import CollisionChecker
    from workbench.workspace.grid import PoseGrid

#: Keys of :func:`evaluate_block` with one value per pose (B, O).
POSE_KEYS = (
    "reached",
    "branches",
    "collision_free",
    "dexterity",
    "shoulder",
    "elbow",
    "wrist",
    "limit_margin",
)
#: Keys of :func:`evaluate_block` with one value per voxel (B,).
VOXEL_KEYS = (
    "reachability",
    "dexterity_best",
    "dexterity_median",
    "near_singular_fraction",
)


def _check_range(grid: PoseGrid, start: int, stop: int) -> tuple[int, int]:
    for name, value in (("start", start), ("stop", stop)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer):
            raise InputError(f"{name} must be an integer, got {value!r}")
    if not 0 <= start < stop <= grid.voxel_count:
        raise InputError(
            f"voxel range [{start}, {stop}) must be non-empty within "
            f"[0, {grid.voxel_count})"
        )
    return int(start), int(stop)


def evaluate_block(
    robot: Robot,
    grid: PoseGrid,
    start: int,
    stop: int,
    *,
    checker: CollisionChecker | None = None,
) -> dict[str, np.ndarray]:
    """Measures of every pose of voxels ``start:stop`` × all orientations.

    Args:
        robot: An arm with a closed form (OPW or UR type).
        grid: The pose grid (positions in the robot's base frame).
        start: First voxel of the block, ``0 <= start < stop``.
        stop: One past its last voxel, ``<= V``.
        checker: Optional collision checker of the robot and a scene.

    Returns:
        Arrays keyed as in the module docstring: :data:`POSE_KEYS` (B, O)
        (``collision_free`` only with a checker) and :data:`VOXEL_KEYS` (B,).

    Raises:
        UnsupportedRobotError: If the robot has no closed form.
        InputError: If the voxel range is empty or outside the grid.
    """
    start, stop = _check_range(grid, start, stop)
    get_closed_form(robot)  # raises UnsupportedRobotError
    return evaluate_block_reference(robot, grid, start, stop, checker=checker)


__all__ = ["POSE_KEYS", "VOXEL_KEYS", "evaluate_block", "singularity_margin"]
