"""The one door into the closed form: Solver, cached per robot, weakly."""

from __future__ import annotations

import gc
import weakref

import numpy as np
import pinocchio as pin
import pytest

from workbench import load_robot
from workbench.errors import InputError
from workbench.ik import (
    BRANCHES,
    FAMILIES,
    UR_BRANCHES,
    Flag,
    Solver,
    UnsupportedRobotError,
    analytic,
    analytic_batch,
    get_solver,
    get_structure,
    nearest,
)
from workbench.model.per_robot import per_robot


@pytest.fixture(scope="module")
def puma():
    return load_robot("puma560")


def test_one_solver_per_robot_object(puma) -> None:
    solver = get_solver(puma)
    assert isinstance(solver, Solver)
    assert get_solver(puma) is solver
    assert solver.family is FAMILIES["opw"] and solver.branches == BRANCHES
    assert solver.robot is puma
    assert not solver.geometry.flags.writeable
    slower = puma.with_limits(velocity_limit=puma.velocity_limit / 2)
    assert get_solver(slower) is not solver


def test_ur_solver_has_ur_labels() -> None:
    solver = get_solver(load_robot("ur5"))
    assert solver.family is FAMILIES["ur"] and solver.branches == UR_BRANCHES


def test_seven_axis_arms_get_the_same_solver_type() -> None:
    for name, family, parameter in (  # (names: the registry's keys)
        ("iiwa14", "srs", "arm angle"),
        ("panda", "franka", "q7"),
    ):
        solver = get_solver(load_robot(name))
        assert isinstance(solver, Solver) and solver.nq == 7
        assert (solver.family, solver.parameter) == (FAMILIES[family], parameter)
    six = get_solver(load_robot("ur5"))
    assert (six.nq, six.parameter, six.parameter_range) == (6, None, None)


def test_no_closed_form_is_refused() -> None:
    with pytest.raises(UnsupportedRobotError, match="9 joint variables"):
        get_solver(load_robot("kinova"))


def test_redundancy_is_refused_without_redundancy(puma) -> None:
    solver = get_solver(puma)
    target = puma.fk(np.full(6, 0.3))
    with pytest.raises(InputError, match="no redundancy"):
        solver.solve(target, redundancy=0.3)
    with pytest.raises(InputError, match="no redundancy"):
        solver.parameter_of(np.zeros(6))
    with pytest.raises(InputError, match="no redundancy"):
        solver.feasible(target)
    with pytest.raises(InputError, match="no redundancy"):
        solver.solve_batch(target.homogeneous[None], redundancy=0.3)


def test_cache_holds_no_robot_alive() -> None:
    robot = load_robot("ur5")
    solver = weakref.ref(get_solver(robot))
    get_structure(robot)
    gone = weakref.ref(robot)
    del robot
    gc.collect()
    assert gone() is None
    assert solver() is None


def test_value_rebuilt_when_the_model_is_replaced(puma) -> None:
    calls = []

    @per_robot
    def count(robot):
        calls.append(robot)
        return len(calls)

    robot = load_robot("puma560")
    assert count(robot) == count(robot) == 1
    robot.model = pin.Model(robot.model)  # an equal copy: the same kinematics
    assert count(robot) == 1
    model = pin.Model(robot.model)
    model.jointPlacements[2].translation[0] += 1e-3
    robot.model = model
    assert count(robot) == 2
    robot.tool_frame_id = robot.model.getFrameId("frame5")
    assert count(robot) == 3 == count(robot)


def test_solve_and_front_door_agree(puma) -> None:
    rng = np.random.default_rng(3)
    qs = rng.uniform(puma.lower, puma.upper, size=(20, 6))
    targets = np.array([puma.fk(q).homogeneous for q in qs])
    solver = get_solver(puma)
    q_batch, valid = solver.solve_batch(targets)
    q_front, valid_front = analytic_batch(puma, targets)
    np.testing.assert_array_equal(q_batch, q_front)
    np.testing.assert_array_equal(valid, valid_front)
    for target, q in zip(targets, qs, strict=True):
        mine = solver.solve(target, q_previous=q)
        front = analytic(puma, target, q_previous=q)
        assert [s.branch for s in mine] == [s.branch for s in front]
        np.testing.assert_array_equal([s.q for s in mine], [s.q for s in front])


def test_solve_arrays_gives_one_byte_of_flags_per_branch(puma) -> None:
    q0 = np.array([0.1, -0.4, 0.3, 0.2, 0.5, -0.1])
    q, flags, solve_flags = get_solver(puma).solve_arrays(puma.fk(q0).homogeneous, q0)
    assert q.shape == (8, 6) and flags.shape == (8,) and flags.dtype == np.uint8
    solutions = analytic(puma, puma.fk(q0), q_previous=q0)
    assert [int(s.flags) for s in solutions] == flags.tolist()
    assert all(Flag.REACHED in s.flags for s in solutions)
    assert solve_flags == 0  # an exact model: every branch is the closed form's


def test_deviation_is_the_structure_s() -> None:
    robot = load_robot("ur5")
    expected = getattr(get_structure(robot), "deviation", None)
    assert get_solver(robot).deviation == expected


def test_track_continues_the_branch_of_the_motion(puma) -> None:
    solver = get_solver(puma)
    q0 = np.array([0.1, -0.4, 0.3, 0.2, 0.5, -0.1])
    start = nearest(analytic(puma, puma.fk(q0)), q0)
    q1 = q0 + 1e-3
    q, index, within = solver.track(puma.fk(q1).homogeneous, q1, start.index, 1e-2)
    assert index == start.index and within
    np.testing.assert_allclose(q, q1, atol=1e-12)
    # after a jump larger than max_step2 the nearest of all eight is taken
    other = analytic(puma, puma.fk(q1))[7]
    q, index, _ = solver.track(puma.fk(q1).homogeneous, other.q, 0, 0.0)
    assert index == 7
    np.testing.assert_allclose(q, other.q, atol=1e-12)
