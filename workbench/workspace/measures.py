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

import os
import threading
from typing import TYPE_CHECKING

import numpy as np

from workbench.errors import InputError, UnsupportedRobotError
from workbench.ik import Solver, get_solver
from workbench.model.per_robot import per_robot
from workbench.model.robot import Robot
from workbench.singularities.conditions import (
    ELBOW_TOL,
    SHOULDER_TOL,
    WRIST_TOL,
    get_factorisation,
)
from workbench.workspace import _measure_kernel as kernel
from workbench.workspace._reference import (
    evaluate_block_reference,
    singularity_margin,
    summarise_voxels,
)

if TYPE_CHECKING:
    from workbench.collision.checker import CollisionChecker
    from workbench.workspace.grid import PoseGrid

#: Poses per chunk of the compiled path: one batch of the closed form
#: (``workbench.ik.solver.BATCH_CHUNK``); its work arrays (~1 MB) stay in the
#: cache, and the Python between kernel calls is ~2 % of the time (at 1024: ~3 %).
CHUNK_POSES = 2048

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


def check_voxel_range(grid: PoseGrid, start: int, stop: int) -> tuple[int, int]:
    """``(start, stop)`` as ints, checked to be a non-empty voxel range of ``grid``.

    Raises:
        InputError: If they are not integers with ``0 <= start < stop <= V``.
    """
    for name, value in (("start", start), ("stop", stop)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer):
            raise InputError(f"{name} must be an integer, got {value!r}")
    if not 0 <= start < stop <= grid.voxel_count:
        raise InputError(
            f"voxel range [{start}, {stop}) must be non-empty within "
            f"[0, {grid.voxel_count})"
        )
    return int(start), int(stop)


