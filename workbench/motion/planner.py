"""Collision-free motions: RRT-Connect on the sphere model, then a C² trajectory.

:func:`plan` is the one door. It

1. checks the start and the goals on the exact meshes (coal, the project's
   :class:`~workbench.collision.CollisionChecker`); where their spheres
   overlap there, the overlap becomes that entry's allowance along the
   motion (a link against that obstacle only, not the whole scene; a
   margin more, no deeper: :data:`ALLOWANCE_MARGIN`; with ``verify`` a link
   pair first gets :data:`ALLOWANCE_SHARE` of its exact clearance at the
   ends, and the margin when the exact check refuses that trajectory);
   with ``verify`` the pairs the spheres cannot separate also first get
   their tables (:func:`get_pair_tables`, :mod:`workbench.motion.pair_tables`),
   dropped with the wider margins;
2. grows two trees (Kuffner & LaValle's RRT-Connect, compiled): from the
   start, and from every goal configuration (a tool-pose goal becomes every
   closed-form branch within the limits; for seven-axis arms, those of
   :data:`REDUNDANCY_SAMPLES` values of the redundancy parameter spread over
   its feasible range; numerical IK where there is no closed form), every
   edge certified free by :mod:`workbench.motion._sphere_kernel`
   (``planner="ompl:NAME"``: OMPL's planner NAME with the same checks instead,
   :mod:`workbench.motion.ompl_planners`);
3. shortens the path (greedy reduction, then :data:`SHORTCUTS` random
   shortcuts between points of two segments, each certified);
4. time-scales it (:func:`~workbench.motion.time_scale`: on the polyline, so
   no corner is cut) and checks the whole motion on the exact meshes
   (:func:`~workbench.motion.verify_trajectory`, 0.25° joint steps).

Random numbers come from ``numpy.random.default_rng(seed)``, so a seed gives
the same path on every run and machine (with the same iteration count: the
time limit is checked between batches of :data:`BATCH` iterations).
"""

from __future__ import annotations

import functools
import math
import time
import weakref
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.collision.checker import CollisionChecker
from workbench.collision.clearance_report import PathClearance
from workbench.collision.scene import Scene
from workbench.errors import InputError, UnreachableError
from workbench.model.per_robot import per_robot
from workbench.model.robot import Robot
from workbench.motion import _sphere_kernel as kernel
from workbench.motion.checker import PackedArrays, SphereChecker
from workbench.motion.ompl_planners import (
    OMPL_PLANNERS,
    PREFIX,
    check_ompl_planner,
    solve_with_ompl,
)
from workbench.motion.pair_tables import PairTables, build_pair_tables
from workbench.motion.spheres import SphereModel, spherize
from workbench.motion.timing import WaypointTrajectory, time_scale
from workbench.motion.verify import verify_trajectory
from workbench.progress import ProgressCallback, StageProgress

FloatArray = npt.NDArray[np.float64]

#: Longest tree edge [rad], Euclidean in joint space.
STEP = 1.0
#: Iterations between two looks at the clock.
BATCH = 64
#: Random shortcuts tried after the greedy reduction.
SHORTCUTS = 64
#: Values of the redundancy parameter tried for a seven-axis pose goal.
REDUNDANCY_SAMPLES = 16
#: Nodes each tree can hold.
CAPACITY = 50_000
#: Distances [m] of the tool's retreats from a tight end, longest first
#: (:func:`_escapes`).
ESCAPE_DISTANCES = (0.1, 0.05, 0.02)
#: An end is tight when a link holding an allowance has a sphere clearance to
#: the scene, allowance included, below this [m].
ESCAPE_GATE = 0.01
#: Allowed overlap [m] beyond what the spheres of an entry have at an end, at least.
ALLOWANCE_MARGIN = 1e-3
#: With ``verify``, the first attempt allows an entry beyond its overlap this
#: share of its exact clearance at the ends (when more than ALLOWANCE_MARGIN);
#: a trajectory the exact check then refuses is planned again with
#: ALLOWANCE_MARGIN alone, in the rest of the time limit.
ALLOWANCE_SHARE = 0.5
#: Planners :func:`plan` offers: the compiled RRT-Connect, then OMPL's
#: (:mod:`workbench.motion.ompl_planners`, the ``[ompl]`` extra).
PLANNERS = ("rrtconnect", *(PREFIX + name for name in OMPL_PLANNERS))


