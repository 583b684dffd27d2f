"""OMPL's geometric planners on the robot's joint space, with the compiled checker.

:func:`solve_with_ompl` runs one planner of OMPL (Şucan, Moll & Kavraki, *The
Open Motion Planning Library*, IEEE RAM 2012; the ``ompl`` wheel's official
bindings, the ``[ompl]`` extra) in a real vector state space bounded by the
joint limits [rad]. A state is valid where the sphere model is free
(:meth:`SphereChecker.is_free`'s kernel) and a motion is valid where the
straight joint segment is certified free (:meth:`SphereChecker.is_segment_free`'s
kernel, OMPL's own :class:`MotionValidator` replaced), so OMPL's paths are
certified like RRT-Connect's, not checked at a resolution. Both cross from C++
into Python on every call.

First-solution planners stop at their first path (a path-length objective any
path satisfies); the asymptotically optimal ones (:data:`OPTIMAL_PLANNERS`)
improve their path until the time limit. OMPL's random numbers are seeded from
``seed`` before each run (``ompl.util.RNG.setSeed``), so a first-solution
planner gives the same path for a seed on every run; an optimal planner's path
also depends on how many iterations the clock allows.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.motion import _sphere_kernel as kernel
from workbench.motion.checker import SphereChecker

FloatArray = npt.NDArray[np.float64]

#: OMPL's geometric planners offered as ``planner="ompl:NAME"`` (those of the
#: ``ompl`` 2.0.1 wheel that plan in a real vector space without extra setup;
#: not AORRTC, whose simplified path of that wheel shrinks to the goal).
OMPL_PLANNERS = (
    "BFMT",
    "BITstar",
    "BKPIECE1",
    "FMT",
    "InformedRRTstar",
    "KPIECE1",
    "LBKPIECE1",
    "PRM",
    "PRMstar",
    "RRT",
    "RRTConnect",
    "RRTstar",
    "SORRTstar",
)
#: The asymptotically optimal ones: they shorten their path until the time
#: limit (FMT and BFMT until their batch of samples is done).
OPTIMAL_PLANNERS = (
    "BFMT",
    "BITstar",
    "FMT",
    "InformedRRTstar",
    "PRMstar",
    "RRTstar",
    "SORRTstar",
)
#: Prefix of an OMPL planner's name in :func:`~workbench.motion.plan`.
PREFIX = "ompl:"
#: Longest edge [rad] of the planners with a range (``setRange``), as RRT-Connect's.
RANGE = 1.0
#: OMPL's seeds are nonzero 32-bit numbers.
_SEEDS = 2**32 - 1


def check_ompl_planner(planner: str) -> str:
    """The OMPL planner's name of ``"ompl:NAME"``.

    Raises:
        InputError: If NAME is not in :data:`OMPL_PLANNERS`, or OMPL is not
            installed (the ``[ompl]`` extra).
    """
    name = planner.removeprefix(PREFIX)
    if name not in OMPL_PLANNERS:
        raise InputError(
            f"unknown OMPL planner {name!r}; one of "
            f"{', '.join(PREFIX + n for n in OMPL_PLANNERS)}"
        )
    _ompl()
    return name


def _ompl() -> tuple[Any, Any, Any]:
    """OMPL's ``base``, ``geometric`` and ``util`` modules.

    Raises:
        InputError: If OMPL is not installed.
    """
    try:
        from ompl import base, geometric, util
    except ImportError as err:
        raise InputError(
            'the OMPL planners need OMPL: pip install "kinematics-workbench[ompl]"'
        ) from err
    return base, geometric, util


def solve_with_ompl(
    name: str,
    checker: SphereChecker,
    robot: Robot,
    q_start: FloatArray,
    goals: FloatArray,
    *,
    seed: int,
    time_limit: float,
) -> tuple[FloatArray, int] | tuple[str, str, int]:
    """A certified path from ``q_start`` to any of ``goals`` by OMPL's ``name``.

    Args:
        name: One of :data:`OMPL_PLANNERS` (checked by
            :func:`check_ompl_planner`).
        checker: The sphere checker of the robot in the scene (free at the
            start and the goals).
        robot: The robot; its joint limits bound the state space [rad].
        q_start: Start (nq,) [rad].
        goals: Goal configurations (M, nq) [rad], any one will do (OMPL's
            ``GoalStates``).
        seed: Seed of OMPL's random numbers.
        time_limit: OMPL's planning budget [s].

    Returns:
        The path (K, nq) [rad] and the number of vertices of the planner's
        graph, or ``(reason, detail, vertices)`` when OMPL found no exact
        solution in the time limit.
    """
    base, geometric, util = _ompl()
    n = robot.nq
    arrays = checker.arrays
    store = np.zeros((kernel.MAX_EVALUATIONS, len(arrays[0])))
    out = np.empty(len(arrays[0]))
    space = base.RealVectorStateSpace(n)
    bounds = base.RealVectorBounds(n)
    for i in range(n):
        bounds.setLow(i, float(robot.lower[i]))
        bounds.setHigh(i, float(robot.upper[i]))
    space.setBounds(bounds)
    level = util.getLogLevel()
    util.setLogLevel(util.LogLevel.LOG_NONE)  # OMPL's note on reseeding
    try:
        util.RNG.setSeed(seed % _SEEDS + 1)
    finally:
        util.setLogLevel(level)
    setup = geometric.SimpleSetup(space)
    info = setup.getSpaceInformation()

    def as_array(state: Any) -> FloatArray:
        return np.array([state[i] for i in range(n)])

    def is_valid(state: Any) -> bool:
        return bool(kernel.clearances(as_array(state), *arrays[1:], True, out))

    class CertifiedMotions(base.MotionValidator):  # type: ignore[name-defined]
        def checkMotion(self, a: Any, b: Any) -> bool:  # OMPL's name
            return bool(kernel.motion_free(as_array(a), as_array(b), *arrays, store))

    setup.setStateValidityChecker(is_valid)
    validator = CertifiedMotions(info)
    info.setMotionValidator(validator)
    objective = base.PathLengthOptimizationObjective(info)
    objective.setCostThreshold(base.Cost(0.0 if name in OPTIMAL_PLANNERS else math.inf))
    setup.setOptimizationObjective(objective)
    planner = getattr(geometric, name)(info)
    if hasattr(planner, "setRange"):
        planner.setRange(RANGE)
    setup.setPlanner(planner)
    start = space.allocState()
    for i in range(n):
        start[i] = float(q_start[i])
    setup.setStartState(start)
    goal = base.GoalStates(info)
    for q in goals:
        state = space.allocState()
        for i in range(n):
            state[i] = float(q[i])
        goal.addState(state)
    setup.setGoal(goal)
    level = util.getLogLevel()
    util.setLogLevel(util.LogLevel.LOG_ERROR)
    try:
        begin = time.perf_counter()
        setup.solve(time_limit)
        elapsed = time.perf_counter() - begin
    finally:
        util.setLogLevel(level)
    data = base.PlannerData(info)
    setup.getPlannerData(data)
    vertices = int(data.numVertices())
    if not setup.haveExactSolutionPath():
        status = str(setup.getLastPlannerStatus())
        return (
            "time limit",
            f"OMPL {name}: no path in {elapsed:.3g} s ({status})",
            vertices,
        )
    path = setup.getSolutionPath()
    waypoints = np.array(
        [as_array(path.getState(k)) for k in range(path.getStateCount())]
    )
    return waypoints, vertices


__all__ = [
    "OMPL_PLANNERS",
    "OPTIMAL_PLANNERS",
    "check_ompl_planner",
    "solve_with_ompl",
]
