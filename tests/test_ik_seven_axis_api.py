"""The closed form of seven-axis arms through the public API (analytic, batch, choice).

The kernels' own precision and edge cases (10⁴ poses per family, singularities)
are tested in their files; here the framework: dispatch, every bad input and
its message, continuity, batch against single poses, the redundancy tools, each
criterion of ``choose_redundancy`` against brute force over a fine grid.
"""

from __future__ import annotations

import math
import pickle
from dataclasses import FrozenInstanceError

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from workbench import Robot, load_robot
from workbench.errors import DimensionError, InfeasibleError, InputError, NonFiniteError
from workbench.ik import (
    FRANKA_BRANCHES,
    SRS_BRANCHES,
    FeasibleRedundancy,
    IKSolution,
    UnreachableError,
    UnsupportedRobotError,
    analytic,
    analytic_batch,
    choose_redundancy,
    get_solver,
    nearest,
)

#: FK of a closed-form solution against its target [m, rad]: a few roundings
#: of the chain's products and of the atan2s.
ATOL_FK = 1e-10
#: Batch against single pose [rad]: the same kernel arithmetic.
ATOL_EXACT = 1e-12
#: Joint values of a round trip [rad] (the kernels' precision, far from
#: singularities).
ATOL_ROUND_TRIP = 1e-8
#: Smallest singular value of the stacked map [J; ∇ parameter] (7 × 7) of a
#: round trip's q: further from singularities (the kernels' own tests cover
#: the near-singular poses) the joint values are exact to ATOL_ROUND_TRIP.
REGULAR = 1e-3
#: Slack of the limit test of brute-force configurations [rad]: the kernels'.
LIMIT_SLACK = 1e-9
#: Grid of the brute-force search over the parameter range.
GRID = 20001
NAMES = ("iiwa14", "panda")
FAMILY = {"iiwa14": "srs", "panda": "franka"}


@pytest.fixture(scope="module", params=NAMES)
def arm(request: pytest.FixtureRequest) -> Robot:
    return load_robot(request.param)


def _wrapped(d: np.ndarray) -> np.ndarray:
    return np.remainder(d + np.pi, 2.0 * np.pi) - np.pi


def _random_q(robot: Robot, rng: np.random.Generator, margin: float = 0.1):
    return rng.uniform(robot.lower + margin, robot.upper - margin)


def _fk_error(robot: Robot, q: np.ndarray, target: np.ndarray) -> float:
    return float(np.abs(robot.fk(q).homogeneous - target).max())


# -- the solver and its dispatch -------------------------------------------------------


def test_solver_of_each_family(arm: Robot) -> None:
    solver = get_solver(arm)
    assert solver is get_solver(arm)  # cached per robot
    assert solver.family.name == FAMILY[arm.name]
    labels = SRS_BRANCHES if solver.family.name == "srs" else FRANKA_BRANCHES
    assert solver.branches == labels == get_solver(arm).branches
    assert solver.parameter == ("arm angle" if solver.family.name == "srs" else "q7")
    if solver.family.name == "srs":
        assert solver.parameter_range == (-math.pi, math.pi)
    else:
        assert solver.parameter_range == (arm.lower[6], arm.upper[6])
    assert not solver.geometry.flags.writeable


def test_analytic_solves_every_branch_for_the_value(arm: Robot) -> None:
    rng = np.random.default_rng(1)
    solver = get_solver(arm)
    for q in (_random_q(arm, rng) for _ in range(20)):
        target = arm.fk(q).homogeneous
        value = get_solver(arm).parameter_of(q)
        solutions = analytic(arm, target, redundancy=value)
        assert solutions and all(isinstance(s, IKSolution) for s in solutions)
        assert [s.index for s in solutions] == sorted({s.index for s in solutions})
        for s in solutions:
            assert s.branch == solver.branches[s.index] and s.redundancy == value
            assert _fk_error(arm, s.q, target) <= ATOL_FK
            assert abs(_wrapped(get_solver(arm).parameter_of(s.q) - value)) <= 1e-9
            inside = bool(np.all((arm.lower <= s.q) & (s.q <= arm.upper)))
            assert (
                s.within_limits == inside
                or np.min(np.abs(np.concatenate([s.q - arm.lower, arm.upper - s.q])))
                <= 1e-9
            )
        # the same through an SE3 target and through the solver
        again = analytic(arm, pin.SE3(target), redundancy=value)
        np.testing.assert_array_equal([s.q for s in again], [s.q for s in solutions])