@dataclass(frozen=True, slots=True, eq=False)
class MotionPlan:
    """Outcome of :func:`plan`; an unsolved request is not an exception.

    Attributes:
        solved: A collision-free motion was found.
        reason: None when solved, else ``"start in collision"``, ``"goal in
            collision"``, ``"goal unreachable"``, ``"time limit"`` or
            ``"iteration limit"``.
        waypoints: (K, nq) [rad]: the shortened path (start ... goal); (0, nq)
            when unsolved.
        trajectory: The time-scaled motion, None when unsolved.
        goal: The goal configuration reached (nq,) [rad], or None.
        setup_time: Checks of the start and goals on the exact meshes and
            the packing of the spheres and the scene [s] (wall clock).
        planning_time: From there to a shortened free path [s] (RRT-Connect
            and shortcutting; the time limit applies to it).
        smoothing_time: Time scaling [s].
        verification_time: The exact-mesh check of the trajectory [s] (0
            without ``verify``).
        min_clearance: Smallest exact distance along the trajectory [m]
            (NaN when unsolved or not verified).
        clearance: The exact-mesh report, None when unsolved or not
            verified.
        iterations: RRT-Connect iterations; for an OMPL planner, the
            vertices of its graph.
        detail: One line on what blocked an unsolved request ("" if solved).
        allowances: ``(link, obstacle or link, metres)`` for each link
            against an obstacle and each link pair whose spheres overlap at
            the start or a goal although the exact meshes are apart there:
            they may overlap that much plus a margin along the motion and no
            more (module docstring); the exact check of the trajectory
            judges the rest.
    """

    solved: bool
    reason: str | None
    waypoints: FloatArray
    trajectory: WaypointTrajectory | None
    goal: FloatArray | None
    setup_time: float
    planning_time: float
    smoothing_time: float
    verification_time: float
    min_clearance: float
    clearance: PathClearance | None = field(repr=False)
    iterations: int
    detail: str = ""
    allowances: tuple[tuple[str, str, float], ...] = ()

    @property
    def path_length(self) -> float:
        """Sum of the waypoints' joint-space segment lengths [rad]."""
        return float(np.sum(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1)))


@per_robot
def _built(robot: Robot) -> dict[str, SphereModel]:
    """The robot's default sphere model once built (``"spheres"``), per robot."""
    return {}


def get_spheres(
    robot: Robot, *, progress: ProgressCallback | None = None
) -> SphereModel:
    """The robot's default sphere model, built once per robot object.

    Args:
        robot: The robot.
        progress: Called as ``progress(done, total)`` while the model is
            built (:func:`~workbench.motion.spherize`); not when it is cached.
    """
    built = _built(robot)
    if "spheres" not in built:
        built["spheres"] = spherize(robot, progress=progress)
    return built["spheres"]


#: The tables of the sphere models seen, held as long as their model is.
_TABLES: weakref.WeakKeyDictionary[SphereModel, PairTables] = (
    weakref.WeakKeyDictionary()
)


def get_pair_tables(
    spheres: SphereModel, *, progress: ProgressCallback | None = None
) -> PairTables:
    """The clearance tables of a sphere model's pairs, built once per model.

    :mod:`workbench.motion.pair_tables`; the exact distances are the robot's
    own, without a scene.

    Args:
        spheres: The sphere model.
        progress: Called as ``progress(done, total)`` while the tables are
            built (:func:`~workbench.motion.pair_tables.build_pair_tables`);
            not when they are cached.
    """
    tables = _TABLES.get(spheres)
    if tables is None:
        tables = build_pair_tables(
            SphereChecker(spheres),
            CollisionChecker(spheres.robot, None),
            progress=progress,
        )
        _TABLES[spheres] = tables
    return tables


