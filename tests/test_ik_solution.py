"""``workbench.ik.IKSolution`` and ``Solutions``: one solution type for every family."""

from __future__ import annotations

import copy
import pickle
from dataclasses import FrozenInstanceError

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from workbench import load_robot
from workbench.ik import (
    Flag,
    IKResult,
    IKSolution,
    Solutions,
    SolveFlag,
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


# -- Solutions: the sequence a solve returns -----------------------------------
LABELS = tuple(f"b{i}" for i in range(8))


def _solutions(
    mask: int, nq: int = 6, solve_flags: int = 0
) -> tuple[Solutions, np.ndarray]:
    """A Solutions whose branch i reaches where bit i of ``mask`` is set."""
    q_all = np.arange(8.0 * nq).reshape(8, nq)
    flags = np.zeros(8, dtype=np.uint8)
    for i in range(8):
        if mask >> i & 1:
            flags[i] = Flag.REACHED | (Flag.WITHIN_LIMITS if i % 2 else 0)
        else:
            q_all[i] = np.nan
    return Solutions.from_arrays(q_all, flags, LABELS, None, solve_flags), q_all


@given(mask=st.integers(0, 255))
def test_solutions_read_as_the_sequence_of_the_reached_branches(mask: int) -> None:
    solutions, q_all = _solutions(mask)
    reached = [i for i in range(8) if mask >> i & 1]
    assert len(solutions) == len(reached) and bool(solutions) == bool(reached)
    assert solutions.indices == tuple(reached)
    assert [s.index for s in solutions] == reached
    assert [s.branch for s in solutions] == [LABELS[i] for i in reached]
    assert [s.index for s in reversed(solutions)] == reached[::-1]
    for k, i in enumerate(reached):
        assert solutions[k] == solutions[k - len(reached)] == list(solutions)[k]
        assert solutions[k].index == i and solutions[k] in solutions
        assert solutions.index(solutions[k]) == k and solutions.count(solutions[k]) == 1
        np.testing.assert_array_equal(solutions[k].q, q_all[i])
        assert solutions[k].within_limits == bool(i % 2)
    assert solutions[1:] == tuple(list(solutions)[1:])
    np.testing.assert_array_equal(solutions.q, q_all[reached].reshape(-1, 6))
    np.testing.assert_array_equal(solutions.q_all, q_all)
    assert ((solutions.flags_all != 0) == [bool(mask >> i & 1) for i in range(8)]).all()
    for k in (len(reached), -len(reached) - 1):
        with pytest.raises(IndexError):
            solutions[k]


def test_solutions_are_immutable_equal_by_value_and_pickle() -> None:
    solutions, _ = _solutions(0b10110110, solve_flags=SolveFlag.BRANCH_VANISHED)
    assert solutions.solve_flags is SolveFlag.BRANCH_VANISHED
    with pytest.raises(FrozenInstanceError):
        solutions.q_all = np.zeros((8, 6))  # type: ignore[misc]
    with pytest.raises(ValueError, match="read-only"):
        solutions.q_all[0, 0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        solutions.flags_all[0] = 1
    with pytest.raises(ValueError, match="read-only"):
        solutions[0].q[0] = 1.0
    again, _ = _solutions(0b10110110, solve_flags=SolveFlag.BRANCH_VANISHED)
    assert again == solutions and hash(again) == hash(solutions)
    assert _solutions(0b10110111)[0] != solutions
    for copied in (pickle.loads(pickle.dumps(solutions)), copy.deepcopy(solutions)):
        assert copied == solutions and list(copied) == list(solutions)
    with pytest.raises(TypeError):
        solutions + solutions
    with pytest.raises(TypeError):
        solutions * 2
    assert "b1" in repr(solutions) and "BRANCH_VANISHED" in repr(solutions)


def test_a_solve_returns_solutions_of_its_arrays(arm) -> None:
    robot, q, solutions = arm
    assert type(solutions) is Solutions and solutions.solve_flags == 0
    q_all, flags, solve_flags = get_solver(robot).solve_arrays(
        robot.fk(q).homogeneous, np.empty(0), redundancy=solutions.redundancy
    )
    assert solve_flags == solutions.solve_flags
    np.testing.assert_array_equal(solutions.q_all, q_all)
    np.testing.assert_array_equal(solutions.flags_all, flags)
    assert solutions.branches == get_solver(robot).branches
    assert not solutions.q_all.flags.writeable
