r"""Clearance along a joint path, with no contact missed between the samples.

The path is known at sample times :math:`t_k`; between two samples it is either
the straight line in joint space (what a controller does with the samples) or
any motion whose joint speeds stay below a bound :math:`V` (a planned spline).
Joint :math:`i` then travels at most :math:`\tau_i = |q_{k+1,i} - q_{k,i}|`,
resp. :math:`V_i (t_{k+1} - t_k)`, and the distance of a pair :math:`p` changes
by at most :math:`\delta_p = \sum_i L_{p,i} \tau_i` (lever arms, see
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
first computed at every :data:`COARSE_STRIDE`-th sample only; the samples in
between are computed for the pairs whose lower bound over the coarse interval
could reach the smallest distance found (or 0). The smallest distance over the
samples is therefore exactly the one a check of every pair at every sample
finds, and ``lower_bound`` holds for the whole continuous path.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.collision.checker import CollisionChecker
from workbench.errors import DimensionError, InputError
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]

#: Margin [m] for coal's distance accuracy (10 x the checker's GJK tolerance).
DISTANCE_TOL = 1e-9
#: Bisection stops when the motion bound of an interval is below this [m].
RESOLUTION = 1e-9
#: Every pair is computed at every COARSE_STRIDE-th sample first.
COARSE_STRIDE = 8


@dataclass(frozen=True, slots=True)
class Contact:
    """Two bodies in contact over a time interval.

    Attributes:
        t: Time of the deepest contact [s].
        body_a, body_b: Link or obstacle names.
        distance: Signed distance at ``t`` [m], <= 0 (minus the penetration).
        t_start, t_end: First and last instant found in contact [s].
    """

    t: float
    body_a: str
    body_b: str
    distance: float
    t_start: float
    t_end: float

    def as_dict(self) -> dict[str, Any]:
        """JSON form: ``{t, body_a, body_b, distance, t_start, t_end}``."""
        return {
            "t": self.t,
            "body_a": self.body_a,
            "body_b": self.body_b,
            "distance": self.distance,
            "t_start": self.t_start,
            "t_end": self.t_end,
        }


@dataclass(frozen=True, slots=True)
class PathClearance:
    """Result of :func:`check_path`.

    Attributes:
        min_clearance: Smallest distance of any checked pair at any sample or
            refinement instant [m] (negative: penetration).
        t, body_a, body_b: Where it occurs.
        lower_bound: Proven lower bound of the signed distance over the whole
            continuous path [m]; > 0 proves the path free (inside contacts it
            is a loose bound on the depth).
        contacts: Contact intervals, by start time.
        samples: Number of samples. evaluations: Pair distances computed.
        refinements: Instants added by bisection.
    """

    min_clearance: float
    t: float
    body_a: str
    body_b: str
    lower_bound: float
    contacts: tuple[Contact, ...]
    samples: int
    evaluations: int
    refinements: int

    @property
    def collision_free(self) -> bool:
        """True when no contact was found (and ``lower_bound`` > 0 proves it)."""
        return not self.contacts and self.lower_bound > 0.0

    @property
    def first_contact(self) -> Contact | None:
        """The contact that starts first, or None."""
        return self.contacts[0] if self.contacts else None

    def as_dict(self) -> dict[str, Any]:
        """JSON form (the ``collision`` keys of ``plan pick-place`` and ``fishcut``)."""
        first = self.first_contact
        return {
            "min_clearance": self.min_clearance,
            "min_clearance_at": {
                "t": self.t,
                "body_a": self.body_a,
                "body_b": self.body_b,
            },
            "clearance_lower_bound": self.lower_bound,
            "collisions": [c.as_dict() for c in self.contacts],
            "first_contact": None if first is None else first.as_dict(),
            "collision_samples": self.samples,
            "collision_evaluations": self.evaluations,
        }


def check_path(
    checker: CollisionChecker,
    t: npt.ArrayLike,
    q: npt.ArrayLike,
    *,
    sample: Callable[[float], FloatArray] | None = None,
    max_joint_speed: npt.ArrayLike | None = None,
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
        stride: Compute distances at every ``stride``-th sample (and the
            last) only; the bound still covers the path through all samples
            (e.g. 10 for a 1 kHz servo path checked at the 100 Hz cycles).

    Returns:
        The clearance report.

    Raises:
        DimensionError, NonFiniteError: If the shapes or values are wrong.
        InputError: If ``t`` does not increase, or ``sample`` is given
            without a positive ``max_joint_speed``.
    """
    robot = checker.robot
    t = np.asarray(t, dtype=np.float64)
    if t.ndim != 1 or t.size == 0:
        raise DimensionError("t", (max(t.size, 1),), t.shape)
    t = as_finite_array(t, t.shape, "t")
    q = as_finite_array(q, (t.size, robot.nq), "q")
    if np.any(np.diff(t) <= 0.0):
        raise InputError("t must be strictly increasing")
    if sample is None:
        travel = np.abs(np.diff(q, axis=0))
    else:
        if max_joint_speed is None:
            raise InputError("check_path with sample= needs max_joint_speed")
        speed = as_finite_array(max_joint_speed, (robot.nv,), "max_joint_speed")
        if np.any(speed < 0.0):
            raise InputError("max_joint_speed must be >= 0")
        travel = np.diff(t)[:, None] * speed[None, :]
    if isinstance(stride, bool) or not isinstance(stride, int) or stride < 1:
        raise InputError(f"stride must be an integer >= 1, got {stride!r}")
    cumulative = np.vstack([np.zeros((1, robot.nv)), np.cumsum(travel, axis=0)])
    keep = np.unique(np.r_[np.arange(0, t.size, stride), t.size - 1])
    if stride > 1 and sample is None:  # bisect along the samples, not across them
        sample = _polyline(t, q)
    check = _PathCheck(checker, t[keep], q[keep], cumulative[keep], sample)
    check.travel_at = lambda s: np.array(  # cumulative travel (nv,) at time s
        [np.interp(s, t, column) for column in cumulative.T]
    )
    return check.run()