def goal_configurations(
    robot: Robot, target: pin.SE3 | npt.ArrayLike, *, seed: int = 0
) -> FloatArray:
    """Configurations (M, nq) [rad] within the limits that put the tool at a pose.

    Args:
        robot: The robot.
        target: Tool pose in the base frame, ``pin.SE3`` or (4, 4) [m].
        seed: Seed of the numerical IK (arms without a closed form).

    Returns:
        Every closed-form branch within the limits (seven-axis arms: for
        :data:`REDUNDANCY_SAMPLES` values of the parameter over its feasible
        range); without a closed form, the distinct solutions of up to four
        numerical solves from random starts.

    Raises:
        UnreachableError: If no configuration within the limits reaches it.
    """
    from workbench import ik

    solver = ik.get_solver(robot) if ik.get_family(robot) is not None else None
    found: list[FloatArray] = []
    if solver is None:
        rng = np.random.default_rng(seed)
        for _ in range(4):
            result = ik.numeric(robot, target, rng=rng)
            if result.success and not any(
                np.allclose(result.q, q, atol=1e-6) for q in found
            ):
                found.append(np.array(result.q))
    elif solver.parameter is None:
        found = [np.array(s.q) for s in solver.solve(target) if s.within_limits]
    else:
        union = solver.feasible(target).union
        total = sum(hi - lo for lo, hi in union)
        values = (
            [
                lo
                + (hi - lo)
                * (k + 0.5)
                / max(1, round(REDUNDANCY_SAMPLES * (hi - lo) / total))
                for lo, hi in union
                for k in range(max(1, round(REDUNDANCY_SAMPLES * (hi - lo) / total)))
            ]
            if total > 0
            else [lo for lo, _ in union]
        )
        for value in values:
            try:
                found += [
                    np.array(s.q)
                    for s in solver.solve(target, redundancy=value)
                    if s.within_limits
                ]
            except UnreachableError:
                continue
    if not found:
        raise UnreachableError(0.0, (0.0, 0.0), "limits")
    return np.array(found)


def require_acceleration_limits(robot: Robot, purpose: str) -> None:
    """Refuse a robot without the acceleration limits the time scaling needs.

    Raises:
        InputError: Naming ``purpose`` and the joints without a finite limit.
    """
    unknown = [
        name
        for name, a in zip(robot.joint_names, robot.acceleration_limit, strict=True)
        if not math.isfinite(a)
    ]
    if unknown:
        raise InputError(
            f"{purpose} needs acceleration limits; {robot.name!r} has none "
            f"for {', '.join(unknown)} (--acceleration-limit at the command line, "
            "Robot.with_limits in Python)"
        )


