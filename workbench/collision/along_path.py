r"""Clearance along a joint path, with no contact missed between the samples.

The path is known at sample times :math:`t_k`; between two samples it is either
the straight line in joint space (what a controller does with the samples) or
any motion whose joint speeds stay below a bound :math:`V` (a planned spline),
optionally with accelerations below :math:`A`. Joint :math:`i` then travels at
most :math:`\tau_i = |q_{k+1,i} - q_{k,i}|`, resp.
:math:`\min(V_i \Delta t, |\Delta q_i| + A_i \Delta t^2 / 2)`, and the
distance of a pair :math:`p` changes by at most
:math:`\delta_p = \sum_i L_{p,i} \tau_i` (lever arms, see
:mod:`workbench.collision.checker`). With :math:`d_k, d_{k+1}` the distances at
the two samples, every instant of the interval is within :math:`\delta_p` of
travel from one of them, so

.. math::
    d(t) \ge \tfrac12 (d_k + d_{k+1} - \delta_p) - \epsilon

(:math:`\epsilon` = :data:`DISTANCE_TOL`, a margin over coal's GJK tolerance
for separated bodies, :data:`~workbench.collision.checker.GJK_TOLERANCE`). When this
lower bound is > 0 the interval is proven free for that pair (conservative
advancement); otherwise the interval is bisected until it is, a contact is
found, or :math:`\delta_p` < :data:`RESOLUTION`. To save work, every pair is
first bounded at every :data:`COARSE_STRIDE`-th sample only, by the distance of
the convex hulls of its meshes
(:meth:`~workbench.collision.CollisionChecker.compute_lower_bounds`, a lower
bound that costs coal a few µs); the exact distance is computed there for the
pairs whose bound is at most the smallest exact distance found (or 0), in
rounds until no bound is, so the smallest exact distance over the coarse
samples and every contact at them are found. The samples in between are
visited for the pairs whose lower bound over the coarse interval (from the
exact distances or the hulls' at its ends) could reach that distance (or 0);
a visited sample is bounded by the hulls too and measured exactly where that
bound could, or where an interval between neighbouring samples is bisected.
The smallest distance over the samples is therefore exactly the one a check
of every pair at every sample finds, and ``lower_bound`` holds for the whole
continuous path.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.collision.checker import CollisionChecker
from workbench.collision.clearance_report import Contact, PathClearance, group_contacts
from workbench.errors import DimensionError, InputError
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]

#: Margin [m] for coal's distance accuracy (10 x the checker's GJK tolerance).
DISTANCE_TOL = 1e-9
#: Bisection stops when the motion bound of an interval is below this [m].
RESOLUTION = 1e-9
#: Every pair is computed at every COARSE_STRIDE-th sample first.
COARSE_STRIDE = 8


def check_path(
    checker: CollisionChecker,
    t: npt.ArrayLike,
    q: npt.ArrayLike,
    *,
    sample: Callable[[float], FloatArray] | None = None,
    max_joint_speed: npt.ArrayLike | None = None,
    max_joint_acceleration: npt.ArrayLike | None = None,
    stride: int = 1,
) -> PathClearance:
    """Minimum clearance and contacts along a joint path.

    Args:
        checker: Robot, scene and pairs.
        t: Sample times (K,) [s], strictly increasing.
        q: Configurations (K, nq) [rad] at ``t``.
        sample: The path between samples, ``sample(t) -> q`` (e.g. a spline);
            None: straight lines in joint space between the samples.
        max_joint_speed: With ``sample``: bound on |q̇| (nv,) [rad/s] over the
            path (e.g. the spline's exact peak speeds).
        max_joint_acceleration: With ``sample``, optional: bound on |q̈| (nv,)
            [rad/s²] of a C¹ path; tightens the travel bound to
            ``|Δq| + A Δt² / 2`` (e.g. the spline's exact peak accelerations).
        stride: Compute distances at every ``stride``-th sample (and the
            last) only; the bound still covers the path through all samples
            (e.g. 10 for a 1 kHz servo path checked at the 100 Hz cycles).

    Returns:
        The clearance report.

    Raises:
        DimensionError, NonFiniteError: If the shapes or values are wrong.
        InputError: If ``t`` does not increase, ``sample`` is given without
            ``max_joint_speed``, or the checker has no pairs.
    """
    robot = checker.robot
    if not checker.pairs:
        raise InputError("nothing to check: the checker has no pairs")
    t = np.asarray(t, dtype=np.float64)
    if t.ndim != 1 or t.size == 0:
        raise DimensionError("t", (max(t.size, 1),), t.shape)
    t = as_finite_array(t, t.shape, "t")
    q = as_finite_array(q, (t.size, robot.nq), "q")
    if np.any(np.diff(t) <= 0.0):
        raise InputError("t must be strictly increasing")
    between: Callable[[Any, FloatArray, Any, FloatArray], FloatArray] = (
        _straight_travel
        if sample is None
        else _bounded_travel(robot.nv, max_joint_speed, max_joint_acceleration)
    )
    travel = between(t[:-1, None], q[:-1], t[1:, None], q[1:])  # (K - 1, nv)
    if isinstance(stride, bool) or not isinstance(stride, int) or stride < 1:
        raise InputError(f"stride must be an integer >= 1, got {stride!r}")
    cumulative = np.vstack([np.zeros((1, robot.nv)), np.cumsum(travel, axis=0)])
    keep = np.unique(np.r_[np.arange(0, t.size, stride), t.size - 1])
    if stride > 1 and sample is None:  # bisect along the samples, not across them
        sample = _polyline(t, q)
        between = _polyline_travel(t, cumulative)
    return _PathCheck(
        checker, t[keep], q[keep], cumulative[keep], sample, between
    ).run()


def _straight_travel(
    t0: float, q0: FloatArray, t1: float, q1: FloatArray
) -> FloatArray:
    """Joint travel (nv,) [rad] of the straight line from ``q0`` to ``q1``."""
    return np.abs(q1 - q0)


def _bounded_travel(
    nv: int, speed: npt.ArrayLike | None, acceleration: npt.ArrayLike | None
) -> Callable[[float, FloatArray, float, FloatArray], FloatArray]:
    r"""Travel bound of a path with :math:`|\dot q| \le V`, :math:`|\ddot q| \le A`.

    :math:`\int |\dot q| \le V \Delta t`, and, as :math:`\dot q - \Delta q /
    \Delta t` vanishes somewhere in the interval and changes at most at rate
    :math:`A`, :math:`\int |\dot q| \le |\Delta q| + A \Delta t^2 / 2`.
    """
    if speed is None:
        raise InputError("check_path with sample= needs max_joint_speed")
    v = as_finite_array(speed, (nv,), "max_joint_speed")
    a = None
    if acceleration is not None:
        a = as_finite_array(acceleration, (nv,), "max_joint_acceleration")
    if np.any(v < 0.0) or (a is not None and np.any(a < 0.0)):
        raise InputError("max_joint_speed and max_joint_acceleration must be >= 0")

    def travel(t0: float, q0: FloatArray, t1: float, q1: FloatArray) -> FloatArray:
        dt = t1 - t0
        if a is None:
            return v * dt
        return np.minimum(v * dt, np.abs(q1 - q0) + 0.5 * a * dt * dt)

    return travel


def _polyline_travel(
    t: FloatArray, cumulative: FloatArray
) -> Callable[[float, FloatArray, float, FloatArray], FloatArray]:
    """Travel (nv,) along the polyline through all samples between two times."""

    def at(s: float) -> FloatArray:
        return np.array([np.interp(s, t, column) for column in cumulative.T])

    return lambda t0, q0, t1, q1: at(t1) - at(t0)


def _polyline(t: FloatArray, q: FloatArray) -> Callable[[float], FloatArray]:
    """The straight lines in joint space through the samples, as ``q(t)``."""

    def evaluate(s: float) -> FloatArray:
        return np.array([np.interp(s, t, column) for column in q.T])

    return evaluate


class _PathCheck:
    """One run of the algorithm of the module docstring."""

    def __init__(self, checker, t, q, cumulative, sample, between) -> None:
        self.checker, self.t, self.q, self.sample = checker, t, q, sample
        self.levers = checker.levers
        self.cumulative = cumulative
        self.between = between
        self.distances = np.full((t.size, len(checker.pairs)), np.nan)  # exact
        self.lower = np.full_like(self.distances, np.nan)  # the hulls' bounds
        self.extra: list[tuple[float, int, float]] = []  # (t, pair, distance)
        self.bounds: list[float] = []
        self.evaluations = 0

    def _evaluate_coarse(self, coarse: npt.NDArray[np.int64]) -> float:
        """Hull bounds at the coarse samples, exact distances where they may be least.

        See the module docstring. Returns the least exact distance [m].
        """
        lower = np.array([self.checker.compute_lower_bounds(self.q[k]) for k in coarse])
        exact = self.checker._measure_where_least(self.q[coarse], lower)
        self.lower[coarse] = lower
        self.distances[coarse] = exact
        self.evaluations += int(np.count_nonzero(~np.isnan(exact)))
        return float(np.nanmin(exact))

    def _motion(self, a: npt.NDArray[np.int64], b: npt.NDArray[np.int64]) -> FloatArray:
        return (self.cumulative[b] - self.cumulative[a]) @ self.levers.T

    def _known(self, k: Any, p: Any = slice(None)) -> FloatArray:
        """Exact distances at samples ``k``, pairs ``p``, where known, else the hulls'.

        ``k`` and ``p`` index as numpy's indices do (ints, arrays, slices).
        """
        d = self.distances[k, p]
        return np.where(np.isnan(d), self.lower[k, p], d)

    def _exact(self, k: int, p: int) -> None:
        """Compute pair ``p``'s exact distance at sample ``k`` if not known."""
        if np.isnan(self.distances[k, p]):
            self.distances[k, p] = self.checker.compute_pair_distance(self.q[k], p)
            self.evaluations += 1

    def run(self) -> PathClearance:
        k_total = self.distances.shape[0]
        coarse = np.unique(np.r_[np.arange(0, k_total, COARSE_STRIDE), k_total - 1])
        threshold = max(self._evaluate_coarse(coarse), 0.0)
        if k_total > 1:
            self._check_intervals(coarse, threshold)
        else:
            self.bounds.append(float(np.min(self._known(coarse)[0])))
        return self._report()

    def _check_intervals(self, coarse: npt.NDArray[np.int64], threshold: float) -> None:
        a, b = coarse[:-1], coarse[1:]
        bound = (
            0.5 * (self._known(a) + self._known(b) - self._motion(a, b)) - DISTANCE_TOL
        )
        need = bound <= threshold
        self.bounds.append(float(np.min(bound, initial=np.inf, where=~need)))
        self.threshold = threshold
        for j, p in zip(*np.nonzero(need), strict=True):
            self._split(int(p), int(a[j]), int(b[j]))

    def _split(self, p: int, lo: int, hi: int) -> None:
        """Branch and bound over the samples of pair ``p`` in ``[lo, hi]``.

        A sample is bounded by the hulls first and measured exactly where the
        bound may be the least (at most the threshold) or an interval between
        two neighbouring samples needs its ends (module docstring).
        """
        d = self.distances
        stack = [(lo, hi)]
        while stack:
            lo, hi = stack.pop()
            motion = float((self.cumulative[hi] - self.cumulative[lo]) @ self.levers[p])
            ends = self._known(lo, p) + self._known(hi, p)
            bound = 0.5 * (float(ends) - motion) - DISTANCE_TOL
            if bound > self.threshold or (hi - lo == 1 and bound > 0.0):
                self.bounds.append(bound)
            elif hi - lo == 1:
                if np.isnan(d[lo, p]) or np.isnan(d[hi, p]):  # bounded only
                    self._exact(lo, p)
                    self._exact(hi, p)
                    stack.append((lo, hi))
                elif d[lo, p] > 0.0 and d[hi, p] > 0.0:
                    self.bounds.append(self._bisect(p, lo, hi))
                else:  # a contact at a sample: the bound only says how deep
                    self.bounds.append(bound)
            else:
                mid = (lo + hi) // 2
                self._measure(mid, p)
                stack += [(mid, hi), (lo, mid)]

    def _measure(self, k: int, p: int) -> None:
        """Bound pair ``p`` at sample ``k`` by the hulls; exactly if it may be least."""
        self.lower[k, p] = self.checker.compute_pair_lower_bound(self.q[k], p)
        if self.lower[k, p] <= self.threshold + DISTANCE_TOL:
            self._exact(k, p)
            self.threshold = min(self.threshold, max(self.distances[k, p], 0.0))

    def _bisect(self, p: int, lo: int, hi: int) -> float:
        """Refine pair ``p`` between samples ``lo`` and ``hi``; its lower bound."""
        levers = self.levers[p]
        stack = [(self.t[lo], self.q[lo], self.distances[lo, p],
                  self.t[hi], self.q[hi], self.distances[hi, p])]  # fmt: skip
        lowest = np.inf
        while stack:
            t0, q0, d0, t1, q1, d1 = stack.pop()
            motion = float(self.between(t0, q0, t1, q1) @ levers)
            bound = 0.5 * (d0 + d1 - motion) - DISTANCE_TOL
            if bound > 0.0 or motion < RESOLUTION or min(d0, d1) <= 0.0:
                lowest = min(lowest, bound)
                continue
            tm = 0.5 * (t0 + t1)
            qm = 0.5 * (q0 + q1) if self.sample is None else self.sample(tm)
            qm = np.asarray(qm, dtype=np.float64)
            dm = self.checker.compute_pair_distance(qm, p)
            self.evaluations += 1
            self.extra.append((float(tm), p, dm))
            stack += [(t0, q0, d0, tm, qm, dm), (tm, qm, dm, t1, q1, d1)]
        return lowest

    def _report(self) -> PathClearance:
        checker, d = self.checker, self.distances
        k, p = np.unravel_index(np.nanargmin(d), d.shape)
        best = (float(d[k, p]), float(self.t[k]), int(p))
        for tm, pm, dm in self.extra:
            if dm < best[0]:
                best = (dm, tm, pm)
        pair = checker.pairs[best[2]]
        return PathClearance(
            min_clearance=best[0],
            t=best[1],
            body_a=pair.body_a,
            body_b=pair.body_b,
            lower_bound=min(min(self.bounds), best[0]),
            contacts=self._contacts(),
            samples=int(self.t.size),
            evaluations=self.evaluations,
            refinements=len(self.extra),
        )

    def _contacts(self) -> tuple[Contact, ...]:
        touching = {
            int(p)
            for p in np.flatnonzero(
                np.where(np.isnan(self.distances), np.inf, self.distances).min(axis=0)
                <= 0.0
            )
        }
        touching |= {pm for _, pm, dm in self.extra if dm <= 0.0}
        points: dict[tuple[str, str], list[tuple[FloatArray, FloatArray]]] = {}
        for p in sorted(touching):
            known = ~np.isnan(self.distances[:, p])
            extra = [(tm, dm) for tm, pm, dm in self.extra if pm == p]
            times = np.r_[self.t[known], [e[0] for e in extra]]
            values = np.r_[self.distances[known, p], [e[1] for e in extra]]
            order = np.argsort(times, kind="stable")
            pair = self.checker.pairs[p]
            points.setdefault((pair.body_a, pair.body_b), []).append(
                (times[order], values[order])
            )
        return group_contacts(points)


__all__ = ["COARSE_STRIDE", "DISTANCE_TOL", "RESOLUTION", "check_path"]
