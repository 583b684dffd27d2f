r"""Orientation planning with a quaternion and a trapezoidal angle (Kang 2007, §4).

The relative rotation :math:`R = R_1^T R_2` is converted to a unit quaternion
``quat_wxyz = [cos(θ/2), u sin(θ/2)]`` taken with ``w >= 0`` (the shortest
path, θ in [0, π]); its axis ``u`` (in the axes of the start frame) and angle θ
define the motion

.. math:: R(t) = R_1 \, \mathrm{Rot}(u, \theta(t)), \qquad
          \omega(t) = R_1 u \, \dot\theta(t) \ \text{(base axes)},

with θ(t) a trapezoidal profile from 0 to θ. The axis is fixed, so the tool
turns about one line through its origin. ``docs/errata-kang-orientation.md``
explains why the quaternion is taken with ``+u``, not Kang's ``−u``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.planning.trapezoidal_profile import TrapezoidalProfile, trapezoid
from workbench.poses import as_rotation, axis_angle_from_rotation
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]

#: Below this angle [rad] the relative rotation counts as none: the axis of a
#: smaller one would be noise, so the profile stays at ``R_start``.
ANGLE_EPS = 1e-15

_ZERO3 = np.zeros(3)
_ZERO3.setflags(write=False)


def _read_only(a: FloatArray) -> FloatArray:
    a = np.array(a, dtype=np.float64)
    a.setflags(write=False)
    return a


def _rotation(value: npt.ArrayLike, name: str) -> FloatArray:
    """:func:`~workbench.poses.as_rotation`, a non-rotation worded as such."""
    r = as_finite_array(value, (3, 3), name)  # NaN and shape errors as they are
    try:
        return as_rotation(r, name)
    except InputError as err:
        raise InputError(f"{name} is not a rotation: {err}") from None


def compute_relative_axis_angle(
    rotation_start: npt.ArrayLike, rotation_goal: npt.ArrayLike, *, check: bool = True
) -> tuple[FloatArray, float]:
    """Axis and angle of the shortest rotation from one orientation to another.

    Args:
        rotation_start: ``R_1``, shape (3, 3), tool frame in base frame.
        rotation_goal: ``R_2``, shape (3, 3).
        check: Validate both; False skips that for float (3, 3) arrays known
            to be rotations (the planner's replanning path).

    Returns:
        ``(u, angle)``: unit axis, shape (3,), in the axes of the start frame,
        and angle in [0, π] [rad], with ``R_2 = R_1 Rot(u, angle)``. At angle 0
        the axis is [1, 0, 0]; at π either sense is shortest and the one with
        its largest component positive is returned.

    Raises:
        InputError: If a matrix is not a rotation (NaN, shape, not orthonormal).
    """
    r1, r2 = rotation_start, rotation_goal
    if check:
        r1 = _rotation(rotation_start, "rotation_start")
        r2 = _rotation(rotation_goal, "rotation_goal")
    # the quaternion with w = cos(angle / 2) >= 0 is the shortest path: its
    # axis and angle in [0, pi] are those of the rotation matrix itself
    axis, angle = axis_angle_from_rotation(r1.T @ r2, check=False)
    if angle <= ANGLE_EPS:
        return np.array([1.0, 0.0, 0.0]), 0.0
    return axis, angle


@dataclass(frozen=True, slots=True)
class OrientationProfile:
    r"""Rotation about one fixed axis with a trapezoidal angle.

    Attributes:
        rotation_start: ``R_1``, shape (3, 3), read-only.
        rotation_goal: ``R_2``, shape (3, 3), read-only.
        axis: Unit axis ``u``, shape (3,), in start-frame axes, read-only.
        axis_base: The same axis in base axes, ``R_1 u``, read-only.
        angle: Total angle [rad], in [0, π].
        profile: The angle θ(t) from 0 to ``angle``.
    """

    rotation_start: FloatArray
    rotation_goal: FloatArray
    axis: FloatArray
    axis_base: FloatArray
    angle: float
    profile: TrapezoidalProfile

    @property
    def duration(self) -> float:
        """Time to reach ``rotation_goal`` [s]."""
        return self.profile.duration

    def sample(self, t: float) -> tuple[FloatArray, FloatArray]:
        """Orientation and angular velocity at time ``t`` [s].

        Returns:
            ``(R, omega)``: rotation (3, 3), tool frame in base frame, and
            angular velocity (3,) [rad/s] in base axes. After the end R stays
            at ``rotation_goal`` (exactly; the read-only array itself) unless
            the profile ends moving.
        """
        theta, theta_d, _ = self.profile.sample(t)
        if theta == self.angle and theta_d == 0.0:  # arrays are read-only
            return self.rotation_goal, _ZERO3
        rotation = self.rotation_start @ pin.exp3(self.axis * theta)
        return rotation, self.axis_base * theta_d

    def sample_acceleration(self, t: float) -> FloatArray:
        """Angular acceleration (3,) [rad/s²] in base axes at time ``t``."""
        return self.axis_base * self.profile.sample(t)[2]


def orientation(
    rotation_start: npt.ArrayLike,
    rotation_goal: npt.ArrayLike,
    max_velocity: float,
    max_acceleration: float,
    *,
    initial_velocity: float = 0.0,
    final_velocity: float = 0.0,
) -> OrientationProfile:
    """Plan a reorientation: shortest-path quaternion, trapezoidal angle.

    Args:
        rotation_start: ``R_1``, shape (3, 3), tool frame in base frame.
        rotation_goal: ``R_2``, shape (3, 3).
        max_velocity: Angular speed bound, > 0 [rad/s].
        max_acceleration: Angular acceleration bound, > 0 [rad/s²].
        initial_velocity: Angular speed about the axis at t = 0 [rad/s], as
            in :func:`~workbench.planning.trapezoidal_profile.trapezoid`.
        final_velocity: Angular speed at the end [rad/s].

    Returns:
        The profile; ``sample(t)`` gives ``(R, omega)``.

    Raises:
        InputError: If a matrix is not a rotation or a limit is not > 0
            (``NonFiniteError`` on NaN).
        InfeasibleError: If the angle is too small for the end speeds.
    """
    axis, angle = compute_relative_axis_angle(rotation_start, rotation_goal)
    profile = trapezoid(
        angle,
        max_velocity,
        max_acceleration,
        initial_velocity=initial_velocity,
        final_velocity=final_velocity,
    )
    r1 = np.asarray(rotation_start, dtype=np.float64)
    return OrientationProfile(
        rotation_start=_read_only(r1),
        rotation_goal=_read_only(rotation_goal),
        axis=_read_only(axis),
        axis_base=_read_only(r1 @ axis),
        angle=angle,
        profile=profile,
    )


__all__ = [
    "ANGLE_EPS",
    "OrientationProfile",
    "compute_relative_axis_angle",
    "orientation",
]
