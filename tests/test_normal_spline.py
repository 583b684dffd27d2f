"""The normal spline of Angeles et al. (1988), Section IV."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from workbench.errors import InputError, NonFiniteError
from workbench.trajectory import (
    compute_literal_spline,
    compute_normal_spline,
)
from workbench.trajectory.periodic_spline import (
    coefficients_from_ordinates,
    solve_ordinates,
)

ATOL_EXACT = 1e-12
PAPER_N = 40


def _ends(n_points: int) -> np.ndarray:
    """[s(0), s(1) - 1, ṡ(0), ṡ(1), s̈(0), s̈(1)]."""
    s, sd, sdd = compute_normal_spline(n_points).evaluate(np.array([0.0, 1.0]))
    return np.array([s[0], s[1] - 1.0, sd[0], sd[1], sdd[0], sdd[1]])


def test_boundary_conditions_8a_8b_at_paper_n() -> None:
    np.testing.assert_allclose(_ends(PAPER_N), 0.0, rtol=0, atol=ATOL_EXACT)


@settings(max_examples=60, deadline=None)
@given(n_points=st.integers(min_value=4, max_value=20_000))
def test_boundary_conditions_hold_for_any_n(n_points: int) -> None:
    np.testing.assert_allclose(_ends(n_points), 0.0, rtol=0, atol=ATOL_EXACT)


def test_boundary_conditions_for_a_million_knots() -> None:
    np.testing.assert_allclose(_ends(1_000_000), 0.0, rtol=0, atol=ATOL_EXACT)


@pytest.mark.parametrize("n_points", [4, 5, PAPER_N, 41, 1000])
def test_spline_is_c2_and_jerk_jumps_only_at_knots(n_points: int) -> None:
    spline = compute_normal_spline(n_points).spline
    a, b, c, d = spline.coefficients
    tau = spline.step
    # value, slope and curvature at the end of segment k equal those at the
    # start of segment k + 1 (eq. (10) evaluated both sides of every knot)
    left = np.array(
        [
            ((a * tau + b) * tau + c) * tau + d,
            (3 * a * tau + 2 * b) * tau + c,
            6 * a * tau + 2 * b,
        ]
    )[:, :-1]
    right = np.array([d, c, 2 * b])[:, 1:]
    np.testing.assert_allclose(left, right, rtol=0, atol=ATOL_EXACT)
    # inside a segment the jerk is constant: s̈ is linear there
    knots = spline.knots
    h = np.array([0.1, 0.5, 0.9]) * tau
    t = knots[:-1, None] + h
    _, _, sdd = spline.evaluate(t)
    slope = np.diff(sdd, axis=1) / np.diff(h)
    expected = np.broadcast_to((6 * a)[:, None], slope.shape)
    np.testing.assert_allclose(slope, expected, rtol=0, atol=1e-9 / tau)
    jerk = spline.jerk(t)
    np.testing.assert_array_equal(jerk, np.repeat((6 * a)[:, None], 3, axis=1))
    # and it does change from segment to segment (it is not a single cubic)
    assert np.ptp(6 * a) > 1.0


@pytest.mark.parametrize("n_points", [4, 7, PAPER_N, 501])
def test_o_n_solve_matches_the_dense_system_18(n_points: int) -> None:
    rng = np.random.default_rng(n_points)
    sdd = rng.normal(size=n_points)
    sdd[0] = sdd[-1] = 0.0
    tau = 1.0 / (n_points - 1)
    m = n_points - 2
    a_mat = tau * (4 * np.eye(m) + np.eye(m, k=1) + np.eye(m, k=-1))
    c_mat = (-2 * np.eye(m) + np.eye(m, k=1) + np.eye(m, k=-1)) / tau
    dense = np.linalg.solve(c_mat, a_mat @ sdd[1:-1]) / 6.0  # eq. (19)
    s = solve_ordinates(sdd, tau)
    assert s[0] == 0.0 and s[-1] == 0.0
    np.testing.assert_allclose(s[1:-1], dense, rtol=0, atol=1e-13)
    # eq. (13): the coefficients reproduce the ordinates and curvatures
    coeffs = coefficients_from_ordinates(s, sdd, tau)
    np.testing.assert_allclose(coeffs[3], s[:-1], rtol=0, atol=0)
    np.testing.assert_allclose(2 * coeffs[1], sdd[:-1], rtol=0, atol=0)


def test_amplitude_at_paper_n_and_limit_two_pi() -> None:
    spline = compute_normal_spline(PAPER_N)
    assert spline.amplitude == pytest.approx(6.29681, abs=1e-5)
    amplitudes = [compute_normal_spline(n).amplitude for n in (40, 400, 4000)]
    errors = np.abs(np.array(amplitudes) - 2 * np.pi)
    # second-order convergence: 10x the knots, ~100x smaller error
    assert errors[0] / errors[1] > 90 and errors[1] / errors[2] > 90
    assert errors[2] < 2e-6


def test_the_printed_amplitude_five_breaks_the_end_slope() -> None:
    # s = t' + A·δ_unit with ṡ(0) = 1 + A·δ'_unit(0) = 1 - A / A*: with the
    # printed A = 5 the spline would start at speed ≈ 0.206, not at rest.
    a_star = compute_normal_spline(PAPER_N).amplitude
    assert 1.0 - 5.0 / a_star == pytest.approx(0.2060, abs=1e-4)


def test_spline_tends_to_the_cycloidal_motion() -> None:
    t = np.linspace(0.0, 1.0, 2001)
    cycloid = t - np.sin(2 * np.pi * t) / (2 * np.pi)
    errors = []
    for n in (40, 400):
        s, _, _ = compute_normal_spline(n).evaluate(t)
        errors.append(np.abs(s - cycloid).max())
    assert errors[0] < 1e-4 and errors[1] < errors[0] / 90


def test_literal_reading_gives_a_sine_not_a_rise() -> None:
    t = np.linspace(0.0, 2.0, 401)
    for amplitude in (1.0, 5.0, math.pi**2):
        literal = compute_literal_spline(PAPER_N, amplitude)
        s, _, _ = literal.evaluate(t)
        sine = -(amplitude / math.pi**2) * np.sin(math.pi * t)
        assert np.abs(s - sine).max() < 2e-3 * amplitude
        s1, sd0 = literal.evaluate(1.0)[0], literal.evaluate(0.0)[1]
        assert abs(s1) < ATOL_EXACT  # (8a) s(1) = 1 fails for every A
        assert sd0 == pytest.approx(-amplitude / math.pi, rel=5e-3)  # (8b) fails


def test_extrema_are_exact_and_bound_every_sample() -> None:
    spline = compute_normal_spline(PAPER_N)
    t = np.linspace(0.0, 1.0, 200_001)
    s, sd, sdd = spline.evaluate(t)
    for ext, values in (
        (spline.position, s),
        (spline.velocity, sd),
        (spline.acceleration, sdd),
    ):
        assert values.max() <= ext.maximum + ATOL_EXACT
        assert values.min() >= ext.minimum - ATOL_EXACT
        assert ext.maximum - values.max() < 1e-6  # samples 5e-6 apart
    assert spline.velocity.t_maximum == pytest.approx(0.5, abs=1e-12)
    assert spline.velocity.maximum == pytest.approx(2.0, abs=1e-5)
    assert spline.velocity.minimum >= 0.0  # monotone rise
    # the peak of ṡ lies inside a segment for even N: sampling knots misses it
    knots_sd = spline.evaluate(spline.spline.knots)[1]
    assert spline.velocity.maximum - knots_sd.max() > 1e-7


def test_find_extremum_of_a_generic_spline() -> None:
    literal = compute_literal_spline(PAPER_N, 5.0)
    ext = literal.find_extremum(0)
    assert ext.minimum == pytest.approx(-5.0 / math.pi**2, rel=5e-3)
    assert ext.t_minimum == pytest.approx(0.5, abs=1e-3)
    assert ext.t_maximum == pytest.approx(1.5, abs=1e-3)
    with pytest.raises(InputError, match="order must be 0, 1 or 2"):
        literal.find_extremum(3)


def test_evaluate_shapes_and_clamping() -> None:
    spline = compute_normal_spline()
    s, sd, sdd = spline.evaluate(0.25)
    assert np.ndim(s) == 0
    s, sd, sdd = spline.evaluate(np.zeros((2, 3)))
    assert s.shape == sd.shape == sdd.shape == (2, 3)
    s, sd, sdd = spline.evaluate(np.array([-1.0, 2.0]))
    np.testing.assert_allclose(s, [0.0, 1.0], rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(sd, 0.0, rtol=0, atol=ATOL_EXACT)
    assert np.all(spline.jerk(np.array([-1.0, 2.0])) == 0.0)


@pytest.mark.parametrize(
    ("n_points", "fragment"),
    [(3, ">= 4"), (0, ">= 4"), (40.5, "must be an int"), ("40", "must be an int")],
)
def test_bad_n_points(n_points, fragment: str) -> None:
    with pytest.raises(InputError, match=fragment):
        compute_normal_spline(n_points)


def test_non_finite_times_raise() -> None:
    with pytest.raises(NonFiniteError, match="finite"):
        compute_normal_spline().evaluate(np.array([0.1, np.nan]))
    with pytest.raises(InputError, match="amplitude must be finite"):
        compute_literal_spline(PAPER_N, math.inf)
