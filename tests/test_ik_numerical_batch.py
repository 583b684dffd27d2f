"""numeric_batch: many targets in one compiled loop; agrees with numeric."""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given
from hypothesis import strategies as st

from workbench import DimensionError, InputError, NonFiniteError, Robot, load_robot
from workbench.ik import IKBatchResult, numeric, numeric_batch

ATOL_IK = 1e-9
"""Pose error accepted from the solver [m] and [rad]."""

ATOL_EXACT = 1e-12
"""Same quantity computed twice."""

ROBOT_NAMES = ("puma560", "puma560-kang", "ur5", "panda")


@pytest.fixture(scope="module", params=ROBOT_NAMES)
def robot(request: pytest.FixtureRequest) -> Robot:
    return load_robot(request.param)


@pytest.fixture(scope="module")
def ur5() -> Robot:
    return load_robot("ur5")


def fk_targets(robot: Robot, rng: np.random.Generator, count: int) -> np.ndarray:
    """Tool poses (count, 4, 4) of configurations uniform within the limits."""
    q = rng.uniform(robot.lower, robot.upper, (count, robot.nq))
    return np.array([robot.fk(row).homogeneous for row in q])


def max_pose_errors(robot: Robot, q: np.ndarray, targets: np.ndarray) -> tuple:
    """Largest position [m] and rotation [rad] error over a batch, from scratch."""
    position = rotation = 0.0
    for row, target in zip(q, targets, strict=True):
        pose = robot.fk(row)
        position = max(position, np.linalg.norm(pose.translation - target[:3, 3]))
        gap = pin.log3(pose.rotation.T @ target[:3, :3])
        rotation = max(rotation, np.linalg.norm(gap))
    return position, rotation


def test_solves_random_reachable_targets(
    robot: Robot, rng: np.random.Generator
) -> None:
    targets = fk_targets(robot, rng, 200)
    result = numeric_batch(robot, targets)
    assert isinstance(result, IKBatchResult)
    assert result.success.all()
    assert max(max_pose_errors(robot, result.q, targets)) <= ATOL_IK
    assert np.all(result.error <= 1e-10)
    assert np.all(result.q >= robot.lower)
    assert np.all(result.q <= robot.upper)


def test_reported_errors_are_the_pose_errors(robot: Robot, rng) -> None:
    targets = fk_targets(robot, rng, 10)
    result = numeric_batch(robot, targets, max_iterations=2)  # stops early
    for i, target in enumerate(targets):
        pose = robot.fk(result.q[i])
        position = np.linalg.norm(pose.translation - target[:3, 3])
        rotation = np.linalg.norm(pin.log3(pose.rotation.T @ target[:3, :3]))
        assert result.position_error[i] == pytest.approx(position, abs=ATOL_EXACT)
        assert result.rotation_error[i] == pytest.approx(rotation, abs=ATOL_EXACT)
    assert np.all(result.iterations <= 2)


def test_first_run_matches_numeric(robot: Robot, rng: np.random.Generator) -> None:
    """Without restarts, the batch takes numeric's steps: the same q."""
    targets = fk_targets(robot, rng, 50)
    batch = numeric_batch(robot, targets)
    for i, target in enumerate(targets):
        single = numeric(robot, target)
        if single.restarts == 0 and batch.restarts[i] == 0:
            np.testing.assert_array_equal(batch.q[i], single.q)
            assert batch.iterations[i] == single.iterations


def test_a_result_does_not_depend_on_the_batch(ur5: Robot, rng) -> None:
    targets = fk_targets(ur5, rng, 60)
    whole = numeric_batch(ur5, targets, rng=5)
    tail = numeric_batch(ur5, targets[30:], rng=5)
    # restart streams are per index: compare targets that needed none
    same = (whole.restarts[30:] == 0) & (tail.restarts == 0)
    np.testing.assert_array_equal(whole.q[30:][same], tail.q[same])
    again = numeric_batch(ur5, targets, rng=np.random.default_rng(3))
    repeat = numeric_batch(ur5, targets, rng=np.random.default_rng(3))
    np.testing.assert_array_equal(again.q, repeat.q)


def test_one_seed_or_one_per_target(ur5: Robot, rng: np.random.Generator) -> None:
    q_true = rng.uniform(ur5.lower + 0.1, ur5.upper - 0.1, (5, ur5.nq))
    targets = np.array([ur5.fk(q).homogeneous for q in q_true])
    near = numeric_batch(ur5, targets, q_true + 0.01)
    assert near.success.all()
    np.testing.assert_allclose(near.q, q_true, rtol=0, atol=1e-8)
    assert np.all(near.restarts == 0)
    same = numeric_batch(ur5, targets[:1], q_true[0] + 0.01)
    np.testing.assert_array_equal(same.q[0], near.q[0])


