"""Trapezoidal profiles: exact phases, Kang's vi/vf flags, replanning, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from workbench import InfeasibleError, InputError, NonFiniteError, planning
from workbench.planning import replan_trapezoid, stopping_profile, trapezoid

ATOL_EXACT = 1e-12
RTOL_LIMIT = 1e-9

limits = st.floats(min_value=0.05, max_value=5.0)
fractions = st.floats(min_value=0.0, max_value=1.0, allow_subnormal=False)


def _check_profile(prof, vmax: float, amax: float, v_bound: float | None = None):
    """Bounds, continuity of s and sd, and sd integrating to s."""
    t = np.linspace(0.0, prof.duration, 2001)
    s, sd, sdd = prof.sample(t)
    bound = vmax if v_bound is None else v_bound
    assert np.all(np.abs(sd) <= bound * (1 + RTOL_LIMIT) + ATOL_EXACT)
    assert np.all(np.abs(sdd) <= amax * (1 + RTOL_LIMIT))
    for tb in prof.times[1:-1]:  # both sides of each phase boundary
        before, after = prof.sample(tb - 1e-12), prof.sample(tb + 1e-12)
        assert after[0] == pytest.approx(before[0], abs=1e-9)
        assert after[1] == pytest.approx(before[1], abs=1e-9)
    if prof.duration > 0:  # trapezoidal rule on the velocity gives the position
        dt = t[1] - t[0]
        integral = np.concatenate([[0.0], np.cumsum(dt * 0.5 * (sd[1:] + sd[:-1]))])
        # exact on each linear piece; each kink costs at most amax dt^2 / 4
        atol = amax * dt * dt * len(prof.times) + 1e-9
        np.testing.assert_allclose(integral, s, rtol=0, atol=atol)


def test_trapezoidal_phases_are_exact():
    prof = trapezoid(1.0, 0.5, 1.0)
    # accelerate 0.5 s (0.125), cruise 1.5 s (0.75), decelerate 0.5 s (0.125)
    assert prof.times == pytest.approx((0.0, 0.5, 2.0, 2.5), abs=ATOL_EXACT)
    assert prof.accelerations == (1.0, 0.0, -1.0)
    assert prof.duration == pytest.approx(2.5, abs=ATOL_EXACT)
    assert prof.peak_velocity == pytest.approx(0.5, abs=ATOL_EXACT)
    assert prof.sample(0.0) == (0.0, 0.0, 0.0)
    assert prof.sample(prof.duration)[:2] == (1.0, 0.0)
    assert prof.sample(1.25) == pytest.approx((0.5, 0.5, 0.0), abs=ATOL_EXACT)


def test_triangular_when_too_short_to_cruise():
    prof = trapezoid(0.1, 0.5, 1.0)
    peak = math.sqrt(1.0 * 0.1)
    assert prof.peak_velocity == pytest.approx(peak, abs=ATOL_EXACT)
    assert peak < 0.5
    assert len(prof.accelerations) == 2  # no cruise phase
    assert prof.duration == pytest.approx(2 * peak, abs=ATOL_EXACT)


@pytest.mark.parametrize(
    ("vi", "vf", "duration"),
    [
        (1, 1, 2.0),  # cruise only: 1 m at 0.5 m/s
        (0, 1, 0.25 + (1.0 - 0.0625) / 0.5),  # StraightLine(P1, P2, 0, 1)
        (1, 0, 0.25 + (1.0 - 0.0625) / 0.5),
    ],
)
def test_kang_velocity_flags(vi, vf, duration):
    vmax = 0.5
    prof = trapezoid(
        1.0, vmax, 2.0, initial_velocity=vi * vmax, final_velocity=vf * vmax
    )
    assert prof.initial_velocity == vi * vmax
    assert prof.final_velocity == vf * vmax
    assert prof.duration == pytest.approx(duration, abs=ATOL_EXACT)
    _check_profile(prof, vmax, 2.0)
    # beyond the end the profile continues at its final speed
    s, sd, sdd = prof.sample(prof.duration + 1.0)
    assert (s, sd, sdd) == pytest.approx((1.0 + vf * vmax, vf * vmax, 0.0))


def test_contract_entry_point_and_array_sampling():
    prof = planning.trapezoid(0.3, 0.2, 0.4)
    s, sd, sdd = prof.sample(np.zeros((2, 3)))
    assert s.shape == sd.shape == sdd.shape == (2, 3)


@pytest.mark.slow
@settings(max_examples=150, deadline=None)
@given(
    distance=st.floats(min_value=0.0, max_value=3.0, allow_subnormal=False),
    vmax=limits,
    amax=limits,
    fi=fractions,
    ff=fractions,
)
def test_trapezoid_properties(distance, vmax, amax, fi, ff):
    v0, vf = fi * vmax, ff * vmax
    assume(distance >= abs(vf * vf - v0 * v0) / (2 * amax) * (1 + 1e-9))
    prof = trapezoid(distance, vmax, amax, initial_velocity=v0, final_velocity=vf)
    assert prof.sample(0.0)[:2] == (0.0, v0)
    assert prof.sample(prof.duration)[:2] == (distance, vf)
    _check_profile(prof, vmax, amax)
    s, sd, _ = prof.sample(np.linspace(0.0, prof.duration, 501))
    assert np.all(sd >= -ATOL_EXACT)  # never goes back
    assert np.all(np.diff(s) >= -1e-12)
    # time-optimal: the bang-coast-bang duration in closed form
    peak = min(vmax, math.sqrt(amax * distance + 0.5 * (v0 * v0 + vf * vf)))
    peak = max(peak, v0, vf)
    ramps = (2 * peak - v0 - vf) / amax
    expected = ramps
    if peak > 0:
        expected += max(
            (distance - (2 * peak * peak - v0 * v0 - vf * vf) / (2 * amax)) / peak, 0.0
        )
    assert prof.duration == pytest.approx(expected, rel=1e-9, abs=1e-9)


@settings(max_examples=150, deadline=None)
@given(
    distance=st.floats(min_value=-2.0, max_value=2.0, allow_subnormal=False),
    vmax=limits,
    amax=limits,
    v0=st.floats(min_value=-6.0, max_value=6.0, allow_subnormal=False),
    ff=st.floats(min_value=-1.0, max_value=1.0, allow_subnormal=False),
)
def test_replan_reaches_any_state_within_bounds(distance, vmax, amax, v0, ff):
    vf = ff * vmax
    prof = replan_trapezoid(
        distance, vmax, amax, initial_velocity=v0, final_velocity=vf
    )
    assert prof.sample(0.0)[:2] == (0.0, v0)
    assert prof.sample(prof.duration)[:2] == (distance, vf)
    _check_profile(prof, vmax, amax, v_bound=max(vmax, abs(v0)))


def test_replan_overshoots_and_comes_back():
    prof = replan_trapezoid(0.0, 1.0, 1.0, initial_velocity=0.5)
    s, _, _ = prof.sample(np.linspace(0.0, prof.duration, 101))
    assert s.max() == pytest.approx(0.125, abs=1e-4)  # v^2 / (2 a) out, then back
    assert prof.sample(prof.duration)[:2] == (0.0, 0.0)


def test_stopping_profile():
    prof = stopping_profile(-0.4, 2.0)
    assert prof.duration == pytest.approx(0.2, abs=ATOL_EXACT)
    assert prof.distance == pytest.approx(-0.04, abs=ATOL_EXACT)
    assert prof.accelerations == (2.0,)
    assert prof.final_velocity == 0.0


@pytest.mark.parametrize(
    ("kwargs", "error", "fragment"),
    [
        ({"max_velocity": 0.0}, InputError, "max_velocity must be > 0"),
        ({"max_velocity": -1.0}, InputError, "max_velocity must be > 0"),
        ({"max_acceleration": 0.0}, InputError, "max_acceleration must be > 0"),
        ({"max_acceleration": -2.0}, InputError, "max_acceleration must be > 0"),
        ({"distance": math.nan}, NonFiniteError, "distance must be finite"),
        ({"max_velocity": math.inf}, NonFiniteError, "max_velocity must be finite"),
        ({"distance": -1.0}, InputError, "distance must be >= 0"),
        ({"initial_velocity": 2.0}, InputError, "initial_velocity must be in"),
        ({"final_velocity": -0.1}, InputError, "final_velocity must be in"),
        ({"distance": "x"}, NonFiniteError, "distance must be a number"),
        (
            {"distance": 0.1, "final_velocity": 1.0},
            InfeasibleError,
            "too short to accelerate from 0 to 1",
        ),
        (
            {"distance": 0.1, "initial_velocity": 1.0},
            InfeasibleError,
            "too short to decelerate from 1 to 0",
        ),
    ],
)
def test_bad_input_raises_clear_errors(kwargs, error, fragment):
    args = {"distance": 1.0, "max_velocity": 1.0, "max_acceleration": 1.0} | kwargs
    with pytest.raises(error, match=fragment):
        trapezoid(
            args.pop("distance"),
            args.pop("max_velocity"),
            args.pop("max_acceleration"),
            **args,
        )


def test_replan_and_sample_errors():
    with pytest.raises(InputError, match="final_velocity"):
        replan_trapezoid(1.0, 1.0, 1.0, initial_velocity=0.0, final_velocity=2.0)
    with pytest.raises(InputError, match="max_acceleration must be > 0"):
        stopping_profile(1.0, 0.0)
    prof = trapezoid(1.0, 1.0, 1.0)
    with pytest.raises(NonFiniteError, match="t must be finite"):
        prof.sample(math.nan)
    with pytest.raises(NonFiniteError, match="t must be finite"):
        prof.sample(np.array([0.0, np.inf]))
