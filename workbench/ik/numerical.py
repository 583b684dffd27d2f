r"""Numerical inverse kinematics for any arm: Newton / Levenberg–Marquardt.

The error of a configuration ``q`` is the SE(3) logarithm of the tool pose seen
from the target, :math:`e(q) = \log_6(T^{-1}\,{}^oM_f(q))`, shape (6,), linear
[m] then angular [rad]; it vanishes exactly at the solution. Its Jacobian is
:math:`J_{\log_6}(T^{-1}\,{}^oM_f)\,J(q)` with Pinocchio's LOCAL frame
Jacobian :math:`J`. The solver uses :math:`J` alone: :math:`J_{\log_6} = I +
O(\|e\|)`, which keeps the convergence quadratic, and on the benchmark targets
it took as many steps as the exact product while saving two calls per step.

Each step :math:`q \leftarrow \mathrm{clip}(q \ominus \Delta q)` is

* square Jacobians (nv = 6): the Newton step :math:`\Delta q = J^{-1} e`
  (LU), shortened to ``_MAX_STEP`` rad; if it is longer than
  ``_SINGULAR_STEP`` (a near-singular J) the damped step below is used;
* otherwise the damped minimum-norm (Levenberg–Marquardt) step

  .. math::

      \Delta q = J^T (J J^T + \lambda I_6)^{-1} e, \qquad
      \lambda = \mu \|e\|^2 + \lambda_0,

  with Sugihara's (2011) damping: large far from the target, vanishing near
  it so that the last steps are Newton steps (for nv < 6, the least-squares
  form :math:`(J^T J + \lambda I)^{-1} J^T e`).

Joint limits: the new ``q`` is clipped into the position limits; a revolute
joint whose range spans a full turn wraps around (:math:`q \mp 2\pi`)
instead, and redundant arms (nv > 6), once :math:`\|e\| <`
``_ACTIVE_SET_ERROR``, re-solve a step that crosses a limit with the crossing
joints frozen (their Jacobian columns zeroed), so the other joints take over.

Redundancy: besides the minimum-norm step, while
:math:`\|e\| >` ``_NULL_OFF_ERROR`` a pull :math:`z = k\,(q_\mathrm{ref}
\ominus q)` towards the seed (or mid-range) is projected, damped, into the
task null space: :math:`\Delta q = J^T (J J^T + \lambda I)^{-1}(e + J z) - z`.
It is switched off for the last steps, where the damping would leak it into
the pose error.

Restarts: when the error has not fallen by 10 % for ``_STALL_STEPS`` steps,
or a run exceeds ``_RUN_STEPS``, the solver restarts from a configuration
drawn uniformly within the limits (numpy Generator, seeded), until
``max_iterations`` steps in all; no restart begins after ``time_budget``
seconds. The hot loop calls
Pinocchio and eigenpy directly on ``robot.model`` / ``robot.data`` with no
per-step validation.

Reference: T. Sugihara, "Solvability-unconcerned inverse kinematics by the
Levenberg–Marquardt method", IEEE Trans. Robotics 27(5), 2011.
"""

from __future__ import annotations

import math
import numbers
import time
from collections.abc import Callable
from dataclasses import dataclass

import eigenpy
import numpy as np
import numpy.typing as npt
import pinocchio as pin
from pinocchio import log3

from workbench.errors import InputError
from workbench.poses import as_se3
from workbench.robot import Robot

FloatArray = npt.NDArray[np.float64]

_DAMPING_GAIN = 3e-2
"""mu in lambda = mu |e|^2 + lambda_0 [1/m^2 ~ 1/rad^2 scale]."""

_DAMPING_FLOOR = 1e-9
"""lambda_0: keeps J J^T + lambda I positive definite at singularities."""

_STALL_STEPS = 6
"""Restart when the error has not dropped by 10 % for this many steps."""

_STALL_RATIO = 0.81
"""Squared-error ratio of one 10 % decrease."""

_RUN_STEPS = 40
"""Restart after this many steps in one run, converging or not."""

_NULL_GAIN = 0.1
"""Gain of the null-space pull to ``q_ref`` (redundant arms only) [1/step]."""

_NULL_OFF_ERROR = 0.3
"""The null-space pull stops once |e| falls below this [m ~ rad]."""

