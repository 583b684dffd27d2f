"""MotionBenchMaker problems planned and verified, and their statistics per scenario.

:func:`run_problem` judges a :class:`~workbench.motion.problems.Problem`'s
validity on the exact meshes, plans it with :func:`~workbench.motion.plan`
(the trajectory verified on the exact meshes at joint steps <= 0.25°) and
keeps the times; :func:`run_problems` runs many, in this process or on a Dask
cluster (:func:`~workbench.motion.batch.run_many`), and :func:`summarise`
gives the table per scenario: valid, solved, planning-time median, p95 and
max, time scaling, total, and the exact check's contacts.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from workbench.model.robot import Robot
from workbench.motion.batch import Planner, plan_options, run_many
from workbench.motion.problems import Problem, Validity, check_validity
from workbench.progress import ProgressCallback

#: Name of the row of :func:`summarise` over every scenario.
ALL = "all"


@dataclass(frozen=True, slots=True)
class ProblemResult:
    """One problem's validity, plan and exact check.

    Attributes:
        scenario, index: The problem.
        validity: Its start and goal on the exact meshes; an invalid
            problem is not planned.
        solved: A motion was found and (with verification) proven free.
        reason: None when solved; ``"invalid: start in collision"`` and
            the like, or :attr:`~workbench.motion.MotionPlan.reason`.
        detail: One line on what blocked it ("" when solved).
        setup_time, planning_time, smoothing_time, verification_time: The
            plan's times [s] (0 for an invalid problem).
        iterations: RRT-Connect iterations.
        path_length: Joint-space length of the shortened path [rad] (NaN
            unsolved).
        duration: The trajectory's duration [s] (NaN without one).
        contacts: Contact intervals the exact check found on the trajectory
            (None: not checked).
        min_clearance: Smallest exact distance along it [m] (NaN: not
            checked).
        seed: The planner's seed.
    """

    scenario: str
    index: int
    validity: Validity
    solved: bool
    reason: str | None
    detail: str
    setup_time: float
    planning_time: float
    smoothing_time: float
    verification_time: float
    iterations: int
    path_length: float
    duration: float
    contacts: int | None
    min_clearance: float
    seed: int

    @property
    def total_time(self) -> float:
        """Planning and time scaling [s] (the exact check apart)."""
        return self.planning_time + self.smoothing_time


@dataclass(frozen=True, slots=True)
class ScenarioSummary:
    """Statistics of one scenario's results (or of all: ``scenario == "all"``).

    Times [s] are over the solved problems (NaN when none is).

    Attributes:
        scenario: Its name.
        problems, valid, solved: Counts (solved among the valid).
        planning_median, planning_p95, planning_max: Planning time.
        smoothing_median: Time scaling. total_median: Planning + time scaling.
        verification_median: The exact check of the trajectory (over the
            solved problems checked).
        verified: Trajectories checked on the exact meshes (an unsolved one
            refused for a contact too).
        with_contacts, contacts: Of them, those with a contact, and the
            contact intervals in all.
    """

    scenario: str
    problems: int
    valid: int
    solved: int
    planning_median: float
    planning_p95: float
    planning_max: float
    smoothing_median: float
    total_median: float
    verification_median: float
    verified: int
    with_contacts: int
    contacts: int


def run_problem(
    robot: Robot,
    problem: Problem,
    *,
    seed: int = 0,
    time_limit: float = 1.0,
    iteration_limit: int = 100_000,
    planner: str = "rrtconnect",
    pose_goal: bool = False,
    verify: bool = True,
) -> ProblemResult:
    """Validity, then :func:`~workbench.motion.plan` of one problem.

    Args:
        robot: The robot, with acceleration limits.
        problem: The problem.
        seed: The planner's seed.
        time_limit: Planning budget [s].
        iteration_limit: RRT-Connect iterations at most.
        planner: ``"rrtconnect"`` or ``"ompl:NAME"`` (:func:`~workbench.motion.plan`).
        pose_goal: Plan to the goal configuration's tool pose
            (``robot.fk(goal)``) instead of to the configuration.
        verify: Check the trajectory on the exact meshes.

    Raises:
        InputError: A joint of the robot is missing from the request, or
            :func:`~workbench.motion.plan` refuses the arguments.
    """
    options = plan_options(seed, time_limit, iteration_limit, planner, verify)
    return _solve(Planner(robot, options, warm=True), problem, pose_goal)


def run_problems(
    robot: Robot,
    problems: Sequence[Problem],
    *,
    seed: int = 0,
    time_limit: float = 1.0,
    iteration_limit: int = 100_000,
    planner: str = "rrtconnect",
    pose_goal: bool = False,
    verify: bool = True,
    scheduler: str | None = None,
    progress: ProgressCallback | None = None,
) -> list[ProblemResult]:
    """:func:`run_problem` of every problem, in this process or on a Dask cluster.

    Each process plans one untimed motion first (the spheres built, the
    kernels loaded) so that no planning time includes them. Every problem is
    planned from ``seed``, so a result does not depend on where it ran.

    Args:
        robot: The robot, with acceleration limits.
        problems: The problems (:func:`~workbench.motion.find_problems`).
        seed: The planner's seed, the same for every problem.
        time_limit: Planning budget of each problem [s].
        iteration_limit: RRT-Connect iterations of each problem at most.
        planner: ``"rrtconnect"`` or ``"ompl:NAME"`` (:func:`~workbench.motion.plan`).
        pose_goal: Plan to the goal configurations' tool poses.
        verify: Check each trajectory on the exact meshes.
        scheduler: A Dask scheduler address (``tcp://HOST:PORT``), or None
            for this process, one problem after the other.
        progress: Called as ``progress(done, total)`` after each problem.

    Returns:
        One result per problem, in their order.

    Raises:
        InputError: As :func:`run_problem`, or the scheduler cannot be
            reached or has no worker.
    """
    options = plan_options(seed, time_limit, iteration_limit, planner, verify)
    shared = (Planner(robot, options), pose_goal)
    return run_many(
        _run_task, shared, list(problems), scheduler=scheduler, progress=progress
    )


def _run_task(shared: tuple[Planner, bool], problem: Problem) -> ProblemResult:
    planner, pose_goal = shared
    return _solve(planner, problem, pose_goal)


def _solve(planner: Planner, problem: Problem, pose_goal: bool) -> ProblemResult:
    robot = planner.robot
    seed = int(planner.options["seed"])
    validity = check_validity(robot, problem)
    head = (problem.scenario, problem.index, validity)
    if not validity.valid:
        detail = f"{validity.body_a} touches {validity.body_b} at the {validity.where}"
        nan = math.nan
        reason = f"invalid: {validity.where} in collision"
        return ProblemResult(
            *head, False, reason, detail, 0.0, 0.0, 0.0, 0.0, 0, nan, nan, None, nan,
            seed,
        )  # fmt: skip
    start, goal = problem.read_request(robot)
    result = planner(problem.scene, start, robot.fk(goal) if pose_goal else goal)
    report = result.clearance
    trajectory = result.trajectory
    return ProblemResult(
        *head,
        bool(result.solved),
        result.reason,
        result.detail,
        result.setup_time,
        result.planning_time,
        result.smoothing_time,
        result.verification_time,
        result.iterations,
        result.path_length if len(result.waypoints) else math.nan,
        math.nan if trajectory is None else float(trajectory.duration),
        None if report is None else len(report.contacts),
        result.min_clearance,
        seed,
    )


def summarise(results: Sequence[ProblemResult]) -> list[ScenarioSummary]:
    """One row per scenario (in the order of first appearance), then ``"all"``."""
    names = list(dict.fromkeys(r.scenario for r in results))
    groups = [(n, [r for r in results if r.scenario == n]) for n in names]
    return [_summary(name, group) for name, group in [*groups, (ALL, list(results))]]


def _summary(name: str, group: list[ProblemResult]) -> ScenarioSummary:
    solved = [r for r in group if r.solved]
    planning = [r.planning_time for r in solved]
    checked = [r for r in group if r.contacts is not None]
    return ScenarioSummary(
        name,
        len(group),
        sum(r.validity.valid for r in group),
        len(solved),
        _quantile(planning, 0.5),
        _quantile(planning, 0.95),
        max(planning, default=math.nan),
        _quantile([r.smoothing_time for r in solved], 0.5),
        _quantile([r.total_time for r in solved], 0.5),
        _quantile([r.verification_time for r in solved if r.contacts is not None], 0.5),
        len(checked),
        sum(1 for r in checked if r.contacts),
        sum(r.contacts or 0 for r in checked),
    )


def _quantile(values: Sequence[float], q: float) -> float:
    if not values:
        return math.nan
    return float(np.quantile(np.asarray(values, dtype=float), q))
