"""The per-pose measures of a block of the pose grid, plainly in NumPy.

The definition of :func:`workbench.workspace.measures.evaluate_block`, written
on top of the public closed form (:meth:`Solver.solve_batch`) and
the analytic singularity factors
(:func:`workbench.singularities.compute_conditions`): the compiled kernel
(:mod:`workbench.workspace._measure_kernel`) is tested against it, and it
serves the robots the kernel does not (the solver refines their branches on
the model), and every block with a collision scene.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from workbench.ik import get_solver
from workbench.model.robot import Robot
from workbench.singularities.conditions import (
    ELBOW_TOL,
    SHOULDER_TOL,
    WRIST_TOL,
    compute_conditions,
    get_factorisation,
)

if TYPE_CHECKING:
    from workbench.collision.checker import CollisionChecker
    from workbench.workspace.grid import PoseGrid

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

TAU = 2.0 * np.pi
INV_TAU = 1.0 / TAU


def block_poses(grid: PoseGrid, start: int, stop: int) -> FloatArray:
    """(B·O, 4, 4) poses of voxels ``start:stop`` × every orientation, voxel-major."""
    positions = grid.positions[start:stop]
    count, orientations = len(positions), grid.orientation_count
    poses = np.zeros((count, orientations, 4, 4))
    poses[:, :, :3, :3] = grid.rotations[None]
    poses[:, :, :3, 3] = positions[:, None]
    poses[:, :, 3, 3] = 1.0
    return poses.reshape(-1, 4, 4)


def limit_representatives(
    q: FloatArray, lower: FloatArray, upper: FloatArray
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Each angle's representative ``q + 2πk`` nearest the middle of its limits.

    That representative lies within the limits if any does, and has the
    largest margin of them all (the margin ``min(q − lower, upper − q)`` falls
    off linearly from the middle). Unbounded joints keep their value, margin
    +inf.

    Args:
        q: (..., n) angles [rad].
        lower: (n,) lower limits [rad].
        upper: (n,) upper limits [rad].

    Returns:
        ``(shifted (..., n), margin (...,), within (...,))``: the
        representatives, the smallest margin over the joints [rad] (negative
        when out of limits) and whether every joint is within its limits.
    """
    bounded = np.isfinite(lower) & np.isfinite(upper)
    mid = 0.5 * (np.where(bounded, lower, 0.0) + np.where(bounded, upper, 0.0))
    turns = np.where(bounded, np.rint((mid - q) * INV_TAU), 0.0)
    shifted = q + turns * TAU
    joint_margin = np.where(
        bounded, np.minimum(shifted - lower, upper - shifted), np.inf
    )
    within = np.all((shifted >= lower) & (shifted <= upper), axis=-1)
    return shifted, np.min(joint_margin, axis=-1), within


def singularity_margin(
    shoulder: npt.ArrayLike, elbow: npt.ArrayLike, wrist: npt.ArrayLike
) -> FloatArray:
    """Distance to the nearest singular locus in units of its tolerance [1].

    ``min(|s|/SHOULDER_TOL, |e|/ELBOW_TOL, |w|/WRIST_TOL)`` with the
    tolerances of :mod:`workbench.singularities.conditions`; below 1 the
    configuration is classified near-singular. Arrays broadcast; NaN stays NaN.

    Args:
        shoulder: Shoulder distance [m] (sign ignored).
        elbow: Elbow sine [1] (sign ignored).
        wrist: sin θ5 [1] (sign ignored).
    """
    s = np.abs(np.asarray(shoulder, dtype=np.float64)) / SHOULDER_TOL
    e = np.abs(np.asarray(elbow, dtype=np.float64)) / ELBOW_TOL
    w = np.abs(np.asarray(wrist, dtype=np.float64)) / WRIST_TOL
    return np.minimum(np.minimum(s, e), w)


