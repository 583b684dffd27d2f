r"""Online, multi-rate Cartesian trajectory planner (Kang 2007, §5), 6R and 7R arms.

Once per planning cycle, :meth:`OnlinePlanner.step` runs Kang's chain:

1. Cartesian motion command of the tool tip (world frame) from the active
   :class:`~workbench.planning.motion_primitives.MotionPrimitive`;
2. wrist-centre (robot tool frame) command, then the robot base frame;
3. closed-form inverse kinematics, the branch nearest the configuration
   extrapolated from the last two commands (continuity, Kang's θ4 flip rule,
   and a smooth θ4/θ6 split at the wrist singularity itself): joint position
   command;
4. inverse velocity kinematics: joint velocity command. Outside the singular
   region it is the exact :math:`J^{-1}\dot x`; inside it the damped least
   squares of :func:`workbench.ik.dls_inverse` (Kang: "the damped least-squares
   Jacobian inverse is adopted instead of the Jacobian inverse in the
   neighborhood of kinematic singularities"), damped about the rate of the
   joint position commands rather than about zero, so that position and
   velocity commands agree in the directions the damping suppresses (the
   servo interpolation would otherwise ripple).

On a seven-axis arm (``iiwa14``, ``panda``) step 3 is the redundant closed
form (``workbench.ik.get_solver``) at a value of the redundancy
parameter (SRS: the arm angle ψ; Franka: q7) that the ``redundancy`` policy
keeps or moves at a bounded rate (:mod:`workbench.planning.redundancy_policy`;
the branch never changes by that choice), and step 4 is
:math:`\dot q = J^\# \dot x + (I - J^\# J)\dot q_r` for the 6 × 7 J
(:func:`workbench.ik.solve_null_space_velocity`), :math:`\dot q_r` the rate
of the joint position commands: outside the singular region the
minimum-norm joint velocity plus the self-motion of the commands (the
parameter's move along the criterion's gradient and the null-space part of
the closed form's own motion), inside it the DLS solution damped about that
rate.

Between cycles the caller may report what the tool touches
(:meth:`~OnlinePlanner.notify`), stop the tool (:meth:`~OnlinePlanner.stop`)
or give a new goal (:meth:`~OnlinePlanner.set_goal`): the new motion is
planned from the state commanded at the last cycle, so position and velocity
stay continuous. The servo level interpolates the joint commands between
planning instants with cubic Hermite polynomials
(:func:`~workbench.planning.servo_interpolation.interpolate_servo`).
"""

from __future__ import annotations

import math
from collections import deque
from typing import NamedTuple

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError, JointLimitError
from workbench.ik import (
    DLS_EPSILON,
    DLS_LAMBDA_MAX,
    get_solver,
    select,
    solve_null_space_velocity,
    solve_velocity,
)
from workbench.model.robot import Robot
from workbench.planning._tracking import wrist_command
from workbench.planning.cartesian_paths import (
    ZERO_TOL,
    CartesianLimits,
    CartesianState,
)
from workbench.planning.motion_primitives import (
    Hold,
    MotionPrimitive,
    PointToPoint,
    Stop,
)
from workbench.planning.redundancy_policy import (
    DEFAULT_MAX_REDUNDANCY_RATE,
    RedundancyTracker,
    check_policy,
)
from workbench.validation import check_positive

FloatArray = npt.NDArray[np.float64]

#: Relative slack on the joint speed check (rounding of the inverse).
SPEED_RTOL = 1e-9

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


class PlannerSample(NamedTuple):
    """The commands of one planning cycle (immutable, a named tuple).

    Attributes:
        t: Time [s].
        position: Tool-tip position (3,) [m], world frame.
        velocity: Tool-tip velocity (3,) [m/s], world axes.
        rotation: Tool orientation (3, 3), world frame.
        angular_velocity: (3,) [rad/s], world axes.
        q: Joint position command (nq,) [rad].
        qd: Joint velocity command (nv,) [rad/s].
        branch: IK branch of ``q``, e.g. ``"right/elbow-up/no-flip"``.
        damped: True if the DLS inverse was used (singular region).
        replanned: True if a new motion was planned for this cycle: a
            primitive began or went on to its next stage, or a reaction to
            :meth:`OnlinePlanner.notify`, ``stop`` or ``set_goal`` since the
            last cycle.
        redundancy: The redundancy parameter of ``q`` [rad] on a seven-axis
            arm (ψ or q7, :attr:`OnlinePlanner.redundancy_parameter`); NaN on
            a six-axis arm.
    """

    t: float
    position: FloatArray
    velocity: FloatArray
    rotation: FloatArray
    angular_velocity: FloatArray
    q: FloatArray
    qd: FloatArray
    branch: str
    damped: bool
    replanned: bool = False
    redundancy: float = math.nan


