r"""The normal spline of Angeles et al. (1988), Section IV, built in O(N).

The normal spline :math:`s(t')`, :math:`t' = t/T \in [0, 1]`, rises from
:math:`s(0) = 0` to :math:`s(1) = 1` with :math:`\dot s` and :math:`\ddot s`
zero at both ends, eqs. (8a)–(8b). Read literally, Section IV makes *s
itself* odd and 2-periodic with knot accelerations :math:`\ddot s_i = A\sin\pi
t_i`, eqs. (11)–(12); that spline is a discrete sine, :math:`s \approx
-(A/\pi^2)\sin\pi t`, with :math:`s(1) = 0` and :math:`\dot s(0) \ne 0`, so it
cannot meet (8a)–(8b) for any A (:func:`compute_literal_spline` builds it).

What is built here is the self-consistent reading: the *deviation*
:math:`\delta(t') = s(t') - t'` is the odd periodic cubic spline, its knot
accelerations are :math:`\ddot s_i = A\sin 2\pi t'_i` (the paper's
:math:`\sin\pi t` on its period [0, 2], rescaled to the motion [0, 1]), and the
amplitude A is the one value that makes :math:`\dot s(0) = 0`. Oddness and
periodicity give :math:`\delta(0) = \delta(1) = 0` and
:math:`\ddot s(0) = \ddot s(1) = 0`, periodicity gives :math:`\dot s(1) =
\dot s(0)`. As N grows the spline tends to the cycloidal motion
:math:`t' - \sin(2\pi t')/2\pi`, and A to :math:`2\pi`; for the paper's
N = 40 A = 6.2968. The printed A = 5 is not reproduced by either reading (see
``docs/errata-angeles-spline.md``).

Knots are uniform, :math:`t'_i = (i-1)\tau`, :math:`\tau = 1/(N-1)`,
i = 1..N, so N counts both ends (the paper's N points on its period [0, 2]).
The ordinates solve the reduced tridiagonal system (18)–(19),
:math:`\tau^2/6\,(\ddot s_{i-1} + 4\ddot s_i + \ddot s_{i+1}) = s_{i-1} -
2 s_i + s_{i+1}` with :math:`s_1 = s_N = 0`; its matrix (1, −2, 1) is solved
exactly by two running sums (the Thomas algorithm for this matrix, in closed
form), O(N) in time and memory. The coefficients are eqs. (13a)–(13d); both
live in :mod:`workbench.trajectory.periodic_spline`.
"""

from __future__ import annotations

import functools
import math
import operator
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.trajectory.periodic_spline import (
    SplineExtremum,
    UniformCubicSpline,
    as_finite_times,
    coefficients_from_ordinates,
    read_only_spline,
    solve_ordinates,
)

FloatArray = npt.NDArray[np.float64]

DEFAULT_N_POINTS = 40
"""Knots of the normal spline in Angeles et al.'s Fig. 1 (N = 40)."""

_MONOTONE_RTOL = 1e-12
"""ṡ >= -this·max ṡ counts as monotone (ṡ(1) = 0 holds to ~1e-17 only)."""

_CACHE_MAX_N = 100_000
"""Largest N that :func:`get_normal_spline` memoises (~3 MB per spline)."""

MIN_N_POINTS = 4
"""Fewest knots for which the construction is defined (N = 3 has all s̈_i = 0)."""


