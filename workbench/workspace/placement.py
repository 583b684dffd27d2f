r"""Base placement: where to put an arm so that it reaches every pose of a task.

A candidate base pose is :math:`B = \mathrm{Trans}(x, y, z)\, R_z(\psi)` in the
world frame; task pose :math:`T` is :math:`B^{-1} T` in the base frame.
:func:`place_base` ranks candidates by :meth:`Placement.rank_key`: every task
pose reached by a usable branch (within the limits, collision-free with the
scene; for a path, a continuous chain of solutions along it, without a flip), then the
worst singularity margin along the task at least 1, then the worst dexterity
|det J|, then the worst margin.

Method, for a region of candidates (yaws × a square lattice at one height):

1. **Screening** against a workspace map
   (:mod:`workbench.workspace._placement_screen`): per yaw, each task pose's
   nearest map orientation, then per candidate its nearest voxel, an O(1)
   lookup in a compiled loop; per candidate the missed poses and the worst
   dexterity and margin of the map's best branches. The map is approximate
   (nearest grid pose: half a voxel, the orientation set's covering radius),
   so the screening only orders the candidates. Without a map, one is built
   in memory over the heights the task needs
   (:func:`~workbench.workspace.task_map.build_task_map`).
2. **Exact verification** of the candidates in that order, a batch at a time
   (:class:`~workbench.workspace.placement_check.PlacementEvaluator`: the
   closed form of every :math:`B^{-1} T`, the limits, the scene, |det J| from
   the analytic factors), until ``top`` of them reach every pose or
   :data:`MAX_VERIFIED` were verified. Every returned :class:`Placement` holds
   the exact values and is ranked by them.

Without a region, the region is
:func:`~workbench.workspace.placement_region.default_region` (the task's x, y
extent widened by the arm's horizontal reach). Explicit candidates
(``mounts``) skip the screening: each is verified exactly.

Seven-axis arms (SRS, Franka) are verified exactly at the K values of the
redundancy parameter of their map (its attribute ``redundancy``; a map built
in memory, or ``mounts`` without a map, at ``redundancy_samples`` values,
default :data:`~workbench.workspace.task_map.TASK_MAP_REDUNDANCY_SAMPLES`), the
meaning of *exact* of their maps: a pose reached only between those values
counts as missed (:mod:`workbench.workspace.placement_check`). Their maps
hold no singularity distances: the screening ranks by missed poses, then
dexterity.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from workbench.collision import Scene
from workbench.errors import InfeasibleError, InputError
from workbench.ik import get_family, get_solver
from workbench.model.robot import Robot
from workbench.validation import as_finite_array
from workbench.workspace._placement_screen import CandidateLattice, Screening
from workbench.workspace.grid import PoseGrid
from workbench.workspace.placement_check import (
    PATH_STEP_MAX,
    Placement,
    PlacementEvaluator,
    base_transform,
    follow_path,
)
from workbench.workspace.placement_region import default_region, task_matrices
from workbench.workspace.redundant import redundancy_values
from workbench.workspace.task_map import TASK_MAP_REDUNDANCY_SAMPLES, build_task_map
from workbench.workspace.task_poses import TaskPoses

FloatArray = npt.NDArray[np.float64]
Progress = Callable[[int, int], None]

#: Default spacing of the candidate base positions [m].
DEFAULT_RESOLUTION = 0.02
#: Default step of the candidate base yaws [rad] (10°).
DEFAULT_YAW_STEP = math.radians(10.0)
#: Most candidates verified exactly while looking for ``top`` that reach
#: every pose.
MAX_VERIFIED = 512
#: Candidates verified per batch (one closed-form call for all their poses)...
VERIFY_BATCH = 16
#: ... and at most this many task poses per batch (its solutions take 0.4 kB
#: each), so a long task is verified a few candidates at a time.
VERIFY_POSES = 200_000


class PlacementInfeasibleError(InfeasibleError):
    """No verified candidate reaches every task pose.

    Attributes:
        best: The best verified candidate (fewest missed poses), or None.
    """

    def __init__(self, message: str, best: Placement | None):
        self.best = best
        super().__init__(message)


class WorkspaceMapLike(Protocol):
    """What the placement reads of a map: ``WorkspaceMap`` or ``TaskMap``."""

    @property
    def grid(self) -> PoseGrid:
        """The map's pose grid."""
        ...

    def __getitem__(self, name: str) -> npt.NDArray[Any]:
        """A per-pose array (V, O) by name."""
        ...


