r"""The redundancy parameter of seven-axis arms: its values, checks and intervals.

A seven-axis arm of a supported family (:mod:`workbench.ik.structure`:
``"srs"``, spherical shoulder, elbow and wrist, e.g. the KUKA LBR iiwa;
``"franka"``, the Franka Panda/FR3 geometry) has, for one tool pose, a
one-parameter family of configurations per branch. Fixing the redundancy
parameter leaves finitely many:

* SRS: the arm angle ψ [rad] in (−π, π], the angle, right-handed about the unit
  vector from the shoulder S to the wrist W, from the reference plane (S, E0,
  W: the arm with θ3 = 0 reaching the same W) to the arm plane (S, E, W); 8
  branches (:data:`SRS_BRANCHES`), kernel :mod:`workbench.ik._srs_kernel`;
* Franka: q7 [rad], the robot's own value of joint 7, within its limits; 8
  branches (:data:`FRANKA_BRANCHES`), kernel :mod:`workbench.ik._franka_kernel`.

Such an arm is solved by its :class:`~workbench.ik.Solver` (``redundancy=``);
this module holds what the parameter needs besides: the check of a value
(:func:`check_redundancy`) and the record of the values that reach a pose
(:class:`FeasibleRedundancy`, :meth:`Solver.feasible
<workbench.ik.Solver.feasible>`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from workbench.errors import InputError, NonFiniteError
from workbench.ik import _franka_kernel, _srs_kernel

#: Branch labels of SRS arms (index order: ``_srs_kernel``'s module docs).
SRS_BRANCHES: tuple[str, ...] = _srs_kernel.BRANCHES
#: Branch labels of Franka arms (index order: ``_franka_kernel``'s module docs).
FRANKA_BRANCHES: tuple[str, ...] = _franka_kernel.BRANCHES


@dataclass(frozen=True, slots=True)
class FeasibleRedundancy:
    """The values of the redundancy parameter that reach one pose within the limits.

    Attributes:
        parameter: ``"arm angle"`` (SRS, ψ) or ``"q7"`` (Franka).
        range: ``(low, high)`` [rad], every value the parameter takes: (−π, π)
            for ψ, joint 7's limits for q7.
        branches: The branch labels, in the order of ``intervals``.
        intervals: Per branch, sorted disjoint closed intervals ``(lo, hi)``
            [rad] of the parameter where that branch reaches the pose with
            every joint within its limits.
        union: Sorted disjoint closed intervals [rad] where some branch does.
        circular: True for the arm angle (SRS): ψ and ψ + 2π are one arm, so
            an interval ending at π and one starting at −π are one arc
            through ±π (they stay two here, each within ``range``); False
            for q7, a joint with limits.
    """

    parameter: str
    range: tuple[float, float]
    branches: tuple[str, ...]
    intervals: tuple[tuple[tuple[float, float], ...], ...]
    union: tuple[tuple[float, float], ...]
    circular: bool


def check_redundancy(value: object, parameter: str) -> float:
    """A value of the redundancy parameter as a finite float [rad].

    Raises:
        InputError: If it is not a real number (a bool is not).
        NonFiniteError: If it is NaN or infinite.
    """
    if isinstance(value, bool) or not isinstance(value, int | float | np.number):
        if isinstance(value, np.ndarray) and value.shape == ():
            return check_redundancy(value[()], parameter)
        raise InputError(f"redundancy ({parameter}) must be a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise NonFiniteError(f"redundancy ({parameter}) must be finite, got {number}")
    return number


def feasible_union(
    intervals: tuple[tuple[tuple[float, float], ...], ...],
) -> tuple[tuple[float, float], ...]:
    """Sorted disjoint closed intervals covering those of every branch."""
    merged: list[list[float]] = []
    for lo, hi in sorted(iv for branch in intervals for iv in branch):
        if merged and lo <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], hi)
        else:
            merged.append([lo, hi])
    return tuple((lo, hi) for lo, hi in merged)


def format_intervals(intervals: tuple[tuple[float, float], ...]) -> str:
    """``"[a, b], [c, d]"`` with 6 significant digits [rad]."""
    return ", ".join(f"[{lo:.6g}, {hi:.6g}]" for lo, hi in intervals)


__all__ = [
    "FRANKA_BRANCHES",
    "SRS_BRANCHES",
    "FeasibleRedundancy",
    "check_redundancy",
    "feasible_union",
    "format_intervals",
]
