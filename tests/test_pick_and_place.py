"""Joint pick-and-place trajectories: sampling, limits, minimum duration, segments."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import random_configurations
from hypothesis import given, settings
from hypothesis import strategies as st

from workbench import (
    DimensionError,
    InputError,
    JointLimitError,
    NonFiniteError,
    load_robot,
    paper_data,
    trajectory,
)

ATOL_EXACT = 1e-12
ATOL_FD = 1e-6
#: A peak seen on a 1 ms grid of the 10 s trajectory (a curvature term off).
RTOL_SAMPLED_PEAK = 1e-5
PAPER_RANGES_DEG = np.array(  # Angeles et al. Sec. V, from Paul et al. [14]
    [[-160, 160], [-225, 45], [-45, 225], [-170, 170], [-135, 135], [-170, 170]]
)
Q_PICK = np.deg2rad(paper_data.ANGELES_PICK_Q_DEG)
Q_PLACE = np.deg2rad(paper_data.ANGELES_PLACE_Q_DEG)
T_PAPER = paper_data.ANGELES_DURATION


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


@pytest.fixture(scope="module")
def paper_traj(puma):
    return trajectory.pick_and_place(puma, Q_PICK, Q_PLACE, T_PAPER)


def test_table3_trajectory_stays_within_the_papers_joint_ranges(puma, paper_traj):
    assert paper_traj.check_limits() == []
    ext = paper_traj.get_extrema(0)
    np.testing.assert_array_less(PAPER_RANGES_DEG[:, 0] - 1e-9, np.rad2deg(ext.minimum))
    np.testing.assert_array_less(np.rad2deg(ext.maximum), PAPER_RANGES_DEG[:, 1] + 1e-9)
    q, _, _ = paper_traj.sample(np.linspace(0.0, T_PAPER, 10_001))
    assert np.all(np.rad2deg(q) >= PAPER_RANGES_DEG[:, 0] - 1e-9)
    assert np.all(np.rad2deg(q) <= PAPER_RANGES_DEG[:, 1] + 1e-9)
    # the model's limits are the paper's ranges
    np.testing.assert_allclose(
        np.rad2deg(np.column_stack([puma.lower, puma.upper])),
        PAPER_RANGES_DEG,
        rtol=0,
        atol=1e-9,
    )


def test_peaks_bound_every_sample_and_are_reached(paper_traj) -> None:
    t = np.linspace(0.0, T_PAPER, 10_001)
    for order, values in zip((1, 2), paper_traj.sample(t)[1:], strict=True):
        ext = paper_traj.get_extrema(order)
        peak = ext.peak
        np.testing.assert_array_equal(
            peak, np.maximum(np.abs(ext.minimum), np.abs(ext.maximum))
        )
        assert np.all(np.abs(values) <= peak * (1 + ATOL_EXACT))
        np.testing.assert_allclose(
            np.max(np.abs(values), axis=0), peak, rtol=RTOL_SAMPLED_PEAK, atol=0
        )


def test_sample_shapes_and_end_conditions(paper_traj) -> None:
    q, qd, qdd = paper_traj.sample(0.0)
    assert q.shape == qd.shape == qdd.shape == (6,)
    np.testing.assert_allclose(q, Q_PICK, rtol=0, atol=ATOL_EXACT)
    q, qd2, qdd2 = paper_traj.sample(T_PAPER)
    np.testing.assert_allclose(q, Q_PLACE, rtol=0, atol=ATOL_EXACT)
    ends = np.concatenate([qd, qdd, qd2, qdd2])
    np.testing.assert_allclose(ends, 0.0, rtol=0, atol=ATOL_EXACT)
    q, qd, qdd = paper_traj.sample(np.linspace(0, T_PAPER, 11))
    assert q.shape == qd.shape == qdd.shape == (11, 6)
    assert paper_traj.jerk(np.linspace(0, T_PAPER, 11)).shape == (11, 6)
    # before and after the motion the robot rests at the ends
    q, qd, _ = paper_traj.sample(np.array([-1.0, T_PAPER + 1.0]))
    np.testing.assert_allclose(q, [Q_PICK, Q_PLACE], rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(qd, 0.0, rtol=0, atol=ATOL_EXACT)


def test_velocity_and_acceleration_are_derivatives(paper_traj) -> None:
    t = np.linspace(0.1, T_PAPER - 0.1, 97)
    h = 1e-5
    q_plus, qd_plus, _ = paper_traj.sample(t + h)
    q_minus, qd_minus, _ = paper_traj.sample(t - h)
    _, qd, qdd = paper_traj.sample(t)
    np.testing.assert_allclose((q_plus - q_minus) / (2 * h), qd, rtol=0, atol=ATOL_FD)
    np.testing.assert_allclose(
        (qd_plus - qd_minus) / (2 * h), qdd, rtol=0, atol=ATOL_FD
    )


@settings(max_examples=40, deadline=None)
@given(
    duration=st.floats(min_value=1e-2, max_value=1e3),
    n_points=st.integers(min_value=4, max_value=400),
    seed=st.integers(min_value=0, max_value=2**31),
)
def test_boundary_conditions_for_any_duration(puma, duration, n_points, seed) -> None:
    rng = np.random.default_rng(seed)
    q0, q1 = random_configurations(puma, rng, 2)
    traj = trajectory.pick_and_place(puma, q0, q1, duration, n_points=n_points)
    q, qd, qdd = traj.sample(np.array([0.0, duration]))
    np.testing.assert_allclose(q, [q0, q1], rtol=0, atol=ATOL_EXACT)
    # rates in normalised units, (8b): ṡ = q̇ T / Δ, s̈ = q̈ T² / Δ
    scale = np.abs(q1 - q0).max()
    np.testing.assert_allclose(qd * duration / scale, 0.0, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(qdd * duration**2 / scale, 0.0, rtol=0, atol=ATOL_EXACT)


def test_works_on_panda(panda, rng) -> None:
    q0, q1 = random_configurations(panda, rng, 2)
    t_min = trajectory.minimum_duration(panda, q0, q1)
    traj = trajectory.pick_and_place(panda, q0, q1, t_min)
    assert traj.check_limits() == []
    q, _, _ = traj.sample(np.linspace(0.0, t_min, 5))
    assert q.shape == (5, 7)
    np.testing.assert_allclose(q[[0, -1]], [q0, q1], rtol=0, atol=ATOL_EXACT)
    peak = np.max(np.abs(traj.get_extrema(1).maximum) / panda.velocity_limit)
    peak = max(peak, np.max(np.abs(traj.get_extrema(1).minimum) / panda.velocity_limit))
    assert peak == pytest.approx(1.0, rel=1e-12)


def test_exact_extrema_bound_dense_samples(paper_traj) -> None:
    t = np.linspace(0.0, T_PAPER, 100_001)
    for order, values in enumerate(paper_traj.sample(t)):
        ext = paper_traj.get_extrema(order)
        assert np.all(values.max(axis=0) <= ext.maximum + ATOL_EXACT)
        assert np.all(values.min(axis=0) >= ext.minimum - ATOL_EXACT)
        np.testing.assert_allclose(values.max(axis=0), ext.maximum, rtol=0, atol=1e-6)


def test_minimum_duration_touches_but_does_not_exceed(puma) -> None:
    t_min = trajectory.minimum_duration(puma, Q_PICK, Q_PLACE)
    # closed form: joint 3 moves 210 deg at 1 rad/s with max ṡ ≈ 2
    spline = trajectory.compute_normal_spline()
    assert t_min == pytest.approx(math.radians(210) * spline.velocity.peak / 1.0)
    traj = trajectory.pick_and_place(puma, Q_PICK, Q_PLACE, t_min)
    assert traj.check_limits() == []
    trajectory.raise_for_violations(traj)  # no error
    ext = traj.get_extrema(1)
    ratio = np.maximum(np.abs(ext.minimum), np.abs(ext.maximum)) / puma.velocity_limit
    assert ratio.max() == pytest.approx(1.0, rel=1e-12, abs=0)
    assert int(np.argmax(ratio)) == 2


def test_shorter_than_minimum_names_joint_time_value_limit(puma) -> None:
    t_min = trajectory.minimum_duration(puma, Q_PICK, Q_PLACE)
    traj = trajectory.pick_and_place(puma, Q_PICK, Q_PLACE, t_min * (1 - 1e-9))
    (violation,) = traj.check_limits()
    assert violation.joint == "joint3" and violation.kind == "velocity"
    assert violation.t == pytest.approx(traj.duration / 2, rel=1e-12)
    assert violation.limit == -1.0 and violation.value < -1.0
    assert violation.as_dict().keys() == {"joint", "t", "value", "limit", "kind"}
    assert "joint3 velocity -1 rad/s at t = 3.6652 s" in violation.message
    with pytest.raises(JointLimitError, match="joint joint3 velocity") as err:
        trajectory.raise_for_violations(traj)
    assert err.value.kind == "velocity" and err.value.t == violation.t


def test_acceleration_limit_binding(puma) -> None:
    slow = puma.with_limits(acceleration_limit=np.full(6, 0.1))
    t_min = trajectory.minimum_duration(slow, Q_PICK, Q_PLACE)
    spline = trajectory.compute_normal_spline()
    expected = math.sqrt(math.radians(210) * spline.acceleration.peak / 0.1)
    assert t_min == pytest.approx(expected, rel=1e-14)
    traj = trajectory.pick_and_place(slow, Q_PICK, Q_PLACE, t_min)
    assert traj.check_limits() == []
    fast = trajectory.pick_and_place(slow, Q_PICK, Q_PLACE, 0.99 * t_min)
    kinds = {(v.joint, v.kind) for v in fast.check_limits()}
    assert ("joint3", "acceleration") in kinds


def test_position_violation_at_the_start(puma) -> None:
    q0 = Q_PICK.copy()
    q0[1] = math.radians(46.0)  # above joint 2's 45 deg
    traj = trajectory.pick_and_place(puma, q0, Q_PLACE, T_PAPER)
    (violation,) = traj.check_limits()
    assert (violation.joint, violation.kind, violation.t) == ("joint2", "position", 0.0)
    assert violation.limit == puma.upper[1] and violation.value == q0[1]


def test_zero_motion_has_zero_minimum_duration(puma) -> None:
    assert trajectory.minimum_duration(puma, Q_PICK, Q_PICK) == 0.0
    traj = trajectory.pick_and_place(puma, Q_PICK, Q_PICK, 1.0)
    assert traj.check_limits() == []


@pytest.mark.parametrize("duration", [0.0, -1.0, math.nan, math.inf, "ten"])
def test_bad_duration(puma, duration) -> None:
    with pytest.raises(InputError, match="duration must be a"):
        trajectory.pick_and_place(puma, Q_PICK, Q_PLACE, duration)


def test_bad_configurations(puma) -> None:
    with pytest.raises(DimensionError, match="6 values expected, 5 given"):
        trajectory.pick_and_place(puma, Q_PICK[:5], Q_PLACE, 1.0)
    with pytest.raises(DimensionError, match="q_place"):
        trajectory.minimum_duration(puma, Q_PICK, Q_PLACE[:5])
    bad = Q_PLACE.copy()
    bad[2] = math.nan
    with pytest.raises(NonFiniteError, match="q_place must be finite"):
        trajectory.pick_and_place(puma, Q_PICK, bad, 1.0)
    with pytest.raises(NonFiniteError, match="finite"):
        trajectory.pick_and_place(puma, Q_PICK, Q_PLACE, 1.0).sample(math.nan)


def test_robot_with_nq_not_nv_is_refused() -> None:
    robot = load_robot("double_pendulum_continuous")
    with pytest.raises(InputError, match="nq = 4 != nv = 2"):
        trajectory.pick_and_place(robot, np.zeros(4), np.zeros(4), 1.0)


def test_uniform_samples(paper_traj) -> None:
    samples = paper_traj.sample_uniform(100.0)
    assert samples.t.size == 1001 and samples.t[-1] == T_PAPER
    uneven = trajectory.pick_and_place(paper_traj.robot, Q_PICK, Q_PLACE, 1.005)
    t = uneven.sample_uniform(100.0).t
    assert t.size == 102 and t[-1] == 1.005 and np.all(np.diff(t) > 0)
    with pytest.raises(InputError, match="rate_hz"):
        paper_traj.sample_uniform(0.0)


def test_pick_via_place_chains_c2_segments_with_dwells(puma) -> None:
    via = np.deg2rad([90.0, -30.0, 100.0, -90.0, -20.0, 90.0])
    points = np.array([Q_PICK, via, Q_PLACE])
    chain = trajectory.pick_via_place(puma, points, [4.0, 5.0], dwell_times=1.5)
    assert chain.duration == pytest.approx(10.5)
    np.testing.assert_allclose(chain.start_times, [0.0, 5.5], rtol=0, atol=0)
    q, qd, qdd = chain.sample(np.array([0.0, 4.0, 4.7, 5.5, 10.5]))
    np.testing.assert_allclose(q, [Q_PICK, via, via, via, Q_PLACE], rtol=0, atol=1e-12)
    np.testing.assert_allclose(qd, 0.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(qdd, 0.0, rtol=0, atol=1e-12)
    # extremes on the chain's clock: joint 1 is fastest in segment 1 (mid-way,
    # t = 2 s), joint 4 in segment 2 (t = 5.5 + 2.5 s)
    ext = chain.get_extrema(1)
    assert ext.t_maximum[0] == pytest.approx(2.0, rel=1e-12)
    assert ext.t_maximum[3] == pytest.approx(8.0, rel=1e-12)
    assert chain.check_limits() == []
    assert chain.sample_uniform(10.0).t.size == 106
    fast = trajectory.pick_via_place(puma, points, [4.0, 0.5])
    (v, *_) = fast.check_limits()
    assert v.kind == "velocity" and v.t > 4.0


def test_pick_via_place_bad_input(puma) -> None:
    points = np.array([Q_PICK, Q_PLACE, Q_PICK])
    with pytest.raises(InputError, match="dwell_times must be >= 0"):
        trajectory.pick_via_place(puma, points, [1.0, 1.0], dwell_times=-1.0)
    with pytest.raises(DimensionError, match="dwell_times"):
        trajectory.pick_via_place(puma, points, [1.0, 1.0], dwell_times=[1.0, 2.0])
    with pytest.raises(InputError, match=r"durations\[1\] must be"):
        trajectory.pick_via_place(puma, points, [1.0, 0.0])
    with pytest.raises(InputError, match="M >= 1"):
        trajectory.pick_via_place(puma, points[:1], [])


def test_time_optimal_comparison(puma) -> None:
    comparison = trajectory.compare_time_optimal(
        puma, Q_PICK, Q_PLACE, use_toppra=False
    )
    assert comparison.optimal_duration == pytest.approx(math.radians(210))
    assert comparison.ratio == pytest.approx(2.0, abs=1e-4)  # max ṡ of the spline
    limited = puma.with_limits(acceleration_limit=np.full(6, 2.0))
    t_star = trajectory.compute_time_optimal_duration(limited, Q_PICK, Q_PLACE)
    assert t_star == pytest.approx(math.radians(210) + 1.0 / 2.0)  # 1/V + V/A
    tiny = puma.with_limits(acceleration_limit=np.full(6, 1e-3))
    triangle = trajectory.compute_time_optimal_duration(tiny, Q_PICK, Q_PLACE)
    assert triangle == pytest.approx(2.0 * math.sqrt(math.radians(210) / 1e-3))


def test_toppra_agrees_with_the_closed_form(puma) -> None:
    pytest.importorskip("toppra")
    limited = puma.with_limits(acceleration_limit=np.full(6, 2.0))
    comparison = trajectory.compare_time_optimal(limited, Q_PICK, Q_PLACE)
    assert comparison.toppra_duration == pytest.approx(
        comparison.optimal_duration, rel=1e-3
    )
