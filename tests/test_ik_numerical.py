"""Numerical IK: convergence on every arm, limits, failure and input errors."""

from __future__ import annotations

import dataclasses
import re
import threading

import numpy as np
import pinocchio as pin
import pytest

from workbench import DimensionError, InputError, NonFiniteError, Robot, load_robot
from workbench.ik import IKResult, numeric
from workbench.ik._chain import StateBlocks

ATOL_IK = 1e-9
"""Pose error accepted from the solver [m] and [rad]."""

ATOL_EXACT = 1e-12
"""Same quantity computed twice."""

DEFAULT_TOL = 1e-10
"""numeric's default threshold on |log6 error|."""

TARGETS_PER_ROBOT = 25

ROBOT_NAMES = ("puma560", "puma560-kang", "ur5", "panda")


@pytest.fixture(scope="module", params=ROBOT_NAMES)
def robot(request: pytest.FixtureRequest) -> Robot:
    return load_robot(request.param)


@pytest.fixture(scope="module")
def ur5() -> Robot:
    return load_robot("ur5")


def pose_errors(robot: Robot, q: np.ndarray, target: pin.SE3) -> tuple[float, float]:
    """Position [m] and rotation [rad] error of the tool at q, from scratch."""
    pose = robot.fk(q)
    position = np.linalg.norm(pose.translation - target.translation)
    rotation = np.linalg.norm(pin.log3(pose.rotation.T @ target.rotation))
    return float(position), float(rotation)


def random_configuration(robot: Robot, rng: np.random.Generator) -> np.ndarray:
    return rng.uniform(robot.lower, robot.upper)


def test_converges_on_random_reachable_targets(
    robot: Robot, rng: np.random.Generator
) -> None:
    for _ in range(TARGETS_PER_ROBOT):
        target = robot.fk(random_configuration(robot, rng))
        result = numeric(robot, target, rng=rng)
        assert result.success, result
        position, rotation = pose_errors(robot, result.q, target)
        assert position <= ATOL_IK
        assert rotation <= ATOL_IK
        assert result.error <= DEFAULT_TOL
        assert np.all(result.q >= robot.lower)
        assert np.all(result.q <= robot.upper)


def test_random_targets_take_few_steps(robot: Robot, rng: np.random.Generator) -> None:
    """The default first guess (nearest candidate) keeps the step count low."""
    steps = []
    for _ in range(100):
        target = robot.fk(random_configuration(robot, rng))
        result = numeric(robot, target, rng=rng)
        assert result.success
        steps.append(result.iterations)
    assert np.median(steps) <= 8


def test_replaced_limits_are_respected(rng: np.random.Generator) -> None:
    """What is cached per robot follows new limit arrays."""
    robot = load_robot("puma560")
    q_true = np.array([0.3, -0.8, 0.6, 0.5, 0.9, 0.4])
    # The wrist-flipped configuration reaches the same pose.
    q_flip = q_true + np.array([0.0, 0.0, 0.0, -np.pi, -1.8, -np.pi])
    target = robot.fk(q_true)
    assert max(pose_errors(robot, q_flip, target)) <= ATOL_EXACT
    assert numeric(robot, target, q_flip).success  # fills the cache
    robot.lower, robot.upper = q_true - 0.3, q_true + 0.3
    for q0 in (None, q_flip):
        result = numeric(robot, target, q0, rng=rng)
        assert result.success
        assert np.all(result.q >= robot.lower)
        assert np.all(result.q <= robot.upper)
        np.testing.assert_allclose(result.q, q_true, rtol=0, atol=1e-8)


def test_default_first_guess_is_repeatable(
    robot: Robot, rng: np.random.Generator
) -> None:
    for _ in range(5):
        target = robot.fk(random_configuration(robot, rng))
        first, second = numeric(robot, target), numeric(robot, target)
        np.testing.assert_array_equal(first.q, second.q)
        assert first.iterations == second.iterations


