"""Input checks shared by every layer: shapes, finiteness, signs."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench.errors import DimensionError, InputError, NonFiniteError

FloatArray = npt.NDArray[np.float64]


def as_finite_array(
    value: npt.ArrayLike, shape: tuple[int, ...], name: str
) -> FloatArray:
    """Return ``value`` as a finite float64 array of the given shape.

    Raises:
        DimensionError: If the shape differs.
        NonFiniteError: If an entry is not a number, NaN or infinite.
    """
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise NonFiniteError(f"{name} must be numbers, got {value!r}") from err
    if arr.shape != shape:
        raise DimensionError(name, shape, arr.shape)
    if not np.all(np.isfinite(arr)):
        raise NonFiniteError(f"{name} must be finite, got {np.array2string(arr)}")
    return arr


def as_vector(value: npt.ArrayLike, size: int, name: str) -> FloatArray:
    """Return ``value`` as a finite float64 vector of shape (size,).

    Raises:
        DimensionError: If the shape is not (size,).
        NonFiniteError: If an entry is not a number, NaN or infinite.
    """
    return as_finite_array(value, (size,), name)


def check_positive(value: float, name: str, *, strict: bool) -> None:
    """Raise unless ``value`` is a finite real number > 0 (``strict``) or >= 0.

    Raises:
        InputError: If it is not (a bool is not a number here).
    """
    ok = isinstance(value, int | float) and not isinstance(value, bool)
    ok = ok and math.isfinite(value) and (value > 0.0 if strict else value >= 0.0)
    if not ok:
        bound = "> 0" if strict else ">= 0"
        raise InputError(f"{name} must be a finite number {bound}, got {value!r}")
