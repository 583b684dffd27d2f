r"""A polyline of joint-space waypoints, checked, and the path bounds of its segments.

Segment s, :math:`\Delta_s = w_{s+1} - w_s`, moves joint i by
:math:`|\Delta_{s,i}|`, so the joint limits bound its path parameter by
:math:`V_s = \min_i v_i / |\Delta_{s,i}|` and
:math:`A_s = \min_i a_i / |\Delta_{s,i}|` (joints that stay out of the minimum).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.trajectory.limits import LIMIT_RTOL
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]

#: Consecutive waypoints closer than this in every joint [rad] are one waypoint.
REPEAT_TOL = 1e-12


def _check_scale(value: float, name: str) -> float:
    try:
        scale = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number in (0, 1], got {value!r}") from None
    if isinstance(value, bool) or not (0.0 < scale <= 1.0):
        raise InputError(f"{name} must be a number in (0, 1], got {value!r}")
    return scale


def check_waypoints(robot: Robot, waypoints: npt.ArrayLike) -> FloatArray:
    """The waypoints as a new (K, nq) array, checked.

    Raises:
        NonFiniteError, InputError: As :func:`~workbench.motion.time_scale`.
    """
    if robot.nq != robot.nv:
        raise InputError(
            f"robot {robot.name} has nq = {robot.nq} != nv = {robot.nv} (continuous "
            "or multi-coordinate joints); the time scaling needs one coordinate "
            "per joint"
        )
    try:
        points = np.array(waypoints, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(
            f"waypoints must be numbers of shape (K, {robot.nq}), got {waypoints!r}"
        ) from None
    if points.ndim != 2 or points.shape[1] != robot.nq:
        raise InputError(
            f"waypoints must have shape (K, {robot.nq}), got shape {points.shape}"
        )
    points = as_finite_array(points, points.shape, "waypoints")
    if points.shape[0] < 2:
        raise InputError(
            f"at least two waypoints are needed, got {points.shape[0]} (one "
            "configuration is no motion)"
        )
    lower, upper = np.asarray(robot.lower), np.asarray(robot.upper)
    outside = (points < lower - LIMIT_RTOL * np.abs(lower)) | (
        points > upper + LIMIT_RTOL * np.abs(upper)
    )
    if outside.any():
        k, i = (int(x[0]) for x in np.nonzero(outside))
        raise InputError(
            f"waypoint {k}: joint {robot.joint_names[i]} at {points[k, i]:.6g} rad "
            f"is outside its limits [{lower[i]:.6g}, {upper[i]:.6g}] rad"
        )
    step = np.max(np.abs(np.diff(points, axis=0)), axis=1)
    repeated = np.flatnonzero(step <= REPEAT_TOL)
    if repeated.size:
        k = int(repeated[0])
        raise InputError(
            f"waypoints {k} and {k + 1} are the same configuration (within "
            f"{REPEAT_TOL:g} rad in every joint): remove repeated waypoints"
        )
    return points


def compute_path_bounds(
    robot: Robot,
    waypoints: npt.ArrayLike,
    velocity_scale: float,
    acceleration_scale: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    r"""Checked waypoints (K, nq) and each segment's :math:`V_s, A_s` (K - 1,)."""
    points = check_waypoints(robot, waypoints)
    v_scale = _check_scale(velocity_scale, "velocity_scale")
    a_scale = _check_scale(acceleration_scale, "acceleration_scale")
    limits = (
        np.asarray(robot.velocity_limit) * v_scale,
        np.asarray(robot.acceleration_limit) * a_scale,
    )
    distance = np.abs(np.diff(points, axis=0))
    moving = np.any(distance > 0.0, axis=0)
    for kind, limit in zip(("velocity", "acceleration"), limits, strict=True):
        unknown = moving & ~np.isfinite(limit)
        if unknown.any():
            names = [robot.joint_names[i] for i in np.flatnonzero(unknown)]
            raise InputError(
                f"robot {robot.name} gives no {kind} limit for {', '.join(names)}: "
                "the time scaling needs the speed and acceleration limits of every "
                "joint that moves (Robot.with_limits, --velocity-limit, "
                "--acceleration-limit)"
            )
    with np.errstate(divide="ignore"):
        speed, accel = (np.min(limit / distance, axis=1) for limit in limits)
    return points, speed, accel
