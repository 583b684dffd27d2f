"""Kang's fish-cutting primitives (2007, Fig. 7), reacting to touch events.

* :class:`VerticalDownCut` (Kang's ``VerticalDownCut(P1, P2, P3, vi)``): move
  down towards ``P2`` (the assumed bone position) at full speed; when the
  flesh is touched slow down to the cutting speed; when the bone is touched
  stop at full deceleration, then return to ``P3``. Without bone the tool
  stops at ``P2``.
* :class:`HorizontalCut` (Kang's ``HorizontalCut(P1, P2, vi, vf)``): cut
  horizontally at the cutting speed; whenever the bone is touched the tool
  rises by one step (Kang: "one step upward ... at the maximum cutting speed
  for one sampling period") and carries on at the new height.

Kang's one-period step is a velocity pulse; here the step is a rest-to-rest
trapezoid of the same height added to the horizontal motion, so the command
keeps a continuous velocity. As in :mod:`workbench.planning.motion_primitives`
the start ``P1`` and the ``vi`` flag are the actual state.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.planning.cartesian_motion import hold_rotation, plan_line, plan_stop
from workbench.planning.cartesian_paths import (
    CartesianLimits,
    CartesianMotion,
    CartesianState,
    OffsetPath,
)
from workbench.planning.motion_primitives import MotionPrimitive
from workbench.planning.trapezoidal_profile import replan_trapezoid
from workbench.tasks.fish import BONE, FLESH
from workbench.validation import as_vector

FloatArray = npt.NDArray[np.float64]

_UP = np.array([0.0, 0.0, 1.0])


def _speed(value: float, name: str) -> float:
    if not isinstance(value, float | int) or not math.isfinite(value) or value <= 0:
        raise InputError(f"{name} must be a finite number > 0, got {value!r}")
    return float(value)


def _line(
    state: CartesianState,
    goal: FloatArray,
    vmax: float,
    limits: CartesianLimits,
    final_velocity: float = 0.0,
) -> CartesianMotion:
    """Straight line at constant orientation, speed bounded by ``vmax``."""
    vmax = min(vmax, limits.max_velocity)
    return CartesianMotion(
        plan_line(
            state, goal, vmax, limits.max_acceleration, final_velocity=final_velocity
        ),
        hold_rotation(
            state, limits.max_angular_velocity, limits.max_angular_acceleration
        ),
    )


class VerticalDownCut(MotionPrimitive):
    """Cut down to the bone, slowing in the flesh, stopping at the bone.

    Args:
        bone_guess: Kang's ``P2`` (3,) [m]: where the bone is assumed; the tool
            stops there if it meets no bone.
        retreat: Kang's ``P3`` (3,) [m]: where the tool goes after the bone.
        cutting_speed: Speed in the flesh [m/s] (Kang: the speed reducing
            rate times the maximum speed).

    Attributes:
        stage: ``"approach"``, ``"cut"``, ``"stop"``, ``"retreat"``.
    """

    def __init__(
        self, bone_guess: npt.ArrayLike, retreat: npt.ArrayLike, *, cutting_speed: float
    ) -> None:
        super().__init__()
        self.bone_guess = as_vector(bone_guess, 3, "bone_guess").copy()
        self.retreat = as_vector(retreat, 3, "retreat").copy()
        self.cutting_speed = _speed(cutting_speed, "cutting_speed")
        self.stage = "approach"

    def plan(self, state: CartesianState, limits: CartesianLimits) -> CartesianMotion:
        """Down towards ``bone_guess`` at full speed."""
        self.stage = "approach"
        return _line(state, self.bone_guess, limits.max_velocity, limits)

    def advance(self, t: float, state: CartesianState, limits: CartesianLimits) -> bool:
        """After the stop at the bone, go to ``retreat``; else done."""
        if self.stage == "stop":
            self.stage = "retreat"
            self.set_motion(_line(state, self.retreat, limits.max_velocity, limits), t)
            return True
        return False

    def on_contact(
        self,
        contact: str | None,
        t: float,
        state: CartesianState,
        limits: CartesianLimits,
    ) -> str | None:
        """Flesh: slow to the cutting speed. Bone: stop at full deceleration."""
        if contact == BONE and self.stage in ("approach", "cut"):
            self.stage = "stop"
            self.set_motion(plan_stop(state, limits), t)
            return BONE
        if contact == FLESH and self.stage == "approach":
            self.stage = "cut"
            motion = _line(state, self.bone_guess, self.cutting_speed, limits)
            self.set_motion(motion, t)
            return FLESH
        return None


class HorizontalCut(MotionPrimitive):
    """Cut horizontally at the cutting speed, stepping up over the bone.

    The cut runs from the actual position to the goal's x, y at the actual
    height (which the bone steps raise).

    Args:
        goal: Kang's ``P2`` (3,) [m]; its z is ignored.
        cutting_speed: Cruise speed [m/s].
        step_height: Rise per bone touch [m] (Kang: cutting speed × one
            planning period).
        end_at_speed: Kang's ``vf = 1``: hand over at the cutting speed.

    Attributes:
        steps: Number of bone steps taken.
    """

    def __init__(
        self,
        goal: npt.ArrayLike,
        *,
        cutting_speed: float,
        step_height: float,
        end_at_speed: bool = False,
    ) -> None:
        super().__init__()
        self.goal = as_vector(goal, 3, "goal").copy()
        self.cutting_speed = _speed(cutting_speed, "cutting_speed")
        self.step_height = _speed(step_height, "step_height")
        self.end_at_speed = end_at_speed
        self.steps = 0
        self._rising_until = -math.inf

    def plan(self, state: CartesianState, limits: CartesianLimits) -> CartesianMotion:
        """Horizontal line to the goal's x, y at the current height."""
        goal = np.array([self.goal[0], self.goal[1], state.position[2]])
        vmax = min(self.cutting_speed, limits.max_velocity)
        return _line(state, goal, vmax, limits, vmax if self.end_at_speed else 0.0)

    def on_contact(
        self,
        contact: str | None,
        t: float,
        state: CartesianState,
        limits: CartesianLimits,
    ) -> str | None:
        """Bone: add a rest-to-rest rise of ``step_height`` (one at a time)."""
        if contact != BONE or t < self._rising_until:
            return None
        vmax = min(self.cutting_speed, limits.max_velocity)
        rise = replan_trapezoid(  # from rest to rest, upwards (checked inputs)
            self.step_height,
            vmax,
            limits.max_acceleration,
            initial_velocity=0.0,
            check=False,
        )
        elapsed = t - self.start_time
        motion = self.motion
        position = OffsetPath(motion.position, _UP, rise, elapsed)
        self.set_motion(CartesianMotion(position, motion.orientation), self.start_time)
        self._rising_until = t + rise.duration
        self.steps += 1
        return BONE


__all__ = ["HorizontalCut", "VerticalDownCut"]
