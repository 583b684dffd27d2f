"""Time scaling of a joint-space polyline and its exact-mesh verification."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from workbench import InputError, load_robot
from workbench.collision import CollisionChecker, Obstacle, Scene
from workbench.errors import NonFiniteError
from workbench.export import read_ros2_bag, write_ros2_bag, write_urscript
from workbench.motion import (
    WORST_RATIO,
    WaypointTrajectory,
    time_optimal_duration,
    time_scale,
    verify_trajectory,
)
from workbench.motion.timing import JERK_FRACTION, PHASES
from workbench.trajectory import (
    check_limits,
    compute_toppra_duration,
    read_trajectory_csv,
    write_trajectory_csv,
)

ATOL_EXACT = 1e-12  # [rad, rad/s, rad/s²] waypoints and rest, exact arithmetic
RTOL_TIGHT = 1e-9  # a bound reached, relative
RTOL_TOPPRA = 1e-3  # TOPP-RA on a 1001-point grid against the closed form
STEP_H = 1e-7  # [s] left and right of a phase boundary
FD_H = 1e-6  # [s] step of the central differences
ROUNDING = 1e-15  # relative rounding of a sampled value (a few units of 2.2e-16)
#: Acceleration limits [rad/s²] given to the catalog arms (their URDFs have none):
#: the Franka datasheet's for the Panda, round values for the others.
ACCELERATION_LIMITS = {
    "puma560": [4.0, 4.0, 4.0, 8.0, 8.0, 8.0],
    "ur5": [8.0] * 6,
    "panda": [15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0],
    "iiwa14": [10.0] * 7,
}
NAMES = tuple(ACCELERATION_LIMITS)


@pytest.fixture(scope="module")
def robots():
    return {
        name: load_robot(name).with_limits(acceleration_limit=limits)
        for name, limits in ACCELERATION_LIMITS.items()
    }


def _polyline(robot, seed: int, count: int) -> np.ndarray:
    """``count`` waypoints within the limits, steps of 1 mrad to 3 rad (log-uniform)."""
    rng = np.random.default_rng(seed)
    lower, upper = robot.lower, robot.upper
    points = [rng.uniform(lower, upper)]
    while len(points) < count:
        direction = rng.normal(size=robot.nq)
        length = 10.0 ** rng.uniform(-3.0, math.log10(3.0))
        step = direction / np.linalg.norm(direction) * length
        points.append(np.clip(points[-1] + step, lower, upper))
    return np.array(points)


CASES = st.tuples(
    st.sampled_from(NAMES),
    st.integers(0, 2**32 - 1),
    st.integers(2, 6),
    st.sampled_from([1.0, 0.5, 0.1]),
    st.sampled_from([1.0, 0.3, 0.01]),
)


def _case(robots, case) -> tuple[WaypointTrajectory, np.ndarray, tuple[float, float]]:
    name, seed, count, v_scale, a_scale = case
    robot = robots[name]
    points = _polyline(robot, seed, count)
    assume(np.all(np.abs(np.diff(points, axis=0)).max(axis=1) > 1e-9))
    traj = time_scale(robot, points, velocity_scale=v_scale, acceleration_scale=a_scale)
    return traj, points, (v_scale, a_scale)


@settings(max_examples=60)
@given(case=CASES)
def test_passes_every_waypoint_at_rest(robots, case) -> None:
    traj, points, _ = _case(robots, case)
    q, qd, qdd = traj.sample(traj.times)
    np.testing.assert_allclose(q, points, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(qd, 0.0, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(qdd, 0.0, rtol=0, atol=ATOL_EXACT)
    assert traj.times[0] == 0.0 and traj.times[-1] == traj.duration
    assert np.all(np.diff(traj.times) > 0.0)
    before, after = traj.sample(np.array([-1.0, traj.duration + 1.0]))[0]
    np.testing.assert_array_equal(before, points[0])
    np.testing.assert_array_equal(after, points[-1])


@settings(max_examples=60)
@given(case=CASES)
def test_follows_the_polyline(robots, case) -> None:
    traj, points, _ = _case(robots, case)
    for s in range(len(points) - 1):
        t = np.linspace(traj.times[s], traj.times[s + 1], 33)
        q = traj.sample(t)[0]
        delta = points[s + 1] - points[s]
        u = (q - points[s]) @ delta / (delta @ delta)
        np.testing.assert_allclose(
            q, points[s] + np.outer(u, delta), rtol=0, atol=ATOL_EXACT
        )
        assert np.all(np.diff(u) >= -ATOL_EXACT)  # forward only, never back
        assert u[0] == 0.0 and u[-1] == pytest.approx(1.0, abs=ATOL_EXACT)


@settings(max_examples=60)
@given(case=CASES)
def test_twice_continuously_differentiable(robots, case) -> None:
    traj, _, _ = _case(robots, case)
    bounds = traj.phase_times
    # The stated jerk phases: ramp 1/6, hold 2/3, ramp 1/6 of the acceleration phase.
    phases = np.diff(bounds).reshape(-1, PHASES)
    t_accel = phases[:, :3].sum(axis=1)
    np.testing.assert_allclose(
        phases[:, [0, 2, 4, 6]] / t_accel[:, None], JERK_FRACTION, rtol=RTOL_TIGHT
    )
    np.testing.assert_allclose(phases[:, 4:].sum(axis=1), t_accel, rtol=RTOL_TIGHT)
    # |jerk| per segment: the peak acceleration over the ramp time.
    peak = np.abs(traj.sample(bounds[1:-1:PHASES])[2]).max(axis=1)
    jerk = float(np.max(peak / phases[:, 0]))
    speed = traj.get_extrema(1).peak.max()
    acceleration = traj.get_extrema(2).peak.max()
    inner = bounds[1:-1]
    left = traj.sample(inner - STEP_H)
    right = traj.sample(inner + STEP_H)
    gaps = [np.abs(a - b).max() for a, b in zip(left, right, strict=True)]
    slopes = (speed, acceleration, jerk)
    for gap, slope in zip(gaps, slopes, strict=True):
        assert gap <= 2.0 * STEP_H * slope * (1.0 + RTOL_TIGHT) + ATOL_EXACT
    # Velocities and accelerations are the derivatives of sample()'s positions:
    # central differences err by at most h² J / 6 and h J / 2 (|q⃛| <= J), plus
    # rounding of the positions' magnitude over h.
    t = np.linspace(0.0, traj.duration, 41)[1:-1]
    q_plus, qd_plus, _ = traj.sample(t + FD_H)
    q_minus, qd_minus, _ = traj.sample(t - FD_H)
    _, qd, qdd = traj.sample(t)
    rounding = ROUNDING / FD_H * (1.0 + np.abs(q_plus).max())
    np.testing.assert_allclose(
        (q_plus - q_minus) / (2 * FD_H),
        qd,
        rtol=0,
        atol=FD_H**2 * jerk / 6.0 + rounding,
    )
    np.testing.assert_allclose(
        (qd_plus - qd_minus) / (2 * FD_H),
        qdd,
        rtol=0,
        atol=FD_H * jerk / 2.0 + ROUNDING / FD_H * (1.0 + speed),
    )


@settings(max_examples=60)
@given(case=CASES)
def test_limits_hold_and_are_reached_on_every_segment(robots, case) -> None:
    traj, points, (v_scale, a_scale) = _case(robots, case)
    robot = traj.robot
    assert check_limits(traj) == []
    v_lim = robot.velocity_limit * v_scale
    a_lim = robot.acceleration_limit * a_scale
    bounds = traj.phase_times.reshape(-1)[:-1].reshape(-1, PHASES)
    for s in range(len(points) - 1):
        t = np.linspace(bounds[s, 0], traj.times[s + 1], 2001)
        _, qd, qdd = traj.sample(np.r_[t, bounds[s, 1], bounds[s, 3]])
        speed = np.abs(qd).max(axis=0) / v_lim
        accel = np.abs(qdd).max(axis=0) / a_lim
        assert speed.max() <= 1.0 + RTOL_TIGHT and accel.max() <= 1.0 + RTOL_TIGHT
        assert accel.max() == pytest.approx(1.0, rel=RTOL_TIGHT)  # always reached
        coasts = bounds[s, 4] - bounds[s, 3] > 0.0
        if coasts:
            assert speed.max() == pytest.approx(1.0, rel=RTOL_TIGHT)


@settings(max_examples=60)
@given(case=CASES)
def test_extrema_are_exact(robots, case) -> None:
    traj, _, _ = _case(robots, case)
    t = np.r_[np.linspace(0.0, traj.duration, 4001), traj.phase_times]
    for order, values in enumerate(traj.sample(t)):
        ext = traj.get_extrema(order)
        np.testing.assert_allclose(ext.maximum, values.max(axis=0), atol=ATOL_EXACT)
        np.testing.assert_allclose(ext.minimum, values.min(axis=0), atol=ATOL_EXACT)
        at_max = np.diagonal(traj.sample(ext.t_maximum)[order])
        np.testing.assert_allclose(at_max, ext.maximum, atol=ATOL_EXACT)
        at_min = np.diagonal(traj.sample(ext.t_minimum)[order])
        np.testing.assert_allclose(at_min, ext.minimum, atol=ATOL_EXACT)


@settings(max_examples=100)
@given(case=CASES)
def test_duration_within_the_worst_ratio_of_the_optimum(robots, case) -> None:
    traj, points, (v_scale, a_scale) = _case(robots, case)
    optimum = time_optimal_duration(
        traj.robot, points, velocity_scale=v_scale, acceleration_scale=a_scale
    )
    ratio = traj.duration / optimum
    assert 1.0 < ratio <= WORST_RATIO * (1.0 + ATOL_EXACT)


def test_worst_ratio_is_that_of_a_segment_too_short_to_coast(robots) -> None:
    robot = robots["panda"]
    q0 = np.zeros(robot.nq)
    q0[3] = -1.0
    short = np.vstack([q0, q0 + 0.01])  # V²/A >> 1: no coasting
    ratio = time_scale(robot, short).duration / time_optimal_duration(robot, short)
    assert WORST_RATIO == pytest.approx(math.sqrt(6.0 / 5.0), abs=ATOL_EXACT)
    assert ratio == pytest.approx(WORST_RATIO, rel=ATOL_EXACT)
    long = np.vstack([q0, q0 + np.r_[2.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]])
    coasting = time_scale(robot, long).duration / time_optimal_duration(robot, long)
    assert 1.0 < coasting < WORST_RATIO
    # Joint 1 alone: 2.5 rad at 2.175 rad/s, 15 rad/s² (1/V + V/(c A) per segment).
    v, a = 2.175 / 2.5, 15.0 / 2.5
    expected = 1.0 / v + v / (a * (1.0 - JERK_FRACTION))
    assert time_scale(robot, long).duration == pytest.approx(expected, rel=ATOL_EXACT)


def test_time_optimal_duration_agrees_with_toppra(robots) -> None:
    pytest.importorskip("toppra")
    robot = robots["panda"]
    points = _polyline(robot, seed=3, count=4)
    per_segment = [
        compute_toppra_duration(robot, a, b) for a, b in itertools.pairwise(points)
    ]
    assert sum(per_segment) == pytest.approx(
        time_optimal_duration(robot, points), rel=RTOL_TOPPRA
    )


def test_sample_shapes(robots) -> None:
    traj = time_scale(robots["ur5"], _polyline(robots["ur5"], 0, 3))
    q, qd, qdd = traj.sample(0.5 * traj.duration)
    assert q.shape == qd.shape == qdd.shape == (6,)
    q, qd, qdd = traj.sample(np.linspace(0.0, traj.duration, 11))
    assert q.shape == qd.shape == qdd.shape == (11, 6)
    assert traj.sample(np.zeros((2, 3)))[0].shape == (2, 3, 6)
    assert not traj.waypoints.flags.writeable and not traj.times.flags.writeable
    with pytest.raises(NonFiniteError, match="t must be finite"):
        traj.sample(np.nan)
    with pytest.raises(InputError, match="order must be 0, 1 or 2"):
        traj.get_extrema(3)


def test_bad_input(robots) -> None:
    robot = robots["panda"]
    points = _polyline(robot, 1, 3)
    with pytest.raises(NonFiniteError, match="waypoints must be finite"):
        time_scale(robot, np.where(points == points[1, 2], np.nan, points))
    with pytest.raises(InputError, match=r"shape \(K, 7\), got shape \(3, 6\)"):
        time_scale(robot, points[:, :6])
    with pytest.raises(InputError, match=r"shape \(K, 7\), got shape \(7,\)"):
        time_scale(robot, points[0])
    with pytest.raises(InputError, match="at least two waypoints are needed, got 1"):
        time_scale(robot, points[:1])
    with pytest.raises(InputError, match="waypoints must be numbers"):
        time_scale(robot, [["a"] * 7, ["b"] * 7])
    outside = points.copy()
    outside[2, 3] = 0.5  # panda_joint4 lies in [-3.0718, -0.0698]
    with pytest.raises(InputError, match=r"waypoint 2: joint panda_joint4 at 0\.5 rad"):
        time_scale(robot, outside)
    repeated = np.vstack([points[:2], points[1:]])
    with pytest.raises(InputError, match="waypoints 1 and 2 are the same"):
        time_scale(robot, repeated)
    for scale in (0.0, 1.5, -1.0, math.nan, True, "fast"):
        with pytest.raises(InputError, match=r"velocity_scale must be a number in"):
            time_scale(robot, points, velocity_scale=scale)
    with pytest.raises(InputError, match=r"acceleration_scale must be a number in"):
        time_optimal_duration(robot, points, acceleration_scale=0.0)


def test_unknown_limits_are_refused(robots) -> None:
    bare = load_robot("panda")  # its URDF gives no acceleration limits
    points = _polyline(bare, 0, 2)
    with pytest.raises(
        InputError, match="gives no acceleration limit for panda_joint1"
    ):
        time_scale(bare, points)
    with pytest.raises(InputError, match="gives no acceleration limit"):
        time_optimal_duration(bare, points)
    no_speed = robots["panda"].with_limits(velocity_limit=[math.inf] + [2.0] * 6)
    with pytest.raises(InputError, match="no velocity limit for panda_joint1:"):
        time_scale(no_speed, points)
    still = points.copy()
    still[:, 0] = points[0, 0]  # the joint without a limit does not move
    assert time_scale(no_speed, still).duration > 0.0


def test_csv_and_exports_take_it(robots, tmp_path: Path) -> None:
    robot = robots["ur5"]
    traj = time_scale(robot, _polyline(robot, 5, 4))
    samples = traj.sample_uniform(100.0)
    assert samples.t[0] == 0.0 and samples.t[-1] == traj.duration
    path = tmp_path / "traj.csv"
    write_trajectory_csv(path, samples, joint_names=robot.joint_names)
    back = read_trajectory_csv(path, robot.nq)
    for name in ("t", "q", "qd", "qdd"):
        np.testing.assert_array_equal(getattr(back, name), getattr(samples, name))
    pytest.importorskip("rosbags")
    write_ros2_bag(tmp_path / "bag", samples, robot.joint_names)
    bag = read_ros2_bag(tmp_path / "bag")
    np.testing.assert_allclose(bag.samples.q, samples.q, rtol=0, atol=ATOL_EXACT)
    assert list(bag.joint_names) == robot.joint_names
    script = write_urscript(tmp_path / "traj.script", samples, robot.joint_names)
    text = script.read_text()
    assert "servoj(" in text and text.count("\n") > samples.t.size


# --- exact-mesh verification ----------------------------------------------------
Q0 = np.array([0.0, -0.6, 2.4, 0.0, 0.5, 0.0])  # [rad] a free PUMA configuration


def _puma_path(robots) -> tuple[np.ndarray, WaypointTrajectory]:
    robot = robots["puma560"]
    steps = np.array([[0.8, 0.0, 0.0, 0, 0, 0], [0.8, 0.2, -0.3, 0, 0, 0]])
    points = np.vstack([Q0, Q0 + steps])
    return points, time_scale(robot, points)


def _box_at(robot, q, size, offset=(0.0, 0.0, 0.0)) -> Scene:
    """A box centred on the tool's position at ``q``, moved by ``offset`` [m]."""
    where = robot.fk(q).translation + np.asarray(offset)
    return Scene("box", (Obstacle("box", "box", size, pin.SE3(np.eye(3), where)),))


