"""ik.select and ik.pick_place_configurations: one rule for every caller."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from conftest import random_configurations

from workbench import InfeasibleError, InputError, ik, load_robot
from workbench.ik import UnreachableError

#: FK of an IK solution against its target (exact math, compiled kernels).
ATOL_FK = 1e-12
SIX_AXIS = ("puma560", "ur5")
SEVEN_AXIS = ("iiwa14", "panda")


@pytest.fixture(scope="module", params=SIX_AXIS + SEVEN_AXIS)
def arm(request):
    return load_robot(request.param)


def _margin(robot, q):
    return float(np.min(np.minimum(q - robot.lower, robot.upper - q)))


def _wrapped_distance(q, reference):
    step = np.remainder(q - reference + np.pi, 2 * np.pi) - np.pi
    return float(np.linalg.norm(step))


@pytest.mark.parametrize("name", SIX_AXIS)
def test_default_is_the_largest_limit_margin(name, rng) -> None:
    robot = load_robot(name)
    for q in random_configurations(robot, rng, 20):
        target = robot.fk(q)
        choice = ik.select(robot, target)
        within = [s for s in ik.analytic(robot, target) if s.within_limits]
        margins = [_margin(robot, s.q) for s in within]
        assert choice.rule == ik.DEFAULT_RULE == "limit_margin"
        assert choice.branch == within[int(np.argmax(margins))].branch
        assert choice.score == max(margins) and choice.within_limits
        assert choice.redundancy is None and choice.criterion is None
        assert choice.solution is not None and not choice.q.flags.writeable
        np.testing.assert_allclose(
            robot.fk(choice.q).homogeneous, target.homogeneous, rtol=0, atol=ATOL_FK
        )


@pytest.mark.parametrize("name", SEVEN_AXIS)
def test_seven_axis_default_is_choose_redundancy(name, rng) -> None:
    robot = load_robot(name)
    target = robot.fk(random_configurations(robot, rng, 1)[0])
    choice = ik.select(robot, target)
    best = ik.choose_redundancy(robot, target)
    assert (choice.branch, choice.redundancy, choice.score) == (
        best.solution.branch,
        best.value,
        best.score,
    )
    assert choice.criterion == "limit_margin" and np.array_equal(
        choice.q, best.solution.q
    )
    manipulable = ik.select(robot, target, criterion="manipulability")
    best = ik.choose_redundancy(robot, target, criterion="manipulability")
    assert manipulable.redundancy == best.value


def test_nearest_finds_the_generating_configuration(arm, rng) -> None:
    q = random_configurations(arm, rng, 1)[0]
    choice = ik.select(arm, arm.fk(q), q_near=q)
    assert choice.rule == "nearest" and choice.within_limits
    assert _wrapped_distance(choice.q, q) < 1e-9  # 7R: the golden search's value
    assert choice.score == pytest.approx(-_wrapped_distance(choice.q, q), abs=1e-15)
    if arm.nq == 7:  # at q's own value: the kernel's exact solution
        value = float(ik.get_solver(arm).parameter_of(q))
        exact = ik.select(arm, arm.fk(q), q_near=q, redundancy=value)
        np.testing.assert_allclose(exact.q, q, rtol=0, atol=1e-12)


def test_named_and_first_branches(arm, rng) -> None:
    target = arm.fk(random_configurations(arm, rng, 1)[0])
    default = ik.select(arm, target)
    named = ik.select(arm, target, branch=default.branch)
    assert named.rule == "branch" and named.branch == default.branch
    first = ik.select(arm, target, rule="first_within_limits")
    if arm.nq == 6:
        within = [s for s in ik.analytic(arm, target) if s.within_limits]
        assert first.branch == within[0].branch and first.score is None
    else:
        feasible = ik.get_solver(arm).feasible(target)
        labels = [
            b for b, i in zip(feasible.branches, feasible.intervals, strict=True) if i
        ]
        assert first.branch == labels[0]


def test_a_branch_out_of_the_limits_is_infeasible(rng) -> None:
    robot = load_robot("puma560")
    for q in random_configurations(robot, rng, 50):
        outside = [s for s in ik.analytic(robot, robot.fk(q)) if not s.within_limits]
        if outside:
            break
    with pytest.raises(InfeasibleError, match=f"on branch {outside[0].branch}"):
        ik.select(robot, robot.fk(q), branch=outside[0].branch)


def test_unreachable_pose() -> None:
    far = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.0]))
    with pytest.raises(UnreachableError):
        ik.select(load_robot("ur5"), far)


def test_an_arm_of_no_family_is_solved_numerically(rng) -> None:
    arm = load_robot("generic6r")
    q = random_configurations(arm, rng, 1)[0]
    choice = ik.select(arm, arm.fk(q), q_near=q)
    assert (choice.branch, choice.index, choice.rule) == ("numeric", None, "numeric")
    assert choice.solution is None and choice.within_limits
    np.testing.assert_allclose(
        arm.fk(choice.q).homogeneous, arm.fk(q).homogeneous, atol=1e-9
    )
    again = ik.select(arm, arm.fk(q), q_near=q)
    assert np.array_equal(again.q, choice.q)  # deterministic


@pytest.mark.parametrize(
    ("name", "options", "fragment"),
    [
        ("ur5", {"rule": "best"}, "rule must be one of"),
        ("ur5", {"rule": "nearest"}, "needs q_near"),
        ("ur5", {"rule": "branch"}, "needs branch"),
        ("ur5", {"branch": "left"}, "unknown branch 'left'; valid: shoulder-right"),
        (
            "ur5",
            {"rule": "limit_margin", "branch": "shoulder-right/elbow-up/wrist-up"},
            "it is the rule",
        ),
        ("ur5", {"redundancy": 0.3}, "seven-axis arms"),
        ("ur5", {"criterion": "manipulability"}, "seven-axis arms"),
        ("ur5", {"q_near": [0.0] * 5}, "6 values expected"),
        ("iiwa14", {"redundancy": 0.3, "criterion": "limit_margin"}, "not with"),
        ("iiwa14", {"redundancy": "half"}, "must be a number"),
        ("iiwa14", {"criterion": "dexterity"}, "criterion must be one of"),
        ("iiwa14", {"criterion": "nearest"}, "needs q_near"),
        ("generic6r", {"branch": "numeric"}, "no closed-form IK"),
    ],
)
def test_bad_requests_raise_input_errors(name, options, fragment) -> None:
    robot = load_robot(name)
    target = robot.fk(np.clip(np.full(robot.nq, 0.3), robot.lower, robot.upper))
    with pytest.raises(InputError, match=fragment):
        ik.select(robot, target, **options)
    with pytest.raises(InputError, match=fragment):
        ik.pick_place_configurations(robot, target, target, **options)


def test_bad_target_is_an_input_error() -> None:
    with pytest.raises(InputError, match="bottom row"):
        ik.select(load_robot("ur5"), np.zeros((4, 4)))


def test_pick_and_place_share_the_branch_of_the_best_pair(arm, rng) -> None:
    q0, q1 = random_configurations(arm, rng, 2)
    pick, place = ik.pick_place_configurations(arm, arm.fk(q0), arm.fk(q1))
    assert pick.branch == place.branch
    assert pick.within_limits and place.within_limits
    for choice, q in ((pick, q0), (place, q1)):
        np.testing.assert_allclose(
            arm.fk(choice.q).homogeneous, arm.fk(q).homogeneous, rtol=0, atol=ATOL_FK
        )
    if arm.nq == 7:
        best = ik.choose_redundancy(arm, arm.fk(q1), branch=place.branch)
        assert place.redundancy == best.value and place.score == best.score
        return
    # six axes: no other branch serving both has a larger smaller margin
    pair = min(_margin(arm, pick.q), _margin(arm, place.q))
    for first in ik.analytic(arm, arm.fk(q0)):
        if not first.within_limits:
            continue
        places = ik.analytic(arm, arm.fk(q1), q_previous=first.q)
        second = next((s for s in places if s.index == first.index), None)
        if second is not None and second.within_limits:
            assert min(_margin(arm, first.q), _margin(arm, second.q)) <= pair
            if first.index == pick.index:  # the place nearest the pick
                assert np.array_equal(second.q, place.q)


def test_without_a_common_branch_the_place_is_nearest_the_pick(rng) -> None:
    robot = load_robot("puma560")
    for _ in range(500):
        q0, q1 = random_configurations(robot, rng, 2)
        picks = [s for s in ik.analytic(robot, robot.fk(q0)) if s.within_limits]
        if not any(
            s.index == p.index and s.within_limits
            for p in picks
            for s in ik.analytic(robot, robot.fk(q1), q_previous=p.q)
        ):
            break
    else:
        pytest.fail("no pair of poses without a common branch in 500 draws")
    pick, place = ik.pick_place_configurations(robot, robot.fk(q0), robot.fk(q1))
    assert pick.branch != place.branch
    assert np.array_equal(pick.q, ik.select(robot, robot.fk(q0)).q)
    nearest = ik.select(robot, robot.fk(q1), q_near=pick.q)
    assert np.array_equal(place.q, nearest.q) and place.rule == "nearest"
    with pytest.raises(InfeasibleError, match="on the pick's branch"):
        ik.pick_place_configurations(
            robot, robot.fk(q0), robot.fk(q1), branch=pick.branch
        )


def test_nearest_pair_minimises_the_joint_motion(rng) -> None:
    robot = load_robot("ur5")
    q0, q1, start = random_configurations(robot, rng, 3)
    pick, place = ik.pick_place_configurations(
        robot, robot.fk(q0), robot.fk(q1), q_near=start
    )
    assert pick.rule == place.rule == "nearest" and pick.branch == place.branch
    motion = _wrapped_distance(pick.q, start) + _wrapped_distance(place.q, pick.q)
    for first in ik.analytic(robot, robot.fk(q0), q_previous=start):
        places = ik.analytic(robot, robot.fk(q1), q_previous=first.q)
        second = next((s for s in places if s.index == first.index), None)
        if first.within_limits and second is not None and second.within_limits:
            other = _wrapped_distance(first.q, start)
            other += _wrapped_distance(second.q, first.q)
            assert other >= motion - 1e-12
