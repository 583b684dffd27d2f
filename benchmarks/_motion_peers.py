"""The planners of :mod:`benchmarks.bench_motion`: VAMP, OMPL, the workbench.

Each runs one MotionBenchMaker problem and returns a :class:`Run`; the paths
are checked on the exact meshes by :func:`check_trajectory` (a trajectory) and
:func:`check_polyline` (a piecewise-linear path). VAMP and OMPL are imported
when their peer is built, so the rest works without them.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from workbench import Robot
from workbench.collision import CollisionChecker, Scene, check_path
from workbench.motion import DEFAULT_MAX_STEP, verify_trajectory

#: Points per call of VAMP's ``validate_motion`` on x86-64 (its rake: one
#: ``__m256`` of 8 floats; 4 on ARM NEON, where the pieces check more coarsely).
VAMP_RAKE = 8


@dataclass(slots=True)
class Run:
    """One planner on one problem (times [s], length [rad])."""

    solved: bool
    planning_time: float = math.nan
    simplification_time: float = math.nan
    length: float = math.nan
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def total_time(self) -> float:
        return self.planning_time + self.simplification_time


def path_length(path: np.ndarray) -> float:
    """Sum of the joint-space Euclidean lengths of a (K, n) path's segments."""
    return float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))


def vamp_environment(vamp: Any, scene: Scene, scenario: str) -> Any:
    """VAMP's environment of a scene, as ``vamp.problem_dict_to_vamp`` builds it.

    Boxes are cuboids; cylinders are capsules, except in ``box`` where VAMP
    replaces them by their bounding cuboids (its own note: the scenario needs
    a top-down grasp of the cylinder).
    """
    from vamp.transformations import euler_from_matrix

    env = vamp.Environment()
    for obstacle in scene.obstacles:
        pose = obstacle.placement.homogeneous
        position = pose[:3, 3].tolist()
        euler = list(euler_from_matrix(pose))
        size = list(obstacle.size)
        if obstacle.shape == "box":
            env.add_cuboid(vamp.Cuboid(position, euler, [s / 2 for s in size]))
        elif obstacle.shape == "cylinder" and scenario == "box":
            radius, length = size
            env.add_cuboid(vamp.Cuboid(position, euler, [radius, radius, length / 2]))
        elif obstacle.shape == "cylinder":
            radius, length = size
            env.add_capsule(vamp.Cylinder(position, euler, radius, length))
        elif obstacle.shape == "sphere":
            env.add_sphere(vamp.Sphere(position, size[0]))
        else:
            raise ValueError(f"VAMP has no {obstacle.shape} ({obstacle.name})")
    return env


class VampPeer:
    """VAMP's RRT-Connect and simplification, as ``evaluate_mbm.py`` runs them."""

    def __init__(self, robot: str) -> None:
        import vamp

        self.vamp = vamp
        (self.module, self.planner, self.plan_settings, self.simplify_settings) = (
            vamp.configure_robot_and_planner_with_kwargs(robot, "rrtc")
        )
        self.sampler = self.module.halton()
        self.joint_names = list(self.module.joint_names())

    def environment(self, scene: Scene, scenario: str) -> Any:
        return vamp_environment(self.vamp, scene, scenario)

    def valid(self, q: Sequence[float], env: Any) -> bool:
        return bool(self.module.validate(list(q), env))

    def run(self, start: Sequence[float], goal: Sequence[float], env: Any) -> Run:
        self.sampler.reset()
        result = self.planner(
            list(start), [list(goal)], env, self.plan_settings, self.sampler
        )
        if not result.solved:
            return Run(False, planning_time=1e-9 * result.nanoseconds)
        simple = self.module.simplify(
            result.path, env, self.simplify_settings, self.sampler
        )
        path = np.asarray(simple.path.numpy(), dtype=float)
        return Run(
            True,
            1e-9 * result.nanoseconds,
            1e-9 * simple.nanoseconds,
            path_length(path),
            {"iterations": int(result.iterations), "path": path.tolist()},
        )


