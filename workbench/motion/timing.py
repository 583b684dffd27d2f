r"""Time scaling of a joint-space polyline: C², rest to rest on every segment.

A planner's waypoints :math:`w_0, \dots, w_M` are joined by straight segments
it certified free of collision, so the motion follows them exactly: on segment
:math:`s`, :math:`q(t) = w_s + \Delta_s\,u(t - t_s)` with
:math:`\Delta_s = w_{s+1} - w_s`, and the path parameter u goes from 0 to 1,
starting and stopping with zero speed and zero acceleration. No corner is cut;
the robot stops at every waypoint. Joint limits :math:`v_i, a_i` bound the path,
:math:`|\dot u| \le V_s = \min_i v_i/|\Delta_{s,i}|` and
:math:`|\ddot u| \le A_s = \min_i a_i/|\Delta_{s,i}|`
(:mod:`workbench.trajectory.time_optimal`).

The profile of u is a double S (trapezoidal acceleration) of seven phases of
constant jerk: the acceleration ramps from 0 to :math:`A_s` during
:data:`JERK_FRACTION` = 1/6 of the acceleration phase :math:`T_a`, holds
:math:`A_s` for 2/3 of it and ramps back to 0 in the last 1/6; u then coasts at
the peak speed when it reaches :math:`V_s`, and decelerates as the mirror image.
The speed gained in :math:`T_a` is :math:`A_s T_a (1 - f)`, :math:`f = 1/6`, and
the distance covered :math:`V_p T_a / 2` (the acceleration is symmetric about
the middle of the phase): exactly what a bang-bang phase of acceleration
:math:`c A_s`, :math:`c = 1 - f = 5/6`, gives. A segment therefore lasts the
bang-coast-bang time with :math:`A_s` replaced by :math:`c A_s`,
:math:`T_s = T^*(V_s, c A_s)`
(:func:`~workbench.trajectory.compute_bang_coast_bang_duration`), and with
:math:`r = V_s^2 / A_s` its ratio to the optimum :math:`T^*(V_s, A_s)` is

.. math::

    \frac{1 + r/c}{1 + r}\ (r \le c), \qquad
    \frac{2\sqrt r}{\sqrt c\,(1 + r)}\ (c < r < 1), \qquad
    \frac{1}{\sqrt c}\ (r \ge 1),

increasing in r, so never above :data:`WORST_RATIO` :math:`= \sqrt{6/5}
\approx 1.0954`, reached by every segment too short to coast. The peak path
acceleration is always :math:`A_s` (a joint at its acceleration limit on every
segment), the peak speed :math:`\min(V_s, \sqrt{c A_s})` (a joint at its speed
limit too when the segment coasts), the jerk :math:`\pm A_s / (f T_a)` in the
ramps. The whole motion is C², with zero speed and acceleration at every
waypoint and at both ends.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.motion._polyline import compute_path_bounds
from workbench.trajectory import (
    JointExtrema,
    JointTrajectorySamples,
    compute_bang_coast_bang_duration,
    sample_uniform,
)
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]
IndexArray = npt.NDArray[np.intp]

#: Share of the acceleration phase taken by each of its two jerk ramps.
JERK_FRACTION = 1.0 / 6.0
#: :math:`c = 1 - f`: the profile covers the path as bang-bang at :math:`c A`.
ACCELERATION_SHARE = 1.0 - JERK_FRACTION
#: Largest ratio of a segment's duration to the time-optimal one, :math:`1/\sqrt c`.
WORST_RATIO = 1.0 / math.sqrt(ACCELERATION_SHARE)
#: Phases of constant jerk per segment.
PHASES = 7


@dataclass(frozen=True, slots=True, eq=False)
class _Profile:
    """The phases of every segment, and the per-segment peaks.

    ``start`` (P,) [s], P = 7 M + 1 (the last: rest at the end); ``state``
    (P, 4): u, u̇, ü at the phase's start and its jerk; ``segment`` (P,), M
    for the final rest. Per segment (M,): ``t_accel`` [s] (T_a), ``t_coast``
    [s], ``peak_speed`` [1/s], ``peak_acceleration`` [1/s²].
    """

    start: FloatArray
    state: FloatArray
    segment: IndexArray
    t_accel: FloatArray
    t_coast: FloatArray
    peak_speed: FloatArray
    peak_acceleration: FloatArray


@dataclass(frozen=True, slots=True, eq=False)
class WaypointTrajectory:
    """A motion along a joint-space polyline, at rest at every waypoint.

    Build one with :func:`time_scale` (module docstring). Before t = 0 and
    after ``duration`` the robot rests at the first / last waypoint.

    Attributes:
        robot: The robot whose limits apply.
        waypoints: The polyline's corners, shape (K, nq) [rad], read-only.
        times: When each waypoint is reached, shape (K,) [s], read-only,
            ``times[0] = 0``, ``times[-1] = duration``.
        duration: Total time [s], > 0.
    """

    robot: Robot
    waypoints: FloatArray
    times: FloatArray
    duration: float
    _profile: _Profile = field(repr=False)

    @property
    def phase_times(self) -> FloatArray:
        """When the jerk changes: 7 per segment, then the end; shape (7 (K-1) + 1,) [s].

        Between two of them every joint is a cubic in t; at each of them q,
        q̇ and q̈ are continuous.
        """
        return self._profile.start

    def sample(self, t: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Positions, velocities and accelerations at time(s) ``t``, exactly.

        Args:
            t: Time [s], scalar or any shape (e.g. (K,)); clamped into
                [0, duration].

        Returns:
            ``(q, qd, qdd)`` [rad, rad/s, rad/s²], each of shape
            ``t.shape + (nq,)``: (nq,) for a scalar, (K, nq) for (K,).

        Raises:
            NonFiniteError: If ``t`` holds NaN or infinity.
        """
        t = np.asarray(t, dtype=np.float64)
        t = np.clip(as_finite_array(t, t.shape, "t"), 0.0, self.duration)
        profile = self._profile
        index = np.searchsorted(profile.start, t, side="right") - 1  # t >= start[0]
        dt = t - profile.start[index]
        u0, v0, a0, jerk = np.moveaxis(profile.state[index], -1, 0)
        u = u0 + dt * (v0 + dt * (0.5 * a0 + dt * (jerk / 6.0)))
        v = v0 + dt * (a0 + dt * (0.5 * jerk))
        a = a0 + dt * jerk
        segment = profile.segment[index]
        delta = self._deltas()[segment]
        q = self.waypoints[segment] + delta * u[..., None]
        return q, delta * v[..., None], delta * a[..., None]

    def _deltas(self) -> FloatArray:
        """Each segment's displacement, then a zero row: (K, nq) [rad]."""
        return np.vstack([np.diff(self.waypoints, axis=0), np.zeros((1, self.nq))])

    @property
    def nq(self) -> int:
        """Joint count."""
        return int(self.waypoints.shape[1])

    def sample_uniform(self, rate_hz: float) -> JointTrajectorySamples:
        """Samples at ``rate_hz`` from 0 to ``duration``, both ends included.

        What :func:`~workbench.trajectory.write_trajectory_csv` and the
        exports (:mod:`workbench.export`) take.

        Raises:
            InputError: If ``rate_hz`` is not finite and > 0.
        """
        return sample_uniform(self, rate_hz)

    def get_extrema(self, order: int) -> JointExtrema:
        r"""Exact per-joint extremes of q (0), q̇ (1) or q̈ (2) over [0, duration].

        Positions are extreme at waypoints; on segment s a joint's speed peaks
        at :math:`\Delta_{s,i} V_p` when the acceleration phase ends, its
        acceleration at :math:`\pm\Delta_{s,i} A_s` on the constant phases.

        Raises:
            InputError: If ``order`` is not 0, 1 or 2.
        """
        if order not in (0, 1, 2):
            raise InputError(f"order must be 0, 1 or 2, got {order!r}")
        start = self.times[:-1]
        profile = self._profile
        delta = np.diff(self.waypoints, axis=0)
        if order == 0:
            values, at = self.waypoints, self.times
        elif order == 1:
            zero = np.zeros((1, self.nq))
            values = np.vstack([zero, delta * profile.peak_speed[:, None]])
            at = np.r_[0.0, start + profile.t_accel]
        else:
            peak = delta * profile.peak_acceleration[:, None]
            ramp = JERK_FRACTION * profile.t_accel
            values = np.vstack([peak, -peak])
            at = np.r_[start + ramp, start + profile.t_accel + profile.t_coast + ramp]
        times = np.broadcast_to(np.asarray(at)[:, None], values.shape)
        low, high = np.argmin(values, axis=0), np.argmax(values, axis=0)
        cols = np.arange(self.nq)
        return JointExtrema(
            minimum=values[low, cols],
            t_minimum=times[low, cols],
            maximum=values[high, cols],
            t_maximum=times[high, cols],
        )


