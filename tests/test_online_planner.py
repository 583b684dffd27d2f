"""Online planner: replanning continuity, stops, multi-rate, wrist singularity."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from workbench import (
    InfeasibleError,
    InputError,
    JointLimitError,
    NonFiniteError,
    load_robot,
)
from workbench.ik import get_solver, get_structure
from workbench.ik.closed_form import analytic, nearest
from workbench.planning import (
    CartesianLimits,
    OnlinePlanner,
    PointToPoint,
    StraightLine,
    interpolate_servo,
)
from workbench.poses import rotation_from_axis_angle

ATOL_EXACT = 1e-12
Q_START = np.array([0.3, 0.4, 0.2, 0.3, 0.8, 0.2])  # away from every singularity
LIMITS = CartesianLimits(0.1, 0.5, 0.4, 1.0)


def _planner(robot, **kwargs) -> OnlinePlanner:
    return OnlinePlanner(robot, Q_START, LIMITS, **kwargs)


def _random_goal(planner: OnlinePlanner, rng: np.random.Generator):
    state = planner.state
    axis = rng.normal(size=3)
    turn = rotation_from_axis_angle(axis / np.linalg.norm(axis), rng.uniform(0, 0.3))
    return state.position + rng.uniform(-0.04, 0.04, 3), state.rotation @ turn


def _line_through(robot, q_mid: np.ndarray, step: np.ndarray):
    """Run a straight line from FK(q_mid) - step to FK(q_mid) + step [m].

    Returns the planner samples and their q, qd as (K, nq) arrays.
    """
    mid = robot.fk(q_mid)
    start = pin.SE3(mid.rotation, mid.translation - step)
    q0 = nearest(analytic(robot, start, q_previous=q_mid), q_mid).q
    planner = OnlinePlanner(robot, q0, LIMITS)
    planner.append(StraightLine(mid.translation + step))
    samples = []
    while not planner.done:
        samples.append(planner.step())
    return samples, np.array([s.q for s in samples]), np.array([s.qd for s in samples])


def _assert_same_state(primitive, planner):
    p, v, r, w = primitive.sample(planner.t)
    s = planner.state
    for a, b in (
        (p, s.position),
        (v, s.velocity),
        (r, s.rotation),
        (w, s.angular_velocity),
    ):
        np.testing.assert_allclose(a, b, rtol=0, atol=ATOL_EXACT)


@pytest.mark.parametrize("seed", range(6))
def test_replanning_at_random_event_times_is_continuous(puma_kang, seed):
    rng = np.random.default_rng(seed)
    planner = _planner(puma_kang)
    planner.append(PointToPoint(*_random_goal(planner, rng)))
    event_cycles = set(rng.choice(np.arange(3, 120), size=4, replace=False).tolist())
    positions, velocities, omegas = [], [], []
    last_goal = None
    while not planner.done:
        sample = planner.step()
        positions.append(sample.position)
        velocities.append(sample.velocity)
        omegas.append(sample.angular_velocity)
        if planner.cycle in event_cycles:
            if rng.uniform() < 0.3:
                planner.stop()
                last_goal = None
            else:
                last_goal = _random_goal(planner, rng)
                planner.set_goal(*last_goal)
            _assert_same_state(planner.active, planner)  # replanned from the state
        assert planner.cycle < 2000
    dt = planner.period
    dp = np.linalg.norm(np.diff(positions, axis=0), axis=1)
    dv = np.linalg.norm(np.diff(velocities, axis=0), axis=1)
    dw = np.linalg.norm(np.diff(omegas, axis=0), axis=1)
    # no jump: per cycle, position moves by at most the speed bound times dt and
    # velocity by at most the acceleration bound times dt (x sqrt 2 with a residual;
    # the turning residual adds a small cross term to the angular acceleration)
    assert dp.max() <= math.sqrt(2) * LIMITS.max_velocity * dt * (1 + 1e-9)
    assert dv.max() <= math.sqrt(2) * LIMITS.max_acceleration * dt * (1 + 1e-9)
    assert dw.max() <= 1.5 * LIMITS.max_angular_acceleration * dt
    np.testing.assert_allclose(velocities[-1], 0.0, atol=ATOL_EXACT)
    if last_goal is not None:
        np.testing.assert_allclose(planner.state.position, last_goal[0], atol=1e-12)
        np.testing.assert_allclose(planner.state.rotation, last_goal[1], atol=1e-12)


def test_stop_event_comes_to_rest_at_full_deceleration(puma_kang):
    planner = _planner(puma_kang)
    start = planner.state.position.copy()
    planner.append(StraightLine(start + np.array([0.0, 0.0, -0.1])))
    for _ in range(40):  # accelerate 0.2 s, then cruise
        planner.step()
    v0 = planner.state.speed
    assert v0 == pytest.approx(LIMITS.max_velocity)
    direction = planner.state.velocity / v0
    planner.append(StraightLine(start))  # the stop clears the queue too
    planner.stop()
    speeds, points = [], []
    while not planner.done:
        s = planner.step()
        speeds.append(np.linalg.norm(s.velocity))
        points.append(s.position)
    t = planner.period * np.arange(1, len(speeds) + 1)
    expected = np.maximum(v0 - LIMITS.max_acceleration * t, 0.0)
    np.testing.assert_allclose(speeds, expected, rtol=0, atol=1e-12)
    at_rest = np.flatnonzero(np.asarray(speeds) < 1e-12)[0] + 1  # cycles to rest
    assert at_rest == round(v0 / LIMITS.max_acceleration / planner.period)
    travel = points[-1] - start  # still on the line
    np.testing.assert_allclose(np.cross(travel, direction), 0.0, atol=1e-12)


def test_joint_commands_track_the_cartesian_command(puma_kang):
    planner = _planner(puma_kang)
    planner.append(PointToPoint(*_random_goal(planner, np.random.default_rng(7))))
    while not planner.done:
        s = planner.step()
        pose = puma_kang.fk(s.q)
        np.testing.assert_allclose(pose.translation, s.position, atol=1e-12)
        np.testing.assert_allclose(pose.rotation, s.rotation, atol=1e-12)
        twist = np.concatenate([s.velocity, s.angular_velocity])
        assert not s.damped  # far from singularities: J^-1 exactly
        np.testing.assert_allclose(puma_kang.jacobian(s.q) @ s.qd, twist, atol=1e-12)


def test_tool_and_world_frames(puma_kang):
    tip = pin.SE3(
        rotation_from_axis_angle([1.0, 0.0, 0.0], 0.3), np.array([0.0, 0.02, 0.1])
    )
    base = pin.SE3(
        rotation_from_axis_angle([0.0, 0.0, 1.0], 0.5), np.array([1.0, 2.0, 0.7])
    )
    planner = _planner(
        puma_kang, transform_tip_to_tool=tip, transform_base_to_world=base
    )
    expected = base * puma_kang.fk(Q_START) * tip
    np.testing.assert_allclose(planner.state.position, expected.translation, atol=1e-12)
    planner.append(PointToPoint(*_random_goal(planner, np.random.default_rng(3))))
    while not planner.done:
        s = planner.step()
        pose = base * puma_kang.fk(s.q) * tip
        np.testing.assert_allclose(pose.translation, s.position, atol=1e-12)
        np.testing.assert_allclose(pose.rotation, s.rotation, atol=1e-12)
        # tip twist from the joint velocity (world axes) equals the command
        jac = puma_kang.jacobian(s.q)
        w = base.rotation @ (jac[3:] @ s.qd)
        lever = s.position - (base * puma_kang.fk(s.q)).translation
        v = base.rotation @ (jac[:3] @ s.qd) + np.cross(w, lever)
        np.testing.assert_allclose(v, s.velocity, atol=1e-12)
        np.testing.assert_allclose(w, s.angular_velocity, atol=1e-12)


def test_hermite_servo_interpolation_is_exact_on_cubics():
    t = np.linspace(0.0, 0.5, 6)
    coeffs = np.array([[0.3, -1.0, 2.0, 0.5], [1.0, 0.0, -3.0, 0.2]])  # 2 joints

    def poly(x, d=0):
        return np.stack([np.polyval(np.polyder(c, d), x) for c in coeffs], axis=-1)

    servo = interpolate_servo(t, poly(t), poly(t, 1), 10)
    assert servo.t.shape == (51,)
    np.testing.assert_allclose(servo.t, np.linspace(0.0, 0.5, 51), atol=1e-15)
    np.testing.assert_allclose(servo.q, poly(servo.t), atol=1e-12)
    np.testing.assert_allclose(servo.qd, poly(servo.t, 1), atol=1e-12)
    np.testing.assert_allclose(servo.qdd, poly(servo.t, 2), atol=1e-9)


def test_multi_rate_servo_samples_from_a_run(puma_kang):
    planner = _planner(puma_kang, planning_rate=50.0, servo_rate=500.0)
    planner.append(StraightLine(planner.state.position + np.array([0.05, 0.0, 0.0])))
    samples = [planner.step() for _ in range(30)]
    t = np.array([s.t for s in samples])
    np.testing.assert_allclose(np.diff(t), 0.02, atol=1e-15)
    servo = interpolate_servo(t, [s.q for s in samples], [s.qd for s in samples], 10)
    np.testing.assert_allclose(servo.q[::10], [s.q for s in samples], atol=0)
    np.testing.assert_allclose(servo.qd[::10], [s.qd for s in samples], atol=0)


def test_wrist_singularity_line_keeps_theta4_continuous_and_speeds_bounded(puma_kang):
    """Straight line through θ5 = 0: no θ4 flip, bounded DLS rates, small task error.

    The line (0.1 m in y at 0.1 m/s, orientation fixed) passes exactly through the
    wrist singularity of q_mid. The closed-form IK keeps the commanded pose exact
    and theta4 smooth; the DLS rates (damped about the rate of the IK positions)
    miss the commanded twist by ~1e-4 (m/s and rad/s, 0.1 % of the tool speed),
    only inside the singular region, and stay bounded where J^-1 would not.
    """
    q_mid = np.array([0.3, 0.5, 0.3, 0.6, 0.0, -0.2])
    samples, q, qd = _line_through(puma_kang, q_mid, np.array([0.0, 0.05, 0.0]))
    k = int(np.argmin(np.abs(q[:, 4])))
    assert abs(q[k, 4]) < 1e-9  # a sample sits on the singularity
    assert np.sign(q[0, 4]) != np.sign(q[-1, 4])  # and θ5 changes sign
    assert np.abs(np.diff(q[:, 3])).max() < 0.01  # θ4 continuous: no π flip
    assert {s.branch.rsplit("/", 1)[1] for s in samples} == {"flip", "no-flip"}
    assert np.all(np.abs(qd) <= puma_kang.velocity_limit)
    for s in samples:  # the position command stays exact
        np.testing.assert_allclose(
            puma_kang.fk(s.q).translation, s.position, atol=1e-12
        )
    twist = np.array(
        [np.concatenate([s.velocity, s.angular_velocity]) for s in samples]
    )
    error = np.array(
        [
            np.linalg.norm(puma_kang.jacobian(s.q) @ s.qd - w)
            for s, w in zip(samples, twist, strict=True)
        ]
    )
    damped = np.array([s.damped for s in samples])
    assert damped[k] and error[k] > 0.0
    assert error.max() <= 0.05 * LIMITS.max_velocity
    assert np.all(error[~damped] < 1e-12)
    # the plain inverse at the singular sample would command unbounded rates
    exact = np.linalg.lstsq(puma_kang.jacobian(q[k]), twist[k], rcond=1e-20)[0]
    assert np.linalg.norm(exact) > 100 * np.abs(qd).max()


def test_events_and_goals_are_validated(puma_kang):
    planner = _planner(puma_kang, check_speed=False)
    with pytest.raises(NonFiniteError):
        planner.set_goal([np.nan, 0.0, 0.0], np.eye(3))
    with pytest.raises(InputError, match="not a MotionPrimitive"):
        planner.append("PTP")
    state, active = planner.state, planner.active
    with pytest.raises(InputError, match="rotation"):  # checked before it runs
        planner.set_goal(state.position, 2.0 * np.eye(3))
    with pytest.raises(InputError, match="rotation"):
        PointToPoint(state.position, np.diag([1.0, 1.0, -1.0]))
    assert planner.state is state and planner.active is active  # nothing changed
    planner.set_goal([2.0, 0.0, 0.0], planner.state.rotation)  # out of reach
    with pytest.raises(InfeasibleError, match="reach"):
        for _ in range(2000):
            planner.step()


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"planning_rate": 0.0}, "planning_rate must be a finite number > 0"),
        ({"servo_rate": math.nan}, "servo_rate must be a finite number > 0"),
        ({"planning_rate": 300.0}, "integer multiple"),
        ({"dls_epsilon": -1.0}, "epsilon"),
    ],
)
def test_bad_planner_arguments(puma_kang, kwargs, fragment):
    with pytest.raises(InputError, match=fragment):
        _planner(puma_kang, **kwargs)


@pytest.mark.parametrize(
    "values", [(0.0, 1, 1, 1), (1, -1.0, 1, 1), (1, 1, math.nan, 1), (1, 1, 1, "x")]
)
def test_bad_cartesian_limits(values):
    with pytest.raises(InputError):
        CartesianLimits(*values)


def test_start_outside_limits_and_robot_without_closed_form(puma_kang):
    q = Q_START.copy()
    q[1] = puma_kang.upper[1] + 0.1
    with pytest.raises(JointLimitError, match="joint2"):
        OnlinePlanner(puma_kang, q, LIMITS)
    with pytest.raises(InputError, match="closed-form IK"):
        OnlinePlanner(load_robot("generic6r"), np.zeros(6), LIMITS)


def test_samples_and_states_are_immutable(puma_kang):
    from workbench.planning import PlannerSample
    from workbench.planning.cartesian_paths import CartesianState

    planner = _planner(puma_kang)
    planner.append(PointToPoint(*_random_goal(planner, np.random.default_rng(5))))
    sample = planner.step()
    assert type(sample) is PlannerSample and type(planner.state) is CartesianState
    for obj in (sample, planner.state):
        with pytest.raises(AttributeError):
            obj.position = None
    assert sample._asdict()["branch"] == sample.branch
    assert not sample.q.flags.writeable
    np.testing.assert_array_equal(planner.state.position, sample.position)


def test_samples_say_which_cycles_planned_a_motion(puma_kang):
    """``replanned``: a primitive began or changed stage, or a stop/goal/event."""
    planner = _planner(puma_kang)
    assert not planner.step().replanned  # holding at rest
    planner.append(PointToPoint(*_random_goal(planner, np.random.default_rng(3))))
    flags = [planner.step().replanned for _ in range(5)]
    assert flags == [True, False, False, False, False]
    planner.stop()
    assert planner.step().replanned and not planner.step().replanned
    planner.set_goal(*_random_goal(planner, np.random.default_rng(4)))
    assert planner.step().replanned


def test_cycle_solves_a_pose_only_the_exact_rigidity_checks_accept(puma_kang):
    """Between the kernel's quick test and RIGIDITY_TOL: solved, not rejected."""
    planner = _planner(puma_kang)
    state, zero = planner.state, np.zeros(3)
    rotation = state.rotation.copy()
    _, q_rigid, index, _ = planner._command_joints(state.position, zero, rotation, zero)
    rotation[:, 0] *= 1.0 + 3e-7  # |x| - 1 past the quick test, within RIGIDITY_TOL
    _, q, index_scaled, _ = planner._command_joints(
        state.position, zero, rotation, zero
    )
    assert index_scaled == index
    np.testing.assert_allclose(q, q_rigid, atol=1e-5)
    rotation[:, 0] *= 1.0 + 1e-5  # beyond RIGIDITY_TOL
    with pytest.raises(InputError, match="orthonormal"):
        planner._command_joints(state.position, zero, rotation, zero)