def plan(
    robot: Robot,
    scene: Scene | None,
    start: npt.ArrayLike,
    goal: npt.ArrayLike | pin.SE3,
    *,
    seed: int = 0,
    time_limit: float = 1.0,
    iteration_limit: int = 100_000,
    planner: str = "rrtconnect",
    spheres: SphereModel | None = None,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
    verify: bool = True,
    progress: StageProgress | None = None,
) -> MotionPlan:
    """A collision-free, time-scaled motion from ``start`` to ``goal``.

    Args:
        robot: The robot, with speed and acceleration limits for the time
            scaling (:meth:`~workbench.model.Robot.with_limits`).
        scene: Obstacles in the base frame, or None.
        start: Start configuration (nq,) [rad].
        goal: A configuration (nq,), several (M, nq) (any one will do) [rad],
            or a tool pose (``pin.SE3`` or a (4, 4) matrix [m]).
        seed: Seed of the planner's random numbers.
        time_limit: Planning budget [s] (wall clock), > 0.
        iteration_limit: RRT-Connect iterations at most, >= 1 (not used by
            the OMPL planners, which stop at the time limit).
        planner: ``"rrtconnect"`` (compiled, the default) or
            ``"ompl:NAME"`` for OMPL's planner NAME (:data:`PLANNERS`;
            :mod:`~workbench.motion.ompl_planners`, the ``[ompl]`` extra),
            with the same checker behind a Python callback, then the same
            shortcuts, time scaling and exact check.
        spheres: The sphere model; default :func:`get_spheres`.
        velocity_scale: Fraction of the speed limits the trajectory uses,
            in (0, 1].
        acceleration_scale: Fraction of the acceleration limits, in (0, 1].
        verify: Check the trajectory on the exact meshes
            (:func:`~workbench.motion.verify_trajectory`); a motion that
            fails it is not ``solved``.
        progress: Called as ``progress(stage, done, total)`` while the
            robot's sphere model (stage ``"sphere cover"``, per geometry) and
            its pair tables (``"pair tables"``, per node) are built, once per
            robot: a UR5 takes about 3 s, MotionBenchMaker's 8 s.

    Returns:
        The plan; ``solved`` False with a ``reason`` when no motion was found.

    Raises:
        InputError: Bad arguments (shapes, limits, an unknown planner, an
            OMPL planner without OMPL installed, a robot without acceleration
            limits).
    """
    t0 = time.perf_counter()
    ompl_name = None
    if isinstance(planner, str) and planner.startswith(PREFIX):
        ompl_name = check_ompl_planner(planner)
    elif planner != "rrtconnect":
        raise InputError(
            f"unknown planner {planner!r}; rrtconnect or {PREFIX}NAME, NAME one of "
            f"{', '.join(OMPL_PLANNERS)}"
        )
    if not (isinstance(time_limit, int | float) and 0 < time_limit < math.inf):
        raise InputError(
            f"time_limit must be a positive number of seconds, got {time_limit!r}"
        )
    if (
        isinstance(iteration_limit, bool)
        or not isinstance(iteration_limit, int)
        or iteration_limit < 1
    ):
        raise InputError(
            f"iteration_limit must be a positive integer, got {iteration_limit!r}"
        )
    require_acceleration_limits(robot, "the time scaling")
    q_start = robot.check_configuration(start)
    exact = CollisionChecker(robot, scene)
    model = spheres or get_spheres(robot, progress=_stage(progress, "sphere cover"))
    empty = np.zeros((0, robot.nq))

    t_search = math.inf

    def failed(reason: str, detail: str, iterations: int = 0) -> MotionPlan:
        now = time.perf_counter()
        return MotionPlan(
            False,
            reason,
            empty,
            None,
            None,
            min(now, t_search) - t0,
            max(0.0, now - t_search),
            0.0,
            0.0,
            math.nan,
            None,
            iterations,
            detail,
        )

    if isinstance(goal, pin.SE3) or np.shape(goal) == (4, 4):
        try:
            goals = goal_configurations(robot, goal, seed=seed)
        except UnreachableError as err:
            return failed("goal unreachable", str(err))
    else:
        raw = np.asarray(goal, dtype=np.float64)
        goals = np.atleast_2d(raw)
        if raw.ndim not in (1, 2) or goals.shape[1] != robot.nq or len(goals) == 0:
            raise InputError(
                f"goal must be a configuration ({robot.nq},), several (M, {robot.nq}) "
                f"or a tool pose, got shape {raw.shape}"
            )
        goals = np.array([robot.check_configuration(q) for q in goals])
    k, least = exact.compute_least_distance(q_start)
    if least <= 0.0:
        a, b = exact.body_pairs[k]
        return failed("start in collision", f"{a} touches {b} at the start")
    nearest = [exact.compute_least_distance(q) for q in goals]
    free_goals = [q for q, (_, d) in zip(goals, nearest, strict=True) if d > 0.0]
    if not free_goals:
        a, b = exact.body_pairs[nearest[0][0]]
        return failed("goal in collision", f"{a} touches {b} at the goal")
    goals = np.array(free_goals)
    ends = np.concatenate([[q_start], goals])

    # With verify: the pairs' tables and wider margins first, the judge after,
    # then the spheres alone on narrow margins (a second checker only when
    # the first has tables).
    tables = (
        get_pair_tables(model, progress=_stage(progress, "pair tables"))
        if verify
        else None
    )
    tabled = tables is not None and bool(tables.pairs)
    first = SphereChecker(model, scene, pair_tables=tables)
    lowest = _end_clearances(first, ends)
    narrow = (
        np.full(lowest[0].shape, ALLOWANCE_MARGIN),
        np.full(lowest[1].shape, ALLOWANCE_MARGIN),
    )

    def without_tables() -> tuple[SphereChecker, EndValues, EndValues]:
        plain = SphereChecker(model, scene)
        return plain, _end_clearances(plain, ends), narrow

    attempts = [without_tables if tabled else lambda: (first, lowest, narrow)]
    if verify:
        # Wider margins for the link pairs only: a link against an obstacle
        # (fingers about the can they grasp) keeps 1 mm (docs/motion.md).
        distances = _end_distances(
            first, exact, ends, (lowest[0] < 0.0, np.zeros(lowest[1].shape, bool))
        )
        wide = (
            np.maximum(ALLOWANCE_SHARE * distances[0], ALLOWANCE_MARGIN),
            narrow[1],
        )
        if tabled or any((w > ALLOWANCE_MARGIN).any() for w in wide):
            attempts.insert(0, lambda: (first, lowest, wide))
    t_search = time.perf_counter()
    spent = [0.0, 0.0, 0.0]  # planning, time scaling, verification [s]
    for attempt, prepare in enumerate(attempts):
        t_attempt = time.perf_counter()  # (the packing counts as planning)
        plain, lowest_here, margin = prepare()
        checker, allowances = _allowing_checker(plain, lowest_here, margin)
        budget = time_limit - spent[0]
        if ompl_name is None:
            # the retreats go no deeper than the narrow margins allow
            retreats = _allowing_checker(plain, lowest_here, narrow)[0]
            search = _search(
                checker,
                retreats,
                robot,
                q_start,
                goals,
                seed,
                t_attempt,
                budget,
                iteration_limit,
            )
        else:
            search = solve_with_ompl(
                ompl_name,
                checker,
                robot,
                q_start,
                goals,
                seed=seed,
                time_limit=budget - (time.perf_counter() - t_attempt),
            )
        if len(search) == 3:
            reason, detail, iterations = search
            return replace(failed(reason, detail, iterations), allowances=allowances)
        path, iterations = search
        if ompl_name is not None:
            arrays = checker.arrays
            store = np.zeros((kernel.MAX_EVALUATIONS, len(arrays[0])))
            path = _shorten(path, np.random.default_rng(seed), arrays, store)
        t_planned = time.perf_counter()
        trajectory = time_scale(
            robot,
            path,
            velocity_scale=velocity_scale,
            acceleration_scale=acceleration_scale,
        )
        t_scaled = time.perf_counter()
        report = verify_trajectory(exact, trajectory) if verify else None
        t_verified = time.perf_counter()
        spent[0] += t_planned - t_attempt
        spent[1] += t_scaled - t_planned
        spent[2] += t_verified - t_scaled
        free = report is None or report.collision_free
        if free or attempt == len(attempts) - 1 or spent[0] >= time_limit:
            break
    path.setflags(write=False)
    goal_reached = np.array(path[-1])
    goal_reached.setflags(write=False)
    return MotionPlan(
        free,
        None if free else "contact on the exact meshes",
        path,
        trajectory,
        goal_reached,
        t_search - t0,
        spent[0],
        spent[1],
        spent[2],
        math.nan if report is None else float(report.min_clearance),
        report,
        iterations,
        ""
        if report is None or free
        else report.describe_first_contact() or "the motion is not proven free",
        allowances,
    )


