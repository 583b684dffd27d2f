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

First guess: ``q0`` when given. Otherwise, for vector-space models (q ~ v),
the nearest by tool pose of ``_SEED_COUNT`` fixed candidates, mid-range and
configurations drawn (fixed seed) around it within ``_SEED_SPREAD`` of the
half-range; their tool poses are computed once per robot, and one
matrix-vector product scores them all (distance: squared position gap plus
``_SEED_ROTATION_WEIGHT`` times :math:`\|R_c - R\|_F^2`). On random
reachable targets this saves about 3 of the ~10 steps taken from mid-range.
Models with multi-coordinate joints start from mid-range (neutral).

Restarts: when the error has not fallen by 10 % for ``_STALL_STEPS`` steps,
or a run exceeds ``_RUN_STEPS``, the solver restarts from a configuration
drawn uniformly within the limits (numpy Generator, seeded), until
``max_iterations`` steps in all; no restart begins after ``time_budget``
seconds.

Speed: the hot loop calls Pinocchio and eigenpy directly on ``robot.model``
/ ``robot.data`` with no per-step validation; what depends on the robot only
(limits, masks, decompositions, candidates) is cached per robot object and
rebuilt if its model, data, limits or tool frame are replaced.

Reference: T. Sugihara, "Solvability-unconcerned inverse kinematics by the
Levenberg–Marquardt method", IEEE Trans. Robotics 27(5), 2011.
"""

from __future__ import annotations

import math
import numbers
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass

import eigenpy
import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.poses import as_se3

FloatArray = npt.NDArray[np.float64]

_DAMPING_GAIN = 3e-2
"""mu in lambda = mu |e|^2 + lambda_0 [1/m^2 ~ 1/rad^2 scale]."""

_DAMPING_FLOOR = 1e-9
"""lambda_0: keeps J J^T + lambda I positive definite at singularities."""

_STALL_STEPS = 4
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

_SEED_COUNT = 1024
"""Candidate first guesses (mid-range included) when no ``q0`` is given."""

_SEED_SPREAD = 0.65
"""Candidates lie within this fraction of the half-range (<= pi) of mid-range."""

_SEED_ROTATION_WEIGHT = 0.05
"""Weight of the rotation gap against the position gap [m^2] in choosing one."""

_SEED_RNG = 20240
"""Fixed seed of the candidates: the first guess is the same in every process."""

_MAX_STEP2, _SINGULAR_STEP2 = _MAX_STEP**2, _SINGULAR_STEP**2
_NULL_OFF_ERROR2, _ACTIVE_SET_ERROR2 = _NULL_OFF_ERROR**2, _ACTIVE_SET_ERROR**2

# Module-level names for the hot loop.
_joint_jacobians = pin.computeJointJacobians
_frame_placement = pin.updateFramePlacement
_frame_jacobian = pin.getFrameJacobian
_log6 = pin.log6
_LOCAL = pin.ReferenceFrame.LOCAL
_maximum, _minimum, _hypot = np.maximum, np.minimum, math.hypot


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
            the candidate configuration nearest the target (see the module
            docstring), deterministic. Redundant arms are pulled towards
            ``q0``, by default towards the middle of the limits (0 where a
            joint is unlimited).
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
    # Fast path for the usual option types; anything else gets the full check.
    if not (
        tol.__class__ is float
        and 0.0 < tol < math.inf
        and max_iterations.__class__ is int
        and max_iterations >= 1
        and (time_budget.__class__ is float or time_budget.__class__ is int)
        and time_budget > 0.0
        and (rng is None or (rng.__class__ is int and rng >= 0))
    ):
        _check_options(tol, max_iterations, time_budget, rng)
    setup = _setup(robot)
    if q0 is None:
        q_ref = setup.mid
        q_start = setup.first_guess(target) if setup.vector_space else None
    else:
        q_start = None
        q_ref = robot.check_configuration(q0)
        q_ref = np.minimum(np.maximum(q_ref, setup.lower), setup.upper)
        if not setup.vector_space:
            q_ref = pin.normalize(setup.model, q_ref)
    deadline = time.perf_counter() + time_budget
    return _solve(setup, target, q_ref, q_start, tol, max_iterations, deadline, rng)


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


class _Setup:
    """What the solver derives from a robot once: limits, masks, scratch space.

    Cached per robot (see :func:`_setup`); rebuilt when the robot's model,
    data, limits or tool frame are other objects than when it was built.
    """

    __slots__ = (
        "constants",
        "data",
        "frame_id",
        "identity",
        "low",
        "lower",
        "mid",
        "model",
        "seed_features",
        "seed_q",
        "span",
        "upper",
        "vector_space",
    )

    def __init__(self, robot: Robot) -> None:
        model, data = robot.model, robot.data
        lower, upper = robot.lower, robot.upper
        self.model, self.data, self.frame_id = model, data, robot.tool_frame_id
        self.lower, self.upper = lower, upper
        nv = model.nv
        self.vector_space = vector_space = model.nq == nv  # then q (+) v is q + v
        self.identity = np.eye(min(nv, 6))
        wide = upper - lower >= 2.0 * math.pi
        wide_joints = vector_space and bool(np.count_nonzero(wide))
        mid = _mid_configuration(model, lower, upper)
        mid.setflags(write=False)
        self.mid = mid
        self.low = np.where(np.isfinite(lower), lower, -_UNBOUNDED_SPAN)
        self.span = np.where(np.isfinite(upper), upper, _UNBOUNDED_SPAN) - self.low
        self.seed_q = self.seed_features = None  # built on first use
        # Decompositions reused across steps and solves.
        lu, llt = eigenpy.PartialPivLU(6), eigenpy.LLT(6)
        # What the solver unpacks in one go (see _solve).
        self.constants = (
            model,
            data,
            self.frame_id,
            lower,
            upper,
            nv,
            vector_space,
            nv == 6,  # square
            nv > 6,  # redundant
            self.identity,
            wide,
            wide_joints,
            # plain: q (+) v = q + v and limits are only clipped
            vector_space and not wide_joints and nv <= 6,
            lu.compute,
            lu.solve,
            llt.compute,
            llt.solve,
        )

    def first_guess(self, target: pin.SE3) -> FloatArray:
        """The candidate whose tool pose is nearest ``target`` (a copy), (nq,)."""
        if self.seed_features is None:
            self._build_seeds()
        scores = target.homogeneous.ravel().dot(self.seed_features)
        return self.seed_q[int(scores.argmin())].copy()

    def _build_seeds(self) -> None:
        model, data, lower, upper = self.model, self.data, self.lower, self.upper
        half = np.minimum(0.5 * self.span, _UNBOUNDED_SPAN)
        draws = np.random.default_rng(_SEED_RNG).uniform(
            -1.0, 1.0, (_SEED_COUNT - 1, model.nq)
        )
        seed_q = np.vstack((self.mid, self.mid + _SEED_SPREAD * half * draws))
        np.minimum(np.maximum(seed_q, lower, out=seed_q), upper, out=seed_q)
        # Score = features . vec(target homogeneous matrix), row-major:
        # -2 w R_c[i, j] at (i, j), -2 p_c[i] at (i, 3), |p_c|^2 at (3, 3).
        features = np.zeros((_SEED_COUNT, 4, 4))
        for row, q in zip(features, seed_q, strict=True):
            pin.forwardKinematics(model, data, q)
            pose = pin.updateFramePlacement(model, data, self.frame_id)
            position = pose.translation
            row[:3, :3] = (-2.0 * _SEED_ROTATION_WEIGHT) * pose.rotation
            row[:3, 3] = -2.0 * position
            row[3, 3] = position.dot(position)
        seed_q.setflags(write=False)
        self.seed_q = seed_q
        # (16, count), so that the product runs along contiguous rows.
        self.seed_features = np.ascontiguousarray(features.reshape(-1, 16).T)

    def matches(self, robot: Robot) -> bool:
        return (
            self.model is robot.model
            and self.data is robot.data
            and self.lower is robot.lower
            and self.upper is robot.upper
            and self.frame_id == robot.tool_frame_id
        )


_SETUPS: weakref.WeakKeyDictionary[Robot, _Setup] = weakref.WeakKeyDictionary()


def _setup(robot: Robot) -> _Setup:
    """The cached :class:`_Setup` of ``robot``, (re)built when stale."""
    setup = _SETUPS.get(robot)
    if setup is None or not setup.matches(robot):
        setup = _SETUPS[robot] = _Setup(robot)
    return setup


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
    setup: _Setup, rng: np.random.Generator | int | None
) -> Callable[[], FloatArray]:
    """Draw configurations uniformly within the limits (+-pi where unlimited)."""
    if not isinstance(rng, np.random.Generator):
        rng = np.random.default_rng(0 if rng is None else int(rng))
    model, low, span = setup.model, setup.low, setup.span
    if setup.vector_space:
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
    setup: _Setup,
    jac: FloatArray,
    e: FloatArray,
    pull: FloatArray | None,
    err2: float,
) -> FloatArray:
    """Damped step (to subtract) with the joints ``q_next`` pushes out frozen.

    Their Jacobian columns are zeroed, so that the other joints of a redundant
    arm take over the motion they cannot make; the step of a zeroed column
    (and of its zeroed pull) is exactly 0.
    """
    free = (q_next >= setup.lower) & (q_next <= setup.upper)
    jac = jac * free
    if pull is not None:
        pull = pull * free
    damping = _DAMPING_GAIN * err2 + _DAMPING_FLOOR
    return _damped_step(jac, e, damping, setup.identity, pull)


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
    setup: _Setup,
    target: pin.SE3,
    q_ref: FloatArray,
    q_start: FloatArray | None,
    tol: float,
    max_iterations: int,
    deadline: float,
    rng: np.random.Generator | int | None,
) -> IKResult:
    """Iterate from ``q_start`` (else ``q_ref``); pull redundant arms to ``q_ref``."""
    (
        model,
        data,
        frame_id,
        lower,
        upper,
        nv,
        vector_space,
        square,
        redundant,
        identity,
        wide,
        wide_joints,
        plain,
        lu_compute,
        lu_solve,
        llt_compute,
        llt_solve,
    ) = setup.constants
    act_inv = target.actInv
    tol2 = tol * tol
    wrap = None  # full-turn revolute joints, found on first use
    sample = None

    q = q_ref.copy() if q_start is None else q_start
    best_q, best_err2, best_pose, best_e = q, math.inf, None, None
    # Steps are counted over all runs; run_start and stall_at are step counts
    # (start of the run, last 10 % fall of its error below stall_level).
    steps = restarts = run_start = stall_at = 0
    stall_level = math.inf
    while True:
        # computeJointJacobians also places the joints (forward kinematics):
        # the frame Jacobian is then read off without another pass.
        _joint_jacobians(model, data, q)
        pose = act_inv(_frame_placement(model, data, frame_id))
        e = _log6(pose).vector
        err2 = _hypot(*e.tolist()) ** 2  # a float: cheaper than e.dot(e) here
        if err2 < best_err2:
            best_q, best_err2, best_pose, best_e = q, err2, pose, e
            if err2 <= tol2:
                break
        if err2 < stall_level:
            stall_level, stall_at = _STALL_RATIO * err2, steps
        if steps >= max_iterations:
            break
        if steps - stall_at >= _STALL_STEPS or steps - run_start >= _RUN_STEPS:
            # The clock only stops restarts: a run that converges is never
            # cut short, e.g. by the process being descheduled.
            if time.perf_counter() > deadline:
                break
            if sample is None:
                sample = _sampler(setup, rng)
            q = sample()
            restarts += 1
            run_start = stall_at = steps
            stall_level = math.inf
            continue
        steps += 1

        # The step dq is subtracted: q <- q (-) dq.
        jac = _frame_jacobian(model, data, frame_id, _LOCAL)
        dq = None
        if square:
            lu_compute(jac)
            dq = lu_solve(e)
            step2 = _hypot(*dq.tolist()) ** 2
            if not step2 <= _MAX_STEP2:  # long, near-singular or NaN
                if step2 < _SINGULAR_STEP2:
                    dq *= _MAX_STEP / math.sqrt(step2)
                else:  # near-singular J (or NaN): damped step below
                    dq = None
        if dq is None:
            pull = None
            damping = _DAMPING_GAIN * err2 + _DAMPING_FLOOR
            if nv < 6:
                dq = _damped_step(jac, e, damping, identity, None)
            else:  # inlined _damped_step: the common path of redundant arms
                normal = jac.dot(jac.T)
                normal += damping * identity
                llt_compute(normal)
                if redundant and err2 > _NULL_OFF_ERROR2:
                    if vector_space:
                        pull = q_ref - q
                        pull *= _NULL_GAIN
                    else:
                        pull = _NULL_GAIN * pin.difference(model, q, q_ref)
                    dq = llt_solve(e + jac.dot(pull)).dot(jac) - pull  # J^T y - z
                else:
                    dq = llt_solve(e).dot(jac)  # J^T y
        if plain:  # vector space, clipping only
            q_next = q - dq
            q = _minimum(_maximum(q_next, lower, out=q_next), upper, out=q_next)
            continue
        if not vector_space:
            q = pin.integrate(model, q, -dq)
            _minimum(_maximum(q, lower, out=q), upper, out=q)
            continue
        q_next = q - dq
        q_clip = _minimum(_maximum(q_next, lower), upper)
        if wide_joints and q_clip.tobytes() != q_next.tobytes():
            # Full-turn revolute joints come back in at the other end.
            if wrap is None:
                wrap = _wrap_mask(jac, wide)
            q_next[wrap & (q_next > upper)] -= 2.0 * math.pi
            q_next[wrap & (q_next < lower)] += 2.0 * math.pi
            q_clip = _minimum(_maximum(q_next, lower), upper)
        if (
            redundant
            and err2 < _ACTIVE_SET_ERROR2
            and q_clip.tobytes() != q_next.tobytes()
        ):
            q_clip = q - _frozen_step(q_next, setup, jac, e, pull, err2)
            _minimum(_maximum(q_clip, lower, out=q_clip), upper, out=q_clip)
        q = q_clip

    # Every q above is a new array, never written to once evaluated.
    best_q.setflags(write=False)
    # The angular part of log6 is log3 of the rotation.
    return IKResult(
        q=best_q,
        success=best_err2 <= tol2,
        iterations=steps,
        error=math.sqrt(best_err2),
        position_error=math.hypot(*best_pose.translation.tolist()),
        rotation_error=math.hypot(*best_e[3:].tolist()),
        restarts=restarts,
    )


__all__ = ["IKResult", "numeric"]
