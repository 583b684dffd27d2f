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

from workbench.poses import as_rotation
from workbench.trajectory.cartesian_paths import (
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
from workbench.trajectory.orientation_profile import (
    OrientationProfile,
    compute_relative_axis_angle,
)
from workbench.trajectory.trapezoidal_profile import (
    replan_trapezoid,
    stopping_profile,
)

FloatArray = npt.NDArray[np.float64]


def _unit(x: FloatArray) -> tuple[FloatArray, float]:
    norm = float(math.hypot(*x))
    return (x / norm if norm > ZERO_TOL else x * 0.0), norm


def _with_residual(
    path: PositionPath, residual: FloatArray, vmax: float, amax: float
) -> PositionPath:
    direction, speed = _unit(residual)
    if speed <= ZERO_TOL:
        return path
    back = replan_trapezoid(0.0, vmax, amax, initial_velocity=speed)
    return OffsetPath(path, direction, back)


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
    """
    delta = np.asarray(goal, dtype=np.float64) - state.position
    direction, distance = _unit(delta)
    if distance <= ZERO_TOL:
        direction, _ = _unit(state.velocity)
        if not direction.any():
            direction = np.array([1.0, 0.0, 0.0])
    along = float(state.velocity @ direction)
    profile = replan_trapezoid(
        distance,
        max_velocity,
        max_acceleration,
        initial_velocity=along,
        final_velocity=final_velocity,
    )
    line = LinePath(state.position.copy(), direction, profile)
    residual = state.velocity - along * direction
    return _with_residual(line, residual, max_velocity, max_acceleration)


def plan_rotation(
    state: CartesianState,
    goal: FloatArray,
    max_velocity: float,
    max_acceleration: float,
) -> OrientationPath:
    """Shortest rotation from the state's orientation to ``goal`` (3, 3), at rest.

    ``state.rotation`` is taken as a rotation (the planner's own state); the
    goal is checked (``InputError`` if it is not a rotation).
    """
    goal = as_rotation(goal, "goal rotation")
    axis, angle = compute_relative_axis_angle(state.rotation, goal, check=False)
    omega = state.angular_velocity
    if angle <= ZERO_TOL and math.hypot(*omega) > ZERO_TOL:
        axis, _ = _unit(state.rotation.T @ omega)
    axis_base = state.rotation @ axis
    along = float(omega @ axis_base)
    profile = replan_trapezoid(
        angle, max_velocity, max_acceleration, initial_velocity=along
    )
    path: OrientationPath = OrientationProfile(
        state.rotation.copy(),
        goal.copy(),
        axis,
        axis_base,
        angle,
        profile,
    )
    turn_axis, speed = _unit(omega - along * axis_base)
    if speed > ZERO_TOL:
        back = replan_trapezoid(
            0.0, max_velocity, max_acceleration, initial_velocity=speed
        )
        path = TurnedOrientation(path, turn_axis, back)
    return path


def plan_move(
    state: CartesianState,
    position: npt.ArrayLike,
    rotation: npt.ArrayLike,
    limits: CartesianLimits,
    *,
    final_velocity: float = 0.0,
) -> CartesianMotion:
    """Move from a moving state to a pose: straight line and shortest rotation.

    Args:
        state: Current tip state (continuity is kept from it).
        position: Goal position (3,) [m], same frame as ``state``.
        rotation: Goal orientation (3, 3).
        limits: Cartesian bounds.
        final_velocity: Speed [m/s] along the line at the goal, in
            ``[0, limits.max_velocity]``; the rotation always ends at rest.

    Returns:
        The motion; position and orientation end at their own instants.
    """
    return CartesianMotion(
        plan_line(
            state,
            np.asarray(position, dtype=np.float64),
            limits.max_velocity,
            limits.max_acceleration,
            final_velocity=final_velocity,
        ),
        plan_rotation(
            state,
            np.asarray(rotation, dtype=np.float64),
            limits.max_angular_velocity,
            limits.max_angular_acceleration,
        ),
    )


def plan_stop(state: CartesianState, limits: CartesianLimits) -> CartesianMotion:
    """Bring the tip to rest at full linear and angular deceleration.

    The tip keeps its direction of motion and its axis of rotation while it
    decelerates, so the stop is as short as the bounds allow.
    """
    direction, speed = _unit(state.velocity)
    position: PositionPath = FixedPosition(state.position.copy())
    if speed > ZERO_TOL:
        profile = stopping_profile(speed, limits.max_acceleration)
        position = LinePath(state.position.copy(), direction, profile)
    axis, spin = _unit(state.angular_velocity)
    orientation: OrientationPath = FixedOrientation(state.rotation.copy())
    if spin > ZERO_TOL:
        profile = stopping_profile(spin, limits.max_angular_acceleration)
        orientation = TurnedOrientation(orientation, axis, profile)
    return CartesianMotion(position, orientation)


__all__ = ["plan_line", "plan_move", "plan_rotation", "plan_stop"]
