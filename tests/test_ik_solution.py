"""``workbench.ik.IKSolution``: one solution type for every family, one flag byte."""

from __future__ import annotations

import copy
import pickle
from dataclasses import FrozenInstanceError

import numpy as np
import pytest

from workbench import load_robot
from workbench.ik import (
    Flag,
    IKResult,
    IKSolution,
    analytic,
    get_solver,
    nearest,
    numeric,
)
from workbench.model.robot import Robot

#: One arm per family and a configuration within its limits, away from singularities.
ARMS = {
    "puma560": np.array([0.2, -0.7, 1.1, 0.4, 0.9, -0.3]),
    "ur5": np.array([0.3, -1.1, 1.2, -0.6, 1.0, 0.4]),
    "iiwa14": np.array([0.3, 0.8, -0.4, -1.2, 0.5, 0.9, 0.2]),
    "panda": np.array([0.2, -0.4, 0.3, -2.0, 0.2, 1.8, 0.6]),
}
FIELDS = (
    "q", "branch", "index", "redundancy", "flags", "within_limits",
    "shoulder_singular", "elbow_singular", "wrist_singular", "parameter_singular",
)  # fmt: skip


@pytest.fixture(scope="module", params=sorted(ARMS))
def arm(request) -> tuple[Robot, np.ndarray, list[IKSolution]]:
    robot = load_robot(request.param)
    q = ARMS[request.param]
    solver = get_solver(robot)
    value = None if solver.parameter is None else float(solver.parameter_of(q))
    return robot, q, analytic(robot, robot.fk(q), redundancy=value)


def test_six_and_seven_axis_arms_share_one_solution_type(arm) -> None:
    robot, q, solutions = arm
    assert solutions and all(type(s) is IKSolution for s in solutions)
    solver = get_solver(robot)
    for s in solutions:
        assert s.q.shape == (robot.nq,)
        assert s.branch == solver.branches[s.index]
        if solver.parameter is None:
            assert s.redundancy is None and not s.parameter_singular
        else:
            assert s.redundancy == pytest.approx(float(solver.parameter_of(q)), abs=0)
    best = nearest(solutions, q)
    np.testing.assert_allclose(best.q, q, rtol=0, atol=1e-9)


def test_flags_are_named_bits_of_one_byte(arm) -> None:
    robot, _, solutions = arm
    q_all, flags, _ = get_solver(robot).solve_arrays(
        robot.fk(arm[1]).homogeneous,
        np.empty(0),
        redundancy=solutions[0].redundancy,
    )
    assert flags.dtype == np.uint8
    for s in solutions:
        bits = Flag(int(flags[s.index]))
        assert s.flags == bits and Flag.REACHED in bits
        assert s.within_limits == (Flag.WITHIN_LIMITS in bits)
        assert s.shoulder_singular == (Flag.SHOULDER_SINGULAR in bits)
        assert s.elbow_singular == (Flag.ELBOW_SINGULAR in bits)
        assert s.wrist_singular == (Flag.WRIST_SINGULAR in bits)
        assert s.parameter_singular == (Flag.PARAMETER_SINGULAR in bits)
    reached = ~np.isnan(q_all[:, 0])
    assert ((flags != 0) == reached).all()  # an unreached branch has the byte 0


def test_solution_is_immutable(arm) -> None:
    _, _, solutions = arm
    s = solutions[0]
    for name in (*FIELDS, "other"):
        with pytest.raises(FrozenInstanceError, match=name):
            setattr(s, name, None)
        with pytest.raises(FrozenInstanceError, match=name):
            delattr(s, name)
    with pytest.raises(ValueError, match="read-only"):
        s.q[0] = 1.0


def test_equality_is_by_value_and_pickling_keeps_it(arm) -> None:
    robot, q, solutions = arm
    again = analytic(robot, robot.fk(q), redundancy=solutions[0].redundancy)
    assert again == solutions and again[0] is not solutions[0]
    assert len({*solutions, *again}) == len(solutions)  # hash agrees with ==
    assert solutions[0] != solutions[1]  # another branch
    for s in solutions:
        copied = pickle.loads(pickle.dumps(s))
        assert copied == s and hash(copied) == hash(s)
        assert not copied.q.flags.writeable
        assert copy.copy(s) is s and copy.deepcopy(s) is s
    assert all(field in repr(solutions[0]) for field in FIELDS if field != "flags")


def test_near_singular_elbow_is_flagged_on_six_axes() -> None:
    """A stretched elbow: elbow-up and elbow-down meet, both flagged."""
    robot = load_robot("ur5")
    solver = get_solver(robot)
    q = np.array([0.3, -1.1, 0.0, -0.6, 1.0, 0.4])  # θ3 = 0: the arm stretched
    solutions = solver.solve(robot.fk(q), q_previous=q)
    stretched = nearest(solutions, q)
    assert stretched.elbow_singular
    twin = next(s for s in solutions if s.index == stretched.index ^ 2)
    assert twin.elbow_singular
    np.testing.assert_allclose(twin.q, stretched.q, rtol=0, atol=1e-6)
    assert not any(s.elbow_singular for s in solver.solve(robot.fk(ARMS["ur5"])))


def test_numerical_result_is_the_same_kind_of_record() -> None:
    robot = load_robot("puma560")
    result = numeric(robot, robot.fk(ARMS["puma560"]))
    assert result.success
    with pytest.raises(FrozenInstanceError, match="success"):
        result.success = False  # type: ignore[misc]
    copied = pickle.loads(pickle.dumps(result))
    assert copied == result and type(copied) is IKResult
    built = IKResult(
        result.q, True, result.iterations, result.error,
        result.position_error, result.rotation_error, result.restarts,
    )  # fmt: skip
    assert built == result
