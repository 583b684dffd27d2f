"""Closest approach of a joint trajectory to each singularity.

For a PUMA-type arm the signed distances of :mod:`workbench.singularities.conditions`
are followed along the samples; for any arm the smallest singular value of
the Jacobian is followed as well. Read a CSV trajectory with
:func:`workbench.trajectory.csv_io.read_trajectory_csv` and pass its ``t`` and
``q``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.singularities.conditions import (
    CONDITION_UNITS,
    compute_conditions,
    find_factorisation,
)
from workbench.singularities.measures import compute_measures
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class ClosestApproach:
    """Where a trajectory comes closest to one singularity type.

    Attributes:
        kind: ``"shoulder"``, ``"elbow"``, ``"wrist"`` or ``"sigma_min"``.
        t: Time of the sample with the smallest |distance| [s].
        index: Index of that sample.
        distance: Signed distance at that sample (σmin for ``"sigma_min"``).
        unit: Unit of ``distance`` (``"m"``, ``"1 (sine)"``, ``"mixed"``).
        crossings: Times [s] where the signed distance changes sign between
            two samples (linear interpolation): the trajectory passes through
            the singular locus there. Empty for ``"sigma_min"``.
    """

    kind: str
    t: float
    index: int
    distance: float
    unit: str
    crossings: tuple[float, ...]

    @property
    def crossed(self) -> bool:
        """True if the trajectory passes through the locus."""
        return bool(self.crossings)


def find_closest_approaches(
    robot: Robot, t: npt.ArrayLike, q: npt.ArrayLike
) -> dict[str, ClosestApproach]:
    """Closest approach to each singularity along sampled joint positions.

    Args:
        robot: Any robot; the shoulder, elbow and wrist entries need a
            PUMA-type DH table, ``"sigma_min"`` is always given.
        t: Sample times, shape (K,) [s], strictly increasing.
        q: Joint positions, shape (K, nq) [rad].

    Returns:
        ``{kind: ClosestApproach}`` for the available kinds.

    Raises:
        InputError: If shapes differ, values are not finite, or ``t`` does not
            increase.
    """
    t = np.asarray(t, dtype=np.float64)
    t = as_finite_array(t, (t.size,), "t")
    q = as_finite_array(q, (t.size, robot.nq), "q")
    if t.size == 0:
        raise InputError("the trajectory has no samples")
    if np.any(np.diff(t) <= 0.0):
        raise InputError("trajectory times must increase strictly")
    signals: dict[str, tuple[FloatArray, str]] = {}
    conditions = (
        {}
        if find_factorisation(robot) is None
        else compute_conditions(robot, q).as_dict()
    )
    for kind, values in conditions.items():
        signals[kind] = (values, CONDITION_UNITS[kind])
    sigma = compute_measures(robot, q).sigma_min
    signals["sigma_min"] = (np.atleast_1d(sigma), "mixed")
    out = {}
    for kind, (values, unit) in signals.items():
        index = int(np.argmin(np.abs(values)))
        crossings = () if kind == "sigma_min" else _crossings(t, values)
        out[kind] = ClosestApproach(
            kind, float(t[index]), index, float(values[index]), unit, crossings
        )
    return out


def _crossings(t: FloatArray, values: FloatArray) -> tuple[float, ...]:
    """Times where ``values`` changes sign, linearly interpolated [s]."""
    sign = np.sign(values)
    times = [float(t[i]) for i in np.flatnonzero(sign == 0.0)]
    for i in np.flatnonzero(sign[:-1] * sign[1:] < 0.0):
        fraction = values[i] / (values[i] - values[i + 1])
        times.append(float(t[i] + fraction * (t[i + 1] - t[i])))
    return tuple(sorted(times))