def _rigid(value: pin.SE3 | None) -> tuple[FloatArray, FloatArray]:
    """Rotation and translation of a transform; None is the identity."""
    if value is None:
        return np.eye(3), np.zeros(3)
    if not isinstance(value, pin.SE3):
        raise InputError(f"expected a pinocchio.SE3, got {type(value).__name__}")
    return value.rotation.copy(), value.translation.copy()


def load_kernels() -> None:
    """Load the planner's kernels that do not call the closed-form IK.

    That is (on a first run: compiles) the joint-velocity solves and the wrist
    command. :class:`OnlinePlanner` calls it on
    construction, so that no planning cycle waits seconds for a compile (the
    damped solve is otherwise first needed in a singular region, possibly deep
    into a run). Apart from the closed form, so that a process can do this
    while another compiles that one (see ``workbench.demo.run``).
    """
    zero, eye = np.zeros(6), np.eye(3)
    solve_velocity(np.eye(6), zero, DLS_EPSILON, DLS_LAMBDA_MAX)  # the exact one
    solve_velocity(np.zeros((6, 6)), zero, DLS_EPSILON, DLS_LAMBDA_MAX)  # damped
    solve_null_space_velocity(
        np.zeros((6, 7)), zero, DLS_EPSILON, DLS_LAMBDA_MAX, np.zeros(7)
    )
    frames = np.vstack([eye, zero[:3], eye, zero[:3]])
    pose, twist = np.empty((4, 4)), np.empty(6)
    wrist_command(eye, zero[:3], zero[:3], zero[:3], frames, pose, twist)


