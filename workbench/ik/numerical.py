r"""Numerical inverse kinematics for any serial arm: Newton / Levenberg–Marquardt.

The error of a configuration ``q`` is the SE(3) logarithm of the tool pose seen
from the target, :math:`e(q) = \log_6(T^{-1}\,{}^oM_f(q))`, shape (6,), linear
[m] then angular [rad]; it vanishes exactly at the solution. The iteration
runs in compiled code (``_chain_kernel``) on the robot's chain, read from its
Pinocchio model (``_chain``); Pinocchio is the reference the compiled forward
kinematics and Jacobian are tested against. The algorithm (damping, limits,
redundancy, first guess, restarts) is described in ``docs/numerical-ik.md``;
in short, each step :math:`q \leftarrow \mathrm{clip}(q - \Delta q)` is the
Newton step :math:`J^{-1} e` for six joints (LOCAL Jacobian :math:`J`,
shortened to 1.5 rad), else, or when J is near-singular, the damped step
:math:`J^T (J J^T + \lambda I)^{-1} e` with Sugihara's damping
:math:`\lambda = \mu \|e\|^2 + \lambda_0`. A run that stalls restarts from
a configuration drawn uniformly within the limits, while the time budget
lasts.

:func:`numeric` solves one target; :func:`~workbench.ik.numeric_batch` many.

Reference: T. Sugihara, "Solvability-unconcerned inverse kinematics by the
Levenberg–Marquardt method", IEEE Trans. Robotics 27(5), 2011.
"""

from __future__ import annotations

import math
import numbers
import time
from operator import itemgetter
from typing import ClassVar, TypeGuard

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.ik import _chain_kernel as kernel
from workbench.ik._chain import FULL_POSE, Chain, get_chain
from workbench.ik._record import FrozenRecord
from workbench.model.robot import Robot
from workbench.poses import as_se3

FloatArray = npt.NDArray[np.float64]

#: What of a target :func:`numeric` reaches (``part=``), by name: the whole
#: pose; the position only (any orientation); the position and the direction
#: of one tool axis, any rotation about it ("free-z": the tool's z axis along
#: the target's, e.g. a drill or a nozzle). The partial targets' errors are
#: the tool's offset and axis in the target's axes (``_chain_kernel``).
TARGET_PARTS: dict[str, int] = {
    "pose": kernel.PART_POSE,
    "position": kernel.PART_POSITION,
    "free-x": kernel.PART_FREE_X,
    "free-y": kernel.PART_FREE_Y,
    "free-z": kernel.PART_FREE_Z,
}

#: Whether ``pin.SE3.homogeneous`` is a C-contiguous array (eigenpy's copy of
#: the matrix), the layout the kernel is called with (see Chain.run).
_HOMOGENEOUS_IS_C: bool = pin.SE3.Identity().homogeneous.flags.c_contiguous


class IKResult(FrozenRecord):
    """Outcome of :func:`numeric`; a failed solve is not an exception.

    Immutable (a :class:`~workbench.ik._record.FrozenRecord`, as
    :class:`~workbench.ik.IKSolution`: assigning a field raises
    :class:`dataclasses.FrozenInstanceError`), equal by value.

    Attributes:
        q: Best configuration found, shape (nq,) [rad], within the position
            limits, read-only.
        success: True when ``error <= tol``.
        iterations: Steps taken, over all restarts.
        error: Norm of the SE(3) log error ``log6(target^-1 * fk(q))``, whose
            six entries mix [m] and [rad].
        position_error: Distance between tool and target origins [m].
        rotation_error: Angle of the tool-to-target rotation [rad].
        restarts: Random restarts used.
    """

    __slots__ = ()
    _fields: ClassVar[tuple[str, ...]] = (
        "q", "success", "iterations", "error", "position_error",
        "rotation_error", "restarts",
    )  # fmt: skip

    def __new__(
        cls,
        q: FloatArray,
        success: bool,
        iterations: int,
        error: float,
        position_error: float,
        rotation_error: float,
        restarts: int,
    ) -> IKResult:
        """The record of these values (``q`` is stored as given)."""
        items = (q, success, iterations, error, position_error, rotation_error)
        return tuple.__new__(cls, (*items, restarts))

    q = property(itemgetter(0), doc="Best configuration (nq,) [rad], read-only.")
    success = property(itemgetter(1), doc="True when ``error <= tol``.")
    iterations = property(itemgetter(2), doc="Steps taken, over all restarts.")
    error = property(itemgetter(3), doc="Norm of the SE(3) log error.")
    position_error = property(itemgetter(4), doc="Position residual [m].")
    rotation_error = property(itemgetter(5), doc="Rotation residual [rad].")
    restarts = property(itemgetter(6), doc="Random restarts used.")