@pytest.mark.parametrize("name", ["ur5", "kuka-kr6-r700", "abb-irb2400"])
def test_any_closed_form_arm_runs_the_primitives(name):
    """OnlinePlanner and its primitives on OPW and UR-type arms: exact poses."""
    robot = load_robot(name)
    structure = get_structure(robot)
    if structure.family == "ur":  # elbow bent, away from every singularity
        q0 = np.array([0.4, -1.2, 1.5, -0.9, 0.8, 0.5])
    else:
        q0 = (robot.lower + robot.upper) / 2.0 + 0.3
        q0[4] = structure.joint_sign[4] * (0.8 - structure.table.joints[4].theta_offset)
        q0 = np.remainder(q0 + np.pi, 2.0 * np.pi) - np.pi
    planner = OnlinePlanner(robot, q0, LIMITS)
    rng = np.random.default_rng(1)
    planner.append(PointToPoint(*_random_goal(planner, rng)))
    planner.append(StraightLine(planner.state.position + np.array([0.03, -0.02, 0.02])))
    samples = []
    while not planner.done:
        samples.append(planner.step())
        assert planner.cycle < 3000
    labels = set(get_solver(robot).branches)
    for s in samples:
        pose = robot.fk(s.q)
        np.testing.assert_allclose(pose.translation, s.position, atol=1e-12)
        np.testing.assert_allclose(pose.rotation, s.rotation, atol=1e-12)
        assert s.branch in labels
    q = np.array([s.q for s in samples])
    assert np.abs(np.diff(q, axis=0)).max() < 0.05


