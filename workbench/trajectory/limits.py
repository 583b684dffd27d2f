r"""Joint limits along a scaled normal spline, checked exactly, and the shortest T.

A joint follows :math:`q_i(t) = q_{i,0} + \Delta_i\,s(t/T)`, so its speed is
:math:`\Delta_i \dot s / T` and its acceleration :math:`\Delta_i \ddot s / T^2`.
Their extremes over the whole motion are the spline's exact extremes (from its
piecewise-polynomial form, not from samples) scaled by :math:`\Delta_i` and
powers of 1/T. The shortest duration that keeps every joint within its speed
limit :math:`v_i` and acceleration limit :math:`a_i` is therefore

.. math::

    T_\min = \max_i \max\left(\frac{|\Delta_i|\,\max|\dot s|}{v_i},
    \sqrt{\frac{|\Delta_i|\,\max|\ddot s|}{a_i}}\right),

the second term only where :math:`a_i` is finite. Position limits do not
depend on T.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError, JointLimitError
from workbench.model.robot import Robot
from workbench.trajectory.normal_spline import DEFAULT_N_POINTS, get_normal_spline
from workbench.validation import as_vector

FloatArray = npt.NDArray[np.float64]

LIMIT_RTOL = 1e-12
"""Relative slack on a limit before it counts as violated.