@dataclass(frozen=True, slots=True)
class NormalSpline:
    r"""The normal spline :math:`s(t')` on [0, 1] (self-consistent reading).

    Build it with :func:`compute_normal_spline`. Outside [0, 1] the motion is
    at rest: ``evaluate`` clamps :math:`t'` into [0, 1].

    Attributes:
        n_points: Number of knots N on [0, 1], both ends included.
        amplitude: A of eq. (12), :math:`\ddot s_i = A \sin 2\pi t'_i`, fixed
            by :math:`\dot s(0) = 0` (tends to :math:`2\pi`).
        spline: The piecewise cubic of s itself (deviation plus :math:`t'`).
        position, velocity, acceleration: Exact extremes of s, ṡ, s̈ on [0, 1].
    """

    n_points: int
    amplitude: float
    spline: UniformCubicSpline
    position: SplineExtremum
    velocity: SplineExtremum
    acceleration: SplineExtremum

    def evaluate(self, t: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(s, ṡ, s̈)`` at normalised times ``t`` (scalar or array, clamped).

        Raises:
            NonFiniteError: If ``t`` holds NaN or infinity.
        """
        return self.spline._evaluate(np.clip(as_finite_times(t), 0.0, 1.0))

    def jerk(self, t: npt.ArrayLike) -> FloatArray:
        """Third derivative (piecewise constant; 0 outside [0, 1])."""
        t = as_finite_times(t)
        return np.where((t >= 0.0) & (t <= 1.0), self.spline.jerk(t), 0.0)


def _check_n_points(n_points: int) -> int:
    try:
        n = operator.index(n_points)
    except TypeError:
        raise InputError(f"n_points must be an int, got {n_points!r}") from None
    if n < MIN_N_POINTS:
        raise InputError(f"n_points must be >= {MIN_N_POINTS}, got {n}")
    return n


def compute_normal_spline(n_points: int = DEFAULT_N_POINTS) -> NormalSpline:
    r"""Synthesise the normal spline with ``n_points`` knots on [0, 1].

    The deviation :math:`s - t'` is the odd periodic spline with knot
    accelerations :math:`\sin 2\pi t'_i`, solved by :func:`solve_ordinates`;
    it is then scaled by the amplitude A that gives :math:`\dot s(0) = 0`.
    Knot data are made exactly antisymmetric about :math:`t' = 1/2`, so
    :math:`\dot s(1) = \dot s(0)` to rounding. O(N); N = 10⁶ takes tens of ms.

    Args:
        n_points: N >= 4 knots, both ends included (default 40, as the paper).

    Returns:
        The spline, meeting (8a)–(8b) to ~1e-15, with its exact extremes.

    Raises:
        InputError: If ``n_points`` is not an int >= 4.
    """
    n = _check_n_points(n_points)
    step = 1.0 / (n - 1)
    half = n // 2
    sdd = np.zeros(n)  # sin(2 pi t_i), exactly odd about t = 1/2
    sdd[:half] = np.sin((2.0 * np.pi * step) * np.arange(half))
    sdd[n - half :] = -sdd[half - 1 :: -1]
    dev = solve_ordinates(sdd, step)
    dev -= dev[::-1].copy()
    dev *= 0.5
    # Slope of the unit deviation at t' = 0, eq. (13c); A makes s'(0) = 0.
    amplitude = -1.0 / ((dev[1] - dev[0]) / step - step * sdd[1] / 6.0)
    dev *= amplitude
    sdd *= amplitude
    coeffs = coefficients_from_ordinates(dev, sdd, step)
    coeffs[2] += 1.0  # s = t' + deviation
    coeffs[2, 0] = 0.0  # s'(0) = 0 by the choice of A; drop its ~1e-16 residue
    coeffs[3] += step * np.arange(n - 1)
    spline = read_only_spline(0.0, step, coeffs)
    velocity = spline.find_extremum(1)
    if velocity.minimum >= -_MONOTONE_RTOL * velocity.maximum:
        # s is monotone (to rounding at the ends): its extremes are the ends.
        position = SplineExtremum(float(coeffs[3, 0]), 0.0, spline._end_value(0), 1.0)
    else:
        position = spline.find_extremum(0)
    return NormalSpline(
        n_points=n,
        amplitude=amplitude,
        spline=spline,
        position=position,
        velocity=velocity,
        acceleration=spline.find_extremum(2),
    )


@functools.lru_cache(maxsize=8)
def _cached(n_points: int) -> NormalSpline:
    return compute_normal_spline(n_points)


def get_normal_spline(n_points: int = DEFAULT_N_POINTS) -> NormalSpline:
    """:func:`compute_normal_spline`, memoised for N <= 10⁵ (planners call this).

    The spline is immutable (frozen, read-only arrays), so sharing it is safe;
    a planning call then costs microseconds instead of ~0.2 ms for N = 40.
    """
    n = _check_n_points(n_points)
    return _cached(n) if n <= _CACHE_MAX_N else compute_normal_spline(n)


def compute_literal_spline(
    n_points: int = DEFAULT_N_POINTS, amplitude: float = 5.0
) -> UniformCubicSpline:
    r"""Section IV read literally: s odd, 2-periodic, :math:`\ddot s_i = A\sin\pi t_i`.

    N knots on the period [0, 2], :math:`s_1 = s_N = 0`, ordinates by eq. (19).
    The result is a discrete sine, :math:`s \approx -(A/\pi^2)\sin\pi t`:
    :math:`s(1) = 0`, :math:`\dot s(0) \approx -A/\pi`, i.e. it violates (8a)
    and (8b). Kept to document that finding, not for planning.

    Args:
        n_points: N >= 4 knots on [0, 2].
        amplitude: A of eq. (12), finite (the paper prints A = 5).

    Raises:
        InputError: If ``n_points`` < 4 or ``amplitude`` is not finite.
    """
    n = _check_n_points(n_points)
    if not math.isfinite(amplitude):
        raise InputError(f"amplitude must be finite, got {amplitude!r}")
    step = 2.0 / (n - 1)
    sdd = amplitude * np.sin(np.pi * step * np.arange(n))
    sdd[0] = sdd[-1] = 0.0
    s = solve_ordinates(sdd, step)
    return read_only_spline(0.0, step, coefficients_from_ordinates(s, sdd, step))
