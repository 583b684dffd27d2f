r"""Trapezoidal velocity profiles along one coordinate (Kang 2007, Fig. 4 and 6).

A profile moves a path coordinate ``s`` from 0 to ``distance`` with the speed
bounded by ``max_velocity`` and the acceleration by ``max_acceleration``: it
accelerates at the limit, cruises, decelerates at the limit, or, when the
distance is too short to reach the cruise speed, it is triangular. Kang's
``vi``/``vf`` flags become ``initial_velocity`` and ``final_velocity``: a
primitive may start or end at full speed.

Two builders share one exact, piecewise-constant-acceleration representation:

* :func:`trapezoid`: Kang's profile; the speed stays in ``[0, max_velocity]``
  and ``s`` never goes back, else the request is infeasible.
* :func:`replan_trapezoid`: the time-optimal profile from any moving state (a
  negative or too-high initial speed, any signed distance), overshooting and
  coming back when it must; the online planner uses it to replan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from workbench.errors import InfeasibleError, InputError, NonFiniteError

FloatArray = npt.NDArray[np.float64]

#: Relative slack on the feasibility tests of :func:`trapezoid`, so that a
#: request at its exact limit (e.g. ``distance == vf**2 / (2 a)``) passes.
FEASIBILITY_RTOL = 1e-12


@dataclass(frozen=True, slots=True)
class TrapezoidalProfile:
    r"""Exact piecewise-constant-acceleration motion of a coordinate ``s``.

    Phase ``k`` starts at ``times[k]`` with ``s = positions[k]`` and
    ``ṡ = velocities[k]`` and has constant ``s̈ = accelerations[k]``; the last
    entry of ``times``/``positions``/``velocities`` is the end state. Outside
    ``[0, duration]`` the motion continues at the initial/final velocity
    (so a profile ending at full speed hands over smoothly).

    Attributes:
        times: Phase start times and the end time, shape (n + 1,) [s].
        positions: ``s`` at those times, (n + 1,) [m or rad].
        velocities: ``ṡ`` at those times, (n + 1,) [m/s or rad/s].
        accelerations: ``s̈`` of each phase, (n,) [m/s² or rad/s²].
    """

    times: tuple[float, ...]
    positions: tuple[float, ...]
    velocities: tuple[float, ...]
    accelerations: tuple[float, ...]

    @property
    def duration(self) -> float:
        """Time to reach the end state [s]."""
        return self.times[-1]

    @property
    def distance(self) -> float:
        """Final ``s`` [m or rad]."""
        return self.positions[-1]

    @property
    def initial_velocity(self) -> float:
        """``ṡ`` at t = 0."""
        return self.velocities[0]

    @property
    def final_velocity(self) -> float:
        """``ṡ`` at the end."""
        return self.velocities[-1]

    @property
    def peak_velocity(self) -> float:
        """Largest ``|ṡ|`` reached [m/s or rad/s]."""
        return max(abs(v) for v in self.velocities)

    def sample(
        self, t: float | npt.ArrayLike
    ) -> tuple[float, float, float] | tuple[FloatArray, FloatArray, FloatArray]:
        """Position, velocity and acceleration at time ``t``.

        Args:
            t: Time [s], a scalar or an array of any shape.

        Returns:
            ``(s, sd, sdd)``: floats for a scalar ``t``, else arrays of the
            shape of ``t``. At a phase boundary the acceleration is the one of
            the phase that starts there.

        Raises:
            NonFiniteError: If ``t`` is NaN or infinite.
        """
        if isinstance(t, (float, int)):
            return self._sample_scalar(float(t))
        ts = np.asarray(t, dtype=np.float64)
        if not np.all(np.isfinite(ts)):
            raise NonFiniteError("t must be finite")
        flat = [self._sample_scalar(x) for x in ts.ravel().tolist()]
        out = np.array(flat, dtype=np.float64).reshape((*ts.shape, 3))
        return out[..., 0], out[..., 1], out[..., 2]

    def _sample_scalar(self, t: float) -> tuple[float, float, float]:
        times = self.times
        if not math.isfinite(t):
            raise NonFiniteError(f"t must be finite, got {t}")
        if t <= 0.0:
            v = self.velocities[0]
            return v * t, v, 0.0
        n = len(self.accelerations)
        k = 0
        while k < n and t >= times[k + 1]:
            k += 1
        tau = t - times[k]
        s0, v0 = self.positions[k], self.velocities[k]
        if k == n:  # after the end: constant final velocity
            return s0 + v0 * tau, v0, 0.0
        a = self.accelerations[k]
        return s0 + (v0 + 0.5 * a * tau) * tau, v0 + a * tau, a


def _finite(value: float, name: str) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError) as err:
        raise NonFiniteError(f"{name} must be a number, got {value!r}") from err
    if not math.isfinite(x):
        raise NonFiniteError(f"{name} must be finite, got {x}")
    return x


def _positive(value: float, name: str) -> float:
    x = _finite(value, name)
    if x <= 0.0:
        raise InputError(f"{name} must be > 0, got {x:g}")
    return x


def _build(
    phases: list[tuple[float, float]], v0: float, vf: float, distance: float
) -> TrapezoidalProfile:
    """Profile from (duration, acceleration) phases; zero-length phases dropped.

    The end state is set to exactly (``distance``, ``vf``), removing the
    rounding of the sums.
    """
    times, positions, velocities, accelerations = [0.0], [0.0], [v0], []
    t = s = 0.0
    v = v0
    for dt, a in phases:
        if dt > 0.0:
            t += dt
            s += (v + 0.5 * a * dt) * dt
            v += a * dt
            times.append(t)
            positions.append(s)
            velocities.append(v)
            accelerations.append(a)
    if accelerations:
        positions[-1], velocities[-1] = distance, vf
    return TrapezoidalProfile(
        tuple(times), tuple(positions), tuple(velocities), tuple(accelerations)
    )


def _time_optimal(
    distance: float, v0: float, vf: float, vmax: float, amax: float
) -> TrapezoidalProfile:
    """Time-optimal profile from (0, v0) to (distance, vf), |vf| <= vmax.

    Arguments trusted: finite, ``vmax`` and ``amax`` > 0.
    """
    v_start, d = v0, distance
    phases: list[tuple[float, float]] = []
    if abs(v0) > vmax:  # first get back within the speed bound
        v1 = math.copysign(vmax, v0)
        dt = (abs(v0) - vmax) / amax
        phases.append((dt, -math.copysign(amax, v0)))
        d -= 0.5 * (v0 + v1) * dt
        v0 = v1
    direct = 0.5 * (v0 + vf) * abs(vf - v0) / amax  # one phase v0 -> vf
    if d >= direct:  # peak above both end speeds
        peak = min(math.sqrt(max(amax * d + 0.5 * (v0 * v0 + vf * vf), 0.0)), vmax)
        peak = max(peak, v0, vf)
        sign = 1.0
    else:  # valley below both: move backwards (overshoot) first
        peak = -min(math.sqrt(max(0.5 * (v0 * v0 + vf * vf) - amax * d, 0.0)), vmax)
        peak = min(peak, v0, vf)
        sign = -1.0
    t1 = sign * (peak - v0) / amax
    t3 = sign * (peak - vf) / amax
    d13 = 0.5 * (v0 + peak) * t1 + 0.5 * (peak + vf) * t3
    cruise = (d - d13) / peak if peak != 0.0 else 0.0
    phases += [(t1, sign * amax), (max(cruise, 0.0), 0.0), (t3, -sign * amax)]
    return _build(phases, v_start, vf, distance)


def trapezoid(
    distance: float,
    max_velocity: float,
    max_acceleration: float,
    *,
    initial_velocity: float = 0.0,
    final_velocity: float = 0.0,
) -> TrapezoidalProfile:
    r"""Kang's trapezoidal (or triangular) profile over ``distance``.

    Accelerates at ``max_acceleration`` from ``initial_velocity``, cruises at
    ``max_velocity`` and decelerates to ``final_velocity``; when ``distance`` is
    too short to cruise the peak speed is
    :math:`\sqrt{a d + (v_i^2 + v_f^2)/2} < v_{max}` (triangular). The speed
    stays in ``[0, max_velocity]``: ``s`` never goes back.

    Args:
        distance: Path length [m] or angle [rad], >= 0.
        max_velocity: Cruise speed, > 0 [m/s or rad/s].
        max_acceleration: Acceleration and deceleration bound, > 0 [m/s², rad/s²].
        initial_velocity: Speed at t = 0, in ``[0, max_velocity]`` (Kang's
            ``vi = 1`` is ``max_velocity``).
        final_velocity: Speed at the end, in ``[0, max_velocity]`` (``vf``).

    Returns:
        The profile; ``sample(t)`` gives ``(s, ṡ, s̈)``.

    Raises:
        NonFiniteError: If an argument is NaN or infinite.
        InputError: If a limit is <= 0, ``distance`` < 0, or an end speed is
            outside ``[0, max_velocity]``.
        InfeasibleError: If ``distance`` is too short to change the speed from
            ``initial_velocity`` to ``final_velocity`` at ``max_acceleration``.
    """
    d = _finite(distance, "distance")
    vmax = _positive(max_velocity, "max_velocity")
    amax = _positive(max_acceleration, "max_acceleration")
    v0 = _finite(initial_velocity, "initial_velocity")
    vf = _finite(final_velocity, "final_velocity")
    if d < 0.0:
        raise InputError(f"distance must be >= 0, got {d:g}")
    for name, v in (("initial_velocity", v0), ("final_velocity", vf)):
        if not 0.0 <= v <= vmax:
            raise InputError(
                f"{name} must be in [0, max_velocity = {vmax:g}], got {v:g}"
            )
    needed = abs(vf * vf - v0 * v0) / (2.0 * amax)
    if d < needed * (1.0 - FEASIBILITY_RTOL):
        verb = "accelerate" if vf > v0 else "decelerate"
        raise InfeasibleError(
            f"distance {d:g} is too short to {verb} from {v0:g} to {vf:g} at "
            f"max_acceleration {amax:g}: needs >= {needed:g}"
        )
    if d <= needed:  # exactly one ramp (or nothing)
        return _build([(abs(vf - v0) / amax, math.copysign(amax, vf - v0))], v0, vf, d)
    return _time_optimal(d, v0, vf, vmax, amax)


def replan_trapezoid(
    distance: float,
    max_velocity: float,
    max_acceleration: float,
    *,
    initial_velocity: float,
    final_velocity: float = 0.0,
    check: bool = True,
) -> TrapezoidalProfile:
    """Time-optimal profile from a moving state to ``distance`` at ``final_velocity``.

    Unlike :func:`trapezoid` the initial speed may be negative or above
    ``max_velocity`` (it is first brought back within the bound at full
    deceleration) and ``distance`` may have either sign: when the target cannot
    be reached without overshooting, the profile stops, comes back and arrives
    at ``final_velocity``. Speed and acceleration bounds are met (except the
    initial excess speed, which only decreases).

    Args:
        distance: Signed target coordinate [m or rad].
        max_velocity: Speed bound, > 0.
        max_acceleration: Acceleration bound, > 0.
        initial_velocity: Signed speed at t = 0, any finite value.
        final_velocity: Signed speed at the end, ``|vf| <= max_velocity``.
        check: Validate the arguments; False skips that for floats known to
            be valid (the online planner's replanning path).

    Raises:
        NonFiniteError: If an argument is NaN or infinite.
        InputError: If a limit is <= 0 or ``|final_velocity| > max_velocity``.
    """
    d, vmax, amax = distance, max_velocity, max_acceleration
    v0, vf = initial_velocity, final_velocity
    if check:
        d = _finite(distance, "distance")
        vmax = _positive(max_velocity, "max_velocity")
        amax = _positive(max_acceleration, "max_acceleration")
        v0 = _finite(initial_velocity, "initial_velocity")
        vf = _finite(final_velocity, "final_velocity")
        if abs(vf) > vmax:
            raise InputError(f"|final_velocity| must be <= {vmax:g}, got {vf:g}")
    return _time_optimal(d, v0, vf, vmax, amax)


def stopping_profile(
    initial_velocity: float, max_acceleration: float, *, check: bool = True
) -> TrapezoidalProfile:
    """Stop from ``initial_velocity`` at full deceleration (one phase).

    Args:
        initial_velocity: Signed speed at t = 0 [m/s or rad/s].
        max_acceleration: Deceleration, > 0.
        check: Validate the arguments (False: as in :func:`replan_trapezoid`).

    Returns:
        A profile of duration ``|v0| / a`` ending at rest after
        ``v0 |v0| / (2 a)``.

    Raises:
        NonFiniteError: If an argument is NaN or infinite.
        InputError: If ``max_acceleration`` <= 0.
    """
    v0, amax = initial_velocity, max_acceleration
    if check:
        v0 = _finite(initial_velocity, "initial_velocity")
        amax = _positive(max_acceleration, "max_acceleration")
    ramp = (abs(v0) / amax, -math.copysign(amax, v0))
    return _build([ramp], v0, 0.0, v0 * abs(v0) / (2.0 * amax))


__all__ = [
    "FEASIBILITY_RTOL",
    "TrapezoidalProfile",
    "replan_trapezoid",
    "stopping_profile",
    "trapezoid",
]