def test_verification_passes_a_free_polyline(robots) -> None:
    robot = robots["puma560"]
    _, traj = _puma_path(robots)
    far = _box_at(robot, Q0, (0.2, 0.2, 0.2), offset=(0.0, 0.0, 3.0))
    checker = CollisionChecker(robot, far)
    report = verify_trajectory(checker, traj)
    assert report.collision_free and report.lower_bound > 0.0
    step = traj.get_extrema(1).peak.max() * traj.duration / (report.samples - 1)
    assert step <= math.radians(0.25)  # no joint moves more between samples
    dense = traj.sample(np.linspace(0.0, traj.duration, 3001))[0]
    brute = min(checker.compute_distances(q).min() for q in dense)
    assert report.lower_bound <= brute


def test_verification_finds_an_obstacle_between_the_waypoints(robots) -> None:
    robot = robots["puma560"]
    points, traj = _puma_path(robots)
    middle = 0.5 * (points[0] + points[1])
    scene = _box_at(robot, middle, (0.05, 0.05, 0.05))
    checker = CollisionChecker(robot, scene)
    scene_pairs = [k for k, p in enumerate(checker.pairs) if p.kind == "scene"]
    ends = np.array([checker.compute_distances(q) for q in points])[:, scene_pairs]
    assert np.all(ends > 0.0)  # every waypoint is free: the segment hits
    report = verify_trajectory(checker, traj)
    assert not report.collision_free
    first = report.first_contact
    assert first.body_b == "box" and 0.0 < first.t < traj.times[1]
    with pytest.raises(InputError, match="max_step must be a finite number > 0"):
        verify_trajectory(checker, traj, max_step=0.0)