def test_reports_position_and_rotation_errors(
    robot: Robot, rng: np.random.Generator
) -> None:
    target = robot.fk(random_configuration(robot, rng))
    result = numeric(robot, target, max_iterations=2)  # stops far from it
    position, rotation = pose_errors(robot, result.q, target)
    np.testing.assert_allclose(result.position_error, position, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(result.rotation_error, rotation, rtol=0, atol=ATOL_EXACT)
    assert result.iterations <= 2


def test_accepts_a_homogeneous_matrix(puma: Robot, rng: np.random.Generator) -> None:
    target = puma.fk(random_configuration(puma, rng))
    result = numeric(puma, target.homogeneous)
    assert result.success
    assert max(pose_errors(puma, result.q, target)) <= ATOL_IK


def test_seed_near_a_solution_returns_that_solution(
    robot: Robot, rng: np.random.Generator
) -> None:
    q_true = random_configuration(robot, rng)
    q_true = np.clip(q_true, robot.lower + 0.1, robot.upper - 0.1)
    target = robot.fk(q_true)
    q0 = q_true + rng.uniform(-0.02, 0.02, robot.nq)
    result = numeric(robot, target, q0)
    assert result.success
    assert result.restarts == 0
    if robot.nv == 6:  # isolated solution: Newton converges onto it
        np.testing.assert_allclose(result.q, q_true, rtol=0, atol=1e-8)
    else:  # redundant: the null-space pull keeps it near the seed
        assert np.max(np.abs(result.q - q0)) < 0.1


def test_target_at_the_wrist_singularity(
    any_puma: Robot, rng: np.random.Generator
) -> None:
    """theta5 = 0: J is singular at the solution; damped steps take over."""
    for _ in range(5):
        q = random_configuration(any_puma, rng)
        q[4] = 0.0
        target = any_puma.fk(q)
        result = numeric(any_puma, target, rng=rng)
        assert result.success
        assert max(pose_errors(any_puma, result.q, target)) <= ATOL_IK


def test_already_solved_takes_no_step(puma: Robot, rng: np.random.Generator) -> None:
    q = random_configuration(puma, rng)
    result = numeric(puma, puma.fk(q), q)
    assert result.success
    assert result.iterations == 0
    np.testing.assert_array_equal(result.q, q)


def test_unreachable_target_returns_failure(
    robot: Robot, rng: np.random.Generator
) -> None:
    target = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.0]))  # 5 m away
    result = numeric(robot, target, rng=rng, time_budget=0.02)
    assert isinstance(result, IKResult)
    assert result.success is False
    assert result.position_error > 1.0
    assert result.q.shape == (robot.nq,)
    assert np.all(result.q >= robot.lower)
    assert np.all(result.q <= robot.upper)


def test_iteration_cap_bounds_the_work(puma: Robot) -> None:
    target = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.0]))
    result = numeric(puma, target, max_iterations=30, time_budget=10.0)
    assert not result.success
    assert result.iterations == 30
    assert result.restarts >= 1  # the error stalls long before


def test_same_seed_same_result(ur5: Robot, rng: np.random.Generator) -> None:
    target = ur5.fk(random_configuration(ur5, rng))
    first = numeric(ur5, target, rng=7)
    second = numeric(ur5, target, rng=np.random.default_rng(7))
    np.testing.assert_array_equal(first.q, second.q)


def test_result_is_frozen_and_read_only(puma: Robot) -> None:
    result = numeric(puma, puma.fk(np.zeros(6)))
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.success = False  # type: ignore[misc]
    with pytest.raises(ValueError, match="read-only"):
        result.q[0] = 1.0


def test_results_keep_their_own_values_across_state_blocks(
    ur5: Robot, rng: np.random.Generator
) -> None:
    """Results share blocks of states (StateBlocks): none overwrites another."""
    solves = 2 * StateBlocks.BLOCK + 5  # into a third block
    targets = [ur5.fk(random_configuration(ur5, rng)) for _ in range(solves)]
    results = [numeric(ur5, target) for target in targets]
    kept = [result.q.copy() for result in results]
    numeric(ur5, targets[0], q0=np.zeros(6))  # and one more with a first guess
    for result, q, target in zip(results, kept, targets, strict=True):
        np.testing.assert_array_equal(result.q, q)
        assert not result.q.flags.writeable and result.success
        assert max(pose_errors(ur5, result.q, target)) <= ATOL_IK