def test_unreachable_targets_fail_within_the_step_budget(robot: Robot) -> None:
    far = np.eye(4)
    far[0, 3] = 5.0  # 5 m away
    targets = np.stack([far, robot.fk(np.clip(np.zeros(robot.nq), robot.lower,
                                              robot.upper)).homogeneous])  # fmt: skip
    result = numeric_batch(robot, targets, max_iterations=100)
    assert result.success.tolist() == [False, True]
    assert result.iterations[0] == 100
    assert result.restarts[0] >= 1
    assert result.position_error[0] > 1.0
    assert np.all(result.q >= robot.lower)
    assert np.all(result.q <= robot.upper)


def test_continuous_joint_robot(tmp_path, rng: np.random.Generator) -> None:
    ur5 = load_robot("ur5")
    text = ur5.description.replace(
        'name="shoulder_pan_joint" type="revolute"',
        'name="shoulder_pan_joint" type="continuous"',
    )
    path = tmp_path / "ur5_continuous.urdf"
    path.write_text(text, encoding="utf-8")
    robot = load_robot(path, tool_frame=ur5.tool_frame)
    v = rng.uniform(-np.pi, np.pi, (10, robot.nv))
    q = [pin.integrate(robot.model, pin.neutral(robot.model), row) for row in v]
    targets = np.array([robot.fk(row).homogeneous for row in q])
    result = numeric_batch(robot, targets)
    assert result.q.shape == (10, 7)
    assert result.success.all()
    assert max(max_pose_errors(robot, result.q, targets)) <= ATOL_IK
    np.testing.assert_allclose(
        np.hypot(result.q[:, 0], result.q[:, 1]), 1.0, rtol=0, atol=ATOL_EXACT
    )


def test_result_arrays_are_read_only(ur5: Robot, rng) -> None:
    result = numeric_batch(ur5, fk_targets(ur5, rng, 2))
    for name in IKBatchResult.__slots__:
        with pytest.raises(ValueError, match="read-only"):
            getattr(result, name)[0] = 0


def test_empty_batch(ur5: Robot) -> None:
    result = numeric_batch(ur5, np.empty((0, 4, 4)))
    assert result.q.shape == (0, ur5.nq)
    assert result.success.shape == (0,)


@given(st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6))
def test_round_trip_property(ur5: Robot, fractions: list[float]) -> None:
    """IK(FK(q)) reaches FK(q), for configurations across the whole range."""
    q = ur5.lower + (np.array(fractions) + 1.0) / 2.0 * (ur5.upper - ur5.lower)
    target = ur5.fk(q)
    result = numeric_batch(ur5, target.homogeneous[np.newaxis])
    assert result.success[0]
    assert max(max_pose_errors(ur5, result.q, target.homogeneous[None])) <= ATOL_IK


@pytest.mark.parametrize(
    ("kwargs", "error", "fragment"),
    [
        ({"targets": np.eye(4)}, DimensionError, "targets"),
        ({"targets": np.full((2, 4, 4), np.nan)}, NonFiniteError, "pose 0"),
        ({"targets": 2.0 * np.eye(4)[None]}, InputError, "pose 0 is not"),
        ({"q0": np.zeros(5)}, DimensionError, "6 values expected, 5 given"),
        ({"q0": np.zeros((3, 6))}, DimensionError, "q0"),
        ({"q0": np.full((1, 6), np.nan)}, NonFiniteError, "q0 must be finite"),
        ({"q0": "abc"}, NonFiniteError, "q0"),
        ({"tol": -1.0}, InputError, "tol must be"),
        ({"max_iterations": 0}, InputError, "max_iterations must be"),
        ({"rng": -3}, InputError, "rng must be"),
    ],
)
def test_bad_input_raises(
    puma: Robot, kwargs: dict, error: type[Exception], fragment: str
) -> None:
    arguments = {"targets": np.eye(4)[None], **kwargs}
    targets = arguments.pop("targets")
    with pytest.raises(error, match=re.escape(fragment)):
        numeric_batch(puma, targets, **arguments)


def test_read_only_inputs(ur5: Robot, rng: np.random.Generator) -> None:
    targets = fk_targets(ur5, rng, 5)
    expected = numeric_batch(ur5, targets)
    targets.setflags(write=False)
    np.testing.assert_array_equal(numeric_batch(ur5, targets).q, expected.q)