A trajectory planned at exactly :func:`minimum_duration` reaches its binding
limit up to a few units of rounding; this slack keeps it feasible.
"""

KINDS = ("position", "velocity", "acceleration")
"""Kinds of limit, indexed by the derivative order 0, 1, 2."""

_UNITS = ("rad", "rad/s", "rad/s²")


@dataclass(frozen=True, slots=True)
class JointExtrema:
    """Per-joint extremes of q, q̇ or q̈ over a whole trajectory.

    Attributes:
        minimum: Smallest value of each joint, shape (nq,) [rad, rad/s, rad/s²].
        t_minimum: When it is reached, shape (nq,) [s].
        maximum: Largest value of each joint, shape (nq,).
        t_maximum: When it is reached, shape (nq,) [s].
    """

    minimum: FloatArray
    t_minimum: FloatArray
    maximum: FloatArray
    t_maximum: FloatArray

    @property
    def peak(self) -> FloatArray:
        """Largest magnitude of each joint, ``max(|minimum|, |maximum|)``, shape (nq,).

        Of q̇ or q̈: the peak joint speed [rad/s] or acceleration [rad/s²],
        what the limits are checked against.
        """
        return np.maximum(np.abs(self.minimum), np.abs(self.maximum))

    @staticmethod
    def combine(parts: list[JointExtrema]) -> JointExtrema:
        """Extremes over the union of several time intervals."""
        lo = np.array([p.minimum for p in parts])
        hi = np.array([p.maximum for p in parts])
        i_lo, i_hi = np.argmin(lo, axis=0), np.argmax(hi, axis=0)
        cols = np.arange(lo.shape[1])
        t_lo = np.array([p.t_minimum for p in parts])
        t_hi = np.array([p.t_maximum for p in parts])
        return JointExtrema(
            lo[i_lo, cols], t_lo[i_lo, cols], hi[i_hi, cols], t_hi[i_hi, cols]
        )


class _HasExtrema(Protocol):
    @property
    def robot(self) -> Robot: ...

    def get_extrema(self, order: int) -> JointExtrema: ...


@dataclass(frozen=True, slots=True)
class LimitViolation:
    """One joint leaving one limit; the worst point of the excursion.

    Attributes:
        joint: Joint name.
        kind: ``"position"``, ``"velocity"`` or ``"acceleration"``.
        t: Time of the largest excursion [s].
        value: Value there [rad, rad/s or rad/s²], signed.
        lower: Lower limit, same unit.
        upper: Upper limit, same unit.
    """

    joint: str
    kind: str
    t: float
    value: float
    lower: float
    upper: float

    @property
    def limit(self) -> float:
        """The limit that is crossed: ``upper`` or ``lower``."""
        return self.upper if self.value > self.upper else self.lower

    @property
    def message(self) -> str:
        """One line naming joint, time, value and limit."""
        unit = _UNITS[KINDS.index(self.kind)]
        return (
            f"joint {self.joint} {self.kind} {self.value:.6g} {unit} at "
            f"t = {self.t:.6g} s exceeds its limit {self.limit:.6g} {unit}"
        )

    def as_dict(self) -> dict[str, object]:
        """``{joint, t, value, limit, kind}`` for JSON."""
        return {
            "joint": self.joint,
            "t": self.t,
            "value": self.value,
            "limit": self.limit,
            "kind": self.kind,
        }

    def to_error(self) -> JointLimitError:
        """The matching :class:`~workbench.errors.JointLimitError`."""
        return JointLimitError(
            self.joint, self.value, self.lower, self.upper, self.t, self.kind
        )


def _rate_limit(robot: Robot, order: int) -> FloatArray:
    """Speed (1) or acceleration (2) limits, inf where not given (see Robot)."""
    return np.asarray(robot.velocity_limit if order == 1 else robot.acceleration_limit)


def _bounds(robot: Robot, order: int) -> tuple[FloatArray, FloatArray]:
    if order == 0:
        return np.asarray(robot.lower), np.asarray(robot.upper)
    limit = _rate_limit(robot, order)
    return -limit, limit


def _exceeds(value: float, bound: float, above: bool) -> bool:
    slack = LIMIT_RTOL * abs(bound)
    return value > bound + slack if above else value < bound - slack


def check_limits(trajectory: _HasExtrema) -> list[LimitViolation]:
    """Every position, speed and acceleration limit the trajectory leaves.

    Uses the exact extremes of the trajectory (:meth:`get_extrema`), so a
    violation between samples is found too. Infinite limits (not given, as a
    URDF's ``velocity="0"``: see :attr:`Robot.velocity_limit`) are never
    violated. A value
    counts as outside when it passes the limit by more than :data:`LIMIT_RTOL`
    of the limit.

    Args:
        trajectory: Any trajectory with ``robot`` and exact
            ``get_extrema(order)``: a :class:`~workbench.trajectory.JointTrajectory`,
            :class:`~workbench.trajectory.SegmentedTrajectory` or
            :class:`~workbench.motion.WaypointTrajectory`.

    Returns:
        The violations, by kind (position, velocity, acceleration) then joint;
        empty when the trajectory is feasible.
    """
    robot = trajectory.robot
    names = robot.joint_names
    found = []
    for order, kind in enumerate(KINDS):
        ext = trajectory.get_extrema(order)
        lower, upper = _bounds(robot, order)
        for i, name in enumerate(names):
            lo, hi = float(lower[i]), float(upper[i])
            for value, t, bound, above in (
                (ext.maximum[i], ext.t_maximum[i], hi, True),
                (ext.minimum[i], ext.t_minimum[i], lo, False),
            ):
                if _exceeds(float(value), bound, above):
                    found.append(
                        LimitViolation(name, kind, float(t), float(value), lo, hi)
                    )
    return found


def raise_for_violations(trajectory: _HasExtrema) -> None:
    """Raise the first violation of :func:`check_limits`, if any.

    Raises:
        JointLimitError: Naming joint, kind, time, value and limits.
    """
    violations = check_limits(trajectory)
    if violations:
        raise violations[0].to_error()


def minimum_duration(
    robot: Robot,
    q_pick: npt.ArrayLike,
    q_place: npt.ArrayLike,
    *,
    n_points: int = DEFAULT_N_POINTS,
) -> float:
    r"""Shortest T of the normal-spline motion within speed and acceleration limits.

    Closed form (see the module docstring) from the spline's exact peaks of
    :math:`|\dot s|` and :math:`|\ddot s|` and ``robot.velocity_limit`` /
    ``robot.acceleration_limit`` (only finite limits count). A
    trajectory planned with exactly this T reaches the binding limit and leaves
    none. Position limits do not depend on T and are not considered.

    Args:
        robot: The robot (nq == nv).
        q_pick: Start configuration, shape (nq,) [rad].
        q_place: End configuration, shape (nq,) [rad].
        n_points: Knots of the normal spline.

    Returns:
        T_min [s]; 0.0 when the two configurations are equal.

    Raises:
        DimensionError: If a configuration has the wrong shape.
        NonFiniteError: If a configuration holds NaN or infinity.
        InputError: If ``n_points`` is invalid or the robot has nq != nv.
    """
    _require_vector_space(robot)
    q0 = as_vector(q_pick, robot.nq, "q_pick")
    q1 = as_vector(q_place, robot.nq, "q_place")
    spline = get_normal_spline(n_points)
    distance = np.abs(q1 - q0)
    by_speed = distance * spline.velocity.peak / _rate_limit(robot, 1)
    acc = _rate_limit(robot, 2)
    finite = np.isfinite(acc)
    by_acc = np.sqrt(distance[finite] * spline.acceleration.peak / acc[finite])
    return float(max(by_speed.max(initial=0.0), by_acc.max(initial=0.0)))


def get_unknown_limits(robot: Robot) -> dict[str, list[str]]:
    """The joints whose speed or acceleration limit the model does not give.

    Such a limit is infinite (a URDF's ``velocity="0"`` or missing
    ``<limit>``; a URDF has no acceleration limits): :func:`minimum_duration`
    and :func:`check_limits` then respect the known limits only.

    Returns:
        ``{"velocity": names, "acceleration": names}``, joint names in
        model order (empty lists when every limit is known).
    """
    names = robot.joint_names
    return {
        kind: [
            n
            for n, v in zip(names, _rate_limit(robot, order), strict=True)
            if not np.isfinite(v)
        ]
        for kind, order in (("velocity", 1), ("acceleration", 2))
    }


def describe_unknown_limits(robot: Robot) -> str | None:
    """One line saying which limits are unknown and what the minimum means.

    None when every speed and acceleration limit is known.
    """
    unknown = get_unknown_limits(robot)
    count = len(robot.joint_names)
    parts = []
    for kind in ("velocity", "acceleration"):
        names = unknown[kind]
        if len(names) == count:
            parts.append(f"no {kind} limit for any joint")
        elif names:
            parts.append(f"no {kind} limit for {', '.join(names)}")
    if not parts:
        return None
    if len(unknown["velocity"]) == len(unknown["acceleration"]) == count:
        meaning = "no minimum duration is known (0 s stands for none)"
    else:
        meaning = "the minimum duration respects the known limits only"
    return f"note: the model gives {'; '.join(parts)}: {meaning}"


def _require_vector_space(robot: Robot) -> None:
    if robot.nq != robot.nv:
        raise InputError(
            f"robot {robot.name} has nq = {robot.nq} != nv = {robot.nv} (continuous "
            "or multi-coordinate joints); the pick-and-place spline needs one "
            "coordinate per joint"
        )