def _polyline(t: FloatArray, q: FloatArray) -> Callable[[float], FloatArray]:
    """The straight lines in joint space through the samples, as ``q(t)``."""

    def evaluate(s: float) -> FloatArray:
        return np.array([np.interp(s, t, column) for column in q.T])

    return evaluate


class _PathCheck:
    """One run of the algorithm of the module docstring."""

    def __init__(self, checker, t, q, cumulative, sample) -> None:
        self.checker, self.t, self.q, self.sample = checker, t, q, sample
        self.levers = checker.levers
        self.cumulative = cumulative
        self.travel_at: Callable[[float], FloatArray] = lambda s: cumulative[0]
        self.distances = np.full((t.size, len(checker.pairs)), np.nan)
        self.extra: list[tuple[float, int, float]] = []  # (t, pair, distance)
        self.bounds: list[float] = []
        self.evaluations = 0

    def _evaluate(
        self, rows: npt.NDArray[np.int64], mask: npt.NDArray[np.bool_]
    ) -> None:
        self.checker.set_active(mask)
        for k in rows:
            self.distances[k, mask] = self.checker.compute_raw_distances(self.q[k])[
                mask
            ]
        self.evaluations += int(len(rows) * np.count_nonzero(mask))

    def _motion(self, a: npt.NDArray[np.int64], b: npt.NDArray[np.int64]) -> FloatArray:
        return (self.cumulative[b] - self.cumulative[a]) @ self.levers.T

    def run(self) -> PathClearance:
        k_total, n_pairs = self.distances.shape
        coarse = np.unique(np.r_[np.arange(0, k_total, COARSE_STRIDE), k_total - 1])
        everything = np.ones(n_pairs, dtype=bool)
        try:
            self._evaluate(coarse, everything)
            threshold = max(float(np.min(self.distances[coarse])), 0.0)
            if k_total > 1:
                self._check_intervals(coarse, threshold)
            else:
                self.bounds.append(float(np.min(self.distances[0])))
        finally:
            self.checker.set_active(None)
        return self._report()

    def _check_intervals(self, coarse: npt.NDArray[np.int64], threshold: float) -> None:
        a, b = coarse[:-1], coarse[1:]
        d = self.distances
        bound = 0.5 * (d[a] + d[b] - self._motion(a, b)) - DISTANCE_TOL
        need = bound <= threshold
        self.bounds.append(float(np.min(bound, initial=np.inf, where=~need)))
        self.threshold = threshold
        for j, p in zip(*np.nonzero(need), strict=True):
            self._split(int(p), int(a[j]), int(b[j]))

    def _split(self, p: int, lo: int, hi: int) -> None:
        """Branch and bound over the samples of pair ``p`` in ``[lo, hi]``."""
        d = self.distances
        stack = [(lo, hi)]
        while stack:
            lo, hi = stack.pop()
            motion = float((self.cumulative[hi] - self.cumulative[lo]) @ self.levers[p])
            bound = 0.5 * (d[lo, p] + d[hi, p] - motion) - DISTANCE_TOL
            if bound > self.threshold or (hi - lo == 1 and bound > 0.0):
                self.bounds.append(bound)
            elif hi - lo == 1:
                if d[lo, p] > 0.0 and d[hi, p] > 0.0:
                    self.bounds.append(self._bisect(p, lo, hi))
                else:  # a contact at a sample: the bound only says how deep
                    self.bounds.append(bound)
            else:
                mid = (lo + hi) // 2
                d[mid, p] = self.checker.compute_pair_distance(self.q[mid], p)
                self.evaluations += 1
                self.threshold = min(self.threshold, max(d[mid, p], 0.0))
                stack += [(mid, hi), (lo, mid)]

    def _bisect(self, p: int, lo: int, hi: int) -> float:
        """Refine pair ``p`` between samples ``lo`` and ``hi``; its lower bound."""
        levers = self.levers[p]
        stack = [(self.t[lo], self.q[lo], self.distances[lo, p],
                  self.t[hi], self.q[hi], self.distances[hi, p])]  # fmt: skip
        lowest = np.inf
        while stack:
            t0, q0, d0, t1, q1, d1 = stack.pop()
            if self.sample is None:
                motion = float(np.abs(q1 - q0) @ levers)
            else:
                motion = float((self.travel_at(t1) - self.travel_at(t0)) @ levers)
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
        runs: dict[tuple[str, str], list[tuple[float, float, float, float]]] = {}
        for p in np.flatnonzero(np.nanmin(self.distances, axis=0) <= 0.0).tolist() + [
            pm for _, pm, dm in self.extra if dm <= 0.0
        ]:
            known = ~np.isnan(self.distances[:, p])
            times = list(self.t[known]) + [tm for tm, pm, _ in self.extra if pm == p]
            values = list(self.distances[known, p]) + [
                dm for _, pm, dm in self.extra if pm == p
            ]
            order = np.argsort(times, kind="stable")
            ts, ds = np.array(times)[order], np.array(values)[order]
            pair = self.checker.pairs[p]
            key = (pair.body_a, pair.body_b)
            runs.setdefault(key, []).extend(_runs(ts, ds))
        contacts = []
        for (body_a, body_b), items in runs.items():
            for t0, t1, tm, dm in _merge(items):
                contacts.append(Contact(tm, body_a, body_b, dm, t0, t1))
        return tuple(sorted(contacts, key=lambda c: (c.t_start, c.body_a, c.body_b)))