_MAX_STEP = 1.5
"""Newton steps (nv = 6) are shortened to this norm [rad]."""

_SINGULAR_STEP = 10.0
"""A Newton step longer than this [rad] means a (near-)singular Jacobian."""

_ACTIVE_SET_ERROR = 0.3
"""Redundant arms re-solve a step that crosses a limit while |e| < this."""

_UNBOUNDED_SPAN = math.pi
"""Restarts draw unlimited coordinates within +-this [rad]."""


@dataclass(frozen=True, slots=True)
class IKResult:
    """Outcome of :func:`numeric`; a failed solve is not an exception.

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

    q: FloatArray
    success: bool
    iterations: int
    error: float
    position_error: float
    rotation_error: float
    restarts: int


def numeric(
    robot: Robot,
    target: pin.SE3 | npt.ArrayLike,
    q0: npt.ArrayLike | None = None,
    *,
    tol: float = 1e-10,
    max_iterations: int = 1000,
    time_budget: float = 0.1,
    rng: np.random.Generator | int | None = None,
) -> IKResult:
    """Solve the inverse kinematics of the tool frame numerically.

    Newton / Levenberg–Marquardt steps on the SE(3) log error, within the
    joint limits, with random restarts (see the module docstring). Works for
    any arm; redundant arms get the minimum-norm solution, pulled towards
    ``q0`` (or mid-range).

    Args:
        robot: The robot; its ``data`` is used as scratch space (so one
            robot must not be solved from two threads at once).
        target: Desired tool pose in the base frame: ``pin.SE3`` or a (4, 4)
            homogeneous matrix, positions in metres.
        q0: First guess, shape (nq,) [rad], clipped into the limits; default
            the middle of the limits (0 where a joint is unlimited).
        tol: Convergence threshold on ``error``, > 0.
        max_iterations: Maximum number of steps over all restarts, >= 1.
        time_budget: No restart begins after this many seconds [s], > 0
            (inf allowed); the run under way always continues, up to
            ``max_iterations`` steps in total.
        rng: Generator, or int seed >= 0, of the restart configurations;
            default seed 0, so that results are reproducible.

    Returns:
        An :class:`IKResult`; ``success`` is False when the target was not
        reached within the budget (e.g. it is out of reach), never None.

    Raises:
        DimensionError: If ``target`` or ``q0`` has the wrong shape.
        NonFiniteError: If ``target`` or ``q0`` holds NaN or infinity.
        InputError: If ``target`` is not rigid, or ``tol``, ``max_iterations``,
            ``time_budget`` or ``rng`` is invalid.
    """
    target = as_se3(target)
    _check_options(tol, max_iterations, time_budget, rng)
    model = robot.model
    lower, upper = robot.lower, robot.upper
    if q0 is None:
        q_ref = _mid_configuration(model, lower, upper)
    else:
        q_ref = robot.check_configuration(q0)
        q_ref = np.minimum(np.maximum(q_ref, lower), upper)
        if model.nq != model.nv:
            q_ref = pin.normalize(model, q_ref)
    deadline = time.perf_counter() + time_budget
    return _solve(robot, target, q_ref, tol, max_iterations, deadline, rng)


def _check_options(
    tol: float, max_iterations: int, time_budget: float, rng: object
) -> None:
    if not (isinstance(tol, int | float) and math.isfinite(tol) and tol > 0.0):
        raise InputError(f"tol must be a finite number > 0, got {tol!r}")
    if not (_is_int(max_iterations) and max_iterations >= 1):
        raise InputError(f"max_iterations must be an int >= 1, got {max_iterations!r}")
    if not (isinstance(time_budget, int | float) and time_budget > 0.0):
        raise InputError(f"time_budget must be > 0 [s], got {time_budget!r}")
    if not (
        rng is None
        or isinstance(rng, np.random.Generator)
        or (_is_int(rng) and rng >= 0)
    ):
        raise InputError(
            f"rng must be a numpy Generator, an int seed >= 0 or None, got {rng!r}"
        )


def _is_int(value: object) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def _mid_configuration(
    model: pin.Model, lower: FloatArray, upper: FloatArray
) -> FloatArray:
    """Middle of the limits; neutral for multi-coordinate joints, 0 if unlimited."""
    mid = 0.5 * (lower + upper)
    if model.nq != model.nv:
        neutral = pin.neutral(model)
        for joint in model.joints[1:]:
            if joint.nq != 1:
                span = slice(joint.idx_q, joint.idx_q + joint.nq)
                mid[span] = neutral[span]
    if not math.isfinite(mid.sum()):
        mid[~np.isfinite(mid)] = 0.0
    return mid


def _sampler(
    model: pin.Model,
    lower: FloatArray,
    upper: FloatArray,
    rng: np.random.Generator | int | None,
) -> Callable[[], FloatArray]:
    """Draw configurations uniformly within the limits (+-pi where unlimited)."""
    if not isinstance(rng, np.random.Generator):
        rng = np.random.default_rng(0 if rng is None else int(rng))
    low = np.where(np.isfinite(lower), lower, -_UNBOUNDED_SPAN)
    span = np.where(np.isfinite(upper), upper, _UNBOUNDED_SPAN) - low
    if model.nq == model.nv:
        return lambda: low + span * rng.random(model.nq)
    return lambda: pin.normalize(model, low + span * rng.random(model.nq))


def _wrap_mask(jac: FloatArray, wide: npt.NDArray[np.bool_]) -> npt.NDArray[np.bool_]:
    """Joints that turn (not slide) and whose range spans a full turn, (nv,).

    Only for vector-space models (q ~ v). A joint turns when its column of the
    LOCAL Jacobian has a unit angular part; a sliding joint has none. (Helical
    joints would count as turning; URDF has none.)
    """
    return wide & (np.einsum("ij,ij->j", jac[3:], jac[3:]) > 0.25)


def _frozen_step(
    q_next: FloatArray,
    robot: Robot,
    jac: FloatArray,
    e: FloatArray,
    identity: FloatArray,
    pull: FloatArray | None,
    err2: float,
) -> FloatArray:
    """Damped step (to subtract) with the joints ``q_next`` pushes out frozen.

    Their Jacobian columns are zeroed, so that the other joints of a redundant
    arm take over the motion they cannot make.
    """
    blocked = (q_next < robot.lower) | (q_next > robot.upper)
    jac = jac.copy()
    jac[:, blocked] = 0.0
    if pull is not None:
        pull = pull.copy()
        pull[blocked] = 0.0
    damping = _DAMPING_GAIN * err2 + _DAMPING_FLOOR
    dq = _damped_step(jac, e, damping, identity, pull)
    dq[blocked] = 0.0
    return dq


def _damped_step(
    jac: FloatArray,
    e: FloatArray,
    damping: float,
    identity: FloatArray,
    pull: FloatArray | None,
) -> FloatArray:
    """Damped least-squares step to subtract from q, shape (nv,).

    ``identity`` is (6, 6) for nv >= 6 (minimum-norm form), (nv, nv) below.
    ``pull`` (nv,) is a null-space motion to add, or None.
    """
    if identity.shape[0] < 6:
        normal = np.dot(jac.T, jac)
        normal += damping * identity
        return eigenpy.LLT(normal).solve(np.dot(jac.T, e))
    normal = np.dot(jac, jac.T)
    normal += damping * identity
    if pull is None:
        return np.dot(jac.T, eigenpy.LLT(normal).solve(e))
    return np.dot(jac.T, eigenpy.LLT(normal).solve(e + np.dot(jac, pull))) - pull


def _solve(
    robot: Robot,
    target: pin.SE3,
    q_ref: FloatArray,
    tol: float,
    max_iterations: int,
    deadline: float,
    rng: np.random.Generator | int | None,
) -> IKResult:
    model, data, frame_id = robot.model, robot.data, robot.tool_frame_id
    lower, upper = robot.lower, robot.upper
    nv = model.nv
    forward_kinematics = pin.forwardKinematics
    frame_placement = pin.updateFramePlacement
    frame_jacobian = pin.computeFrameJacobian
    log6, integrate, difference = pin.log6, pin.integrate, pin.difference
    local = pin.ReferenceFrame.LOCAL
    dot, maximum, minimum = np.dot, np.maximum, np.minimum
    # Decompositions reused across steps (saves building one per step).
    lu, llt = eigenpy.PartialPivLU(6), eigenpy.LLT(6)
    lu_compute, lu_solve = lu.compute, lu.solve
    llt_compute, llt_solve = llt.compute, llt.solve
    clock = time.perf_counter
    vector_space = model.nq == nv  # then q (+) v is q + v
    square, redundant = nv == 6, nv > 6
    identity = np.eye(min(nv, 6))
    wide = upper - lower >= 2.0 * math.pi
    wide_joints = vector_space and bool(np.count_nonzero(wide))
    check_limits = wide_joints or (vector_space and redundant)
    active_set2 = _ACTIVE_SET_ERROR**2
    wrap = None  # full-turn revolute joints, found on first use
    tol2, null_off2 = tol * tol, _NULL_OFF_ERROR**2
    max_step2, singular_step2 = _MAX_STEP**2, _SINGULAR_STEP**2
    sample = None

    q = q_ref.copy()
    best_q, best_err2, best_pose = q, math.inf, None
    steps = restarts = run_steps = stall_at = 0
    run_best = math.inf
    while True:
        forward_kinematics(model, data, q)
        pose = target.actInv(frame_placement(model, data, frame_id))
        e = log6(pose).vector
        err2 = float(e.dot(e))
        if err2 < best_err2:
            best_q, best_err2, best_pose = q, err2, pose
            if err2 <= tol2:
                break
        if err2 < _STALL_RATIO * run_best:
            run_best, stall_at = err2, run_steps
        if steps >= max_iterations:
            break
        if run_steps - stall_at >= _STALL_STEPS or run_steps >= _RUN_STEPS:
            # The clock only stops restarts: a run that converges is never
            # cut short, e.g. by the process being descheduled.
            if clock() > deadline:
                break
            if sample is None:
                sample = _sampler(model, lower, upper, rng)
            q = sample()
            restarts += 1
            run_steps = stall_at = 0
            run_best = math.inf
            continue
        steps += 1
        run_steps += 1

        # The step dq is subtracted: q <- q (-) dq.
        jac = frame_jacobian(model, data, q, frame_id, local)
        dq = pull = None
        if square:
            lu_compute(jac)
            dq = lu_solve(e)
            step2 = float(dq.dot(dq))
            if not step2 < singular_step2:  # near-singular (or NaN): damp
                dq = None
            elif step2 > max_step2:
                dq *= _MAX_STEP / math.sqrt(step2)
        if dq is None:
            damping = _DAMPING_GAIN * err2 + _DAMPING_FLOOR
            if nv < 6:
                dq = _damped_step(jac, e, damping, identity, None)
            else:  # inlined _damped_step: the common path of redundant arms
                normal = dot(jac, jac.T)
                normal += damping * identity
                llt_compute(normal)
                if redundant and err2 > null_off2:
                    pull = _NULL_GAIN * difference(model, q, q_ref)
                    dq = dot(jac.T, llt_solve(e + dot(jac, pull))) - pull
                else:
                    dq = dot(jac.T, llt_solve(e))
        if not vector_space:
            q = integrate(model, q, -dq)
            minimum(maximum(q, lower, out=q), upper, out=q)
            continue
        q_next = q - dq
        if not check_limits:
            q = minimum(maximum(q_next, lower, out=q_next), upper, out=q_next)
            continue
        q_clip = minimum(maximum(q_next, lower), upper)
        if wide_joints and q_clip.tobytes() != q_next.tobytes():
            # Full-turn revolute joints come back in at the other end.
            if wrap is None:
                wrap = _wrap_mask(jac, wide)
            q_next[wrap & (q_next > upper)] -= 2.0 * math.pi
            q_next[wrap & (q_next < lower)] += 2.0 * math.pi
            q_clip = minimum(maximum(q_next, lower), upper)
        if redundant and err2 < active_set2 and q_clip.tobytes() != q_next.tobytes():
            q_clip = q - _frozen_step(q_next, robot, jac, e, identity, pull, err2)
            minimum(maximum(q_clip, lower, out=q_clip), upper, out=q_clip)
        q = q_clip

    best_q = best_q.copy()
    best_q.setflags(write=False)
    translation = best_pose.translation
    rotation = log3(best_pose.rotation)
    return IKResult(
        q=best_q,
        success=best_err2 <= tol2,
        iterations=steps,
        error=math.sqrt(best_err2),
        position_error=math.sqrt(translation.dot(translation)),
        rotation_error=math.sqrt(rotation.dot(rotation)),
        restarts=restarts,
    )


__all__ = ["IKResult", "numeric"]
