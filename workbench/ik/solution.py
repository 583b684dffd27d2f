"""One branch of a closed-form solve, for every family: :class:`IKSolution`.

A solve (:meth:`workbench.ik.Solver.solve`, :func:`workbench.ik.analytic`)
returns one :class:`IKSolution` per branch that reaches the pose. The
solutions of one solve share its read-only (B, nq) result array (each ``q`` is
a row of it, made when read) and its branch labels; each holds its branch
index, its byte of flag bits (:mod:`workbench.ik._flags`, one encoding for
6R and 7R arms) and the value of the redundancy parameter (None on a 6R arm).
It is a :class:`~workbench.ik._record.FrozenRecord`: immutable (assigning a
field raises :class:`dataclasses.FrozenInstanceError`), equal by value,
hashable and picklable.
"""

from __future__ import annotations

from operator import itemgetter
from typing import ClassVar

import numpy as np
import numpy.typing as npt

from workbench.ik._flags import (
    ELBOW_SINGULAR,
    PARAMETER_SINGULAR,
    SHOULDER_SINGULAR,
    WITHIN_LIMITS,
    WRIST_SINGULAR,
    Flag,
)
from workbench.ik._record import FrozenRecord

FloatArray = npt.NDArray[np.float64]


class IKSolution(FrozenRecord):
    """One closed-form branch of a 6R or 7R arm for one pose (immutable).

    Attributes:
        q: Configuration (nq,) [rad], read-only: each angle the representative
            (mod 2π) within the joint limits when one is, else in (−π, π] —
            or, when ``q_previous`` was given, the one nearest it.
        branch: Label, one of the solver's ``branches`` (e.g.
            ``"right/elbow-up/no-flip"``, ``"shoulder-left/elbow-up/wrist-down"``).
        index: Position of ``branch`` in the solver's ``branches``.
        redundancy: The redundancy parameter [rad] of a seven-axis arm (SRS:
            arm angle ψ; Franka: q7); None on a six-axis arm.
        flags: The branch's :class:`~workbench.ik.Flag` bits.
        within_limits: True if every joint of ``q`` is within its limits.
        shoulder_singular: The branch meets its shoulder twin (6R: the right
            and left arms meet, the wrist centre on the cylinder |D| around
            the base axis to 1e-10 m; on the base axis θ1 is free).
        elbow_singular: The branch meets its elbow twin (stretched or folded).
        wrist_singular: The branch meets its wrist twin (6R: |sin θ5| <=
            ``WRIST_SINGULAR_TOL``, θ4 and θ6 then one member of a
            one-parameter family).
        parameter_singular: The redundancy parameter is degenerate here (SRS:
            the wrist centre on axis 1); always False on a 6R arm.

    Two solutions are equal when all these fields are (``q`` entry by entry).
    """

    __slots__ = ()
    _fields: ClassVar[tuple[str, ...]] = (
        "q", "branch", "index", "redundancy", "within_limits",
        "shoulder_singular", "elbow_singular", "wrist_singular",
        "parameter_singular",
    )  # fmt: skip
    # items: (q of the solve (B, nq), index, flag bits, labels, redundancy)

    @property
    def q(self) -> FloatArray:
        """Configuration (nq,) [rad], read-only."""
        return self[0][self[1]]

    @property
    def branch(self) -> str:
        """Branch label."""
        return self[3][self[1]]

    index = property(itemgetter(1), doc="Position of ``branch`` in ``branches``.")
    redundancy = property(
        itemgetter(4), doc="Redundancy parameter [rad] (7R), or None (6R)."
    )

    @property
    def flags(self) -> Flag:
        """The flag bits of the branch."""
        return Flag(self[2])

    @property
    def within_limits(self) -> bool:
        """True if every joint is within its limits."""
        return self[2] & WITHIN_LIMITS != 0

    @property
    def shoulder_singular(self) -> bool:
        """True if the branch meets its shoulder twin."""
        return self[2] & SHOULDER_SINGULAR != 0

    @property
    def elbow_singular(self) -> bool:
        """True if the branch meets its elbow twin."""
        return self[2] & ELBOW_SINGULAR != 0

    @property
    def wrist_singular(self) -> bool:
        """True if the branch meets its wrist twin."""
        return self[2] & WRIST_SINGULAR != 0

    @property
    def parameter_singular(self) -> bool:
        """True if the redundancy parameter is degenerate at this pose."""
        return self[2] & PARAMETER_SINGULAR != 0


__all__ = ["IKSolution"]
