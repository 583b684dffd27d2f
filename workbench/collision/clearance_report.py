"""What a clearance check found: the minimum, the contacts, the proven bound."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


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

    def describe_first_contact(self) -> str | None:
        """One line on the first contact (the commands' error), or None without one.

        ``collision of A with B from t = ... s, distance ... m at t = ... s``
        and, when there are more, how many.
        """
        first = self.first_contact
        if first is None:
            return None
        more = len(self.contacts) - 1
        extra = f" (and {more} more contact(s))" if more else ""
        return (
            f"collision of {first.body_a} with {first.body_b} "
            f"from t = {first.t_start:.6g} s, distance {first.distance:.6g} m at "
            f"t = {first.t:.6g} s{extra}"
        )

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


def group_contacts(
    points: dict[tuple[str, str], list[tuple[FloatArray, FloatArray]]],
) -> tuple[Contact, ...]:
    """Contact intervals from the distances of each geometry pair over time.

    Args:
        points: Per body pair, one ``(times (n,) [s], distances (n,) [m])``
            per geometry pair of the two bodies, times sorted.

    Returns:
        One contact per body pair and maximal run of samples at distance
        <= 0 (overlapping runs of geometry pairs merged), by start time.
    """
    contacts = []
    for (body_a, body_b), series in points.items():
        runs = [run for ts, ds in series for run in _runs(ts, ds)]
        for t0, t1, tm, dm in _merge(runs):
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


__all__ = ["Contact", "PathClearance", "group_contacts"]