def test_solution_is_immutable_and_pickles(arm: Robot) -> None:
    q = _random_q(arm, np.random.default_rng(2))
    solution = analytic(arm, arm.fk(q), redundancy=get_solver(arm).parameter_of(q))[0]
    with pytest.raises(FrozenInstanceError):
        solution.branch = "x"  # type: ignore[misc]
    with pytest.raises(FrozenInstanceError):
        del solution.q
    with pytest.raises(ValueError, match="read-only"):
        solution.q[0] = 0.0
    copy = pickle.loads(pickle.dumps(solution))
    np.testing.assert_array_equal(copy.q, solution.q)
    assert (copy.branch, copy.redundancy, copy.within_limits) == (
        solution.branch, solution.redundancy, solution.within_limits,
    )  # fmt: skip
    assert "IKSolution(q=" in repr(solution)


def test_continuity_from_q_previous(arm: Robot) -> None:
    """redundancy=None keeps q_previous's parameter; the nearest branch steps little."""
    rng = np.random.default_rng(3)
    for q in (_random_q(arm, rng, 0.3) for _ in range(20)):
        q_next = q + rng.uniform(-0.01, 0.01, 7)
        q_next[6] = q[6]  # (Franka: q7 kept, the pose is reached for it)
        target = arm.fk(q_next).homogeneous
        kept = analytic(arm, target, q_previous=q)
        value = get_solver(arm).parameter_of(q)
        given_value = analytic(arm, target, q_previous=q, redundancy=value)
        np.testing.assert_array_equal([s.q for s in kept], [s.q for s in given_value])
        assert all(s.redundancy == value for s in kept)
        step = nearest(kept, q).q - q
        assert np.abs(step).max() <= 0.1  # one small step, no other branch
        for s in kept:  # each angle the representative nearest q_previous
            assert np.all(np.abs(s.q - q) <= math.pi + 1e-12)


@pytest.mark.slow
def test_batch_equals_single_pose(arm: Robot) -> None:
    rng = np.random.default_rng(4)
    qs = np.array([_random_q(arm, rng) for _ in range(64)])
    targets = np.array([arm.fk(q).homogeneous for q in qs])
    values = get_solver(arm).parameter_of(qs)
    assert isinstance(values, np.ndarray) and values.shape == (64,)
    np.testing.assert_array_equal(values, [get_solver(arm).parameter_of(q) for q in qs])
    q_all, valid = analytic_batch(arm, targets, redundancy=values)
    count = len(get_solver(arm).branches)
    assert q_all.shape == (64, count, 7) and valid.shape == (64, count)
    solver = get_solver(arm)
    for i in range(64):
        single, _, _ = solver.solve_arrays(
            targets[i], np.empty(0), redundancy=float(values[i])
        )
        np.testing.assert_array_equal(valid[i], np.isfinite(single[:, 0]))
        np.testing.assert_allclose(q_all[i], single, rtol=0, atol=ATOL_EXACT)
    # one value for every pose (Franka: some poses out of reach for that q7)
    value = float(values[0])
    q_one, valid_one = analytic_batch(arm, targets, redundancy=value)
    for i in range(64):
        try:
            single, _, _ = solver.solve_arrays(
                targets[i], np.empty(0), redundancy=value
            )
        except UnreachableError:
            assert not valid_one[i].any() and np.isnan(q_one[i]).all()
            continue
        np.testing.assert_allclose(q_one[i], single, rtol=0, atol=ATOL_EXACT)
        np.testing.assert_array_equal(valid_one[i], np.isfinite(single[:, 0]))


def test_track_continues_the_branch(arm: Robot) -> None:
    rng = np.random.default_rng(5)
    solver = get_solver(arm)
    q = _random_q(arm, rng, 0.3)
    value = get_solver(arm).parameter_of(q)
    target = arm.fk(q).homogeneous
    index = next(s.index for s in analytic(arm, target, redundancy=value)
                 if np.abs(s.q - q).max() <= ATOL_ROUND_TRIP)  # fmt: skip
    q_next, got, within = solver.track(target, q + 1e-3, index, 0.01, redundancy=value)
    assert got == index and within
    np.testing.assert_allclose(q_next, q, rtol=0, atol=ATOL_ROUND_TRIP)