def time_scale(
    robot: Robot,
    waypoints: npt.ArrayLike,
    *,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
) -> WaypointTrajectory:
    """The C² motion along a polyline, rest to rest on every segment (module doc).

    Every segment is as short as the double-S profile allows within the
    robot's speed and acceleration limits (scaled), at most
    :data:`WORST_RATIO` times the time-optimal duration of the same segment
    (:func:`time_optimal_duration`).

    Args:
        robot: Any robot with one coordinate per joint (nq == nv) and the
            speed and acceleration limits of every joint that moves
            (:meth:`~workbench.model.Robot.with_limits`).
        waypoints: Shape (K, nq) [rad], K >= 2, within the position limits,
            no two consecutive ones equal (closer than
            :data:`~workbench.motion.REPEAT_TOL` in every joint): a planner's
            path after shortcutting.
        velocity_scale: Fraction of every speed limit used, in (0, 1].
        acceleration_scale: Fraction of every acceleration limit, in (0, 1].

    Returns:
        The trajectory, through waypoint k at ``times[k]``.

    Raises:
        NonFiniteError: If a waypoint holds NaN or infinity.
        InputError: If the waypoints are not numbers of shape (K, nq), there
            are fewer than two, two consecutive ones are equal, one leaves
            the position limits, a scale is not in (0, 1], a moving joint has
            no speed or acceleration limit, or the robot has nq != nv.
    """
    points, speed, accel = compute_path_bounds(
        robot, waypoints, velocity_scale, acceleration_scale
    )
    durations = compute_bang_coast_bang_duration(speed, ACCELERATION_SHARE * accel)
    times = np.concatenate([[0.0], np.cumsum(durations)])
    points.setflags(write=False)
    times.setflags(write=False)
    profile = _build_profile(speed, accel, durations, times)
    return WaypointTrajectory(robot, points, times, float(times[-1]), profile)