def place_base(
    robot: Robot,
    targets: TaskPoses | npt.ArrayLike,
    *,
    region: Sequence[float] | None = None,
    height: float = 0.0,
    yaw_step: float = DEFAULT_YAW_STEP,
    resolution: float = DEFAULT_RESOLUTION,
    mounts: npt.ArrayLike | None = None,
    map: WorkspaceMapLike | str | Path | None = None,
    scene: Scene | None = None,
    top: int = 10,
    path: bool | None = None,
    redundancy_samples: int | None = None,
    progress: Progress | None = None,
) -> list[Placement]:
    """Rank base poses of ``robot`` for a task (method: module docstring).

    Args:
        robot: An OPW or UR-type six-axis arm, or a seven-axis arm of the SRS
            or Franka family (its closed form verifies every result).
        targets: The task: :class:`~workbench.workspace.task_poses.TaskPoses`,
            or poses of the tool frame in the world frame, (N, 4, 4) [m] or
            (N, 7) rows ``x y z qx qy qz qw``.
        region: ``(xmin, xmax, ymin, ymax)`` [m]: candidate base positions on
            a square lattice of spacing ``resolution`` from ``(xmin, ymin)``
            at height ``height``; None (without ``mounts``) is
            :func:`~workbench.workspace.placement_region.default_region`, the
            task's x, y extent widened by the arm's reach, as on the command
            line.
        height: z of the base [m] for the region's candidates.
        yaw_step: Step of the candidate yaws [rad]: ``0, step, ...`` below 2π.
        resolution: Spacing of the candidate positions [m].
        mounts: Explicit candidates instead of a region: (M, 4) rows
            ``x, y, z, yaw`` [m, rad], each verified exactly.
        map: A workspace map of ``robot`` for the screening (``open_map``'s
            ``WorkspaceMap``, its path, or a
            :class:`~workbench.workspace.task_map.TaskMap`); None builds one in
            memory over the task's heights.
        scene: Obstacles in the world frame: a usable branch must also be
            free of collisions with them and of self-collisions.
        top: How many placements to return (>= 1).
        path: The task is a path (one branch along it, no flip); default
            ``targets.ordered`` for ``TaskPoses``, else False.
        redundancy_samples: Seven-axis arms without ``map``: K, the values
            of the redundancy parameter the map built in memory and the
            verification solve at (default
            :data:`~workbench.workspace.task_map.TASK_MAP_REDUNDANCY_SAMPLES`);
            with a map, its values are used.
        progress: Called as ``progress(done, total)`` during the screening
            (yaws) and the verification (candidates).

    Returns:
        Up to ``top`` exactly verified placements that reach every task pose,
        best first (:meth:`Placement.rank_key`).

    Raises:
        PlacementInfeasibleError: If no verified candidate reaches every pose
            (the message names the best one and how many poses it misses).
        InputError: On malformed arguments, a map of another robot, or
            ``redundancy_samples`` with a map or for a six-axis arm.
        UnsupportedRobotError: If the robot has no closed form.
    """
    task = task_matrices(targets)
    ordered = targets.ordered if isinstance(targets, TaskPoses) else False
    ordered = ordered if path is None else bool(path)
    if isinstance(top, bool) or not isinstance(top, int) or top < 1:
        raise InputError(f"top must be an integer >= 1, got {top!r}")
    seven_axis = _check_samples(robot, map, redundancy_samples)
    if mounts is not None:
        if region is not None:
            raise InputError("give a region or mounts, not both")
        rows = np.asarray(mounts, dtype=np.float64)
        rows = as_finite_array(rows, (len(rows) if rows.ndim == 2 else -1, 4), "mounts")
        values = None
        if seven_axis:
            given = None if map is None else _get_map(robot, map, task, 0.0, None)
            values = _values(robot, given, redundancy_samples)
        evaluator = PlacementEvaluator(robot, task, scene, ordered, values)
        placements = []
        size = _batch_size(len(task) * len(evaluator.values))
        for start in range(0, len(rows), size):
            placements += evaluator.evaluate(rows[start : start + size])
        return _best(placements, top, len(task))
    if region is None:
        region = default_region(robot, task, resolution=resolution)
    lattice = CandidateLattice.make(region, float(height), yaw_step, resolution)
    the_map = _get_map(robot, map, task, lattice.height, redundancy_samples)
    values = _values(robot, the_map, redundancy_samples) if seven_axis else None
    evaluator = PlacementEvaluator(robot, task, scene, ordered, values)
    screening = Screening(
        the_map.grid, the_map.__getitem__, task, lattice, distances=not seven_axis
    )
    verified: dict[int, Placement] = {}
    size = _batch_size(len(task) * len(evaluator.values))
    for flat in _candidates(screening, top, size, progress):
        batch = evaluator.evaluate(lattice.rows(flat))
        verified.update(zip(flat.tolist(), batch, strict=True))
        if progress is not None:
            progress(len(verified), MAX_VERIFIED)
        if sum(p.all_reachable for p in verified.values()) >= top:
            break
    return _best(list(verified.values()), top, len(task))


