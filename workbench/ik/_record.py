r"""The one immutability mechanism of the IK results: a tuple read by named fields.

:class:`~workbench.ik.IKSolution` (closed form) and
:class:`~workbench.ik.IKResult` (numerical) are :class:`FrozenRecord`\\ s: a
``tuple`` subclass without instance attributes (``__slots__ = ()``) whose
items are the record's values and whose fields are read-only properties over
them. Assigning or deleting any attribute raises
:class:`dataclasses.FrozenInstanceError`, as on a frozen dataclass, and the
arrays a record holds are read-only.

Why a tuple: it is made by one C call, ``tuple.__new__(cls, items)``, with no
Python-level ``__init__`` (a frozen dataclass sets each field through
``object.__setattr__``, several times slower), which a solve returning eight
solutions pays eight times.

Equality is by value, field by field (arrays by :func:`numpy.array_equal`,
NaN equal to NaN); hashing hashes the same values (arrays by their bytes).
Records pickle and copy as themselves.
"""

from __future__ import annotations

from dataclasses import FrozenInstanceError
from typing import Any, ClassVar, TypeVar

import numpy as np

R = TypeVar("R", bound="FrozenRecord")


class FrozenRecord(tuple[Any, ...]):
    """Base of the IK result records (module docs).

    Subclasses list their public fields in ``_fields`` (for ``repr``,
    equality and hashing) and read their items through properties.
    """

    __slots__ = ()
    _fields: ClassVar[tuple[str, ...]] = ()

    def __setattr__(self, name: str, value: object) -> None:
        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name: str) -> None:
        raise FrozenInstanceError(f"cannot delete field {name!r}")

    def _values(self) -> tuple[Any, ...]:
        return tuple(getattr(self, name) for name in self._fields)

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        theirs = other._values()
        return all(_same(a, b) for a, b in zip(self._values(), theirs, strict=True))

    def __ne__(self, other: object) -> bool:
        equal = self.__eq__(other)
        return equal if equal is NotImplemented else not equal

    def __hash__(self) -> int:
        return hash(tuple(_hashable(v) for v in self._values()))

    def __repr__(self) -> str:
        fields = ", ".join(f"{name}={value!r}" for name, value in self._items())
        return f"{type(self).__name__}({fields})"

    def _items(self) -> list[tuple[str, Any]]:
        return list(zip(self._fields, self._values(), strict=True))

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        return (_rebuild, (type(self), tuple(self)))

    def __copy__(self: R) -> R:
        return self

    def __deepcopy__(self: R, memo: dict[int, Any]) -> R:
        return self


def _rebuild(cls: type[R], items: tuple[Any, ...]) -> R:
    """A record of class ``cls`` holding ``items`` (for pickling)."""
    for item in items:
        if type(item) is np.ndarray and item.flags.writeable:
            item.setflags(write=False)  # an unpickled array comes writable
    return tuple.__new__(cls, items)


def _same(a: object, b: object) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return bool(np.array_equal(a, b, equal_nan=True))  # type: ignore[arg-type]
    if isinstance(a, float) and isinstance(b, float) and a != a and b != b:
        return True  # NaN fields (e.g. errors of a failed solve) are equal
    return bool(a == b)


def _hashable(value: object) -> object:
    if isinstance(value, np.ndarray):
        return (value.shape, value.tobytes())
    return value


__all__ = ["FrozenRecord"]