def _stage(progress: StageProgress | None, stage: str) -> ProgressCallback | None:
    """``progress`` for one stage: ``progress(stage, done, total)``."""
    return None if progress is None else functools.partial(progress, stage)


#: Values at the ends of a motion: per clearance entry (L + P,) and per
#: link–obstacle pair (L, O) [m].
EndValues = tuple[FloatArray, FloatArray]


def _end_clearances(checker: SphereChecker, ends: FloatArray) -> EndValues:
    """The least sphere clearances over the ends: entries, link–obstacle pairs.

    A link–obstacle pair's is computed only at the ends where its link
    overlaps the scene (elsewhere it is no less than the link's entry, >= 0,
    and gets no allowance).
    """
    entries = np.array([checker.clearances(q) for q in ends])
    n_links = len(checker.links)
    by_obstacle = np.full((n_links, len(checker.scene.obstacles)), np.inf)
    for q, at_q in zip(ends, entries, strict=True):
        if (at_q[:n_links] < 0.0).any():
            np.minimum(by_obstacle, checker.obstacle_clearances(q), out=by_obstacle)
    return entries.min(axis=0), by_obstacle


def _allowing_checker(
    plain: SphereChecker, lowest: EndValues, margin: EndValues
) -> tuple[SphereChecker, tuple[tuple[str, str, float], ...]]:
    """The checker that allows each pair the overlap it has at an end.

    The ends are free on the exact meshes (checked before), so an overlap of
    their spheres is the spheres' excess, not a contact: that link pair, or
    that link against that obstacle (not the whole scene), may overlap that
    much plus its ``margin`` along the motion.

    Args:
        plain: The checker without allowance.
        lowest: Each entry's and each link–obstacle pair's least sphere
            clearance over the ends (:func:`_end_clearances`).
        margin: What each overlapping one may overlap more, the same shapes.
    """
    n_links = len(plain.links)
    entries, by_obstacle = (
        np.where(low < 0.0, more - low, 0.0)
        for low, more in zip(lowest, margin, strict=True)
    )
    entries[:n_links] = 0.0  # a link against the scene: per obstacle
    if not (entries.any() or by_obstacle.any()):
        return plain, ()
    obstacles = [obstacle.name for obstacle in plain.scene.obstacles]
    allowances = tuple(
        (plain.links[li], obstacles[o], float(by_obstacle[li, o]))
        for li, o in zip(*np.nonzero(by_obstacle), strict=True)
    ) + tuple(
        (a, b, float(entries[n_links + k]))
        for k, (a, b) in enumerate(plain.pairs)
        if entries[n_links + k] > 0
    )
    return plain.with_allowance(entries, by_obstacle), allowances