def numeric(
    robot: Robot,
    target: pin.SE3 | npt.ArrayLike,
    q0: npt.ArrayLike | None = None,
    *,
    tol: float = 1e-10,
    max_iterations: int = 1000,
    time_budget: float = 0.1,
    rng: np.random.Generator | int | None = None,
    part: str = "pose",
    weights: npt.ArrayLike | None = None,
) -> IKResult:
    """Solve the inverse kinematics of the tool frame numerically.

    Newton / Levenberg–Marquardt steps on the SE(3) log error, within the
    joint limits, with random restarts (see ``docs/numerical-ik.md``). Works
    for any serial arm of revolute, continuous and prismatic joints;
    redundant arms get the minimum-norm solution, pulled towards ``q0`` (or
    mid-range). Thread-safe: the robot is only read.

    Args:
        robot: The robot.
        target: Desired tool pose in the base frame: ``pin.SE3`` or a (4, 4)
            homogeneous matrix, positions in metres.
        q0: First guess, shape (nq,) [rad], clipped into the limits; default
            the candidate configuration whose tool pose is nearest the target,
            deterministic. Redundant arms are pulled towards ``q0``, by default
            towards the middle of the limits (0 where a joint is unlimited).
        tol: Convergence threshold on ``error``, > 0.
        max_iterations: Maximum number of steps over all restarts, >= 1.
        time_budget: No restart begins more than this many seconds [s]
            after the first run stalled, > 0 (inf allowed); the run under way
            always continues (at most 40 steps), up to ``max_iterations``
            steps in total.
        rng: Generator, or int seed >= 0, of the restart configurations;
            default seed 0, so that results are reproducible. Drawn from only
            when a restart is due.
        part: What of the target is reached, a name of :data:`TARGET_PARTS`:
            ``"pose"``, ``"position"``, ``"free-x"``/``"free-y"``/``"free-z"``.
            An arm of fewer than six joints asked for a pose, or a target out
            of reach, gets the configuration of least error found
            (``success`` False, the residuals in the result).
        weights: With ``part="pose"``: 6 weights >= 0 of the error entries
            ``[x, y, z, rx, ry, rz]`` (target frame; default all 1).

    Returns:
        An :class:`IKResult`; ``success`` is False when the target was not
        reached within the budget (e.g. it is out of reach), never None.
        ``error`` is the norm of the error aimed at (weighted, or of the
        partial target); ``position_error`` and ``rotation_error`` are the
        tool's true distance and angle from the target.

    Raises:
        DimensionError: If ``target`` or ``q0`` has the wrong shape.
        NonFiniteError: If ``target`` or ``q0`` holds NaN or infinity.
        InputError: If ``target`` is not rigid, or ``tol``, ``max_iterations``,
            ``time_budget``, ``rng``, ``part`` or ``weights`` is invalid, or a
            joint of the arm is neither revolute nor prismatic.
    """
    # Fast paths for the usual types; anything else gets the full checks.
    if target.__class__ is pin.SE3 and _HOMOGENEOUS_IS_C:
        matrix = target.homogeneous
    elif (
        target.__class__ is np.ndarray
        and target.dtype == np.float64
        and target.shape == (4, 4)
        and target.flags.c_contiguous
        and target.flags.writeable  # one compiled signature for all calls
    ):
        matrix = target  # finite and rigid: checked by the kernel
    else:
        matrix = np.ascontiguousarray(as_se3(target).homogeneous)
    if not (
        tol.__class__ is float
        and 0.0 < tol < math.inf
        and max_iterations.__class__ is int
        and max_iterations >= 1
        and (time_budget.__class__ is float or time_budget.__class__ is int)
        and time_budget > 0.0
        and (rng is None or (rng.__class__ is int and rng >= 0))
    ):
        check_options(tol, max_iterations, rng)
        if not (isinstance(time_budget, int | float) and time_budget > 0.0):
            raise InputError(f"time_budget must be > 0 [s], got {time_budget!r}")
        tol, max_iterations = float(tol), int(max_iterations)
    chain = get_chain(robot)
    weighting, aim = (
        (FULL_POSE, 0)
        if weights is None and part == "pose"
        else check_part(part, weights)
    )
    n = chain.n
    # This solve's state: row `row` of a block, [q, best q, stats] (kernel.run)
    states, states_read_only, row = chain.states.take()
    packed, q_ref, features, starts = chain.run_inputs  # (writable: see Chain)
    if q0 is None:
        q_base, guess = chain.mid, True
    else:
        q_base = reference_configuration(robot, chain, q0)
        q_ref = chain.to_chain(q_base)
        states[row, :n] = q_ref
        (features, starts), guess = chain.run_no_seeds, False
    tol2 = tol * tol
    run = chain.run  # kernel.run's compiled code: our arguments are typed
    status, err2, position, rotation, steps = run(
        packed, matrix, q_ref, states, row, tol2, max_iterations, guess, features,
        starts, True, weighting, aim,
    )  # fmt: skip
    if status == kernel.NOT_RIGID:  # the kernel's test is the exact one
        as_se3(target)  # raises the error that says why
        raise InputError("target is not a rigid transform")  # (as_se3 raised)
    restarts = 0
    if status == kernel.STALLED:
        # The clock only stops restarts: a run that converges is never cut
        # short, e.g. by the process being descheduled. It starts here, so
        # that a solve needing no restart does not read it.
        deadline = time.perf_counter() + time_budget
        generator = _generator(rng)
        while True:
            states[row, :n] = chain.low + chain.span * generator.random(n)
            restarts += 1
            status, err2, position, rotation, steps = run(
                packed, matrix, q_ref, states, row, tol2, max_iterations, False,
                features, starts, False, weighting, aim,
            )  # fmt: skip
            if status != kernel.STALLED or time.perf_counter() > deadline:
                break
    if chain.identity:
        best_q = states_read_only[row, n : 2 * n]
    else:
        best_q = chain.to_configuration(states[row, n : 2 * n], q_base)
        best_q.setflags(write=False)
    return tuple.__new__(  # IKResult(...) without its Python-level __new__
        IKResult,
        (best_q, err2 <= tol2, steps, math.sqrt(err2), position, rotation, restarts),
    )