@per_robot
def _constants(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """The packed constants of :func:`kernel.measure_poses` for ``robot``."""
    fac = get_factorisation(robot)
    values = {
        "ur": fac.measure_formula,
        "constant": fac.constant,
        "a1": fac.a1,
        "a2": fac.a2,
        "a3": fac.a3,
        "d4": fac.d4,
        "a4": fac.a4,
        "sigma3d4": fac.sigma3 * fac.d4,
        "sigma4d5": fac.sigma4 * fac.d5,
        "forearm": fac.forearm,
        "shoulder_tol": SHOULDER_TOL,
        "elbow_tol": ELBOW_TOL,
        "wrist_tol": WRIST_TOL,
    }
    factors = np.array([values[name] for name in kernel.FACTOR_SLOTS])
    lower, upper = robot.lower, robot.upper
    bounded = np.isfinite(lower) & np.isfinite(upper)
    joints = np.stack(
        [
            np.asarray(fac.joint_sign, dtype=np.float64),
            np.asarray(fac.theta_offset, dtype=np.float64),
            lower,
            upper,
            0.5 * (np.where(bounded, lower, 0.0) + np.where(bounded, upper, 0.0)),
            bounded.astype(np.float64),
        ]
    )
    return factors, np.ascontiguousarray(joints)


def get_core_count() -> int:
    """Cores this process may run on (at least 1): the default thread count.

    The threads of a map build, of the placement screening and of the
    joint-space map each run compiled kernels that release the GIL.
    """
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


class _Work(threading.local):
    """One thread's work arrays of :func:`_evaluate_compiled`, reused by its calls.

    Allocating them per block made glibc map (and the kernel zero) fresh
    pages on every call once its mmap threshold is fixed, as it is in Dask's
    nanny-started workers (``MALLOC_TRIM_THRESHOLD_``): half the speed.
    """

    def __init__(self) -> None:
        self.poses = np.empty((CHUNK_POSES, 4, 4))
        self.q = np.empty((CHUNK_POSES, 8, 6))
        self.valid = np.empty((CHUNK_POSES, 8), dtype=bool)
        # grown to fit the largest block: float64 (2, P), uint8 (2, P), float32 (5, P)
        self.dexterity = np.empty(0)
        self.counts = np.empty(0, dtype=np.uint8)
        self.measures = np.empty(0, dtype=np.float32)

    def get(self, name: str, rows: int, total: int) -> np.ndarray:
        """A (rows, total) view of this thread's buffer ``name``, grown if needed."""
        buffer = getattr(self, name)
        if buffer.size < rows * total:
            buffer = np.empty(rows * total, dtype=buffer.dtype)
            setattr(self, name, buffer)
        view: np.ndarray = buffer[: rows * total].reshape(rows, total)
        return view


_work = _Work()


def _evaluate_compiled(
    robot: Robot,
    solver: Solver,
    grid: PoseGrid,
    start: int,
    stop: int,
    reuse: bool,
) -> dict[str, np.ndarray]:
    """:func:`evaluate_block` through the compiled kernels (no scene).

    The work arrays are the thread's (:class:`_Work`); so are the per-pose
    outputs with ``reuse``, else they are new arrays.
    """
    factors, joints = _constants(robot)
    positions = np.ascontiguousarray(grid.positions[start:stop])
    rotations = np.ascontiguousarray(grid.rotations)
    count, orientations = stop - start, grid.orientation_count
    total = count * orientations
    work = _work
    if reuse:
        counts, measures = work.get("counts", 2, total), work.get("measures", 5, total)
    else:
        counts = np.empty((2, total), dtype=np.uint8)
        measures = np.empty((5, total), dtype=np.float32)
    dexterity = work.get("dexterity", 2, total)
    poses, q, valid = work.poses, work.q, work.valid
    for first in range(0, total, CHUNK_POSES):
        n = min(CHUNK_POSES, total - first)
        kernel.fill_poses(positions, rotations, first, poses[:n])
        solver.solve_batch_into(poses[:n], q[:n], valid[:n])
        kernel.measure_poses(
            factors, joints, q[:n], valid[:n], first, counts, measures, dexterity
        )
    shape = (count, orientations)
    out: dict[str, np.ndarray] = {
        "reached": counts[0].reshape(shape),
        "branches": counts[1].reshape(shape),
    }
    for index, key in enumerate(("dexterity", "shoulder", "elbow", "wrist")):
        out[key] = measures[index].reshape(shape)
    out["limit_margin"] = measures[4].reshape(shape)
    out.update(
        summarise_voxels(dexterity[0].reshape(shape), dexterity[1].reshape(shape))
    )
    return out


def evaluate_block(
    robot: Robot,
    grid: PoseGrid,
    start: int,
    stop: int,
    *,
    checker: CollisionChecker | None = None,
    reuse: bool = False,
) -> dict[str, np.ndarray]:
    """Measures of every pose of voxels ``start:stop`` × all orientations.

    Through the compiled kernels (:mod:`workbench.workspace._measure_kernel`
    after :meth:`Solver.solve_batch_into`, which also refines the
    branches of a URDF that is of its family only up to an error); with a
    ``checker``, through the NumPy definition
    (:mod:`workbench.workspace._reference`), one collision query per in-limit
    branch, much slower.

    Args:
        robot: An arm with a closed form (OPW or UR type).
        grid: The pose grid (positions in the robot's base frame).
        start: First voxel of the block, ``0 <= start < stop``.
        stop: One past its last voxel, ``<= V``.
        checker: Optional collision checker of the robot and a scene.
        reuse: Return the per-pose arrays in this thread's buffers (compiled
            path), which its next call with ``reuse`` overwrites: for a
            caller that stores the block at once (a map build), sparing the
            allocation and first touch of ~11 MB per block of 1024 × 512.

    Returns:
        Arrays keyed as in the module docstring: :data:`POSE_KEYS` (B, O)
        (``collision_free`` only with a checker) and :data:`VOXEL_KEYS` (B,).

    Raises:
        UnsupportedRobotError: If the robot has no closed form.
        InputError: If the voxel range is empty or outside the grid.
    """
    start, stop = check_voxel_range(grid, start, stop)
    solver = get_solver(robot)  # raises UnsupportedRobotError
    if solver.parameter is not None:
        raise UnsupportedRobotError(
            f"robot {robot.name!r} is a seven-axis arm ({solver.family.name.upper()} "
            "family): its atlas solves at values of the redundancy parameter, "
            "see workspace.evaluate_redundant_block"
        )
    if checker is None:
        return _evaluate_compiled(robot, solver, grid, start, stop, reuse)
    return evaluate_block_reference(robot, grid, start, stop, checker=checker)


__all__ = [
    "CHUNK_POSES",
    "POSE_KEYS",
    "VOXEL_KEYS",
    "check_voxel_range",
    "evaluate_block",
    "get_core_count",
    "singularity_margin",
]
