"""The online planner on seven-axis arms: null-space velocity, redundancy policy."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given
from hypothesis import strategies as st

from workbench import InfeasibleError, InputError, Robot, load_robot
from workbench.ik import (
    DLS_EPSILON,
    DLS_LAMBDA_MAX,
    compute_tool_poses,
    get_solver,
    nearest,
    solve_null_space_velocity,
)
from workbench.planning import CartesianLimits, OnlinePlanner, StraightLine
from workbench.planning.online_planner import SPEED_RTOL
from workbench.planning.redundancy_policy import (
    KEEP_LIMIT_MARGIN,
    LIMIT_SHARPNESS,
    compute_limit_gradient,
    compute_limit_margin,
    compute_limit_score,
    compute_manipulability_gradient,
)
from workbench.poses import rotation_from_axis_angle

#: Against NumPy's pseudo-inverse (LAPACK SVD), relative to the largest entry.
RTOL_SVD = 1e-12
#: The closed form's pose against Pinocchio's FK [m, 1].
ATOL_POSE = 1e-12
#: J q̇ against the commanded twist [m/s, rad/s].
ATOL_TWIST = 1e-10
#: The trace against ik's parameter of the command [rad].
ATOL_PARAMETER = 1e-9
#: Central differences of the limit score (step 1e-6 rad).
ATOL_FD = 1e-6
#: Central differences (step 1e-6 rad) of the manipulability [m³/rad]: the
#: truncation ~1e-12, the rounding of √det ~1e-16 / 1e-6.
ATOL_FD_GRADIENT = 1e-9
LIMITS_PERIOD = 0.01  # [s], the planner's default planning period


def _wide_jacobian(seed: int, squash: float) -> np.ndarray:
    """Random 6 × 7 J, singular values >= 0.1 but the smallest times ``squash``."""
    rng = np.random.default_rng(seed)
    u, sigma, vt = np.linalg.svd(rng.normal(size=(6, 7)), full_matrices=False)
    sigma = np.maximum(sigma, 0.1)
    sigma[-1] *= squash
    return (u * sigma) @ vt


@given(seed=st.integers(0, 2**32 - 1))
def test_null_space_velocity_is_the_pseudo_inverse_plus_the_projected_motion(seed):
    jacobian = _wide_jacobian(seed, 1.0)
    rng = np.random.default_rng(seed + 1)
    twist, qd_null = rng.normal(size=6), rng.normal(size=7)
    qd, damped = solve_null_space_velocity(
        jacobian, twist, DLS_EPSILON, DLS_LAMBDA_MAX, qd_null
    )
    pinv = np.linalg.pinv(jacobian)
    expected = pinv @ twist + (np.eye(7) - pinv @ jacobian) @ qd_null
    scale = max(1.0, np.abs(expected).max())
    np.testing.assert_allclose(qd, expected, rtol=0, atol=RTOL_SVD * scale)
    np.testing.assert_allclose(jacobian @ qd, twist, rtol=0, atol=RTOL_SVD * scale)
    assert not damped


@given(seed=st.integers(0, 2**32 - 1), squash=st.sampled_from([1e-3, 1e-8, 1e-16, 0.0]))
def test_null_space_velocity_is_damped_in_the_singular_region(seed, squash):
    jacobian = _wide_jacobian(seed, squash)
    rng = np.random.default_rng(seed + 1)
    twist, qd_null = rng.normal(size=6), rng.normal(size=7)
    qd, damped = solve_null_space_velocity(
        jacobian, twist, DLS_EPSILON, DLS_LAMBDA_MAX, qd_null
    )
    # the DLS inverse of workbench.ik.dls_inverse, written out from LAPACK's SVD
    u, sigma, vt = np.linalg.svd(jacobian, full_matrices=False)
    lambda2 = (1.0 - (sigma[-1] / DLS_EPSILON) ** 2) * DLS_LAMBDA_MAX**2
    dls = (vt.T * (sigma / (sigma**2 + lambda2))) @ u.T
    expected = dls @ twist + (np.eye(7) - dls @ jacobian) @ qd_null
    scale = max(1.0, np.abs(expected).max())
    np.testing.assert_allclose(qd, expected, rtol=0, atol=RTOL_SVD * scale)
    assert damped


# -- the planner on seven-axis arms ------------------------------------------------
#: The iiwa14 near joint 1's upper limit; turning the tool 0.7 rad about the
#: base axis along a straight line takes q1 beyond it at the start's arm angle.
IIWA_START = np.array([2.5, 0.7, 0.3, -1.3, 0.2, 1.0, 0.1])
TURN = 0.7  # [rad]
LIMITS = CartesianLimits(0.1, 0.5, 0.4, 1.0)
#: The panda away from its limits.
PANDA_START = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])


@pytest.fixture(scope="module")
def iiwa() -> Robot:
    return load_robot("iiwa14")


@pytest.fixture(scope="module")
def panda() -> Robot:
    return load_robot("panda")


def _turned_goal(robot: Robot, q_start: np.ndarray) -> pin.SE3:
    start = robot.fk(q_start)
    turn = rotation_from_axis_angle(np.array([0.0, 0.0, 1.0]), TURN)
    return pin.SE3(start.rotation, turn @ start.translation)


def _run(robot: Robot, q_start: np.ndarray, goal: np.ndarray, **kwargs):
    planner = OnlinePlanner(robot, q_start, LIMITS, **kwargs)
    planner.append(StraightLine(goal))
    samples = []
    while not planner.done:
        samples.append(planner.step())
    return planner, samples


@pytest.fixture(scope="module")
def iiwa_keep(iiwa):
    return _run(iiwa, IIWA_START, _turned_goal(iiwa, IIWA_START).translation)


def test_the_kept_arm_angle_would_leave_the_limits(iiwa):
    solver = get_solver(iiwa)
    psi = solver.parameter_of(IIWA_START)
    start = nearest(solver.solve(iiwa.fk(IIWA_START), redundancy=psi), IIWA_START)
    goal = solver.solve(
        _turned_goal(iiwa, IIWA_START), redundancy=psi, q_previous=IIWA_START
    )
    kept = next(s for s in goal if s.branch == start.branch)
    assert not kept.within_limits and kept.q[0] > iiwa.upper[0]


def test_keep_moves_the_arm_angle_only_when_it_must(iiwa, iiwa_keep):
    planner, samples = iiwa_keep
    trace = np.array([s.redundancy for s in samples])
    psi = get_solver(iiwa).parameter_of(IIWA_START)
    q = np.array([s.q for s in samples])
    margins = np.minimum(q - iiwa.lower, iiwa.upper - q).min(axis=1)
    moving = np.flatnonzero(trace != psi)
    assert moving.size and abs(trace[-1] - psi) > 0.1  # it moved, ...
    # ... only once a joint came within KEEP_LIMIT_MARGIN of a limit
    assert np.all(margins[: moving[0]] >= KEEP_LIMIT_MARGIN)
    assert trace[0] == psi and planner.redundancy == trace[-1]
    assert planner.redundancy_parameter == "arm angle"
    assert planner.redundancy_policy == "keep"


def test_commands_stay_within_the_limits_continuous_and_on_one_branch(iiwa, iiwa_keep):
    _, samples = iiwa_keep
    q = np.array([IIWA_START] + [s.q for s in samples])
    assert np.all((q >= iiwa.lower) & (q <= iiwa.upper))
    step = np.abs(np.diff(q, axis=0))
    assert np.all(step <= iiwa.velocity_limit * LIMITS_PERIOD * (1 + SPEED_RTOL))
    qd = np.array([s.qd for s in samples])
    assert np.all(np.abs(qd) <= iiwa.velocity_limit * (1 + SPEED_RTOL))
    assert len({s.branch for s in samples}) == 1


def test_the_trace_is_the_parameter_of_each_command(iiwa, iiwa_keep):
    _, samples = iiwa_keep
    solver = get_solver(iiwa)
    trace = np.array([s.redundancy for s in samples])
    q = np.array([s.q for s in samples])
    step = np.remainder(solver.parameter_of(q) - trace + np.pi, 2 * np.pi) - np.pi
    np.testing.assert_allclose(step, 0.0, rtol=0, atol=ATOL_PARAMETER)


def test_commands_meet_the_pose_and_realise_the_twist(iiwa, iiwa_keep):
    _, samples = iiwa_keep
    for s in samples:
        pose = iiwa.fk(s.q)
        np.testing.assert_allclose(pose.translation, s.position, rtol=0, atol=ATOL_POSE)
        np.testing.assert_allclose(pose.rotation, s.rotation, rtol=0, atol=ATOL_POSE)
        if not s.damped:
            jacobian = pin.computeFrameJacobian(
                iiwa.model, iiwa.data, s.q, iiwa.tool_frame_id, pin.LOCAL_WORLD_ALIGNED
            )
            twist = np.concatenate([s.velocity, s.angular_velocity])
            np.testing.assert_allclose(jacobian @ s.qd, twist, rtol=0, atol=ATOL_TWIST)


def test_limit_margin_policy_keeps_more_margin_than_keep(iiwa, iiwa_keep):
    _, kept = iiwa_keep
    goal = _turned_goal(iiwa, IIWA_START).translation
    _, moved = _run(iiwa, IIWA_START, goal, redundancy="limit_margin")

    def margin(samples) -> float:
        q = np.array([s.q for s in samples])
        return float(np.minimum(q - iiwa.lower, iiwa.upper - q).min())

    assert margin(moved) > margin(kept) + 0.1


def test_panda_trace_is_q7_and_keep_holds_it_away_from_limits(panda):
    start = panda.fk(PANDA_START)
    goal = start.translation + np.array([0.0, 0.1, -0.1])
    planner, samples = _run(panda, PANDA_START, goal)
    q = np.array([s.q for s in samples])
    trace = np.array([s.redundancy for s in samples])
    assert np.array_equal(trace, q[:, 6]) and np.all(trace == PANDA_START[6])
    assert planner.redundancy_parameter == "q7"


def test_manipulability_policy_raises_the_manipulability(panda):
    start = panda.fk(PANDA_START)
    goal = start.translation + np.array([0.0, 0.1, -0.1])
    _, kept = _run(panda, PANDA_START, goal)
    _, moved = _run(panda, PANDA_START, goal, redundancy="manipulability")

    def manipulability(samples) -> float:
        return float(compute_tool_poses(panda, np.array([samples[-1].q]))[2][0])

    assert manipulability(moved) > manipulability(kept)


@pytest.mark.parametrize(
    ("name", "kwargs", "fragment"),
    [
        ("iiwa14", {"redundancy": "nearest"}, "unknown redundancy policy"),
        ("iiwa14", {"max_redundancy_rate": 0.0}, "max_redundancy_rate"),
        ("puma560-kang", {"redundancy": "keep"}, "no redundancy"),
    ],
)
def test_bad_redundancy_options(name, kwargs, fragment):
    robot = load_robot(name)
    q = IIWA_START if robot.nq == 7 else np.zeros(6)
    with pytest.raises(InputError, match=fragment):
        OnlinePlanner(robot, q, LIMITS, **kwargs)


@given(seed=st.integers(0, 2**32 - 1))
def test_limit_score_is_a_smooth_minimum_and_its_gradient_is_exact(seed):
    rng = np.random.default_rng(seed)
    lower = rng.uniform(-3.0, -0.5, 7)
    upper = rng.uniform(0.5, 3.0, 7)
    q = rng.uniform(lower, upper)
    score = compute_limit_score(q, lower, upper)
    low = compute_limit_margin(q, lower, upper)
    assert low - math.log(14) / LIMIT_SHARPNESS - 1e-12 <= score <= low + 1e-12
    gradient = compute_limit_gradient(q, lower, upper)
    step = 1e-6
    numeric = [
        (
            compute_limit_score(q + step * e, lower, upper)
            - compute_limit_score(q - step * e, lower, upper)
        )
        / (2 * step)
        for e in np.eye(7)
    ]
    np.testing.assert_allclose(gradient, numeric, rtol=0, atol=ATOL_FD)
    rows = compute_limit_score(np.stack([q, q]), lower, upper)
    np.testing.assert_allclose(rows, [score, score], rtol=0, atol=1e-15)


@pytest.mark.parametrize("name", ["iiwa14", "panda"])
def test_try_track_is_track_without_the_error(name):
    robot = load_robot(name)
    solver = get_solver(robot)
    q = IIWA_START if name == "iiwa14" else PANDA_START
    pose = robot.fk(q).homogeneous
    value = solver.parameter_of(q)
    found = solver.try_track(pose, q, 0, 10.0, redundancy=value)
    expected = solver.track(pose, q, 0, 10.0, redundancy=value)
    assert found is not None
    np.testing.assert_array_equal(found[0], expected[0])
    assert found[1:] == expected[1:]
    far = pose.copy()
    far[:3, 3] = [5.0, 0.0, 0.0]  # [m], beyond any reach
    assert solver.try_track(far, q, 0, 10.0, redundancy=value) is None
    with pytest.raises(InfeasibleError):
        solver.track(far, q, 0, 10.0, redundancy=value)


@pytest.mark.parametrize(
    ("q6", "direction"),
    [(0.01, (0.0, 1.0, 0.0)), (0.003, (0.0, 1.0, 0.0)), (0.01, (0.6, 0.6, 0.0))],
)
def test_near_the_wrist_singularity_no_joint_spins(iiwa, q6, direction):
    """A line passing near sin θ6 = 0: the closed form at a constant arm angle spins
    q5 and q7 beyond their speed limits; the planner's commands stay continuous."""
    q_mid = np.array([0.3, 0.6, 0.2, -1.2, 0.4, q6, 0.3])
    step = 0.05 * np.array(direction)  # [m]
    solver = get_solver(iiwa)
    psi = solver.parameter_of(q_mid)
    mid = iiwa.fk(q_mid)
    q0 = nearest(
        solver.solve(pin.SE3(mid.rotation, mid.translation - step), redundancy=psi),
        q_mid,
    ).q
    _, samples = _run(iiwa, q0, mid.translation + step)
    q = np.array([q0] + [s.q for s in samples])
    ratio = np.abs(np.diff(q, axis=0)) / (iiwa.velocity_limit * LIMITS_PERIOD)
    assert ratio.max() <= 1.0
    for s in samples:
        np.testing.assert_allclose(iiwa.fk(s.q).translation, s.position, atol=ATOL_POSE)
    # the closed form at the start's arm angle along the same poses
    kept, previous, index = (
        [],
        q0,
        nearest(solver.solve(iiwa.fk(q0), redundancy=psi), q0).index,
    )
    for s in samples:
        pose = pin.SE3(s.rotation, s.position).homogeneous
        previous, index, _ = solver.track(pose, previous, index, 10.0, redundancy=psi)
        kept.append(previous)
    kept_ratio = np.abs(np.diff(np.array([q0, *kept]), axis=0)) / (
        iiwa.velocity_limit * LIMITS_PERIOD
    )
    assert kept_ratio.max() > 1.0


def test_a_pose_out_of_reach_raises(iiwa):
    planner = OnlinePlanner(iiwa, IIWA_START, LIMITS, check_speed=False)
    start = iiwa.fk(IIWA_START).translation
    planner.append(StraightLine(2.5 * start))  # radially out: the elbow stretches
    with pytest.raises(InfeasibleError, match="out of reach"):
        while not planner.done:
            planner.step()


@pytest.mark.parametrize("name", ["iiwa14", "panda"])
def test_manipulability_gradient_against_the_compiled_chain(name):
    robot = load_robot(name)
    rng = np.random.default_rng(7)
    step = 1e-6  # [rad], central differences of compute_tool_poses' √det(J Jᵀ)
    for _ in range(5):
        q = rng.uniform(robot.lower, robot.upper)
        w, gradient = compute_manipulability_gradient(robot, q)
        shifted = q + step * np.concatenate([np.eye(7), -np.eye(7)])
        values = compute_tool_poses(robot, np.vstack([q, shifted]))[2]
        numeric = (values[1:8] - values[8:]) / (2 * step)
        assert w == pytest.approx(values[0], abs=1e-14)
        np.testing.assert_allclose(gradient, numeric, rtol=0, atol=ATOL_FD_GRADIENT)