def time_optimal_duration(
    robot: Robot,
    waypoints: npt.ArrayLike,
    *,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
) -> float:
    """The time-optimal duration along the polyline, stopping at each waypoint.

    The sum over segments of the bang-coast-bang optimum
    (:func:`~workbench.trajectory.compute_bang_coast_bang_duration`): at a
    corner the joint velocities change direction, which bounded
    accelerations allow only at rest. TOPP-RA finds the same on each
    straight segment.

    Args:
        robot: As for :func:`time_scale`.
        waypoints: As for :func:`time_scale`, shape (K, nq) [rad].
        velocity_scale: As for :func:`time_scale`.
        acceleration_scale: As for :func:`time_scale`.

    Returns:
        T* [s]; ``time_scale(...).duration / T*`` is at most
        :data:`WORST_RATIO`.

    Raises:
        NonFiniteError, InputError: As :func:`time_scale`.
    """
    _, speed, accel = compute_path_bounds(
        robot, waypoints, velocity_scale, acceleration_scale
    )
    return float(np.sum(compute_bang_coast_bang_duration(speed, accel)))


def _build_profile(
    speed: FloatArray, accel: FloatArray, durations: FloatArray, times: FloatArray
) -> _Profile:
    """The seven phases of each segment, segment s starting at ``times[s]``."""
    share = ACCELERATION_SHARE * accel
    coasts = speed * speed <= share
    peak = np.where(coasts, speed, np.sqrt(share))
    t_accel = peak / share
    t_coast = np.where(coasts, np.maximum(durations - 2.0 * t_accel, 0.0), 0.0)
    ramp = JERK_FRACTION * t_accel
    jerk = accel / ramp
    hold = t_accel - 2.0 * ramp
    u2, v2 = accel * ramp * ramp / 6.0, 0.5 * accel * ramp
    u3, v3 = u2 + v2 * hold + 0.5 * accel * hold * hold, v2 + accel * hold
    u4 = 0.5 * peak * t_accel
    m = speed.size
    offsets = np.empty((m, PHASES))
    offsets[:, 0] = 0.0
    offsets[:, 1] = ramp
    offsets[:, 2] = t_accel - ramp
    offsets[:, 3] = t_accel
    offsets[:, 4] = t_accel + t_coast
    offsets[:, 5] = durations - t_accel + ramp
    offsets[:, 6] = durations - ramp
    # (u, u̇, ü, jerk) at the start of each phase; the last row: rest at the end.
    state = np.zeros((m * PHASES + 1, 4))
    phases = state[:-1].reshape(m, PHASES, 4)
    phases[:, 1:, 0] = np.column_stack([u2, u3, u4, 1.0 - u4, 1.0 - u3, 1.0 - u2])
    phases[:, 1:, 1] = np.column_stack([v2, v3, peak, peak, v3, v2])
    phases[:, 1:3, 2] = accel[:, None]
    phases[:, 5:, 2] = -accel[:, None]
    phases[:, 0::6, 3] = jerk[:, None]
    phases[:, 2:5:2, 3] = -jerk[:, None]
    segment = np.r_[np.repeat(np.arange(m), PHASES), m]
    start = np.r_[(times[:-1, None] + offsets).reshape(-1), times[-1]]
    for array in (start, state, segment):
        array.setflags(write=False)
    return _Profile(start, state, segment, t_accel, t_coast, peak, accel)
