r"""The joint command of a seven-axis arm, its redundancy chosen once per cycle.

A seven-axis arm reaches a tool pose along a one-parameter self-motion: the
closed form of :func:`workbench.ik.get_solver` takes that parameter
(SRS arms: the arm angle ψ; Franka: q7) besides the pose. The online planner
(:class:`~workbench.planning.OnlinePlanner`) asks :class:`RedundancyTracker`
for each cycle's joint command, which moves the parameter v by a policy:

* ``"keep"``: v stays constant unless it must move: when the configuration it
  gives comes within :data:`KEEP_LIMIT_MARGIN` of a joint limit, it moves
  towards a larger limit margin, the faster the nearer the limit (rate zero at
  the margin, ``max_rate`` at the limit);
* ``"limit_margin"``: v moves towards the largest joint-limit margin
  (:func:`compute_limit_score`, a smooth minimum of the margins);
* ``"manipulability"``: towards the largest manipulability
  :math:`\sqrt{\det J J^T}` (6 × 7 J), switching to the limit margin while a
  joint is within :data:`KEEP_LIMIT_MARGIN` of its limit.

A move is one Newton step on the criterion h(v) from its values at v and
v ± :data:`PROBE_STEP` (the full step where h is concave, else the largest
step uphill), bounded so that v moves at most ``max_rate`` [rad/s] and its
rate changes by at most ``max_rate`` per :data:`RATE_RAMP_TIME`; the command is
the closed form at the new value (the pose met exactly, the branch kept).
Between cycles the joints then move by the pose's own motion plus a
self-motion :math:`\dot v\, \partial q/\partial v`, which spans the null
space of J: :math:`\dot v` follows :math:`\partial h/\partial v = \nabla_q h
\cdot \partial q/\partial v`, so this is the projected gradient
:math:`(I - J^+J)\nabla_q h` up to a positive factor.

**Near a singularity of the closed form** the command is the differential
one instead (:meth:`RedundancyTracker.track`): where the closed form at the
kept (or moved) value would move a joint faster than :data:`FAST_SHARE` of
its speed limit, or where a joint's :math:`|\partial q/\partial v|` exceeds
:data:`SINGULAR_GAIN` (a wrist or shoulder singularity of the 6 × 6 map at a
constant parameter, the arm angle's algorithmic singularity, q7 turning back
where the Panda's q2 = 0). It is the damped-least-squares step with a
null-space term, :math:`q + T\,(J^\# \dot x + (I - J^\# J) z)` (J 6 × 7,
:func:`workbench.ik.solve_null_space_velocity`; z the gradient of the
criterion: of the limit score while a joint is near a limit or the policy is
``"limit_margin"``, else of the manipulability
(:func:`compute_manipulability_gradient`) under ``"manipulability"``, zero
under ``"keep"``), put exactly on the pose by Gauss–Newton steps; v becomes
its parameter.
Near those singularities the least joint motion does not spin the joints
that the closed form at a constant parameter would spin; a Franka arm that
keeps q7 would otherwise turn the tool about its axis with the other six
joints. The branch label may then change (continuously, where the path
crosses the singular configuration).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.ik import (
    DLS_EPSILON,
    DLS_LAMBDA_MAX,
    Solver,
    compute_limit_margin,
    compute_tool_poses,
    require_family,
    solve_null_space_velocity,
)
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_LOCAL = pin.ReferenceFrame.LOCAL

#: The policies of :class:`RedundancyTracker` (``OnlinePlanner(redundancy=...)``).
REDUNDANCY_POLICIES = ("keep", "limit_margin", "manipulability")

#: A joint this near [rad] one of its limits makes every policy move the
#: parameter towards a larger limit margin.
KEEP_LIMIT_MARGIN = 0.15

#: Default largest rate [rad/s] of the redundancy parameter (policy moves).
DEFAULT_MAX_REDUNDANCY_RATE = 0.5

#: Step [rad] of the parameter for the slope and curvature of a criterion.
PROBE_STEP = 1e-3

#: Time [s] in which the parameter's rate may go from 0 to ``max_rate``.
RATE_RAMP_TIME = 0.2

#: Share of its speed limit beyond which a joint's step under the closed form
#: makes the command the differential one.
FAST_SHARE = 0.5

#: Largest |∂q/∂v| [rad/rad] of a joint at which the closed form is used; the
#: command is the differential one beyond.
SINGULAR_GAIN = 8.0

#: Sharpness [1/rad] of the soft minimum in :func:`compute_limit_score`.
LIMIT_SHARPNESS = 20.0

#: Gauss–Newton steps of the differential command stop below this pose error
#: [m, rad] (or after :data:`MAX_POSE_STEPS`).
POSE_TOL = 1e-13

#: Largest number of Gauss–Newton steps of the differential command.
MAX_POSE_STEPS = 4

#: Parameter steps below this [rad] are not taken (the kept value is exact).
MIN_STEP = 1e-12


def _limit_weights(
    q: FloatArray, lower: FloatArray, upper: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Soft minima (...,) of the 2n margins of q (..., n), their weights (..., 2n)."""
    margins = np.concatenate([q - lower, upper - q], axis=-1)
    low = margins.min(axis=-1, keepdims=True)  # factored out: no overflow
    weights = np.exp(-LIMIT_SHARPNESS * (margins - low))
    total = weights.sum(axis=-1, keepdims=True)
    score = low - np.log(total) / LIMIT_SHARPNESS
    return score[..., 0], weights / total