def test_ur_line_through_the_wrist_singularity_keeps_the_wrist_continuous():
    """UR5: a straight line through sin θ5 = 0; θ6 and θ4 continuous, DLS rates."""
    robot = load_robot("ur5")
    structure = get_structure(robot)
    q_mid = np.array([0.4, -1.2, 1.5, -0.9, 0.0, 0.5])
    q_mid[4] = -structure.joint_sign[4] * structure.table.joints[4].theta_offset
    q_mid[4] = np.remainder(q_mid[4] + np.pi, 2.0 * np.pi) - np.pi
    mid = robot.fk(q_mid)
    assert any(s.wrist_singular for s in analytic(robot, mid))
    samples, q, qd = _line_through(robot, q_mid, np.array([0.0, 0.0, 0.05]))
    theta5 = structure.table.joints[4].theta_offset + structure.joint_sign[4] * q[:, 4]
    sin5 = np.abs(np.sin(theta5))
    k = int(np.argmin(sin5))
    assert sin5[k] < 1e-3  # the line passes the singular region
    assert np.abs(np.diff(q, axis=0)).max() < 0.01  # no π flip of θ4 or θ6
    assert np.all(np.abs(qd) <= robot.velocity_limit)
    for s in samples:
        np.testing.assert_allclose(robot.fk(s.q).translation, s.position, atol=1e-12)
    damped = np.array([s.damped for s in samples])
    assert damped[k]
    twist = np.array(
        [np.concatenate([s.velocity, s.angular_velocity]) for s in samples]
    )
    exact = np.linalg.lstsq(robot.jacobian(q[k]), twist[k], rcond=1e-20)[0]
    assert np.linalg.norm(qd[k]) < np.linalg.norm(exact)  # DLS: bounded rates
