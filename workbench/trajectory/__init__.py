"""Joint-space trajectories after Angeles et al. (1988).

The normal cubic spline with zero end velocity and acceleration, scaled per joint
between two inverse-kinematics solutions (``pick_and_place``; with via points,
``pick_via_place``); the Cartesian trajectory by forward kinematics; joint position
and speed limit checks; the minimum physically possible duration and its comparison
with a time-optimal parametrisation; joint trajectory CSV files. Kang's online
Cartesian planning is in :mod:`workbench.planning`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from workbench._lazy import attach

if TYPE_CHECKING:
    from workbench.trajectory.cartesian import (
        CartesianSamples,
        PosePickAndPlace,
        as_target_pose,
        compute_cartesian_trajectory,
        pick_and_place_from_poses,
    )
    from workbench.trajectory.csv_io import (
        MAX_SAMPLES,
        JointTrajectorySamples,
        TrajectoryFileError,
        check_sample_count,
        read_trajectory_csv,
        write_trajectory_csv,
    )
    from workbench.trajectory.limits import (
        JointExtrema,
        LimitViolation,
        check_limits,
        describe_unknown_limits,
        get_unknown_limits,
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
    from workbench.trajectory.pick_and_place import (
        JointTrajectory,
        pick_and_place,
        sample_uniform,
    )
    from workbench.trajectory.segments import SegmentedTrajectory, pick_via_place
    from workbench.trajectory.time_optimal import (
        TimeOptimalComparison,
        compare_time_optimal,
        compute_bang_coast_bang_duration,
        compute_time_optimal_duration,
        compute_toppra_duration,
    )

__all__ = [
    "MAX_SAMPLES",
    "CartesianSamples",
    "JointExtrema",
    "JointTrajectory",
    "JointTrajectorySamples",
    "LimitViolation",
    "NormalSpline",
    "PosePickAndPlace",
    "SegmentedTrajectory",
    "SplineExtremum",
    "TimeOptimalComparison",
    "TrajectoryFileError",
    "UniformCubicSpline",
    "as_target_pose",
    "check_limits",
    "check_sample_count",
    "compare_time_optimal",
    "compute_bang_coast_bang_duration",
    "compute_cartesian_trajectory",
    "compute_literal_spline",
    "compute_normal_spline",
    "compute_time_optimal_duration",
    "compute_toppra_duration",
    "describe_unknown_limits",
    "get_normal_spline",
    "get_unknown_limits",
    "minimum_duration",
    "pick_and_place",
    "pick_and_place_from_poses",
    "pick_via_place",
    "raise_for_violations",
    "read_trajectory_csv",
    "sample_uniform",
    "write_trajectory_csv",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