def _end_distances(
    checker: SphereChecker,
    exact: CollisionChecker,
    ends: FloatArray,
    wanted: tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]],
) -> EndValues:
    """The least exact distances [m] over the ends of the ``wanted`` pairs.

    ``wanted`` and the result are (L + P,) for the link pairs (after the
    links' entries, which are not used) and (L, O) for the link–obstacle
    pairs; the others, and a pair without an exact one, get 0.
    """
    n_links = len(checker.links)
    links = {link: li for li, link in enumerate(checker.links)}
    obstacles = {obstacle.name: o for o, obstacle in enumerate(checker.scene.obstacles)}
    pairs = {frozenset(pair): k for k, pair in enumerate(checker.pairs)}
    flat = np.concatenate([wanted[0][n_links:], wanted[1].ravel()])
    owner = np.full(len(exact.pairs), -1)  # index into flat
    for j, pair in enumerate(exact.pairs):
        if pair.kind == "scene":
            li, o = links.get(pair.body_a, -1), obstacles.get(pair.body_b, -1)
            if li >= 0 and o >= 0:
                owner[j] = len(checker.pairs) + li * wanted[1].shape[1] + o
        else:
            owner[j] = pairs.get(frozenset((pair.body_a, pair.body_b)), -1)
    active = (owner >= 0) & flat[np.maximum(owner, 0)]
    out = np.full(len(flat), np.inf)
    if active.any():
        for q in ends:
            distances = exact.compute_distances(q, active=active)
            np.minimum.at(out, owner[active], distances[active])
    out = np.where(np.isfinite(out) & flat, out, 0.0)
    entries = np.zeros(len(wanted[0]))
    entries[n_links:] = out[: len(checker.pairs)]
    return entries, out[len(checker.pairs) :].reshape(wanted[1].shape)