def compute_limit_score(
    q: FloatArray, lower: FloatArray, upper: FloatArray
) -> float | FloatArray:
    r"""Smooth joint-limit margin [rad]: the soft minimum of the 2n margins.

    :math:`-\frac{1}{\beta}\log\sum_j (e^{-\beta (q_j - l_j)} + e^{-\beta (u_j -
    q_j)})` with :math:`\beta` = :data:`LIMIT_SHARPNESS`: at most the smallest
    margin, at least it minus :math:`\log(2n)/\beta` (0.13 rad for 7 joints),
    and smooth, so that steps along it do not chatter where two joints'
    margins cross.

    Args:
        q: Configuration (n,) [rad], or (N, n).
        lower: Lower joint limits (n,) [rad].
        upper: Upper joint limits (n,) [rad].

    Returns:
        A float, or (N,).
    """
    score = _limit_weights(q, lower, upper)[0]
    return float(score) if score.ndim == 0 else score


def compute_limit_gradient(
    q: FloatArray, lower: FloatArray, upper: FloatArray
) -> FloatArray:
    """Gradient (n,) [rad/rad] of :func:`compute_limit_score` with respect to q.

    The softmax weights of the lower margins less those of the upper ones
    (its 1-norm is at most 1).

    Args:
        q: Configuration (n,) [rad].
        lower: Lower joint limits (n,) [rad].
        upper: Upper joint limits (n,) [rad].
    """
    weights = _limit_weights(q, lower, upper)[1]
    return weights[: len(q)] - weights[len(q) :]


def compute_manipulability_gradient(
    robot: Robot, q: FloatArray
) -> tuple[float, FloatArray]:
    r"""Manipulability :math:`w = \sqrt{\det J J^T}` and its gradient (nv,).

    With the tool Jacobian J in the tool frame (LOCAL; w is the same in any
    frame at the tool origin), :math:`\partial w/\partial q_k = w\,
    \mathrm{tr}(J^+ \partial J/\partial q_k)`, and the columns of a serial
    chain's body Jacobian move with the later joints only, by the Lie bracket
    of twists: :math:`\partial J_i/\partial q_k = [J_i, J_k]` for i < k, 0
    otherwise, :math:`[(v_i, \omega_i), (v_k, \omega_k)] = (\omega_i \times
    v_k - \omega_k \times v_i,\ \omega_i \times \omega_k)`.

    Args:
        robot: A serial arm of revolute joints with at least six of them.
        q: Configuration (nq,) [rad], where J has full rank 6.

    Returns:
        ``(w, gradient)``: w [m³ for revolute joints] and (nv,) [per rad].
    """
    jacobian = pin.computeFrameJacobian(
        robot.model, robot.data, q, robot.tool_frame_id, _LOCAL
    )
    linear, angular = jacobian[:3].T, jacobian[3:].T  # (nv, 3)
    gram = jacobian @ jacobian.T
    w = math.sqrt(max(float(np.linalg.det(gram)), 0.0))
    pseudo_inverse = np.linalg.solve(gram, jacobian).T  # (nv, 6)
    brackets = np.concatenate(
        [
            np.cross(angular[:, None], linear[None, :])
            - np.cross(angular[None, :], linear[:, None]),
            np.cross(angular[:, None], angular[None, :]),
        ],
        axis=2,
    )  # (nv, nv, 6): [J_i, J_k]
    later = np.triu(np.ones((len(linear), len(linear))), 1)  # i < k
    gradient = w * np.einsum("ik,ia,ika->k", later, pseudo_inverse, brackets)
    return w, gradient