def _regularity(robot: Robot, q: np.ndarray) -> float:
    """σ_min of the 6 × 7 Jacobian stacked on the parameter's gradient (1 × 7).

    Zero where the pose and the parameter do not fix q locally: a shoulder,
    elbow or wrist singularity of the branch at that parameter value.
    """
    h = 1e-6
    steps = np.concatenate([q + h * np.eye(7), q - h * np.eye(7)])
    values = get_solver(robot).parameter_of(steps)
    gradient = _wrapped(values[:7] - values[7:]) / (2 * h)
    stacked = np.vstack([robot.jacobian_local(q), gradient])
    return float(np.linalg.svd(stacked, compute_uv=False)[-1])


@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(
    name=st.sampled_from(NAMES),
    unit=st.lists(st.floats(0.02, 0.98), min_size=7, max_size=7),
)
def test_round_trip_contains_q(name: str, unit: list[float]) -> None:
    """analytic(fk(q), redundancy=solver.parameter_of(q)) holds q."""
    robot = load_robot(name)
    q = robot.lower + np.asarray(unit) * (robot.upper - robot.lower)
    assume(_regularity(robot, q) > REGULAR)
    target = robot.fk(q).homogeneous
    value = get_solver(robot).parameter_of(q)
    solutions = analytic(robot, target, redundancy=value)
    error = min(np.abs(_wrapped(s.q - q)).max() for s in solutions)
    assert error <= ATOL_ROUND_TRIP
    assert nearest(solutions, q).within_limits


# -- bad input -------------------------------------------------------------------------


def test_bad_input_is_refused_with_its_message(arm: Robot) -> None:
    q = _random_q(arm, np.random.default_rng(6))
    target = arm.fk(q).homogeneous
    value = get_solver(arm).parameter_of(q)
    parameter = get_solver(arm).parameter
    with pytest.raises(InputError, match=f"give redundancy=.*{parameter}") as err:
        analytic(arm, target)
    assert "choose_redundancy" in str(err.value)
    with pytest.raises(InputError, match="give redundancy="):
        analytic_batch(arm, target[None])
    with pytest.raises(DimensionError):
        analytic(arm, target, q_previous=np.zeros(6))
    with pytest.raises(DimensionError):
        analytic(arm, target[:3], redundancy=value)
    nan = target.copy()
    nan[0, 3] = np.nan
    with pytest.raises(NonFiniteError):
        analytic(arm, nan, redundancy=value)
    with pytest.raises(NonFiniteError, match="targets must be finite: pose 1"):
        analytic_batch(arm, np.array([target, nan]), redundancy=value)
    with pytest.raises(NonFiniteError, match="redundancy"):
        analytic(arm, target, redundancy=math.nan)
    with pytest.raises(NonFiniteError):
        analytic_batch(arm, target[None], redundancy=[math.inf])
    with pytest.raises(InputError, match="must be a number"):
        analytic(arm, target, redundancy="0.5")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="must be a number"):
        analytic(arm, target, redundancy=True)
    with pytest.raises(DimensionError):
        analytic_batch(arm, np.array([target, target]), redundancy=[0.1, 0.2, 0.3])
    sheared = target.copy()
    sheared[0, 1] += 1e-3
    with pytest.raises(InputError, match="target rotation"):
        analytic(arm, sheared, redundancy=value)
    with pytest.raises(InputError, match="rigid transforms: pose 0"):
        analytic_batch(arm, sheared[None], redundancy=value)
    with pytest.raises(NonFiniteError):
        get_solver(arm).parameter_of(np.full(7, np.nan))
    with pytest.raises(DimensionError):
        get_solver(arm).parameter_of(np.zeros((3, 6)))


def test_six_axis_arm_has_no_redundancy() -> None:
    robot = load_robot("ur5")
    target = robot.fk(np.full(6, 0.3)).homogeneous
    with pytest.raises(InputError, match="no redundancy"):
        analytic(robot, target, redundancy=0.0)
    with pytest.raises(InputError, match="no redundancy"):
        analytic_batch(robot, target[None], redundancy=0.0)
    with pytest.raises(InputError, match="no redundancy"):
        get_solver(robot).parameter_of(np.zeros(6))
    assert len(analytic(robot, target)) == 8  # unchanged without redundancy
    with pytest.raises(UnsupportedRobotError, match="9 joint variables"):
        analytic(load_robot("kinova"), np.eye(4), redundancy=0.0)


def test_unreachable_srs_says_why() -> None:
    robot = load_robot("iiwa14")
    target = np.eye(4)
    target[:3, 3] = [2.0, 0.0, 0.5]  # 2 m out: the arm reaches 0.82 m + flange
    with pytest.raises(UnreachableError) as err:
        analytic(robot, target, redundancy=0.3)
    message = str(err.value)
    assert message.startswith("out of reach for every arm angle: wrist centre at")
    assert "reach is [0.02, 0.82] m" in message
    assert err.value.bounds == pytest.approx((0.02, 0.82), abs=1e-12)
    with pytest.raises(UnreachableError):
        choose_redundancy(robot, target)
    assert get_solver(robot).feasible(target).union == ()


