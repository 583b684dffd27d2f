"""Input checks shared by every layer: shapes, finiteness, signs."""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.errors import DimensionError, InputError, NonFiniteError

#: Integers of more digits in a JSON file are read as floats (beyond 1e308: inf,
#: which the finiteness checks refuse) instead of as unbounded Python ints.
JSON_INT_DIGITS = 18

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


def parse_float(text: str) -> float:
    """A number as numpy and pandas read it: ASCII text of a Python float.

    Python's ``float`` also takes ``"1_0"`` (as 10) and digits of other scripts
    (Arabic-Indic, full-width), which the tools a file goes to next refuse.

    Raises:
        ValueError: If ``text`` is not ASCII, holds an underscore, or is no
            float.
    """
    if not text.isascii() or "_" in text:
        raise ValueError(f"not a plain ASCII number: {text!r}")
    return float(text)


def parse_int(text: str) -> int:
    """An integer as :func:`parse_float` reads numbers (ASCII, no underscore).

    Raises:
        ValueError: If ``text`` is not ASCII, holds an underscore, or is no
            integer.
    """
    if not text.isascii() or "_" in text:
        raise ValueError(f"not a plain ASCII integer: {text!r}")
    return int(text)


def read_json_file(path: str | Path, error: type[InputError], what: str) -> Any:
    """The parsed JSON of a file, every failure an ``error`` with one line.

    Integers of more than :data:`JSON_INT_DIGITS` digits become floats, so a
    400-digit number is ``inf`` (refused by the caller's finiteness checks)
    rather than an integer no float holds.

    Args:
        path: The file.
        error: The error class to raise (e.g. ``SceneFileError``).
        what: What the file is, for the message (``"scene"``).

    Raises:
        InputError: (as ``error``) If the file cannot be read, is not UTF-8, is
            not JSON, or is nested too deeply to parse.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise error(f"cannot read {what} {path}: {err.strerror or err}") from err
    except UnicodeDecodeError as err:
        raise error(f"{path}: not UTF-8 text (byte {err.start})") from err
    try:
        return json.loads(text, parse_int=_json_int)
    except json.JSONDecodeError as err:
        raise error(
            f"{path}: not valid JSON (line {err.lineno}, column {err.colno}: {err.msg})"
        ) from err
    except RecursionError as err:
        raise error(f"{path}: JSON nested too deeply to read") from err


def _json_int(text: str) -> int | float:
    digits = len(text.lstrip("-"))
    return int(text) if digits <= JSON_INT_DIGITS else float(text)


def read_csv_file(
    path: str | Path, error: type[InputError], what: str
) -> list[list[str]]:
    """The rows of a CSV file (header first), every failure an ``error`` with one line.

    Args:
        path: The file.
        error: The error class to raise (e.g. ``TrajectoryFileError``).
        what: What the file is, for the message (``"trajectory"``).

    Raises:
        InputError: (as ``error``) If the file cannot be read, is not UTF-8 or
            is not CSV (e.g. a field longer than ``csv.field_size_limit()``).
    """
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as stream:
            return list(csv.reader(stream))
    except OSError as err:
        raise error(f"cannot read {what} {path}: {err.strerror or err}") from err
    except UnicodeDecodeError as err:
        raise error(f"{path}: not UTF-8 text (byte {err.start})") from err
    except csv.Error as err:
        raise error(f"{path}: not a CSV file ({err})") from err


def iter_data_rows(rows: list[list[str]]) -> Iterator[tuple[int, list[str]]]:
    """``(line, row)`` of the rows after the header; blank and ``#`` lines skipped."""
    for line, row in enumerate(rows[1:], start=2):
        if not row or all(not field.strip() for field in row):
            continue
        if row[0].lstrip().startswith("#"):
            continue
        yield line, row
