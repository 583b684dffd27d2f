r"""Cubic splines on uniform knots from their knot second derivatives (Sec. IV).

The machinery of Angeles et al. (1988), Section IV, independent of the normal
spline: the segment form (10), the coefficients (13a)–(13d) and the reduced
tridiagonal system (18)–(19) for the ordinates, solved in O(N); plus exact
evaluation and exact extremes of the resulting piecewise cubic.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError, NonFiniteError

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class SplineExtremum:
    """Smallest and largest value of one derivative of a spline, and where.

    Attributes:
        minimum: Smallest value over the whole domain (exact, not sampled).
        t_minimum: Where it is reached (the first such place).
        maximum: Largest value over the whole domain.
        t_maximum: Where it is reached.
    """

    minimum: float
    t_minimum: float
    maximum: float
    t_maximum: float

    @property
    def peak(self) -> float:
        """Largest absolute value, ``max(|minimum|, |maximum|)``."""
        return max(abs(self.minimum), abs(self.maximum))


@dataclass(frozen=True, slots=True)
class UniformCubicSpline:
    r"""A piecewise cubic on uniform knots, eq. (10).

    On segment k (0-based), :math:`t_k \le t \le t_{k+1}`, with
    :math:`h = t - t_k`: :math:`s = a_k h^3 + b_k h^2 + c_k h + d_k`.

    Attributes:
        start: First knot :math:`t_1`.
        step: Knot spacing :math:`\tau` > 0.
        coefficients: Shape (4, N-1): rows a, b, c, d, one column per segment,
            read-only.
    """

    start: float
    step: float
    coefficients: FloatArray

    @property
    def n_points(self) -> int:
        """Number of knots N."""
        return int(self.coefficients.shape[1]) + 1

    @property
    def end(self) -> float:
        """Last knot :math:`t_N`."""
        return self.start + (self.n_points - 1) * self.step

    @property
    def knots(self) -> FloatArray:
        """Knot times, shape (N,)."""
        return self.start + self.step * np.arange(self.n_points, dtype=np.float64)

    def _locate(self, t: FloatArray) -> tuple[npt.NDArray[np.intp], FloatArray]:
        u = (t - self.start) * (1.0 / self.step)
        # truncation = floor for u >= 0; below 0 the clip gives segment 0 anyway
        k = np.clip(np.asarray(u).astype(np.intp), 0, self.n_points - 2)
        return k, (u - k) * self.step

    def _evaluate(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        k, h = self._locate(t)
        a, b, c, d = np.take(self.coefficients, k, axis=1)
        a3 = 3.0 * a
        s = ((a * h + b) * h + c) * h + d
        sd = (a3 * h + 2.0 * b) * h + c
        sdd = 2.0 * (a3 * h + b)
        return s, sd, sdd

    def evaluate(self, t: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Value, first and second derivative at ``t``.

        Args:
            t: Scalar or array of times within [start, end]; outside, the
                first or last cubic is extrapolated.

        Returns:
            ``(s, sd, sdd)``, each with the shape of ``t``.

        Raises:
            NonFiniteError: If ``t`` holds NaN or infinity.
        """
        return self._evaluate(as_finite_times(t))

    def jerk(self, t: npt.ArrayLike) -> FloatArray:
        """Third derivative at ``t``, constant on each segment (shape of ``t``).

        At a knot the value of the segment that starts there is returned.
        """
        k, _ = self._locate(as_finite_times(t))
        return 6.0 * np.take(self.coefficients[0], k)

    def find_extremum(self, order: int) -> SplineExtremum:
        """Exact extremes of the value (0), slope (1) or second derivative (2).

        Candidates are the knots and, inside each segment, the zeros of the
        next derivative (a root of a quadratic for order 0, of a line for
        order 1); s̈ is piecewise linear, so for order 2 the knots suffice.

        Raises:
            InputError: If ``order`` is not 0, 1 or 2.
        """
        a, b, c, d = self.coefficients
        if order not in (0, 1, 2):
            raise InputError(f"order must be 0, 1 or 2, got {order!r}")
        at_knots = (d, c, 2.0 * b)[order]
        candidates = [
            _extremes_of(at_knots, self.start, self.step),
            _extremes_of(np.array([self._end_value(order)]), self.end, 0.0),
        ]
        if order < 2:
            tau = self.step
            with np.errstate(divide="ignore", invalid="ignore"):
                if order == 1:  # vertex of the quadratic slope
                    roots: tuple[FloatArray, ...] = (-b / (3.0 * a),)
                else:
                    roots = _quadratic_roots(3.0 * a, 2.0 * b, c)
            for h in roots:
                inside = np.flatnonzero((h > 0.0) & (h < tau))
                if inside.size:
                    hi = h[inside]
                    ai, bi, ci, di = self.coefficients[:, inside]
                    vals = (
                        ((ai * hi + bi) * hi + ci) * hi + di
                        if order == 0
                        else (3.0 * ai * hi + 2.0 * bi) * hi + ci
                    )
                    times = self.start + inside * tau + hi
                    i, j = int(np.argmin(vals)), int(np.argmax(vals))
                    candidates.append(
                        (
                            float(vals[i]),
                            float(times[i]),
                            float(vals[j]),
                            float(times[j]),
                        )
                    )
        lo = min(candidates, key=lambda x: x[0])
        hi_ = max(candidates, key=lambda x: x[2])
        return SplineExtremum(lo[0], lo[1], hi_[2], hi_[3])

    def _end_value(self, order: int) -> float:
        a, b, c, d = self.coefficients[:, -1]
        h = self.step
        if order == 0:
            return float(((a * h + b) * h + c) * h + d)
        if order == 1:
            return float((3.0 * a * h + 2.0 * b) * h + c)
        return float(6.0 * a * h + 2.0 * b)