def test_unreachable_franka_names_the_feasible_q7() -> None:
    robot = load_robot("panda")
    solver = get_solver(robot)
    rng = np.random.default_rng(7)
    grid = np.linspace(*solver.parameter_range, 41)
    for q in (_random_q(robot, rng) for _ in range(50)):
        target = robot.fk(q).homogeneous
        _, valid = solver.solve_batch(
            np.broadcast_to(target, (41, 4, 4)), redundancy=grid
        )
        missing = np.flatnonzero(~valid.any(axis=1))
        if len(missing):
            break
    else:
        pytest.fail("no pose of 50 misses some q7")
    value = float(grid[missing[0]])
    with pytest.raises(UnreachableError) as err:
        analytic(robot, target, redundancy=value)
    message = str(err.value)
    assert message.startswith(f"out of reach for q7 = {value:.6g} rad: ")
    union = get_solver(robot).feasible(target).union
    assert union and any(lo <= q[6] <= hi for lo, hi in union)
    assert f"feasible q7 (every joint within its limits): [{union[0][0]:.6g}, " in (
        message
    )


def test_an_arc_through_pi_is_said_to_join() -> None:
    """The arm angle is circular: intervals at −π and π are one arc (SRS)."""
    from workbench.cli._redundancy import describe_feasible

    robot = load_robot("iiwa14")
    target = np.eye(4)
    target[:3, :3] = np.diag([-1.0, 1.0, -1.0])
    target[:3, 3] = [0.5, 0.2, 0.7]
    feasible = get_solver(robot).feasible(target)
    assert feasible.circular and len(feasible.union) == 2
    assert feasible.union[0][0] == -math.pi and feasible.union[-1][1] == math.pi
    for value in (math.pi - 1e-6, -math.pi + 1e-6):  # both sides of ±π serve
        assert any(s.within_limits for s in analytic(robot, target, redundancy=value))
    assert describe_feasible(feasible, False).endswith(
        "(the first and the last are one arc through ±π)"
    )


def test_choose_redundancy_says_why_no_value_serves() -> None:
    """Out of reach for every q7 (sampled), or reached outside the limits only."""
    robot = load_robot("panda")
    far = np.eye(4)
    far[:3, 3] = [5.0, 0.2, 0.5]
    with pytest.raises(UnreachableError) as err:
        choose_redundancy(robot, far)
    message = str(err.value)
    assert message.startswith("out of reach for every q7 in [-2.8973, 2.8973] rad")
    assert err.value.distance == pytest.approx(np.linalg.norm([5.0, 0.2]), abs=0.2)
    low = np.eye(4)  # the hand in the base: reached, never within the limits
    low[:3, :3] = np.diag([1.0, -1.0, -1.0])
    low[2, 3] = 0.2
    solver = get_solver(robot)
    grid = np.linspace(*solver.parameter_range, 721)
    _, valid = solver.solve_batch(np.broadcast_to(low, (721, 4, 4)), redundancy=grid)
    assert valid.any()
    with pytest.raises(InfeasibleError, match="reached outside them"):
        choose_redundancy(robot, low)


# -- redundancy tools ------------------------------------------------------------------


def test_feasible_intervals_are_feasible(arm: Robot) -> None:
    rng = np.random.default_rng(8)
    solver = get_solver(arm)
    q = _random_q(arm, rng, 0.2)
    feasible = get_solver(arm).feasible(arm.fk(q))
    assert isinstance(feasible, FeasibleRedundancy)
    assert feasible.parameter == solver.parameter
    assert feasible.circular is (solver.family.name == "srs")
    assert feasible.branches == solver.branches
    assert len(feasible.intervals) == len(solver.branches)
    value = get_solver(arm).parameter_of(q)
    assert any(lo - 1e-9 <= value <= hi + 1e-9 for lo, hi in feasible.union)
    for b, intervals in enumerate(feasible.intervals):
        for lo, hi in intervals:
            assert lo <= hi
            assert any(u_lo <= lo and hi <= u_hi for u_lo, u_hi in feasible.union)
            middle = 0.5 * (lo + hi)
            branch = [s for s in analytic(arm, arm.fk(q), redundancy=middle)
                      if s.index == b]  # fmt: skip
            assert branch and branch[0].within_limits
    lows = [lo for lo, _ in feasible.union]
    assert lows == sorted(lows)
    assert all(
        a[1] < b[0]
        for a, b in zip(feasible.union[:-1], feasible.union[1:], strict=True)
    )


