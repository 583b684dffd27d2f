"""Motion around obstacles: plan, time-scale and verify collision-free motions.

:func:`plan` is the one door (:mod:`.plan`): RRT-Connect on a conservative
sphere model of the robot (:mod:`.spheres`, :func:`spherize`), checked in
compiled code against the scene with certified segments (:mod:`.checker`,
:class:`SphereChecker`), shortened, time-scaled and verified on the exact
meshes.
:mod:`.requests` reads MoveIt motion requests (start and joint goal) as
configurations of a robot; MoveIt planning scenes are read by
:func:`workbench.collision.read_scene`. :mod:`.timing` turns a planner's
joint-space polyline into a C² trajectory within the joint limits
(:func:`time_scale`), and :mod:`.verify` checks a trajectory on the exact
meshes, proven between its samples (:func:`verify_trajectory`).
:mod:`.around` plans around the scene when a pick-and-place spline collides
(:func:`plan_around`, :class:`PlannedAround`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from workbench._lazy import attach

if TYPE_CHECKING:
    from workbench.motion._polyline import REPEAT_TOL
    from workbench.motion.around import PlannedAround, plan_around
    from workbench.motion.checker import SphereChecker
    from workbench.motion.planner import MotionPlan, goal_configurations, plan
    from workbench.motion.requests import MotionRequest, read_request
    from workbench.motion.spheres import LinkSpheres, SphereModel, spherize
    from workbench.motion.timing import (
        WORST_RATIO,
        WaypointTrajectory,
        time_optimal_duration,
        time_scale,
    )
    from workbench.motion.verify import DEFAULT_MAX_STEP, verify_trajectory

__all__ = [
    "DEFAULT_MAX_STEP",
    "REPEAT_TOL",
    "WORST_RATIO",
    "LinkSpheres",
    "MotionPlan",
    "MotionRequest",
    "PlannedAround",
    "SphereChecker",
    "SphereModel",
    "WaypointTrajectory",
    "goal_configurations",
    "plan",
    "plan_around",
    "read_request",
    "spherize",
    "time_optimal_duration",
    "time_scale",
    "verify_trajectory",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