def _check_samples(robot: Robot, given: object, samples: int | None) -> bool:
    """Whether ``robot`` is a seven-axis arm; checks ``redundancy_samples``.

    Raises:
        InputError: If ``samples`` is given for a six-axis arm or with a map.
    """
    family = get_family(robot)
    seven_axis = family is not None and family.redundant
    if samples is not None and not seven_axis:
        raise InputError(
            f"redundancy samples are for seven-axis arms, not {robot.name}"
        )
    if samples is not None and given is not None:
        raise InputError(
            "the map fixes the values of the redundancy parameter: give "
            "redundancy samples only without a map"
        )
    return seven_axis


def _values(
    robot: Robot, the_map: WorkspaceMapLike | None, samples: int | None
) -> FloatArray:
    """(K,) the redundancy values [rad] of a seven-axis arm's map, else K = samples.

    Raises:
        InputError: If the map holds no redundancy values.
    """
    if the_map is None:
        count = TASK_MAP_REDUNDANCY_SAMPLES if samples is None else samples
        range_ = get_solver(robot).parameter_range
        if range_ is None:
            raise InputError(f"{robot.name} has no redundancy parameter")
        return redundancy_values(range_, count)
    attrs = getattr(the_map, "attrs", None)
    values = getattr(the_map, "redundancy", None)
    if attrs is not None:
        values = (attrs.get("redundancy") or {}).get("values")
    if values is None:
        raise InputError(
            f"the map holds no values of {robot.name}'s redundancy parameter "
            "(not a seven-axis closed-form map)"
        )
    return np.asarray(values, dtype=np.float64)


def _batch_size(poses: int) -> int:
    """Candidates per verification batch for a task of ``poses`` poses."""
    return max(1, min(VERIFY_BATCH, VERIFY_POSES // poses))


def _candidates(
    screening: Screening, top: int, size: int, progress: Progress | None
) -> Iterator[npt.NDArray[np.int64]]:
    """Batches of candidates to verify, best screened first, up to MAX_VERIFIED.

    First those that the pruned screening finds reaching every pose; if fewer
    than ``top`` (or they fail the exact check), the full screening's order
    continues, without the ones already given.
    """
    given = np.zeros(math.prod(screening.lattice.shape), dtype=bool)
    order = screening.rank(prune=True, progress=progress)[: screening.reached]
    count = 0
    for full in (False, True):
        if full:
            if count >= MAX_VERIFIED:
                return
            order = screening.rank(prune=False, progress=progress)
            order = order[~given[order]]
        for start in range(0, len(order), size):
            batch = order[start : start + min(size, MAX_VERIFIED - count)]
            if not len(batch):
                return
            given[batch] = True
            count += len(batch)
            yield batch


def _get_map(
    robot: Robot,
    given: WorkspaceMapLike | str | Path | None,
    task: FloatArray,
    height: float,
    samples: int | None,
) -> WorkspaceMapLike:
    """The map to screen with, checked to be of ``robot`` (K = ``samples`` if built)."""
    if given is None:
        heights = task[:, 2, 3] - height
        return build_task_map(robot, heights, redundancy_samples=samples)
    if isinstance(given, str | Path):
        from workbench.workspace.store import open_map

        given = open_map(given)
    attrs = getattr(given, "attrs", None)
    if attrs is not None:
        if (attrs.get("robot"), attrs.get("tool_frame")) != (
            robot.name,
            robot.tool_frame,
        ):
            raise InputError(
                f"the map is of robot {attrs.get('robot')!r}, tool frame "
                f"{attrs.get('tool_frame')!r}, not {robot.name!r}, "
                f"{robot.tool_frame!r}"
            )
        if attrs.get("sampled"):
            raise InputError(
                "a sampled map cannot screen base placements (they need a "
                "closed-form map)"
            )
    return given


def _best(placements: list[Placement], top: int, count: int) -> list[Placement]:
    """The ``top`` best that reach every pose; else PlacementInfeasibleError."""
    ranked = sorted(placements, key=Placement.rank_key)
    feasible = [p for p in ranked if p.all_reachable]
    if feasible:
        return feasible[:top]
    best = ranked[0] if ranked else None
    where = ""
    if best is not None:
        where = (
            f"; the best verified, base at x={best.x:.4g} m, y={best.y:.4g} m, "
            f"z={best.z:.4g} m, yaw={math.degrees(best.yaw):.4g} deg, misses "
            f"{best.missed} of {count}"
            + ("" if best.missed else " (no branch follows the whole path)")
        )
    raise PlacementInfeasibleError(
        f"no base placement reaches all {count} task poses{where}", best
    )


__all__ = [
    "DEFAULT_RESOLUTION",
    "DEFAULT_YAW_STEP",
    "MAX_VERIFIED",
    "PATH_STEP_MAX",
    "VERIFY_BATCH",
    "VERIFY_POSES",
    "Placement",
    "PlacementInfeasibleError",
    "WorkspaceMapLike",
    "base_transform",
    "follow_path",
    "place_base",
]
