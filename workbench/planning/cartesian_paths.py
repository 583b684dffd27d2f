"""Cartesian paths of the tool tip: states, limits, lines, arcs, rotations.

Every path has a ``duration`` [s] and ``sample(t)``: position paths give
``(p, v)``, orientation paths ``(R, omega)``, all in one frame (world or
base), angular velocity in that frame's axes; a :class:`CartesianMotion`
pairs one of each on one clock. Paths are immutable; they are planned by
:mod:`workbench.planning.cartesian_motion` and sampled once per planning
cycle, so ``sample`` is kept lean.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple, Protocol

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.planning.trapezoidal_profile import TrapezoidalProfile

FloatArray = npt.NDArray[np.float64]

ZERO_TOL = 1e-12

_ZERO3 = np.zeros(3)
_ZERO3.setflags(write=False)


class CartesianState(NamedTuple):
    """Pose and twist of the tool tip, all in one frame (world or base).

    Immutable (a named tuple: built once per planning cycle, so cheap to make).

    Attributes:
        position: Shape (3,) [m].
        velocity: Shape (3,) [m/s].
        rotation: Shape (3, 3), tool axes in the frame.
        angular_velocity: Shape (3,) [rad/s], in the frame's axes.
    """

    position: FloatArray
    velocity: FloatArray
    rotation: FloatArray
    angular_velocity: FloatArray

    @property
    def speed(self) -> float:
        """Norm of ``velocity`` [m/s]."""
        return float(math.hypot(*self.velocity))


@dataclass(frozen=True, slots=True)
class CartesianLimits:
    """Bounds of a Cartesian motion (validated on construction).

    Attributes:
        max_velocity: Tool-tip speed [m/s], > 0.
        max_acceleration: Tool-tip acceleration [m/s²], > 0.
        max_angular_velocity: [rad/s], > 0.
        max_angular_acceleration: [rad/s²], > 0.
    """

    max_velocity: float
    max_acceleration: float
    max_angular_velocity: float
    max_angular_acceleration: float

    def __post_init__(self) -> None:
        for name in self.__slots__:
            value = getattr(self, name)
            if not isinstance(value, float | int) or not math.isfinite(value):
                raise InputError(f"{name} must be a finite number, got {value!r}")
            if value <= 0.0:
                raise InputError(f"{name} must be > 0, got {value:g}")


class PositionPath(Protocol):
    """Anything with ``duration`` and ``sample(t) -> (p, v)``."""

    @property
    def duration(self) -> float: ...  # noqa: D102

    def sample(self, t: float) -> tuple[FloatArray, FloatArray]: ...  # noqa: D102


class OrientationPath(Protocol):
    """Anything with ``duration`` and ``sample(t) -> (R, omega)``."""

    @property
    def duration(self) -> float: ...  # noqa: D102

    def sample(self, t: float) -> tuple[FloatArray, FloatArray]: ...  # noqa: D102


@dataclass(frozen=True, slots=True)
class FixedPosition:
    """A position held still; ``duration`` 0."""

    position: FloatArray
    duration: float = 0.0

    def sample(self, t: float) -> tuple[FloatArray, FloatArray]:
        """``(p, 0)``."""
        return self.position, _ZERO3


@dataclass(frozen=True, slots=True)
class FixedOrientation:
    """An orientation held still; ``duration`` 0."""

    rotation: FloatArray
    duration: float = 0.0

    def sample(self, t: float) -> tuple[FloatArray, FloatArray]:
        """``(R, 0)``."""
        return self.rotation, _ZERO3


@dataclass(frozen=True, slots=True)
class LinePath:
    """``p(t) = start + direction * s(t)``, ``direction`` a unit vector."""

    start: FloatArray
    direction: FloatArray
    profile: TrapezoidalProfile

    @property
    def duration(self) -> float:
        """Duration of the profile [s]."""
        return self.profile.duration

    def sample(self, t: float) -> tuple[FloatArray, FloatArray]:
        """Position (3,) [m] and velocity (3,) [m/s] at ``t`` [s]."""
        s, sd, _ = self.profile.sample(t)
        return self.start + self.direction * s, self.direction * sd


@dataclass(frozen=True, slots=True)
class ArcPath:
    """Arc ``p = center + radius (cos φ radial + sin φ normal)``, φ = s / radius."""

    center: FloatArray
    radial: FloatArray
    normal: FloatArray
    radius: float
    profile: TrapezoidalProfile

    @property
    def duration(self) -> float:
        """Duration of the profile [s]."""
        return self.profile.duration

    def sample(self, t: float) -> tuple[FloatArray, FloatArray]:
        """Position (3,) [m] and velocity (3,) [m/s] at ``t`` [s]."""
        s, sd, _ = self.profile.sample(t)
        c, sn = math.cos(s / self.radius), math.sin(s / self.radius)
        p = (
            self.center
            + (c * self.radius) * self.radial
            + (sn * self.radius) * self.normal
        )
        return p, (-sn * sd) * self.radial + (c * sd) * self.normal


@dataclass(frozen=True, slots=True)
class OffsetPath:
    """``base(t) + direction * s(t - t0)``: a residual or a step added to a path."""

    base: PositionPath
    direction: FloatArray
    profile: TrapezoidalProfile
    t0: float = 0.0

    @property
    def duration(self) -> float:
        """End of the later of the two motions [s]."""
        return max(self.base.duration, self.t0 + self.profile.duration)

    def sample(self, t: float) -> tuple[FloatArray, FloatArray]:
        """Position (3,) [m] and velocity (3,) [m/s] at ``t`` [s]."""
        p, v = self.base.sample(t)
        if t < self.t0:  # the offset starts at t0 (with its initial speed)
            return p, v
        s, sd, _ = self.profile.sample(t - self.t0)
        return p + self.direction * s, v + self.direction * sd


@dataclass(frozen=True, slots=True)
class TurnedOrientation:
    """``Rot(axis, θ(t)) · base(t)``, ``axis`` fixed in the frame's axes."""

    base: OrientationPath
    axis: FloatArray
    profile: TrapezoidalProfile

    @property
    def duration(self) -> float:
        """End of the later of the two motions [s]."""
        return max(self.base.duration, self.profile.duration)

    def sample(self, t: float) -> tuple[FloatArray, FloatArray]:
        """Rotation (3, 3) and angular velocity (3,) [rad/s] at ``t`` [s]."""
        rotation, omega = self.base.sample(t)
        theta, theta_d, _ = self.profile.sample(t)
        turn = pin.exp3(self.axis * theta)
        return turn @ rotation, self.axis * theta_d + turn @ omega


@dataclass(frozen=True, slots=True)
class CartesianMotion:
    """A position path and an orientation path on one clock (t = 0 at start)."""

    position: PositionPath
    orientation: OrientationPath

    @property
    def duration(self) -> float:
        """End of the later of position and orientation [s]."""
        return max(self.position.duration, self.orientation.duration)

    def sample(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """``(p, v, R, omega)`` at ``t`` [s], shapes (3,), (3,), (3, 3), (3,)."""
        p, v = self.position.sample(t)
        rotation, omega = self.orientation.sample(t)
        return p, v, rotation, omega

    def get_state(self, t: float) -> CartesianState:
        """The sample at ``t`` as a :class:`CartesianState`."""
        return CartesianState(*self.sample(t))


__all__ = [
    "ZERO_TOL",
    "ArcPath",
    "CartesianLimits",
    "CartesianMotion",
    "CartesianState",
    "FixedOrientation",
    "FixedPosition",
    "LinePath",
    "OffsetPath",
    "OrientationPath",
    "PositionPath",
    "TurnedOrientation",
]