def _extremes_of(
    values: FloatArray, start: float, step: float
) -> tuple[float, float, float, float]:
    """(min, its time, max, its time) of values at start + k·step."""
    i, j = int(np.argmin(values)), int(np.argmax(values))
    return float(values[i]), start + i * step, float(values[j]), start + j * step


def as_finite_times(t: npt.ArrayLike) -> FloatArray:
    """``t`` as a float64 array (any shape), checked finite.

    Raises:
        NonFiniteError: If ``t`` is not numbers or holds NaN or infinity.
    """
    try:
        arr = np.asarray(t, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise NonFiniteError(f"t must be numbers, got {t!r}") from err
    if not np.isfinite(arr).all():
        raise NonFiniteError("t must be finite")
    return arr


def _quadratic_roots(
    a: FloatArray, b: FloatArray, c: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Both real roots of a x² + b x + c per entry (NaN where none/degenerate)."""
    disc = b * b - 4.0 * a * c
    with np.errstate(divide="ignore", invalid="ignore"):
        sq = np.sqrt(np.where(disc >= 0.0, disc, np.nan))
        q = -0.5 * (b + np.copysign(sq, b))  # no cancellation
        r1 = np.where(a != 0.0, q / a, -c / b)
        r2 = np.where(q != 0.0, c / q, np.nan)
    return r1, r2


def solve_ordinates(second_derivatives: npt.ArrayLike, step: float) -> FloatArray:
    r"""Ordinates of a cubic spline from its knot second derivatives, eq. (19).

    Solves the reduced system (18), :math:`s_{i-1} - 2 s_i + s_{i+1} =
    \tfrac{\tau^2}{6}(\ddot s_{i-1} + 4\ddot s_i + \ddot s_{i+1})`,
    i = 2..N-1, with :math:`s_1 = s_N = 0`, in O(N): with
    :math:`\Delta_i = s_{i+1} - s_i` the system reads
    :math:`\Delta_i - \Delta_{i-1} = r_i`, so :math:`\Delta` is a running sum
    of r, s a running sum of :math:`\Delta`, and :math:`\Delta_1` is fixed by
    :math:`s_N = 0`.

    Args:
        second_derivatives: :math:`\ddot s_i`, shape (N,), N >= 3.
        step: Knot spacing :math:`\tau` > 0.

    Returns:
        :math:`s_i`, shape (N,), with ``s[0] = s[-1] = 0``.
    """
    sdd = np.asarray(second_derivatives, dtype=np.float64)
    m = sdd.size - 2
    r = np.add(sdd[:-2], sdd[2:])
    r += 4.0 * sdd[1:-1]
    r *= step * step / 6.0
    # Delta_1 + ... + Delta_{N-1} = s_N = 0 with Delta_i = Delta_1 + cumsum(r):
    delta = np.empty(m + 1)
    np.cumsum(r, out=delta[1:])
    delta[0] = -float(delta[1:].sum()) / (m + 1)
    delta[1:] += delta[0]
    s = np.empty(m + 2)
    s[0] = 0.0
    np.cumsum(delta, out=s[1:])
    s[-1] = 0.0  # exact: the running sum leaves ~N·eps here
    return s


def coefficients_from_ordinates(
    ordinates: FloatArray, second_derivatives: FloatArray, step: float
) -> FloatArray:
    """Segment coefficients, rows a, b, c, d, shape (4, N-1), eqs. (13a)–(13d)."""
    s, sdd = ordinates, second_derivatives
    coeffs = np.empty((4, s.size - 1))
    a, b, c, d = coeffs
    np.subtract(sdd[1:], sdd[:-1], out=a)
    a *= 1.0 / (6.0 * step)
    np.multiply(sdd[:-1], 0.5, out=b)
    # (13c): c = ds/tau - tau (sdd_{k+1} + 2 sdd_k)/6 = ds/tau - tau^2 a - tau b
    np.subtract(s[1:], s[:-1], out=c)
    c *= 1.0 / step
    c -= (step * step) * a
    c -= step * b
    d[:] = s[:-1]
    return coeffs


def read_only_spline(
    start: float, step: float, coeffs: FloatArray
) -> UniformCubicSpline:
    """A :class:`UniformCubicSpline` owning ``coeffs``, made read-only."""
    coeffs.setflags(write=False)
    return UniformCubicSpline(float(start), float(step), coeffs)
