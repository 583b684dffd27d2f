"""Motion around obstacles: plan, time-scale and verify collision-free motions.

:func:`plan` is the one door (:mod:`.plan`): RRT-Connect on a conservative
sphere model of the robot (:mod:`.spheres`, :func:`spherize`), checked in
compiled code against the scene with certified segments (:mod:`.checker`,
:class:`SphereChecker`; the pairs its spheres cannot separate get clearance
tables over their relative joints, :mod:`.pair_tables`), shortened,
time-scaled and verified on the exact meshes; ``planner="ompl:NAME"`` runs
one of OMPL's planners
(:data:`OMPL_PLANNERS`, :mod:`.ompl_planners`) with the same checker instead.
:mod:`.problems` finds MotionBenchMaker problem sets and judges their
validity, :mod:`.problem_runs` plans and summarises them (:func:`run_problems`,
:func:`summarise`), and :mod:`.batch` plans many requests here or on a Dask
cluster (:func:`plan_many`). :mod:`.requests` reads MoveIt motion requests
(start and joint goal) as configurations of a robot; MoveIt planning scenes
are read by :func:`workbench.collision.read_scene`. :mod:`.timing` turns a
planner's joint-space polyline into a C² trajectory within the joint limits
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
    from workbench.motion.batch import plan_many
    from workbench.motion.checker import SphereChecker
    from workbench.motion.ompl_planners import OMPL_PLANNERS, OPTIMAL_PLANNERS
    from workbench.motion.pair_tables import PairTables, build_pair_tables
    from workbench.motion.planner import (
        PLANNERS,
        MotionPlan,
        get_pair_tables,
        goal_configurations,
        plan,
    )
    from workbench.motion.problem_runs import (
        ProblemResult,
        ScenarioSummary,
        run_problem,
        run_problems,
        summarise,
    )
    from workbench.motion.problems import (
        Problem,
        Validity,
        check_validity,
        find_problems,
    )
    from workbench.motion.requests import MotionRequest, parse_request, read_request
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
    "OMPL_PLANNERS",
    "OPTIMAL_PLANNERS",
    "PLANNERS",
    "REPEAT_TOL",
    "WORST_RATIO",
    "LinkSpheres",
    "MotionPlan",
    "MotionRequest",
    "PairTables",
    "PlannedAround",
    "Problem",
    "ProblemResult",
    "ScenarioSummary",
    "SphereChecker",
    "SphereModel",
    "Validity",
    "WaypointTrajectory",
    "build_pair_tables",
    "check_validity",
    "find_problems",
    "get_pair_tables",
    "goal_configurations",
    "parse_request",
    "plan",
    "plan_around",
    "plan_many",
    "read_request",
    "run_problem",
    "run_problems",
    "spherize",
    "summarise",
    "time_optimal_duration",
    "time_scale",
    "verify_trajectory",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
