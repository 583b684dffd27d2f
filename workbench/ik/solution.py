r"""The result of a closed-form solve: :class:`Solutions` of :class:`IKSolution`.

A solve (:meth:`workbench.ik.Solver.solve`, :func:`workbench.ik.analytic`)
returns one :class:`Solutions`: the read-only sequence of the branches that
reach the pose, one :class:`IKSolution` each, in the order of the solver's
``branches``, with the solve's arrays (``q_all`` (B, nq), ``flags_all`` (B,))
and its solve-level :class:`~workbench.ik.SolveFlag`\ s. The solutions are
made when read (indexing, iterating): a solve builds one object, not one per
branch, and a caller that wants arrays reads ``q``, ``q_all`` and
``flags_all`` without building any. The solutions of one solve share its
read-only (B, nq) result array (each ``q`` is a row of it, made when read) and
its branch labels; each holds its branch index, its byte of flag bits
(:mod:`workbench.ik._flags`, one encoding for 6R and 7R arms) and the value of
the redundancy parameter (None on a 6R arm).

Both are :class:`~workbench.ik._record.FrozenRecord`\ s: immutable (assigning
a field raises :class:`dataclasses.FrozenInstanceError`), equal by value,
hashable and picklable.
"""

from __future__ import annotations

from collections.abc import Iterator
from operator import itemgetter
from typing import Any, ClassVar, SupportsIndex, overload

import numpy as np
import numpy.typing as npt

from workbench.ik._flags import (
    ELBOW_SINGULAR,
    PARAMETER_SINGULAR,
    SHOULDER_SINGULAR,
    WITHIN_LIMITS,
    WRIST_SINGULAR,
    Flag,
    SolveFlag,
)
from workbench.ik._record import FrozenRecord, _rebuild

FloatArray = npt.NDArray[np.float64]
FlagArray = npt.NDArray[np.uint8]


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


_new = tuple.__new__
_item = tuple.__getitem__
_items = tuple.__iter__