class OnlinePlanner:
    """Kang's online planner: Cartesian command, IK with continuity, DLS rates.

    Args:
        robot: An arm with closed-form IK: OPW (``puma560-kang``, the KUKA
            and ABB models), UR-type (``ur5``), or a seven-axis SRS
            (``iiwa14``) or Franka (``panda``) arm.
        q_start: Initial configuration (nq,) [rad], within the limits.
        limits: Cartesian speed and acceleration bounds of the tool tip.
        planning_rate: Planning cycles per second [Hz], > 0.
        servo_rate: Servo samples per second [Hz], an integer multiple of
            ``planning_rate``.
        transform_tip_to_tool: Pose of the tool tip in the robot's tool frame
            (the wrist centre for the PUMA models, ``tool0`` for UR); identity
            if None.
        transform_base_to_world: Pose of the robot base in the world frame
            the motions are given in; identity if None.
        dls_epsilon: Size of the singular region (see ``workbench.ik``).
        dls_lambda_max: Damping at a singularity.
        check_speed: Raise if a joint velocity command exceeds its limit.
        redundancy: Seven-axis arms only: how the redundancy parameter moves,
            ``"keep"`` (the default: constant unless a joint nears a limit),
            ``"limit_margin"`` or ``"manipulability"``
            (:mod:`workbench.planning.redundancy_policy`).
        max_redundancy_rate: Seven-axis arms: largest rate of the parameter
            [rad/s], > 0.

    Raises:
        InputError: Bad rates, configuration, transforms or policy; a
            ``redundancy`` policy for a six-axis arm; a robot without
            closed-form IK (``UnsupportedRobotError``).
        JointLimitError: If ``q_start`` is outside the limits.
    """

    def __init__(
        self,
        robot: Robot,
        q_start: npt.ArrayLike,
        limits: CartesianLimits,
        *,
        planning_rate: float = 100.0,
        servo_rate: float = 1000.0,
        transform_tip_to_tool: pin.SE3 | None = None,
        transform_base_to_world: pin.SE3 | None = None,
        dls_epsilon: float = DLS_EPSILON,
        dls_lambda_max: float = DLS_LAMBDA_MAX,
        check_speed: bool = True,
        redundancy: str | None = None,
        max_redundancy_rate: float = DEFAULT_MAX_REDUNDANCY_RATE,
    ) -> None:
        for name, rate in (
            ("planning_rate", planning_rate),
            ("servo_rate", servo_rate),
        ):
            if not (isinstance(rate, float | int) and math.isfinite(rate) and rate > 0):
                raise InputError(f"{name} must be a finite number > 0, got {rate!r}")
        ratio = servo_rate / planning_rate
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise InputError(
                f"servo_rate ({servo_rate:g} Hz) must be an integer multiple of "
                f"planning_rate ({planning_rate:g} Hz)"
            )
        if not isinstance(limits, CartesianLimits):
            raise InputError("limits must be a CartesianLimits")
        self.robot = robot
        self.limits = limits
        self.planning_rate = float(planning_rate)
        self.servo_rate = float(servo_rate)
        self.period = 1.0 / self.planning_rate
        self.dls_epsilon = dls_epsilon
        self.dls_lambda_max = dls_lambda_max
        self.check_speed = check_speed
        check_positive(dls_epsilon, "epsilon", strict=True)  # as dls_inverse
        check_positive(dls_lambda_max, "lambda_max", strict=False)
        check_positive(max_redundancy_rate, "max_redundancy_rate", strict=True)
        # No cycle waits for a compile: the kernels are loaded here (or, on a
        # first run, compiled), the closed form by the solve below and the
        # branch choice by the first command at the end.
        load_kernels()
        tip = _rigid(transform_tip_to_tool)  # (rotation, translation)
        base = _rigid(transform_base_to_world)
        q0 = robot.check_configuration(q_start)
        self._check_position(q0, 0.0)
        self._q = q0
        self._q_before: FloatArray | None = None  # the command before self._q
        self._qd = np.zeros(robot.nv)
        self._cycle = 0
        self._frame_id = robot.tool_frame_id
        self._speed_limit = robot.velocity_limit * (1.0 + SPEED_RTOL)
        self._min_speed_limit = float(self._speed_limit.min())
        # squared joint step of two cycles at the speed limits (branch selection)
        self._max_step2 = float(np.sum((2.0 * self.period * robot.velocity_limit) ** 2))
        # the frames of _tracking.wrist_command
        self._frames = np.vstack([tip[0].T, -tip[1], base[0], base[1]])
        oMf = robot.fk(q0)
        self._tracker: RedundancyTracker | None = None
        if robot.nq == 7:  # a seven-axis arm, else UnsupportedRobotError
            solver = get_solver(robot)
            self._tracker = RedundancyTracker(
                robot,
                solver,
                check_policy("keep" if redundancy is None else redundancy),
                self.period,
                max_redundancy_rate,
                q0,
            )
            self._labels = solver.branches
            start = select(
                robot, oMf, q_near=q0, redundancy=self._tracker.value
            )  # the rule "nearest" at the policy's value
            self._branch = int(start.index or 0)
        else:
            if redundancy is not None:
                raise InputError(
                    f"robot {robot.name!r} has no redundancy (6 joints): the "
                    "redundancy policy is for seven-axis arms"
                )
            self._closed_form = get_solver(robot)  # fails early without one
            self._labels = self._closed_form.branches
            self._branch = int(select(robot, oMf, q_near=q0).index or 0)  # "nearest"
        p = oMf.translation + oMf.rotation @ tip[1]
        rotation = oMf.rotation @ tip[0]
        p, rotation = base[0] @ p + base[1], base[0] @ rotation
        zero = np.zeros(3)
        self._state = CartesianState(p, zero, rotation, zero)
        self._replanned = False  # by notify, stop or set_goal since the last step
        self._queue: deque[MotionPrimitive] = deque()
        self._active: MotionPrimitive = Hold()
        self._active.begin(self._state, 0.0, limits)
        self._command_joints(p, zero, rotation, zero)  # loads the branch choice
        if self._tracker is not None:  # that call is no cycle: back at q0
            self._tracker.reset(q0)

    # -- state ---------------------------------------------------------------
    @property
    def t(self) -> float:
        """Time [s] of the last planning cycle."""
        return self._cycle * self.period

    @property
    def cycle(self) -> int:
        """Number of planning cycles run."""
        return self._cycle

    @property
    def q(self) -> FloatArray:
        """Joint position command of the last cycle (nq,) [rad] (a copy)."""
        return self._q.copy()

    @property
    def state(self) -> CartesianState:
        """Tool-tip state commanded at the last cycle (world frame)."""
        return self._state

    @property
    def redundancy(self) -> float | None:
        """Redundancy parameter of the last command [rad]; None on a 6R arm."""
        return None if self._tracker is None else self._tracker.value

    @property
    def redundancy_parameter(self) -> str | None:
        """``"arm angle"`` (SRS) or ``"q7"`` (Franka); None on a 6R arm."""
        return None if self._tracker is None else self._tracker.solver.parameter

    @property
    def redundancy_policy(self) -> str | None:
        """The ``redundancy`` policy; None on a 6R arm."""
        return None if self._tracker is None else self._tracker.policy

    @property
    def active(self) -> MotionPrimitive:
        """The primitive being executed."""
        return self._active

    @property
    def done(self) -> bool:
        """True when every primitive has run and the tool holds at rest."""
        return isinstance(self._active, Hold) and not self._queue

    # -- commands ------------------------------------------------------------
    def append(self, *primitives: MotionPrimitive) -> None:
        """Queue primitives; each starts where the previous one ends."""
        for primitive in primitives:
            if not isinstance(primitive, MotionPrimitive):
                raise InputError(f"not a MotionPrimitive: {primitive!r}")
            self._queue.append(primitive)

    def notify(self, contact: str | None) -> str | None:
        """Tell the active primitive what the tool touches now.

        Returns:
            The event name if the primitive replanned, else None.
        """
        event = self._active.on_contact(contact, self.t, self._state, self.limits)
        self._replanned |= event is not None
        return event

    def stop(self) -> None:
        """Stop event: come to rest at full deceleration; the queue is cleared."""
        self._queue.clear()
        self._replace(Stop())

    def set_goal(self, position: npt.ArrayLike, rotation: npt.ArrayLike) -> None:
        """New goal: move there from the current moving state (the queue stays)."""
        self._replace(PointToPoint(position, rotation))

    def _replace(self, primitive: MotionPrimitive) -> None:
        primitive.begin(self._state, self.t, self.limits)
        self._active = primitive
        self._replanned = True

    def _next_primitive(self, state: CartesianState) -> MotionPrimitive:
        if self._queue:
            return self._queue.popleft()
        moving = max(math.hypot(*state.velocity), math.hypot(*state.angular_velocity))
        return Stop() if moving > ZERO_TOL else Hold()

    # -- the planning cycle --------------------------------------------------
    def step(self) -> PlannerSample:
        """Run one planning cycle and return its commands.

        Raises:
            JointLimitError: If a joint position (or, with ``check_speed``,
                velocity) command leaves its limit.
            UnreachableError: If the tool is commanded out of reach.
        """
        t = (self._cycle + 1) * self.period
        primitive = self._active
        replanned, self._replanned = self._replanned, False
        if self._queue and isinstance(primitive, Hold):  # new work after a hold
            primitive = self._queue.popleft()
            primitive.begin(self._state, self.t, self.limits)
            replanned = True
        while t >= primitive.end_time:
            replanned = True
            t_end = primitive.end_time
            end = primitive.get_state(t_end)
            if not primitive.advance(t_end, end, self.limits):
                primitive = self._next_primitive(end)
                primitive.begin(end, t_end, self.limits)
        self._active = primitive
        p, v, rotation, omega = primitive.sample(t)
        twist, q, index, within = self._command_joints(p, v, rotation, omega)
        if not within:
            self._check_position(q, t)
        jacobian = pin.computeFrameJacobian(
            self.robot.model, self.robot.data, q, self._frame_id, _LWA
        )
        redundancy = math.nan
        if self._tracker is None:
            qd, damped = solve_velocity(
                jacobian,
                twist,
                self.dls_epsilon,
                self.dls_lambda_max,
                lambda: self._position_rate(q, twist),
            )
        else:
            redundancy = self._tracker.value
            qd, damped = solve_null_space_velocity(
                jacobian,
                twist,
                self.dls_epsilon,
                self.dls_lambda_max,
                self._command_rate(q, twist),
            )
        if self.check_speed and max(map(abs, qd.tolist())) > self._min_speed_limit:
            self._check_speed(qd, t)
        self._cycle += 1
        self._q_before, self._q = self._q, q
        self._qd, self._branch = qd, index
        self._state = CartesianState(p, v, rotation, omega)
        return PlannerSample(
            t,
            p,
            v,
            rotation,
            omega,
            q,
            qd,
            self._labels[index],
            damped,
            replanned,
            redundancy,
        )

    def _command_joints(
        self, p: FloatArray, v: FloatArray, rotation: FloatArray, omega: FloatArray
    ) -> tuple[FloatArray, FloatArray, int, bool]:
        """Tip command (world) -> wrist twist (base axes) and joint command.

        Steps 2 and 3 of the cycle: the wrist-centre command in the base frame
        (``_tracking.wrist_command``), then the IK solution that continues the
        motion (:meth:`~workbench.ik.Solver.track`, from the
        configuration predicted from the last two commands, so that at a wrist
        singularity, θ4 and θ6 free, the wrist keeps moving as it was).

        Returns:
            ``(twist, q, branch index, within limits)``: the wrist-centre twist
            (6,) [m/s, rad/s], linear first, base axes; ``q`` read-only.
        """
        q_before = self._q if self._q_before is None else self._q_before
        pose, twist = np.empty((4, 4)), np.empty(6)
        wrist_command(rotation, p, v, omega, self._frames, pose, twist)
        q_predicted = 2.0 * self._q - q_before  # the wrist keeps moving as it was
        if self._tracker is not None:
            q, index, within = self._tracker.track(
                pose, twist, self._q, q_predicted, self._branch, self._max_step2
            )
        else:
            q, index, within = self._closed_form.track(
                pose, q_predicted, self._branch, self._max_step2
            )
        q.setflags(write=False)
        return twist, q, index, within

    def _position_rate(self, q: FloatArray, twist: FloatArray) -> FloatArray:
        """Rate of the joint position commands ending at ``q``: the DLS reference.

        Second-order backward difference (first order on the first cycle);
        zero when the tool is commanded at rest.
        """
        if not twist.any():
            return np.zeros(len(q))
        if self._q_before is None:
            return (q - self._q) / self.period
        return (3.0 * q - 4.0 * self._q + self._q_before) / (2.0 * self.period)

    def _command_rate(self, q: FloatArray, twist: FloatArray) -> FloatArray:
        """Rate of the joint position commands of a 7R arm: the null-space term.

        As :meth:`_position_rate` while the tool moves; with the tool at rest,
        the first-order difference ``(q - q_last) / period``: zero when the
        parameter holds, the self-motion when it moves.
        """
        if twist.any():
            return self._position_rate(q, twist)
        return (q - self._q) / self.period

    def _check_speed(self, qd: FloatArray, t: float) -> None:
        ratio = np.abs(qd) / self._speed_limit
        j = int(np.argmax(ratio))
        if ratio[j] > 1.0:
            lim = float(self.robot.velocity_limit[j])
            name = self.robot.joint_names[j]
            raise JointLimitError(name, float(qd[j]), -lim, lim, t=t, kind="velocity")

    def _check_position(self, q: FloatArray, t: float) -> None:
        lower, upper = self.robot.lower, self.robot.upper
        bad = np.flatnonzero((q < lower - 1e-9) | (q > upper + 1e-9))
        if bad.size:
            j = int(bad[0])
            name = self.robot.joint_names[j]
            raise JointLimitError(
                name, float(q[j]), float(lower[j]), float(upper[j]), t=t
            )


__all__ = ["SPEED_RTOL", "OnlinePlanner", "PlannerSample"]
