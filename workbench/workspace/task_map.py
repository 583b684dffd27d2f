"""A workspace map held in memory, over the heights a task needs.

:func:`~workbench.workspace.placement.place_base` screens its candidates
against a workspace map; without one it builds this one: the arm's reach in
x and y, only the slab of base-frame heights the task poses lie at (the
base height is fixed, so a task pose keeps its height in the base frame
whatever the candidate), computed with
:func:`~workbench.workspace.measures.evaluate_block`, block by block, on a
thread per core (the closed-form kernels release the GIL). A seven-axis arm's
map is solved at K values of its redundancy parameter
(:func:`~workbench.workspace.redundant.evaluate_redundant_block`, default
:data:`TASK_MAP_REDUNDANCY_SAMPLES`), which the placement then verifies at.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.ik import get_family, get_solver
from workbench.model.robot import Robot
from workbench.workspace.grid import PoseGrid, default_bounds, make_pose_grid
from workbench.workspace.measures import evaluate_block, get_core_count
from workbench.workspace.redundant import evaluate_redundant_block, redundancy_values

#: Voxel edge [m] of the map :func:`build_task_map` builds by default.
TASK_MAP_RESOLUTION = 0.05
#: Orientations per voxel of that map (a uniform set).
TASK_MAP_ORIENTATIONS = 512
#: K of a seven-axis arm's map: values of the redundancy parameter per pose.
TASK_MAP_REDUNDANCY_SAMPLES = 8
#: The per-pose arrays the placement reads.
TASK_MAP_KEYS = ("branches", "dexterity", "shoulder", "elbow", "wrist")
#: ... of a seven-axis arm (no singularity distances).
TASK_MAP_REDUNDANT_KEYS = ("branches", "dexterity")
#: Voxels per block of :func:`build_task_map`.
_BLOCK_VOXELS = 256


@dataclass(frozen=True)
class TaskMap:
    """A workspace map held in memory (:func:`build_task_map`).

    Attributes:
        grid: Its pose grid (base frame).
        arrays: The per-pose arrays :data:`TASK_MAP_KEYS` of
            :func:`~workbench.workspace.measures.evaluate_block`, each (V, O)
            (seven-axis arms: :data:`TASK_MAP_REDUNDANT_KEYS`).
        redundancy: Seven-axis arms: (K,) the values of the redundancy
            parameter [rad] the map was solved at; None for six-axis arms.
    """

    grid: PoseGrid
    arrays: dict[str, npt.NDArray[Any]]
    redundancy: npt.NDArray[np.float64] | None = None

    def __getitem__(self, name: str) -> npt.NDArray[Any]:
        """The array called ``name``, shape (V, O)."""
        return self.arrays[name]


def build_task_map(
    robot: Robot,
    heights: npt.ArrayLike,
    *,
    resolution: float = TASK_MAP_RESOLUTION,
    orientations: int = TASK_MAP_ORIENTATIONS,
    redundancy_samples: int | None = None,
) -> TaskMap:
    """The map of ``robot`` over the slab of base-frame heights a task needs.

    Args:
        robot: An arm with a closed form.
        heights: (N,) heights of the task poses in the base frame [m] (their
            world z minus the base height).
        resolution: Voxel edge [m], > 0.
        orientations: Orientations per voxel (uniform set), >= 1.
        redundancy_samples: Seven-axis arms: K
            (:func:`~workbench.workspace.redundant.redundancy_values`),
            default :data:`TASK_MAP_REDUNDANCY_SAMPLES`; None for others.

    Returns:
        The map over the arm's reach in x and y
        (:func:`~workbench.workspace.grid.default_bounds`) and, in z, from the
        lowest to the highest of ``heights`` within that reach (one layer at
        its top when none is within: every pose is then missed).

    Raises:
        UnsupportedRobotError: If the robot has no closed form.
        InputError: On a bad resolution or orientation count, or
            ``redundancy_samples`` out of range or given for a six-axis arm.
    """
    family = get_family(robot)
    if family is None or not family.redundant:
        if redundancy_samples is not None:
            raise InputError(
                f"redundancy samples are for seven-axis arms, not {robot.name}"
            )
        keys: tuple[str, ...] = TASK_MAP_KEYS
        values, count = None, 0
    else:
        range_ = get_solver(robot).parameter_range
        if range_ is None:  # (a seven-axis family has one)
            raise InputError(f"robot {robot.name!r} is no seven-axis arm")
        count = TASK_MAP_REDUNDANCY_SAMPLES
        count = count if redundancy_samples is None else redundancy_samples
        values = redundancy_values(range_, count)
        keys = TASK_MAP_REDUNDANT_KEYS
    z = np.asarray(heights, dtype=np.float64).reshape(-1)
    box = default_bounds(robot)
    low = max(float(z.min()), float(box[0, 2]))
    high = min(float(z.max()), float(box[1, 2]))
    if low > high:
        low = high = float(box[1, 2])
    box[:, 2] = low, high
    grid = make_pose_grid(
        robot, resolution=resolution, orientations=orientations, bounds=box
    )

    def block(start: int) -> dict[str, npt.NDArray[Any]]:
        stop = min(start + _BLOCK_VOXELS, grid.voxel_count)
        if values is not None:
            return evaluate_redundant_block(robot, grid, start, stop, count=count)
        return evaluate_block(robot, grid, start, stop)

    starts = range(0, grid.voxel_count, _BLOCK_VOXELS)
    with ThreadPoolExecutor(get_core_count()) as pool:
        blocks = list(pool.map(block, starts))
    arrays = {k: np.concatenate([b[k] for b in blocks]) for k in keys}
    return TaskMap(grid, arrays, values)


__all__ = [
    "TASK_MAP_KEYS",
    "TASK_MAP_ORIENTATIONS",
    "TASK_MAP_REDUNDANCY_SAMPLES",
    "TASK_MAP_REDUNDANT_KEYS",
    "TASK_MAP_RESOLUTION",
    "TaskMap",
    "build_task_map",
]