class OmplPeer:
    """OMPL's RRTConnect with VAMP's checker behind Python callbacks."""

    def __init__(self, vamp: VampPeer, time_limit: float) -> None:
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ou

        ou.setLogLevel(ou.LogLevel.LOG_WARN)
        self.ob, self.og, self.vamp, self.time_limit = ob, og, vamp, time_limit
        n = len(vamp.joint_names)
        self.space = ob.RealVectorStateSpace(n)
        bounds = ob.RealVectorBounds(n)
        lower, upper = vamp.module.lower_bounds(), vamp.module.upper_bounds()
        for i in range(n):  # VAMP's joint space, in VAMP's joint order
            bounds.setLow(i, float(lower[i]))
            bounds.setHigh(i, float(upper[i]))
        self.space.setBounds(bounds)
        self.n = n
        #: Longest piece [rad] one ``validate_motion`` call checks (module doc).
        self.piece = VAMP_RAKE / float(vamp.module.resolution())
        self.range = float(vamp.plan_settings.range)

    def run(self, start: Sequence[float], goal: Sequence[float], env: Any) -> Run:
        ob, og, module, n = self.ob, self.og, self.vamp.module, self.n
        setup = og.SimpleSetup(self.space)
        info = setup.getSpaceInformation()

        def state_valid(state: Any) -> bool:
            return bool(module.validate([state[i] for i in range(n)], env))

        piece = self.piece

        class Motion(ob.MotionValidator):
            def checkMotion(self, a: Any, b: Any) -> bool:
                qa = np.array([a[i] for i in range(n)])
                qb = np.array([b[i] for i in range(n)])
                pieces = max(1, math.ceil(float(np.linalg.norm(qb - qa)) / piece))
                points = qa + np.linspace(0.0, 1.0, pieces + 1)[:, None] * (qb - qa)
                return all(
                    module.validate_motion(
                        points[k].tolist(), points[k + 1].tolist(), env, False
                    )
                    for k in range(pieces)
                )

        setup.setStateValidityChecker(state_valid)
        validator = Motion(info)
        info.setMotionValidator(validator)
        planner = og.RRTConnect(info)
        planner.setRange(self.range)
        setup.setPlanner(planner)
        states = []
        for q in (start, goal):
            state = self.space.allocState()
            for i, value in enumerate(q):
                state[i] = float(value)
            states.append(state)
        setup.setStartAndGoalStates(states[0], states[1])
        setup.setup()
        solved = bool(setup.solve(self.time_limit)) and setup.haveExactSolutionPath()
        planning = setup.getLastPlanComputationTime()
        if not solved:
            status = str(setup.getLastPlannerStatus())
            return Run(False, planning_time=planning, extra={"status": status})
        setup.simplifySolution()
        path = setup.getSolutionPath()
        q = np.array(
            [
                [path.getState(k)[i] for i in range(n)]
                for k in range(path.getStateCount())
            ]
        )
        return Run(True, planning, setup.getLastSimplificationTime(), path_length(q))


