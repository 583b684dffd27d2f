"""Online Cartesian planning after Kang (2007).

Trapezoidal speed profiles and quaternion orientation profiles, Cartesian paths and
motions, the motion primitives of Kang's Fig. 7 (point-to-point, straight line,
semicircle, stop, hold), the online planner (closed-form IK with branch continuity, DLS
joint rates near singularities, replanning on events) and the servo-rate interpolation.
"""

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
from workbench.planning.servo_interpolation import interpolate_servo
from workbench.planning.trapezoidal_profile import (
    TrapezoidalProfile,
    replan_trapezoid,
    stopping_profile,
    trapezoid,
)

__all__ = [
    "CartesianLimits",
    "CartesianMotion",
    "CartesianState",
    "Hold",
    "MotionPrimitive",
    "OnlinePlanner",
    "OrientationProfile",
    "PlannerSample",
    "PointToPoint",
    "SemiCircleUp",
    "Stop",
    "StraightLine",
    "TrapezoidalProfile",
    "compute_relative_axis_angle",
    "interpolate_servo",
    "orientation",
    "plan_move",
    "plan_stop",
    "replan_trapezoid",
    "stopping_profile",
    "trapezoid",
]