class Solutions(FrozenRecord):
    """The branches of one closed-form solve that reach the pose (immutable).

    A read-only sequence of :class:`IKSolution` (``len``, indexing, slicing
    to a tuple, iteration, ``in``), one per branch whose flags have the ``REACHED`` bit,
    in the order of ``branches``; never empty when a solve returns it (a pose
    no branch reaches raises ``UnreachableError``). Each solution is built
    when it is read.

    Attributes:
        q: (k, nq) [rad], the configurations of the k solutions (a new array
            at each read).
        q_all: (B, nq) [rad], read-only, one row per branch of the solver
            (B = ``len(branches)``), NaN rows for branches that do not reach.
        flags_all: (B,) uint8, read-only, the :class:`~workbench.ik.Flag` bits
            of every branch (0 where it does not reach).
        branches: The solver's branch labels, B of them.
        indices: Branch indices of the k solutions, ascending.
        redundancy: The redundancy parameter [rad] of a seven-axis arm (ψ or
            q7); None on a six-axis arm.
        solve_flags: What holds for the whole solve
            (:class:`~workbench.ik.SolveFlag`; 0 on an exact model).

    Equal by value to another :class:`Solutions` (arrays entry by entry);
    compare ``list(a) == list(b)`` to compare the solutions alone.
    """

    __slots__ = ()
    _fields: ClassVar[tuple[str, ...]] = (
        "q_all", "flags_all", "branches", "redundancy", "solve_flags",
    )  # fmt: skip
    # items: (q_all, flags_all, labels, redundancy, solve-flag byte); q_all
    # read-only, flags_all never handed out but as a read-only view. Being a
    # tuple only stores the items: the sequence it is to its readers is that
    # of its solutions, so every tuple operation that would show the items is
    # overridden below.

    @classmethod
    def from_arrays(
        cls,
        q_all: FloatArray,
        flags_all: FlagArray,
        branches: tuple[str, ...],
        redundancy: float | None = None,
        solve_flags: int = 0,
    ) -> Solutions:
        """The solutions held by a solve's arrays (the solver builds them so).

        Args:
            q_all: (B, nq) [rad], NaN rows where a branch does not reach; made
                read-only here.
            flags_all: (B,) uint8 flag bits, 0 where a branch does not reach
                (held, read through read-only views: the caller keeps no
                reference to it).
            branches: The B branch labels.
            redundancy: The redundancy parameter [rad] (7R) or None (6R).
            solve_flags: The solve's :class:`~workbench.ik.SolveFlag` bits.
        """
        q_all.setflags(write=False)
        return _new(cls, (q_all, flags_all, branches, redundancy, solve_flags))

    @property
    def q_all(self) -> FloatArray:
        """(B, nq) [rad], one row per branch, NaN where it does not reach."""
        return _item(self, 0)

    @property
    def flags_all(self) -> FlagArray:
        """(B,) uint8 flag bits of every branch, 0 where it does not reach."""
        view = _item(self, 1).view()
        view.setflags(write=False)
        return view

    @property
    def branches(self) -> tuple[str, ...]:
        """The solver's branch labels."""
        return _item(self, 2)

    @property
    def redundancy(self) -> float | None:
        """Redundancy parameter [rad] (7R), or None (6R)."""
        return _item(self, 3)

    @property
    def solve_flags(self) -> SolveFlag:
        """The flag bits of the whole solve."""
        return SolveFlag(_item(self, 4))

    @property
    def indices(self) -> tuple[int, ...]:
        """Branch indices of the solutions, ascending."""
        return tuple(i for i, bits in enumerate(_item(self, 1).tobytes()) if bits)

    @property
    def q(self) -> FloatArray:
        """(k, nq) configurations of the solutions [rad] (a new array)."""
        return _item(self, 0)[list(self.indices)]

    def __len__(self) -> int:
        flags = _item(self, 1).tobytes()
        return len(flags) - flags.count(0)

    def __bool__(self) -> bool:
        return bool(_item(self, 1).any())

    def __iter__(self) -> Iterator[IKSolution]:
        q, flags, labels, value, _ = _items(self)
        return iter(
            [
                _new(IKSolution, (q, i, bits, labels, value))
                for i, bits in enumerate(flags.tobytes())
                if bits
            ]
        )

    def __reversed__(self) -> Iterator[IKSolution]:
        return reversed(list(self))

    @overload
    def __getitem__(self, key: SupportsIndex) -> IKSolution: ...

    @overload
    def __getitem__(self, key: slice) -> tuple[IKSolution, ...]: ...

    def __getitem__(
        self, key: SupportsIndex | slice
    ) -> IKSolution | tuple[IKSolution, ...]:
        if isinstance(key, slice):
            return tuple(list(self)[key])
        q, flags, labels, value, _ = _items(self)
        count = len(self)
        k = key.__index__()
        if k < 0:
            k += count
        if not 0 <= k < count:
            raise IndexError("solution index out of range")
        if count != len(labels):  # some branches do not reach
            k = self.indices[k]
        return _new(IKSolution, (q, k, int(flags[k]), labels, value))

    def __contains__(self, item: object) -> bool:
        return any(item == solution for solution in self)

    def index(
        self, value: Any, start: SupportsIndex = 0, stop: SupportsIndex = 2**63 - 1
    ) -> int:
        """Position of the first solution equal to ``value`` (ValueError if none)."""
        return list(self).index(value, start, stop)

    def count(self, value: Any) -> int:
        """How many solutions equal ``value``."""
        return list(self).count(value)

    def __add__(self, other: object) -> Any:
        return NotImplemented

    def __mul__(self, other: object) -> Any:
        return NotImplemented

    __rmul__ = __mul__

    def __lt__(self, other: object) -> bool:
        return NotImplemented

    __le__ = __gt__ = __ge__ = __lt__

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        return (_rebuild, (type(self), tuple(_items(self))))

    def __repr__(self) -> str:
        return f"Solutions({list(self)!r}, solve_flags={self.solve_flags!r})"


__all__ = ["IKSolution", "Solutions"]