class WorkbenchPeer:
    """``workbench.motion.plan`` from a joint goal or a tool pose, checked exactly."""

    def __init__(
        self, plan: Callable[..., Any], time_limit: float, verify: bool = True
    ) -> None:
        self.plan, self.time_limit, self.verify = plan, time_limit, verify

    def run(
        self,
        robot: Robot,
        scene: Scene,
        checker: CollisionChecker,
        start: np.ndarray,
        goal: Any,
        seed: int,
    ) -> Run:
        result = self.plan(
            robot,
            scene,
            start,
            goal,
            seed=seed,
            time_limit=self.time_limit,
            verify=self.verify,
        )
        extra: dict[str, Any] = {
            "iterations": int(result.iterations),
            "setup_time": float(getattr(result, "setup_time", 0.0)),
        }
        if not result.solved:
            extra["status"] = getattr(result, "reason", None) or "no path"
            extra["detail"] = getattr(result, "detail", "")
        trajectory = result.trajectory
        if trajectory is not None and self.verify:
            report = getattr(result, "clearance", None)
            if report is None:
                extra.update(check_trajectory(checker, trajectory))
            else:  # plan checked its trajectory on the same exact meshes
                extra.update(
                    _clearance(report, float(result.verification_time), trajectory)
                )
        if not result.solved:
            return Run(False, float(result.planning_time), extra=extra)
        extra["min_clearance"] = float(result.min_clearance)
        return Run(
            True,
            float(result.planning_time),
            float(result.smoothing_time),
            path_length(np.asarray(result.waypoints, dtype=float)),
            extra,
        )


def check_trajectory(checker: CollisionChecker, trajectory: Any) -> dict[str, Any]:
    """``workbench.motion.verify_trajectory`` at its 0.25° steps, timed.

    Args:
        checker: The robot, the problem's scene and the pairs (exact meshes).
        trajectory: A trajectory with ``robot``, ``duration`` [s],
            ``sample(t)`` and ``get_extrema(order)``.

    Returns:
        ``contacts`` (count), ``verify_time`` [s], ``samples``,
        ``verify_min_clearance`` [m], ``verify_lower_bound`` [m] (proven over
        the whole motion), ``contact_pairs`` (``"a – b"``) and ``duration`` [s].
    """
    begin = time.perf_counter()
    report = verify_trajectory(checker, trajectory)
    return _clearance(report, time.perf_counter() - begin, trajectory)


def _clearance(report: Any, seconds: float, trajectory: Any) -> dict[str, Any]:
    """A ``PathClearance`` of a trajectory, checked in ``seconds``, as a dict."""
    return {
        "contacts": len(report.contacts),
        "verify_time": seconds,
        "samples": int(report.samples),
        "verify_min_clearance": float(report.min_clearance),
        "verify_lower_bound": float(report.lower_bound),
        "contact_pairs": sorted({f"{c.body_a} – {c.body_b}" for c in report.contacts}),
        "duration": float(trajectory.duration),
    }


def check_polyline(checker: CollisionChecker, path: np.ndarray) -> dict[str, Any]:
    """A piecewise-linear path (K, nq) [rad] checked on the exact meshes, timed.

    Each segment is cut so that no joint moves more than
    ``workbench.motion.DEFAULT_MAX_STEP`` (0.25°) between two samples, then
    ``check_path`` proves the straight lines between them (its ``t`` is the
    sample's number: the path has no timing).

    Returns:
        ``contacts``, ``verify_time`` [s], ``samples``,
        ``verify_min_clearance`` [m], ``verify_lower_bound`` [m] and
        ``contact_pairs`` (``"a – b"``).
    """
    begin = time.perf_counter()
    pieces = [path[:1]]
    for a, b in itertools.pairwise(path):
        n = max(1, math.ceil(float(np.max(np.abs(b - a))) / DEFAULT_MAX_STEP))
        pieces.append(a + np.linspace(0.0, 1.0, n + 1)[1:, None] * (b - a))
    q = np.vstack(pieces)
    report = check_path(checker, np.arange(len(q), dtype=float), q)
    return {
        "contacts": len(report.contacts),
        "verify_time": time.perf_counter() - begin,
        "samples": int(report.samples),
        "verify_min_clearance": float(report.min_clearance),
        "verify_lower_bound": float(report.lower_bound),
        "contact_pairs": sorted({f"{c.body_a} – {c.body_b}" for c in report.contacts}),
    }


def get_workbench_plan() -> Callable[..., Any] | None:
    """``workbench.motion.plan``, or None where this version has none."""
    try:
        from workbench.motion import plan
    except (ImportError, AttributeError):
        return None
    return plan
