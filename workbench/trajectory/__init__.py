"""Trajectories: Angeles' normal spline and the pick-and-place motions built on it.

Public entry points (see INTERFACE.md): ``pick_and_place``, ``minimum_duration``.
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
from workbench.trajectory.cartesian import (
    CartesianSamples,
    IKChoice,
    PosePickAndPlace,
    as_target_pose,
    compute_cartesian_trajectory,
    pick_and_place_from_poses,
    select_ik_solution,
)
from workbench.trajectory.limits import (
    JointExtrema,
    LimitViolation,
    check_limits,
    minimum_duration,
    raise_for_violations,
)
from workbench.trajectory.normal_spline import (
    NormalSpline,
    SplineExtremum,
    UniformCubicSpline,
    compute_literal_spline,
    compute_normal_spline,
    get_normal_spline,
)
from workbench.trajectory.pick_and_place import JointTrajectory, pick_and_place
from workbench.trajectory.segments import SegmentedTrajectory, pick_via_place
from workbench.trajectory.time_optimal import (
    TimeOptimalComparison,
    compare_time_optimal,
    compute_time_optimal_duration,
    compute_toppra_duration,
)

__all__ = [
    "CartesianLimits",
    "CartesianMotion",
    "CartesianSamples",
    "CartesianState",
    "Hold",
    "IKChoice",
    "JointExtrema",
    "JointTrajectory",
    "LimitViolation",
    "MotionPrimitive",
    "NormalSpline",
    "OnlinePlanner",
    "OrientationProfile",
    "PlannerSample",
    "PointToPoint",
    "PosePickAndPlace",
    "SegmentedTrajectory",
    "SemiCircleUp",
    "SplineExtremum",
    "Stop",
    "StraightLine",
    "TimeOptimalComparison",
    "TrapezoidalProfile",
    "UniformCubicSpline",
    "as_target_pose",
    "check_limits",
    "compare_time_optimal",
    "compute_cartesian_trajectory",
    "compute_literal_spline",
    "compute_normal_spline",
    "compute_relative_axis_angle",
    "compute_time_optimal_duration",
    "compute_toppra_duration",
    "get_normal_spline",
    "interpolate_servo",
    "minimum_duration",
    "orientation",
    "pick_and_place",
    "pick_and_place_from_poses",
    "pick_via_place",
    "plan_move",
    "plan_stop",
    "raise_for_violations",
    "replan_trapezoid",
    "select_ik_solution",
    "stopping_profile",
    "trapezoid",
]