def _collision_free(
    checker: CollisionChecker, shifted: FloatArray, usable: BoolArray
) -> BoolArray:
    """(N, 8): usable branches whose representative touches nothing."""
    free = np.zeros_like(usable)
    for pose, branch in zip(*np.nonzero(usable), strict=True):
        distances = checker.compute_distances(shifted[pose, branch])
        free[pose, branch] = bool(np.all(distances > 0.0))
    return free


def evaluate_block_reference(
    robot: Robot,
    grid: PoseGrid,
    start: int,
    stop: int,
    *,
    checker: CollisionChecker | None = None,
) -> dict[str, np.ndarray]:
    """Measures of voxels ``start:stop`` (see ``measures.evaluate_block``)."""
    solver = get_solver(robot)
    fac = get_factorisation(robot)
    count, orientations = stop - start, grid.orientation_count
    q, valid = solver.solve_batch(block_poses(grid, start, stop))
    shifted, margin, within = limit_representatives(q, robot.lower, robot.upper)
    usable = valid & within
    out: dict[str, np.ndarray] = {
        "reached": valid.sum(axis=1).astype(np.uint8),
        "branches": usable.sum(axis=1).astype(np.uint8),
    }
    if checker is not None:
        usable = _collision_free(checker, shifted, usable)
        out["collision_free"] = usable.sum(axis=1).astype(np.uint8)
    conditions = compute_conditions(robot, np.where(valid[..., None], q, 0.0))
    s, e, w = conditions.shoulder, conditions.elbow, conditions.wrist
    det = np.abs(fac.constant * s * e * w)
    score = np.where(usable, det, -1.0)
    top = score == score.max(axis=1, keepdims=True)
    best = np.argmax(np.where(top, margin, -np.inf), axis=1)  # ties: first
    rows = np.arange(len(best))
    has = usable.any(axis=1)

    def pick(values: FloatArray) -> FloatArray:
        return np.where(has, values[rows, best], np.nan)

    dexterity = pick(det)
    sing = singularity_margin(pick(s), pick(e), pick(w))
    out["dexterity"] = dexterity.astype(np.float32)
    out["shoulder"] = np.abs(pick(s)).astype(np.float32)
    out["elbow"] = np.abs(pick(e)).astype(np.float32)
    out["wrist"] = np.abs(pick(w)).astype(np.float32)
    out["limit_margin"] = pick(margin).astype(np.float32)
    shape = (count, orientations)
    out = {key: value.reshape(shape) for key, value in out.items()}
    out.update(summarise_voxels(dexterity.reshape(shape), sing.reshape(shape)))
    return out


def summarise_voxels(
    dexterity: FloatArray, margin: FloatArray
) -> dict[str, np.ndarray]:
    """The per-voxel measures of a block from its per-pose ones.

    Args:
        dexterity: (B, O) |det J| [m³] of each pose's best branch, NaN where
            no branch is usable.
        margin: (B, O) singularity margin [1] of that branch (NaN likewise).

    Returns:
        ``reachability``, ``dexterity_best``, ``dexterity_median``,
        ``near_singular_fraction``, each (B,) float32 (``evaluate_block``).
    """
    has = ~np.isnan(dexterity)
    reached = has.sum(axis=1)
    some = reached > 0
    near = (margin < 1.0).sum(axis=1)  # NaN compares False
    best = np.full(len(has), np.nan)
    median = np.full(len(has), np.nan)
    if some.any():
        best[some] = np.nanmax(dexterity[some], axis=1)
        median[some] = np.nanmedian(dexterity[some], axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        fraction = np.where(some, near / np.maximum(reached, 1), np.nan)
    return {
        "reachability": (reached / has.shape[1]).astype(np.float32),
        "dexterity_best": best.astype(np.float32),
        "dexterity_median": median.astype(np.float32),
        "near_singular_fraction": fraction.astype(np.float32),
    }


__all__ = [
    "TAU",
    "block_poses",
    "evaluate_block_reference",
    "limit_representatives",
    "singularity_margin",
    "summarise_voxels",
]