def reference_configuration(
    robot: Robot, chain: Chain, q0: npt.ArrayLike
) -> FloatArray:
    """``q0`` (nq,) checked, clipped into the limits and normalised (a new array).

    Raises:
        DimensionError: If ``q0`` does not have nq entries.
        NonFiniteError: If an entry is NaN or infinite.
    """
    q = robot.check_configuration(q0)
    q = np.minimum(np.maximum(q, chain.lower), chain.upper)
    if robot.model.nq != robot.model.nv:
        q = pin.normalize(robot.model, q)
    return q


def check_part(part: str, weights: npt.ArrayLike | None) -> tuple[FloatArray, int]:
    """``(weights (6,), kernel part)`` of ``numeric``'s ``part=`` and ``weights=``.

    Raises:
        InputError: If ``part`` is no name of :data:`TARGET_PARTS`, or
            ``weights`` are given with a partial target or are not 6 finite
            numbers >= 0, not all zero.
    """
    if part not in TARGET_PARTS:
        names = ", ".join(TARGET_PARTS)
        raise InputError(f"part {part!r}: expected one of {names}")
    if weights is None:
        return np.ones(6), TARGET_PARTS[part]
    if part != "pose":
        raise InputError(f"weights apply to part='pose' only, not {part!r}")
    return check_weights(weights), TARGET_PARTS[part]


def check_weights(weights: npt.ArrayLike) -> FloatArray:
    """The (6,) weights of ``numeric``'s ``weights=`` (a new, writable array).

    Raises:
        InputError: If ``weights`` are not 6 finite numbers >= 0, or all zero.
    """
    try:
        values = np.array(weights, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"weights must be 6 numbers >= 0, got {weights!r}") from None
    if values.shape != (6,) or not np.all(np.isfinite(values)) or np.any(values < 0):
        raise InputError(f"weights must be 6 finite numbers >= 0, got {weights!r}")
    if not values.any():
        raise InputError("weights are all 0: nothing of the target would count")
    return values


def check_options(tol: float, max_iterations: int, rng: object) -> None:
    """Raise InputError unless ``tol``, ``max_iterations`` and ``rng`` are valid."""
    if not (isinstance(tol, int | float) and math.isfinite(tol) and tol > 0.0):
        raise InputError(f"tol must be a finite number > 0, got {tol!r}")
    if not (_is_int(max_iterations) and max_iterations >= 1):
        raise InputError(f"max_iterations must be an int >= 1, got {max_iterations!r}")
    if not (
        rng is None
        or isinstance(rng, np.random.Generator)
        or (_is_int(rng) and rng >= 0)
    ):
        raise InputError(
            f"rng must be a numpy Generator, an int seed >= 0 or None, got {rng!r}"
        )


def _is_int(value: object) -> TypeGuard[int]:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def _generator(rng: np.random.Generator | int | None) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    return np.random.default_rng(0 if rng is None else int(rng))
