"""Numbers made ready for JSON: builtin types, rounding noise printed as 0.

A vector computed in floating point is accurate relative to its largest entry,
so an entry below that entry's rounding step is rounding noise: a joint at
``4.04e-15`` deg beside one at 180 deg is 0 (a float64 holds 15 significant
digits). :func:`to_json_ready` turns such
entries of every list of floats into 0 (and ``-0.0`` into ``0.0``); scalars and
lists of mixed values are kept as they are, because a lone residual of
``1e-16`` is a measurement.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: Decimal digits a float64 holds reliably (DBL_DIG): below half a unit of the
#: largest entry's 15th significant digit, an entry of a vector is noise.
FLOAT64_DIGITS = int(np.finfo(np.float64).precision)


def to_json_ready(value: Any, *, digits: int | None = None) -> Any:
    """``value`` with NumPy data as builtins and rounding noise of vectors as 0.

    Args:
        value: Nested dicts, lists, tuples, NumPy arrays and scalars; other
            objects are returned as they are.
        digits: Significant digits every float is cut to; None keeps full
            precision. In a list of floats, an entry smaller than half a unit
            of the largest one's last significant digit (``digits``, or
            :data:`FLOAT64_DIGITS` at full precision) becomes 0.

    Returns:
        The same structure, lists for tuples and arrays.
    """
    if isinstance(value, dict):
        return {key: to_json_ready(item, digits=digits) for key, item in value.items()}
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        items = [to_json_ready(item, digits=digits) for item in value]
        return _zero_rounding_noise(items, digits)
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and math.isfinite(value):
        return value + 0.0 if digits is None else float(f"{value:.{digits}g}") + 0.0
    return value


def _zero_rounding_noise(items: list[Any], digits: int | None) -> list[Any]:
    """In a vector (a list of floats only), entries within rounding of 0 become 0."""
    if not all(isinstance(x, float) for x in items):
        return items  # a record of mixed values, not a vector
    finite = [abs(x) for x in items if math.isfinite(x)]
    if len(finite) < 2:
        return items
    step = 0.5 * 10.0 ** (1 - (FLOAT64_DIGITS if digits is None else digits))
    threshold = step * max(finite)
    return [0.0 if abs(x) < threshold else x for x in items]