def _brute_force(robot: Robot, target: np.ndarray, criterion: str, q_previous):
    """Best score over a grid of GRID values of the parameter, every branch."""
    solver = get_solver(robot)
    grid = np.linspace(*solver.parameter_range, GRID)
    q, valid = solver.solve_batch(
        np.broadcast_to(target, (GRID, 4, 4)), redundancy=grid
    )
    q = q[valid]
    ok = np.all((q >= robot.lower - LIMIT_SLACK) & (q <= robot.upper + LIMIT_SLACK),
                axis=1)  # fmt: skip
    q = q[ok]
    if criterion == "limit_margin":
        scores = np.minimum(q - robot.lower, robot.upper - q).min(axis=1)
    elif criterion == "manipulability":
        scores = np.array([_manipulability(robot, x) for x in q])
    else:
        scores = -np.linalg.norm(_wrapped(q - q_previous), axis=1)
    return float(scores.max())


def _manipulability(robot: Robot, q: np.ndarray) -> float:
    """Yoshikawa's measure from Pinocchio's world-frame Jacobian."""
    jac = robot.jacobian_local(q)
    world = np.zeros_like(jac)
    rotation = robot.fk(q).rotation
    world[:3], world[3:] = rotation @ jac[:3], rotation @ jac[3:]
    return math.sqrt(max(np.linalg.det(world @ world.T), 0.0))


@pytest.mark.slow
@pytest.mark.parametrize("criterion", ["limit_margin", "manipulability", "nearest"])
def test_choice_beats_brute_force(arm: Robot, criterion: str) -> None:
    rng = np.random.default_rng(9)
    q = _random_q(arm, rng, 0.3)
    target = arm.fk(q).homogeneous
    previous = q + rng.uniform(-0.2, 0.2, 7)
    choice = choose_redundancy(arm, target, criterion=criterion, q_previous=previous)
    best = _brute_force(arm, target, criterion, previous)
    assert choice.criterion == criterion
    assert choice.score >= best - 1e-9  # refined: no grid value is better
    assert choice.score <= best + 1e-3  # ... nor much worse than the grid's best
    s = choice.solution
    assert s.redundancy == choice.value and s.within_limits
    assert _fk_error(arm, s.q, target) <= ATOL_FK
    if criterion == "limit_margin":
        own = np.minimum(s.q - arm.lower, arm.upper - s.q).min()
    elif criterion == "manipulability":
        own = _manipulability(arm, s.q)
    else:
        own = -np.linalg.norm(_wrapped(s.q - previous))
    assert own == pytest.approx(choice.score, abs=1e-9)
    again = choose_redundancy(arm, target, criterion=criterion, q_previous=previous)
    assert again.value == choice.value  # deterministic


def test_choice_of_one_branch_and_bad_choices(arm: Robot) -> None:
    q = _random_q(arm, np.random.default_rng(10), 0.3)
    target = arm.fk(q).homogeneous
    solver = get_solver(arm)
    feasible = get_solver(arm).feasible(target)
    b = next(i for i, intervals in enumerate(feasible.intervals) if intervals)
    by_label = choose_redundancy(arm, target, branch=solver.branches[b])
    by_index = choose_redundancy(arm, target, branch=b)
    assert by_label.solution.index == by_index.solution.index == b
    assert by_label.value == by_index.value
    assert any(lo <= by_label.value <= hi for lo, hi in feasible.intervals[b])
    with pytest.raises(InputError, match="criterion must be one of"):
        choose_redundancy(arm, target, criterion="fast")
    with pytest.raises(InputError, match='"nearest" needs q_previous'):
        choose_redundancy(arm, target, criterion="nearest")
    with pytest.raises(InputError, match="is not one of"):
        choose_redundancy(arm, target, branch="left")
    with pytest.raises(InputError, match=r"not in 0\.\."):
        choose_redundancy(arm, target, branch=len(solver.branches))
    with pytest.raises(DimensionError):
        choose_redundancy(arm, target, q_previous=np.zeros(3))
    empty = [i for i, intervals in enumerate(feasible.intervals) if not intervals]
    if empty:
        with pytest.raises(InfeasibleError, match="within the joint limits"):
            choose_redundancy(arm, target, branch=empty[0])