def check_policy(policy: str) -> str:
    """The policy, checked against :data:`REDUNDANCY_POLICIES`.

    Raises:
        InputError: If it is not one of them.
    """
    if policy not in REDUNDANCY_POLICIES:
        raise InputError(
            f"unknown redundancy policy {policy!r}; use one of "
            f"{', '.join(REDUNDANCY_POLICIES)}"
        )
    return policy


class RedundancyTracker:
    """Each cycle's joint command of a seven-axis arm, the parameter by a policy.

    Args:
        robot: The arm (joint limits, speed limits, Jacobian).
        solver: Its closed form, ``workbench.ik.get_solver(robot)``.
        policy: One of :data:`REDUNDANCY_POLICIES`.
        period: Planning period [s], > 0.
        max_rate: Largest rate of the parameter's policy moves [rad/s], > 0.
        q_start: The first configuration (7,) [rad]; its parameter is the
            first value.

    Attributes:
        value: The parameter of the last command [rad] (ψ or q7).
        differential: True if the last command was the differential one.
    """

    def __init__(
        self,
        robot: Robot,
        solver: Solver,
        policy: str,
        period: float,
        max_rate: float,
        q_start: FloatArray,
    ) -> None:
        self.robot = robot
        self.solver = solver
        self.policy = check_policy(policy)
        self._lower, self._upper = robot.lower, robot.upper
        if solver.parameter_range is None:
            raise InputError(f"robot {robot.name!r} has no redundancy parameter")
        self._range = solver.parameter_range
        # the arm angle is taken mod 2π; q7 is a joint value with limits
        self._periodic = require_family(robot).parameter_periodic
        self._period = period
        self._max_rate = max_rate
        self._max_step = max_rate * period
        self._max_step_change = self._max_step * period / RATE_RAMP_TIME
        self._fast_step = FAST_SHARE * robot.velocity_limit * period
        self._zero = np.zeros(robot.nv)
        self.reset(q_start)

    def reset(self, q: FloatArray) -> None:
        """Start again at configuration ``q`` (7,) [rad]: its parameter, at rest."""
        self.value = float(self.solver.parameter_of(q))
        self.differential = False
        self._last_step = 0.0  # the parameter's step at the last cycle [rad]

    def track(
        self,
        pose: FloatArray,
        twist: FloatArray,
        q_last: FloatArray,
        q_predicted: FloatArray,
        branch: int,
        max_step2: float,
    ) -> tuple[FloatArray, int, bool]:
        """The joint command of one cycle; moves :attr:`value` by the policy.

        Args:
            pose: (4, 4) tool frame in the robot's base frame [m].
            twist: (6,) the tool frame's commanded twist [m/s, rad/s], linear
                first, base axes.
            q_last: (7,) the last cycle's command [rad].
            q_predicted: (7,) configuration predicted for this cycle [rad].
            branch: Branch index of the last command.
            max_step2: Largest squared joint step [rad²] that keeps the branch
                (see ``Solver.track``).

        Returns:
            ``(q (7,), branch index, within limits)``.

        Raises:
            UnreachableError: If the pose is out of reach.
        """
        value, last_step, self._last_step = self.value, self._last_step, 0.0
        self.differential = False
        kept = self.solver.try_track(
            pose, q_predicted, branch, max_step2, redundancy=value
        )
        if kept is None or self._too_fast(kept[0], q_last):
            return self._differential_command(pose, twist, q_last, branch)
        q0, index, _ = kept
        margin = compute_limit_margin(q0, self._lower, self._upper)
        near = margin < KEEP_LIMIT_MARGIN
        if self.policy == "keep" and not near:
            return kept
        low = self._shift(value, -PROBE_STEP)
        high = self._shift(value, PROBE_STEP)
        below = self.solver.try_track(pose, q0, index, max_step2, redundancy=low)
        above = self.solver.try_track(pose, q0, index, max_step2, redundancy=high)
        if below is None or above is None or below[1] != index or above[1] != index:
            return self._differential_command(pose, twist, q_last, index)
        derivative = (above[0] - below[0]) / self._span(low, high)  # ∂q/∂v
        if float(np.abs(derivative).max()) > SINGULAR_GAIN:
            return self._differential_command(pose, twist, q_last, index)
        q_all = np.stack([below[0], q0, above[0]])
        step = self._policy_step(q_all, margin, last_step)
        if abs(step) < MIN_STEP:
            return kept
        moved = self.solver.try_track(
            pose, q0, index, max_step2, redundancy=self._shift(value, step)
        )
        if moved is None or moved[1] != index or self._too_fast(moved[0], q_last):
            return self._differential_command(pose, twist, q_last, index)
        self.value, self._last_step = self._shift(value, step), step
        return moved

    # -- helpers ----------------------------------------------------------------
    def _too_fast(self, q: FloatArray, q_last: FloatArray) -> bool:
        """True if a joint's step exceeds :data:`FAST_SHARE` of its speed limit."""
        return bool((np.abs(q - q_last) > self._fast_step).any())

    def _policy_step(self, q_all: FloatArray, margin: float, last_step: float) -> float:
        """The policy's step [rad] of the parameter.

        Args:
            q_all: (3, 7) configurations at v − δ, v, v + δ [rad].
            margin: Limit margin of ``q_all[1]`` [rad].
            last_step: The parameter's step at the last cycle [rad].
        """
        near = margin < KEEP_LIMIT_MARGIN
        bound = self._max_step
        if self.policy == "keep":  # from 0 at the margin to max_rate at a limit
            bound *= min(1.0, (KEEP_LIMIT_MARGIN - margin) / KEEP_LIMIT_MARGIN)
        h = self._criterion("limit_margin" if near else self.policy, q_all)
        slope = (h[2] - h[0]) / (2.0 * PROBE_STEP)
        curvature = (h[2] - 2.0 * h[1] + h[0]) / (PROBE_STEP * PROBE_STEP)
        newton = -slope / curvature if curvature < 0.0 else math.copysign(bound, slope)
        low = max(-bound, last_step - self._max_step_change)
        high = min(bound, last_step + self._max_step_change)
        return max(min(low, 0.0), min(max(high, 0.0), newton))

    def _differential_command(
        self, pose: FloatArray, twist: FloatArray, q_last: FloatArray, index: int
    ) -> tuple[FloatArray, int, bool]:
        """The command near a singularity of the closed form (module docstring).

        ``q_last + period · (J# twist + (I − J# J) z)``, then Gauss–Newton
        steps ``q += J⁺ e`` on the pose error ``e`` until it is below
        :data:`POSE_TOL`; :attr:`value` becomes its parameter and the branch
        the closed form's branch nearest it at that value. Without
        convergence in :data:`MAX_POSE_STEPS` steps: the closed form at the
        last value (which raises if the pose is out of reach).

        Args:
            pose: (4, 4) target pose of the tool frame, base frame [m].
            twist: (6,) commanded twist [m/s, rad/s], base axes.
            q_last: (7,) last command [rad].
            index: Branch index of the last command.

        Returns:
            ``(q, branch index, within limits)``.

        Raises:
            UnreachableError: If the pose is out of reach.
        """
        self.differential = True
        robot = self.robot
        margin = compute_limit_margin(q_last, self._lower, self._upper)
        null = self._zero
        if margin < KEEP_LIMIT_MARGIN or self.policy == "limit_margin":
            ramp = 1.0
            if self.policy != "limit_margin":
                ramp = min(1.0, (KEEP_LIMIT_MARGIN - margin) / KEEP_LIMIT_MARGIN)
            gradient = compute_limit_gradient(q_last, self._lower, self._upper)
            null = self._max_rate * ramp * gradient
        elif self.policy == "manipulability":  # its direction, at max_rate
            gradient = compute_manipulability_gradient(robot, q_last)[1]
            size = float(np.linalg.norm(gradient))
            if size > 0.0:
                null = (self._max_rate / size) * gradient
        q = q_last + self._period * self._velocity(q_last, twist, null, _LWA)
        target = pin.SE3(pose)
        for _ in range(MAX_POSE_STEPS + 1):
            error = pin.log6(robot.fk(q).actInv(target)).vector  # tool axes
            if np.abs(error).max() <= POSE_TOL:
                break
            q = q + self._velocity(q, error, self._zero, _LOCAL, damped=False)
        else:  # no convergence: out of reach (the closed form's error says why)
            return self.solver.track(pose, q_last, index, 0.0, redundancy=self.value)
        value = float(self.solver.parameter_of(q))
        found = self.solver.try_track(pose, q, index, 0.0, redundancy=value)  # nearest
        if found is not None:
            index = found[1]
        within = bool(((q >= self._lower) & (q <= self._upper)).all())
        self._last_step = value - self.value
        if self._periodic:
            self._last_step = math.remainder(self._last_step, 2.0 * math.pi)
        self.value = value
        return q, index, within

    def _velocity(
        self,
        q: FloatArray,
        twist: FloatArray,
        null: FloatArray,
        frame: pin.ReferenceFrame,
        *,
        damped: bool = True,
    ) -> FloatArray:
        """``J# twist + (I − J# J) null`` at ``q`` (7,) [rad/s], J in ``frame``.

        ``damped=False``: the pseudo-inverse J⁺ (no damping), for the
        Gauss–Newton steps on a pose error, which the damping would slow to
        a crawl near a singularity of J.
        """
        robot = self.robot
        jacobian = pin.computeFrameJacobian(
            robot.model, robot.data, q, robot.tool_frame_id, frame
        )
        damping = DLS_LAMBDA_MAX if damped else 0.0
        qd, _ = solve_null_space_velocity(jacobian, twist, DLS_EPSILON, damping, null)
        return qd

    def _shift(self, value: float, step: float) -> float:
        """``value + step`` within the parameter's range (ψ wraps, q7 clips)."""
        moved = value + step
        if self._periodic:
            moved = math.remainder(moved, 2.0 * math.pi)
            return math.pi if moved == -math.pi else moved
        low, high = self._range
        return min(high, max(low, moved))

    def _span(self, low: float, high: float) -> float:
        """``high - low`` along the parameter (across ±π for ψ), > 0."""
        span = high - low
        if self._periodic:
            span = math.remainder(span, 2.0 * math.pi)
        return span if span > 0.0 else PROBE_STEP

    def _criterion(self, name: str, q_all: FloatArray) -> FloatArray:
        """The criterion at each row of ``q_all`` (3, 7)."""
        if name == "manipulability":
            return compute_tool_poses(self.robot, q_all)[2]
        return _limit_weights(q_all, self._lower, self._upper)[0]


__all__ = [
    "DEFAULT_MAX_REDUNDANCY_RATE",
    "FAST_SHARE",
    "KEEP_LIMIT_MARGIN",
    "LIMIT_SHARPNESS",
    "MAX_POSE_STEPS",
    "MIN_STEP",
    "POSE_TOL",
    "PROBE_STEP",
    "RATE_RAMP_TIME",
    "REDUNDANCY_POLICIES",
    "SINGULAR_GAIN",
    "RedundancyTracker",
    "check_policy",
    "compute_limit_gradient",
    "compute_limit_margin",
    "compute_limit_score",
    "compute_manipulability_gradient",
]