def test_state_blocks_hand_out_each_state_once_across_threads() -> None:
    fresh = np.array([0.0, 0.0, np.inf])
    blocks = StateBlocks(fresh)
    taken: list[list[tuple[np.ndarray, np.ndarray, int]]] = [[] for _ in range(4)]

    def take(into: list) -> None:
        for _ in range(3 * StateBlocks.BLOCK):
            into.append(blocks.take())

    threads = [threading.Thread(target=take, args=(t,)) for t in taken]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    states = [
        (block[row], read_only[row]) for into in taken for block, read_only, row in into
    ]
    addresses = {state.__array_interface__["data"][0] for state, _ in states}
    assert len(addresses) == len(states) == 12 * StateBlocks.BLOCK
    for state, read_only in states:
        np.testing.assert_array_equal(state, fresh)  # fresh when handed out
        assert state.flags.writeable and state.flags.c_contiguous
        assert not read_only.flags.writeable and np.shares_memory(state, read_only)


def test_continuous_joint_robot(tmp_path, rng: np.random.Generator) -> None:
    """nq != nv: a UR5 whose first joint is continuous (cos, sin)."""
    ur5 = load_robot("ur5")
    text = ur5.description
    head, tail = text.split('name="shoulder_pan_joint" type="revolute"', 1)
    path = tmp_path / "ur5_continuous.urdf"
    path.write_text(head + 'name="shoulder_pan_joint" type="continuous"' + tail)
    robot = load_robot(path, tool_frame=ur5.tool_frame)
    assert (robot.nq, robot.nv) == (7, 6)
    for _ in range(5):
        v = rng.uniform(-np.pi, np.pi, robot.nv)
        q = pin.integrate(robot.model, pin.neutral(robot.model), v)
        target = robot.fk(q)
        result = numeric(robot, target, rng=rng)
        assert result.success
        assert max(pose_errors(robot, result.q, target)) <= ATOL_IK
        np.testing.assert_allclose(
            np.hypot(result.q[0], result.q[1]), 1.0, rtol=0, atol=ATOL_EXACT
        )


def test_five_joint_arm_reaches_its_own_poses(
    puma: Robot, rng: np.random.Generator
) -> None:
    """nv < 6: the least-squares branch; FK poses are reachable."""
    model = pin.buildReducedModel(puma.model, [6], np.zeros(6))  # lock joint 6
    robot = Robot("puma5", model, puma.urdf_path, puma.tool_frame, package_dirs=[])
    for _ in range(5):
        target = robot.fk(random_configuration(robot, rng))
        result = numeric(robot, target, rng=rng)
        assert result.success
        assert max(pose_errors(robot, result.q, target)) <= ATOL_IK


@pytest.mark.parametrize(
    ("kwargs", "error", "fragment"),
    [
        ({"target": np.eye(3)}, DimensionError, "shape (4, 4)"),
        ({"target": np.full((4, 4), np.nan)}, NonFiniteError, "finite"),
        ({"target": 2.0 * np.eye(4)}, InputError, "bottom row"),
        ({"target": np.diag([2.0, 1.0, 1.0, 1.0])}, InputError, "orthonormal"),
        ({"q0": np.zeros(5)}, DimensionError, "6 values expected, 5 given"),
        ({"q0": np.full(6, np.nan)}, NonFiniteError, "finite"),
        ({"tol": 0.0}, InputError, "tol must be"),
        ({"tol": float("nan")}, InputError, "tol must be"),
        ({"max_iterations": 0}, InputError, "max_iterations must be"),
        ({"max_iterations": 2.5}, InputError, "max_iterations must be"),
        ({"time_budget": -1.0}, InputError, "time_budget must be"),
        ({"rng": "seed"}, InputError, "rng must be"),
    ],
)
def test_bad_input_raises(
    puma: Robot, kwargs: dict, error: type[Exception], fragment: str
) -> None:
    arguments = {"target": np.eye(4), **kwargs}
    target = arguments.pop("target")
    with pytest.raises(error, match=re.escape(fragment)):
        numeric(puma, target, **arguments)


def test_the_time_budget_starts_after_setup(rng: np.random.Generator) -> None:
    """A new robot's first solve: building its chain and loading the compiled
    kernel do not eat the default 0.1 s budget, so restarts still happen."""
    robot = load_robot("ur5")  # a new object: its chain is built in this call
    target = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.0]))  # out of reach
    result = numeric(robot, target, rng=rng)
    assert not result.success
    assert result.restarts >= 1


def test_read_only_target_is_accepted(puma: Robot, rng: np.random.Generator) -> None:
    target = puma.fk(random_configuration(puma, rng)).homogeneous
    target.setflags(write=False)
    result = numeric(puma, target)
    assert result.success
    assert max(pose_errors(puma, result.q, pin.SE3(target))) <= ATOL_IK