def _runs(ts: FloatArray, ds: FloatArray) -> list[tuple[float, float, float, float]]:
    """Runs of consecutive contacts: ``(t_start, t_end, t_deepest, deepest)``."""
    out, start = [], None
    inside = ds <= 0.0
    for i in range(len(ts) + 1):
        if i < len(ts) and inside[i]:
            start = i if start is None else start
        elif start is not None:
            j = start + int(np.argmin(ds[start:i]))
            out.append((float(ts[start]), float(ts[i - 1]), float(ts[j]), float(ds[j])))
            start = None
    return out


def _merge(items: list[tuple[float, float, float, float]]) -> list[tuple[float, ...]]:
    """Merge overlapping runs of one body pair (several geometry pairs)."""
    merged: list[list[float]] = []
    for t0, t1, tm, dm in sorted(set(items)):
        if merged and t0 <= merged[-1][1]:
            last = merged[-1]
            last[1] = max(last[1], t1)
            if dm < last[3]:
                last[2], last[3] = tm, dm
        else:
            merged.append([t0, t1, tm, dm])
    return [tuple(m) for m in merged]


__all__ = [
    "COARSE_STRIDE",
    "DISTANCE_TOL",
    "RESOLUTION",
    "Contact",
    "PathClearance",
    "check_path",
]
