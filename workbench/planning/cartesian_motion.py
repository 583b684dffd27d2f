r"""Cartesian tool motions planned from a moving state (Kang 2007, §5, Fig. 6).

A :class:`CartesianMotion` pairs a position path with an orientation path,
each driven by its own trapezoidal profile, so that position and orientation
may end at different instants (Kang: "the maximum linear and angular
accelerations are used so that the position and orientation planning might
end at different instants in time").

Replanning from a moving state (:func:`plan_move`, :func:`plan_stop`) keeps
position and velocity continuous. The velocity is split into its component
along the new path, which the path's profile starts from, and the rest, which
an additive *residual* brings back to zero at full deceleration and then
returns to the path (an overshoot), so the goal is still reached exactly:

.. math:: p(t) = p_0 + e\,s(t) + n\,r(t), \qquad
          R(t) = \mathrm{Rot}(m, \rho(t))\, R_0 \mathrm{Rot}(u, \theta(t)),

with ``r`` and ρ profiles from (0, speed) back to (0, 0). Each component
respects its speed and acceleration bound; during a redirection with a
residual the norm of the sum may exceed a bound by up to √2 (and the angular
acceleration by the cross term :math:`\dot\rho\,\dot\theta` as the turning
residual swings the main axis). Replans along the current direction of
motion, such as every event of the fish-cutting program, have no residual.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.planning.cartesian_paths import (
    ZERO_TOL,
    CartesianLimits,
    CartesianMotion,
    CartesianState,
    FixedOrientation,
    FixedPosition,
    LinePath,
    OffsetPath,
    OrientationPath,
    PositionPath,
    TurnedOrientation,
)
from workbench.planning.orientation_profile import (
    OrientationProfile,
    compute_relative_axis_angle,
)
from workbench.planning.trapezoidal_profile import (
    replan_trapezoid,
    stopping_profile,
)
from workbench.poses import as_rotation
from workbench.validation import as_vector

FloatArray = npt.NDArray[np.float64]


def _unit(x: list[float]) -> tuple[list[float], float]:
    """Unit vector along ``x`` and its norm; zero below ``ZERO_TOL``.

    Plain floats: replanning runs in one planning cycle, where numpy calls on
    3-vectors cost microseconds each.
    """
    norm = math.hypot(*x)
    if norm <= ZERO_TOL:
        return [0.0, 0.0, 0.0], norm
    return [c / norm for c in x], norm


def split_velocity(
    velocity: list[float], direction: list[float]
) -> tuple[float, list[float], float]:
    """Split a velocity (3 floats) about a unit ``direction`` (3 floats).

    Returns:
        ``(along, rest_direction, rest_speed)``: the speed along
        ``direction``, and the unit vector and norm of the remainder (zero
        vector below ``ZERO_TOL``).
    """
    (vx, vy, vz), (ex, ey, ez) = velocity, direction
    along = vx * ex + vy * ey + vz * ez
    rest, speed = _unit([vx - along * ex, vy - along * ey, vz - along * ez])
    return along, rest, speed


def add_residual(
    path: PositionPath,
    direction: list[float],
    speed: float,
    max_velocity: float,
    max_acceleration: float,
) -> PositionPath:
    """``path`` plus a residual that starts at ``speed`` along ``direction``.

    The residual decelerates at ``max_acceleration`` and comes back to zero
    offset; none when ``speed`` is below ``ZERO_TOL``.
    """
    if speed <= ZERO_TOL:
        return path
    back = replan_trapezoid(
        0.0, max_velocity, max_acceleration, initial_velocity=speed, check=False
    )
    return OffsetPath(path, np.array(direction), back)


def plan_line(
    state: CartesianState,
    goal: FloatArray,
    max_velocity: float,
    max_acceleration: float,
    *,
    final_velocity: float = 0.0,
) -> PositionPath:
    """Straight line from the state's position to ``goal`` (3,) [m].

    The tip arrives at ``final_velocity`` [m/s] along the line. The part of the
    current velocity across the line is brought back to zero by a residual.
    Arguments are trusted (finite; the primitives check them when built).
    """
    start, velocity = state.position.tolist(), state.velocity.tolist()
    (gx, gy, gz), (px, py, pz) = goal.tolist(), start
    delta = [gx - px, gy - py, gz - pz]
    direction, distance = _unit(delta)
    if distance <= ZERO_TOL:
        direction, _ = _unit(velocity)
        if not any(direction):
            direction = [1.0, 0.0, 0.0]
    along, rest, speed = split_velocity(velocity, direction)
    profile = replan_trapezoid(
        distance,
        max_velocity,
        max_acceleration,
        initial_velocity=along,
        final_velocity=final_velocity,
        check=False,
    )
    line = LinePath(state.position.copy(), np.array(direction), profile)
    return add_residual(line, rest, speed, max_velocity, max_acceleration)


def plan_rotation(
    state: CartesianState,
    goal: FloatArray,
    max_velocity: float,
    max_acceleration: float,
    *,
    check: bool = True,
) -> OrientationPath:
    """Shortest rotation from the state's orientation to ``goal`` (3, 3), at rest.

    ``state.rotation`` is taken as a rotation (the planner's own state); the
    goal is checked (``InputError`` if it is not a rotation) unless ``check``
    is False (a goal checked before).
    """
    if check:
        goal = as_rotation(goal, "goal rotation")
    axis, angle = compute_relative_axis_angle(state.rotation, goal, check=False)
    omega = state.angular_velocity.tolist()
    if angle <= ZERO_TOL and math.hypot(*omega) > ZERO_TOL:
        axis = np.array(_unit((state.rotation.T @ state.angular_velocity).tolist())[0])
    axis_base = state.rotation @ axis
    along, turn_axis, speed = split_velocity(omega, axis_base.tolist())
    profile = replan_trapezoid(
        angle, max_velocity, max_acceleration, initial_velocity=along, check=False
    )
    path: OrientationPath = OrientationProfile(
        state.rotation.copy(), goal.copy(), axis, axis_base, angle, profile
    )
    if speed > ZERO_TOL:
        back = replan_trapezoid(
            0.0, max_velocity, max_acceleration, initial_velocity=speed, check=False
        )
        path = TurnedOrientation(path, np.array(turn_axis), back)
    return path


def hold_rotation(
    state: CartesianState, max_velocity: float, max_acceleration: float
) -> OrientationPath:
    """Keep the state's orientation: :func:`plan_rotation` to ``state.rotation``.

    At rest it is held fixed; a spinning tool stops at full deceleration and
    turns back to it.
    """
    rotation = FixedOrientation(state.rotation.copy())
    axis, spin = _unit(state.angular_velocity.tolist())
    if spin <= ZERO_TOL:
        return rotation
    back = replan_trapezoid(
        0.0, max_velocity, max_acceleration, initial_velocity=spin, check=False
    )
    return TurnedOrientation(rotation, np.array(axis), back)


def plan_move(
    state: CartesianState,
    position: npt.ArrayLike,
    rotation: npt.ArrayLike,
    limits: CartesianLimits,
    *,
    final_velocity: float = 0.0,
    check: bool = True,
) -> CartesianMotion:
    """Move from a moving state to a pose: straight line and shortest rotation.

    Args:
        state: Current tip state (continuity is kept from it).
        position: Goal position (3,) [m], same frame as ``state``.
        rotation: Goal orientation (3, 3).
        limits: Cartesian bounds.
        final_velocity: Speed [m/s] along the line at the goal, in
            ``[0, limits.max_velocity]``; the rotation always ends at rest.
        check: Validate the goal and ``final_velocity``; False for a goal
            checked before (float arrays, a rotation; the planner's primitives).

    Returns:
        The motion; position and orientation end at their own instants.

    Raises:
        InputError: If the goal is not a finite position and a rotation, or
            ``final_velocity`` is out of range (``NonFiniteError`` on NaN).
    """
    goal = np.asarray(position, dtype=np.float64)
    if check:
        vmax = limits.max_velocity
        if not 0.0 <= final_velocity <= vmax:  # also False for NaN
            raise InputError(
                f"final_velocity must be in [0, {vmax:g}], got {final_velocity!r}"
            )
        goal = as_vector(position, 3, "position")
    return CartesianMotion(
        plan_line(
            state,
            goal,
            limits.max_velocity,
            limits.max_acceleration,
            final_velocity=final_velocity,
        ),
        plan_rotation(
            state,
            np.asarray(rotation, dtype=np.float64),
            limits.max_angular_velocity,
            limits.max_angular_acceleration,
            check=check,
        ),
    )


def plan_stop(state: CartesianState, limits: CartesianLimits) -> CartesianMotion:
    """Bring the tip to rest at full linear and angular deceleration.

    The tip keeps its direction of motion and its axis of rotation while it
    decelerates, so the stop is as short as the bounds allow.
    """
    direction, speed = _unit(state.velocity.tolist())
    position: PositionPath = FixedPosition(state.position.copy())
    if speed > ZERO_TOL:
        profile = stopping_profile(speed, limits.max_acceleration, check=False)
        position = LinePath(state.position.copy(), np.array(direction), profile)
    axis, spin = _unit(state.angular_velocity.tolist())
    orientation: OrientationPath = FixedOrientation(state.rotation.copy())
    if spin > ZERO_TOL:
        profile = stopping_profile(spin, limits.max_angular_acceleration, check=False)
        orientation = TurnedOrientation(orientation, np.array(axis), profile)
    return CartesianMotion(position, orientation)


__all__ = [
    "add_residual",
    "hold_rotation",
    "plan_line",
    "plan_move",
    "plan_rotation",
    "plan_stop",
    "split_velocity",
]