def _search(
    checker: SphereChecker,
    retreats: SphereChecker,
    robot: Robot,
    q_start: FloatArray,
    goals: FloatArray,
    seed: int,
    t0: float,
    time_limit: float,
    iteration_limit: int,
) -> tuple[FloatArray, int] | tuple[str, str, int]:
    """RRT-Connect and shortcutting; the path or (reason, detail, iterations).

    ``retreats`` certifies the ends' retreats (:func:`_escapes`): ``checker``
    with narrower allowances, so that they are free for ``checker`` too.
    """
    n = robot.nq
    arrays = checker.arrays
    store = np.zeros((kernel.MAX_EVALUATIONS, len(arrays[0])))
    rng = np.random.default_rng(seed)
    for q in goals:  # a straight segment first
        if kernel.motion_free(q_start, q, *arrays, store):
            return _shorten(np.array([q_start, q]), rng, arrays, store), 0
    roots = (q_start[None], goals)
    escapes = [[_escapes(retreats, robot, q, store) for q in tree] for tree in roots]
    seeded = max(
        len(tree) + sum(map(len, e)) for tree, e in zip(roots, escapes, strict=True)
    )
    capacity = min(max(CAPACITY, 2 * seeded), iteration_limit * 8 + seeded + 1)
    nodes = np.zeros((2, capacity, n))
    parents = np.full((2, capacity), -1, dtype=np.int64)
    counts = np.zeros(2, dtype=np.int64)
    for k in (0, 1):
        nodes[k, : len(roots[k])] = roots[k]
        counts[k] = len(roots[k])
        for root, branches in enumerate(escapes[k]):
            for q in branches:
                nodes[k, counts[k]] = q
                parents[k, counts[k]] = root
                counts[k] += 1
    state = np.zeros(4, dtype=np.int64)
    lower, upper = np.array(robot.lower), np.array(robot.upper)
    while True:
        done = int(state[3])
        batch = min(BATCH, iteration_limit - done)
        if batch <= 0:
            return "iteration limit", f"no path in {done} iterations", done
        uniforms = rng.random((batch, n))
        kernel.grow_trees(
            nodes, parents, counts, state, uniforms, lower, upper, STEP, *arrays, store
        )
        if state[0] == 1:
            break
        if counts.max() + 1 >= capacity:
            return "iteration limit", f"the trees hold {capacity} nodes", int(state[3])
        if time.perf_counter() - t0 > time_limit:
            return "time limit", f"no path in {time_limit:g} s", int(state[3])
    half = [_branch(nodes[k], parents[k], int(state[1 + k])) for k in (0, 1)]
    path = np.concatenate([half[0][::-1], half[1][1:]])
    return _shorten(path, rng, arrays, store), int(state[3])


def _escapes(
    checker: SphereChecker, robot: Robot, q: FloatArray, store: FloatArray
) -> list[FloatArray]:
    """Tool retreats from a tight end: first branches of its tree.

    At an end where a link's spheres overlap the scene (the link holds an
    allowance there: the fingers about the can they reach for), most
    directions of joint space lead deeper, so random extensions seldom leave
    it. Along each axis of the tool frame, both ways, the tool's longest
    straight move of :data:`ESCAPE_DISTANCES` (first order, ``J⁺ v``, clipped
    to the limits) that is certified free becomes a child of the end in its
    tree.
    """
    n_links = len(checker.links)
    allowed = (checker.allowance[:n_links] > 0.0) | checker.obstacle_allowance.any(
        axis=1
    )
    entries = checker.clearances(q)[:n_links]
    if not (allowed & (entries < ESCAPE_GATE)).any():
        return []
    inverse = np.linalg.pinv(robot.jacobian_local(q))
    arrays = checker.arrays
    out = []
    for axis in range(3):
        for sign in (1.0, -1.0):
            for distance in ESCAPE_DISTANCES:
                twist = np.zeros(6)
                twist[axis] = sign * distance
                escape = np.clip(q + inverse @ twist, robot.lower, robot.upper)
                if kernel.motion_free(q, escape, *arrays, store):
                    out.append(escape)
                    break
    return out


def _branch(nodes: FloatArray, parents: npt.NDArray[np.int64], tip: int) -> FloatArray:
    out = []
    while tip >= 0:
        out.append(nodes[tip])
        tip = int(parents[tip])
    return np.array(out)


def _shorten(
    path: FloatArray,
    rng: np.random.Generator,
    arrays: PackedArrays,
    store: FloatArray,
) -> FloatArray:
    buffer = np.zeros((len(path) + 2 * SHORTCUTS + 2, path.shape[1]))
    buffer[: len(path)] = path
    length = np.array([len(path)], dtype=np.int64)
    kernel.shortcut(buffer, length, rng.random((SHORTCUTS, 2)), *arrays, store)
    out = buffer[: int(length[0])]
    keep = np.concatenate(
        [[True], np.any(np.abs(np.diff(out, axis=0)) > 1e-12, axis=1)]
    )
    return np.array(out[keep])


__all__ = [
    "PLANNERS",
    "MotionPlan",
    "get_spheres",
    "goal_configurations",
    "plan",
]
