"""Online Cartesian planning after Kang (2007).

Trapezoidal speed profiles and quaternion orientation profiles, Cartesian paths and
motions, the motion primitives of Kang's Fig. 7 (point-to-point, straight line,
semicircle, stop, hold), the online planner (closed-form IK with branch continuity, DLS
joint rates near singularities, replanning on events) and the servo-rate interpolation.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from workbench._lazy import attach

if TYPE_CHECKING:
    from workbench.planning.cartesian_motion import plan_move, plan_stop
    from workbench.planning.cartesian_paths import (
        CartesianLimits,
        CartesianMotion,
        CartesianState,
    )
    from workbench.planning.motion_primitives import (
        Hold,
        MotionPrimitive,
        PointToPoint,
        SemiCircleUp,
        Stop,
        StraightLine,
    )
    from workbench.planning.online_planner import OnlinePlanner, PlannerSample
    from workbench.planning.orientation_profile import (
        OrientationProfile,
        compute_relative_axis_angle,
        orientation,
    )
    from workbench.planning.redundancy_policy import (
        DEFAULT_MAX_REDUNDANCY_RATE,
        FAST_SHARE,
        KEEP_LIMIT_MARGIN,
        LIMIT_SHARPNESS,
        MAX_POSE_STEPS,
        MIN_STEP,
        POSE_TOL,
        PROBE_STEP,
        RATE_RAMP_TIME,
        REDUNDANCY_POLICIES,
        SINGULAR_GAIN,
        RedundancyTracker,
        compute_limit_gradient,
        compute_limit_margin,
        compute_limit_score,
        compute_manipulability_gradient,
    )
    from workbench.planning.servo_interpolation import interpolate_servo
    from workbench.planning.trapezoidal_profile import (
        TrapezoidalProfile,
        replan_trapezoid,
        stopping_profile,
        trapezoid,
    )

__all__ = [
    "DEFAULT_MAX_REDUNDANCY_RATE",
    "FAST_SHARE",
    "KEEP_LIMIT_MARGIN",
    "LIMIT_SHARPNESS",
    "MAX_POSE_STEPS",
    "MIN_STEP",
    "POSE_TOL",
    "PROBE_STEP",
    "RATE_RAMP_TIME",
    "REDUNDANCY_POLICIES",
    "SINGULAR_GAIN",
    "CartesianLimits",
    "CartesianMotion",
    "CartesianState",
    "Hold",
    "MotionPrimitive",
    "OnlinePlanner",
    "OrientationProfile",
    "PlannerSample",
    "PointToPoint",
    "RedundancyTracker",
    "SemiCircleUp",
    "Stop",
    "StraightLine",
    "TrapezoidalProfile",
    "compute_limit_gradient",
    "compute_limit_margin",
    "compute_limit_score",
    "compute_manipulability_gradient",
    "compute_relative_axis_angle",
    "interpolate_servo",
    "orientation",
    "plan_move",
    "plan_stop",
    "replan_trapezoid",
    "stopping_profile",
    "trapezoid",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
