"""Motion primitives of Kang's path planner (2007, Fig. 7), planned online.

Each primitive is planned when it starts, from the *actual* state the previous
one left (Kang's ``vi`` flag: a primitive that follows one ending at full speed
starts at full speed), so consecutive primitives join without a jump in
position or velocity. Kang's start points ``P1`` are therefore not arguments:
the start is where the tool is. The ``vf`` flag is ``end_at_speed``.

| Kang (Fig. 7)                  | here                                      |
| ------------------------------ | ----------------------------------------- |
| ``PTP(P1, P2)``                | ``PointToPoint(position, rotation)``      |
| ``StraightLine(P1, P2, vi, vf)`` | ``StraightLine(position, end_at_speed=vf)`` |
| ``SemiCircleUp(P1, P2)``       | ``SemiCircleUp(position)``                |

The fish-cutting primitives that react to touch events live in
:mod:`workbench.tasks.cuts`. A primitive object is stateful and used once.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.planning.cartesian_motion import (
    add_residual,
    hold_rotation,
    plan_line,
    plan_move,
    plan_stop,
    split_velocity,
)
from workbench.planning.cartesian_paths import (
    ArcPath,
    CartesianLimits,
    CartesianMotion,
    CartesianState,
    FixedOrientation,
    FixedPosition,
)
from workbench.planning.trapezoidal_profile import replan_trapezoid
from workbench.poses import as_rotation
from workbench.validation import as_vector

FloatArray = npt.NDArray[np.float64]

#: Height difference [m] tolerated between the ends of a semicircle.
LEVEL_TOL = 1e-6


class MotionPrimitive:
    """Base class: one or more Cartesian motions, planned from the actual state.

    Subclasses implement :meth:`plan`; multi-stage ones also :meth:`advance`
    (next stage when a motion ends) and :meth:`on_contact` (react to events).
    """

    def __init__(self) -> None:
        self._motion: CartesianMotion | None = None
        self._start = 0.0
        self._end = 0.0

    def plan(self, state: CartesianState, limits: CartesianLimits) -> CartesianMotion:
        """The first motion of the primitive, from ``state``."""
        raise NotImplementedError

    def begin(self, state: CartesianState, t: float, limits: CartesianLimits) -> None:
        """Plan from ``state`` and start at time ``t`` [s]."""
        self.set_motion(self.plan(state, limits), t)

    def set_motion(self, motion: CartesianMotion, t: float) -> None:
        """Replace the current motion by ``motion`` starting at ``t`` [s]."""
        self._motion, self._start = motion, t
        self._end = t + motion.duration

    @property
    def motion(self) -> CartesianMotion:
        """The motion being executed."""
        if self._motion is None:
            raise InputError(f"{type(self).__name__} has not begun")
        return self._motion

    @property
    def start_time(self) -> float:
        """Start time [s] of the current motion."""
        return self._start

    @property
    def end_time(self) -> float:
        """End time [s] of the current motion (inf for a hold)."""
        if self._motion is None:
            raise InputError(f"{type(self).__name__} has not begun")
        return self._end

    def sample(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """``(p, v, R, omega)`` of the current motion at absolute time ``t``."""
        return self._motion.sample(t - self._start)  # type: ignore[union-attr]

    def get_state(self, t: float) -> CartesianState:
        """The state at absolute time ``t`` [s]."""
        return CartesianState(*self.sample(t))

    def advance(self, t: float, state: CartesianState, limits: CartesianLimits) -> bool:
        """Start the next stage at ``t`` when the current motion has ended.

        Returns:
            True if a new motion was started, False if the primitive is done.
        """
        return False

    def on_contact(
        self,
        contact: str | None,
        t: float,
        state: CartesianState,
        limits: CartesianLimits,
    ) -> str | None:
        """React to what the tool touches at time ``t`` (``state``).

        Args:
            contact: What the tool tip is in: e.g. ``"flesh"``, ``"bone"`` or
                None.
            t: Time [s] of ``state``, the last commanded sample.
            state: The tool state at ``t``.
            limits: Cartesian bounds.

        Returns:
            The event name if the primitive replanned, else None.
        """
        return None


def _goal(position: npt.ArrayLike) -> FloatArray:
    p = as_vector(position, 3, "position").copy()
    p.setflags(write=False)
    return p


class Hold(MotionPrimitive):
    """Stay at rest where the tool is, for ever (the tool must be at rest)."""

    def plan(self, state: CartesianState, limits: CartesianLimits) -> CartesianMotion:
        """Fixed pose, infinite duration."""
        return CartesianMotion(
            FixedPosition(state.position.copy(), math.inf),
            FixedOrientation(state.rotation.copy(), math.inf),
        )


class Stop(MotionPrimitive):
    """Come to rest at full linear and angular deceleration."""

    def plan(self, state: CartesianState, limits: CartesianLimits) -> CartesianMotion:
        """See :func:`~workbench.planning.cartesian_motion.plan_stop`."""
        return plan_stop(state, limits)


class PointToPoint(MotionPrimitive):
    """Kang's ``PTP``: straight line and quaternion rotation, ending at rest.

    Position and orientation follow their own trapezoidal profiles (linear
    and angular limits) and may end at different instants (Kang, Fig. 6).

    Args:
        position: Goal position (3,) [m], in the planner's frame.
        rotation: Goal orientation (3, 3).

    Raises:
        InputError: If the goal is not a finite position and a rotation.
    """

    def __init__(self, position: npt.ArrayLike, rotation: npt.ArrayLike) -> None:
        super().__init__()
        self.position = _goal(position)
        self.rotation = as_rotation(rotation, "rotation").copy()

    def plan(self, state: CartesianState, limits: CartesianLimits) -> CartesianMotion:
        """Plan from ``state``; see :func:`plan_move`."""
        return plan_move(state, self.position, self.rotation, limits, check=False)


class StraightLine(MotionPrimitive):
    """Kang's ``StraightLine``: a straight line at constant orientation.

    Args:
        position: Goal position (3,) [m].
        end_at_speed: Kang's ``vf = 1``: arrive at ``max_velocity`` and hand
            over to the next primitive at that speed.
        max_velocity: Speed bound [m/s]; default the planner's linear limit.
    """

    def __init__(
        self,
        position: npt.ArrayLike,
        *,
        end_at_speed: bool = False,
        max_velocity: float | None = None,
    ) -> None:
        super().__init__()
        self.position = _goal(position)
        self.end_at_speed = end_at_speed
        self.max_velocity = max_velocity

    def plan(self, state: CartesianState, limits: CartesianLimits) -> CartesianMotion:
        """Plan from ``state``; the orientation of ``state`` is kept."""
        vmax = self.max_velocity or limits.max_velocity
        return CartesianMotion(
            plan_line(
                state,
                self.position,
                vmax,
                limits.max_acceleration,
                final_velocity=vmax if self.end_at_speed else 0.0,
            ),
            hold_rotation(
                state, limits.max_angular_velocity, limits.max_angular_acceleration
            ),
        )


class SemiCircleUp(MotionPrimitive):
    """Kang's ``SemiCircleUp``: an upward half circle to a point at the same height.

    The circle lies in the vertical plane through the start and the goal; it
    leaves the start going straight up and reaches the goal going straight
    down, at full speed (``end_at_speed``), so it joins a ``StraightLine`` up
    and a ``VerticalDownCut`` at full speed without a velocity jump. The
    centripetal acceleration is ``v² / r``: keep the radius above
    ``max_velocity² / max_acceleration``.

    Args:
        position: Goal position (3,) [m], at the start's height.
        up: Upward unit vector (3,) of the planner's frame.
        end_at_speed: Arrive at full speed (Kang); False ends at rest.
    """

    def __init__(
        self,
        position: npt.ArrayLike,
        *,
        up: npt.ArrayLike = (0.0, 0.0, 1.0),
        end_at_speed: bool = True,
    ) -> None:
        super().__init__()
        self.position = _goal(position)
        up_vector = as_vector(up, 3, "up")
        self.up = up_vector / math.hypot(*up_vector)
        self.end_at_speed = end_at_speed

    def plan(self, state: CartesianState, limits: CartesianLimits) -> CartesianMotion:
        """Plan from ``state``.

        Raises:
            InputError: If the goal is not at the start's height or coincides
                with the start.
        """
        start, velocity = state.position.tolist(), state.velocity.tolist()
        (gx, gy, gz), (px, py, pz) = self.position.tolist(), start
        chord = [gx - px, gy - py, gz - pz]
        up = self.up.tolist()
        rise = chord[0] * up[0] + chord[1] * up[1] + chord[2] * up[2]
        if abs(rise) > LEVEL_TOL:
            raise InputError(
                f"SemiCircleUp needs its ends at one height; the goal is {rise:.6g} m "
                "above the start"
            )
        radius = 0.5 * math.hypot(*chord)
        if radius <= LEVEL_TOL:
            raise InputError("SemiCircleUp needs a goal away from the start")
        center = np.array(
            [px + 0.5 * chord[0], py + 0.5 * chord[1], pz + 0.5 * chord[2]]
        )
        radial = np.array([-0.5 * c / radius for c in chord])
        along, rest, speed = split_velocity(velocity, up)
        vmax, amax = limits.max_velocity, limits.max_acceleration
        profile = replan_trapezoid(
            math.pi * radius,
            vmax,
            amax,
            initial_velocity=along,
            final_velocity=vmax if self.end_at_speed else 0.0,
            check=False,
        )
        arc = ArcPath(center, radial, self.up.copy(), radius, profile)
        path = add_residual(arc, rest, speed, vmax, amax)
        orientation = hold_rotation(
            state, limits.max_angular_velocity, limits.max_angular_acceleration
        )
        return CartesianMotion(path, orientation)


__all__ = [
    "LEVEL_TOL",
    "Hold",
    "MotionPrimitive",
    "PointToPoint",
    "SemiCircleUp",
    "Stop",
    "StraightLine",
]
