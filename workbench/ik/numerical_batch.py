"""Numerical IK of many targets in one compiled loop (workspace, reachability).

:func:`numeric_batch` runs the algorithm of :func:`~workbench.ik.numeric`
(``docs/numerical-ik.md``) on each target in turn without returning to
Python: restart configurations are drawn in compiled code (SplitMix64, one
stream per target, so a target's result does not depend on the rest of the
batch), and the work per target is bounded by ``max_iterations`` instead of a
clock.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import DimensionError, NonFiniteError
from workbench.ik import _chain_kernel as kernel
from workbench.ik._chain import Chain, get_chain
from workbench.ik._targets import as_targets, check_poses
from workbench.ik.numerical import (
    check_options,
    check_part,
    reference_configuration,
)
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class IKBatchResult:
    """Outcome of :func:`numeric_batch`, one entry per target; arrays read-only.

    Attributes:
        q: Best configuration per target, shape (N, nq) [rad], within the
            position limits.
        success: (N,) bool, True where ``error <= tol``.
        iterations: (N,) int, steps taken per target, over all its restarts.
        error: (N,) norm of the SE(3) log error ``log6(target^-1 * fk(q))``.
        position_error: (N,) distance between tool and target origins [m].
        rotation_error: (N,) angle of the tool-to-target rotation [rad].
        restarts: (N,) int, random restarts used per target.
    """

    q: FloatArray
    success: npt.NDArray[np.bool_]
    iterations: npt.NDArray[np.int64]
    error: FloatArray
    position_error: FloatArray
    rotation_error: FloatArray
    restarts: npt.NDArray[np.int64]


def numeric_batch(
    robot: Robot,
    targets: npt.ArrayLike,
    q0: npt.ArrayLike | None = None,
    *,
    tol: float = 1e-10,
    max_iterations: int = 1000,
    rng: np.random.Generator | int | None = None,
    part: str = "pose",
    weights: npt.ArrayLike | None = None,
) -> IKBatchResult:
    """Solve the inverse kinematics of the tool frame for many targets.

    Args:
        robot: The robot (only read: thread-safe).
        targets: (N, 4, 4) homogeneous tool poses in the base frame [m].
        q0: First guess, (nq,) for every target or (N, nq) one per target
            [rad], clipped into the limits; redundant arms are pulled towards
            it. Default: per target, the candidate configuration whose tool
            pose is nearest (as :func:`~workbench.ik.numeric`), pulled
            towards mid-range.
        tol: Convergence threshold on ``error``, > 0.
        max_iterations: Maximum number of steps per target over all its
            restarts, >= 1 (bounds the time an unreachable target takes).
        rng: Generator, or int seed >= 0, of the restart streams (one number
            is drawn from a Generator); default seed 0, so that results are
            reproducible.
        part: What of each target is reached, as
            :func:`~workbench.ik.numeric`'s (a name of ``ik.TARGET_PARTS``).
        weights: With ``part="pose"``, 6 weights of the error, as
            :func:`~workbench.ik.numeric`'s.

    Returns:
        An :class:`IKBatchResult`; unreached targets have ``success`` False.

    Raises:
        DimensionError: If ``targets`` is not (N, 4, 4) or ``q0`` has the
            wrong shape.
        NonFiniteError: If a target or ``q0`` holds NaN or infinity.
        InputError: If a target is not rigid, or ``tol``, ``max_iterations``
            or ``rng`` is invalid, or a joint of the arm is neither revolute
            nor prismatic.
    """
    # Writable and C-contiguous (copied only if not): one compiled signature.
    poses = np.require(as_targets(targets), requirements=["C", "W"])
    check_poses(poses, 0)
    check_options(tol, max_iterations, rng)
    chain = get_chain(robot)
    count = len(poses)
    if q0 is None:
        q_base = chain.mid[np.newaxis]
        q_ref, q_start, seeds = (
            chain.mid_values[np.newaxis],
            chain.no_start,
            chain.seeds,
        )
    else:
        q_base = _first_guesses(robot, chain, q0, count)
        q_ref = q_start = chain.to_chain(q_base)
        q_ref.setflags(write=False)  # as chain.mid_values: one compiled signature
        seeds = chain.no_seeds
    if isinstance(rng, np.random.Generator):
        seed = int(rng.integers(0, 2**63))
    else:
        seed = 0 if rng is None else int(rng)
    weighting = check_part(part, weights)
    values = np.empty((count, chain.n))
    stats = np.empty((count, kernel.N_STATS))
    kernel.solve_batch(
        chain.packed,
        poses,
        np.ascontiguousarray(q_ref),
        np.ascontiguousarray(q_start),
        *seeds,
        float(tol) ** 2,
        int(max_iterations),
        seed % 2**63,  # always an int64 for the kernel
        *weighting,
        values,
        stats,
    )
    q = chain.to_configuration(values, q_base)
    err2 = stats[:, kernel.ERR2]
    result = IKBatchResult(
        q=q,
        success=err2 <= float(tol) ** 2,
        iterations=stats[:, kernel.STEPS].astype(np.int64),
        error=np.sqrt(err2),
        position_error=stats[:, kernel.POSITION].copy(),
        rotation_error=stats[:, kernel.ROTATION].copy(),
        restarts=stats[:, kernel.RESTARTS].astype(np.int64),
    )
    for array in (result.q, result.success, result.iterations, result.error):
        array.setflags(write=False)
    for array in (result.position_error, result.rotation_error, result.restarts):
        array.setflags(write=False)
    return result


def _first_guesses(
    robot: Robot, chain: Chain, q0: npt.ArrayLike, count: int
) -> FloatArray:
    """``q0`` checked, clipped, normalised: (1, nq) for all targets or (count, nq)."""
    try:
        arr = np.asarray(q0, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise NonFiniteError(f"q0 must be numbers, got {q0!r}") from err
    if arr.ndim == 1:
        return reference_configuration(robot, chain, arr)[np.newaxis]
    if arr.shape != (count, robot.nq):
        raise DimensionError("q0", (count, robot.nq), arr.shape)
    if not np.isfinite(arr).all():
        raise NonFiniteError("q0 must be finite")
    arr = np.minimum(np.maximum(arr, chain.lower), chain.upper)
    if robot.model.nq != robot.model.nv:
        arr = np.array([pin.normalize(robot.model, q) for q in arr])
    return arr


__all__ = ["IKBatchResult", "numeric_batch"]
