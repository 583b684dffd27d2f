"""Argument helpers shared by the commands."""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.errors import NonFiniteError


def add_robot_argument(
    parser: argparse.ArgumentParser, default: str | None = None
) -> None:
    """``--robot NAME|PATH`` (required unless a default is given)."""
    parser.add_argument(
        "--robot",
        required=default is None,
        default=default,
        help="robot name (puma560, puma560-kang, ur5, panda, ...) or path to a .urdf"
        + (f" (default: {default})" if default else ""),
    )


def add_json_flag(parser: argparse.ArgumentParser) -> None:
    """``--json``: print exactly one JSON object on stdout."""
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def add_angle_arguments(parser: argparse.ArgumentParser, name: str = "q") -> None:
    """``(--deg | --rad) Q...``: joint values and their unit."""
    unit = parser.add_mutually_exclusive_group(required=True)
    unit.add_argument("--deg", action="store_true", help="joint values in degrees")
    unit.add_argument("--rad", action="store_true", help="joint values in radians")
    parser.add_argument(
        name, nargs="+", type=finite_float, metavar="Q", help="joint values"
    )


def finite_float(text: str) -> float:
    """Argparse type: a finite float."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"not a finite number: {text!r}")
    return value


def joint_values_rad(
    args: argparse.Namespace, values: list[float]
) -> npt.NDArray[np.float64]:
    """Joint values from the command line, converted to radians."""
    q = np.asarray(values, dtype=np.float64)
    if not np.all(np.isfinite(q)):
        raise NonFiniteError("joint values must be finite")
    return np.deg2rad(q) if args.deg else q


def print_json(payload: dict[str, Any]) -> None:
    """Print one JSON object (NumPy arrays become lists) on stdout."""
    json.dump(payload, sys.stdout, default=_to_builtin, allow_nan=False)
    sys.stdout.write("\n")


def _to_builtin(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def format_vector(values: npt.ArrayLike, digits: int = 6) -> str:
    """Numbers on one line, fixed precision, sign-aligned."""
    return "  ".join(
        f"{x: .{digits}f}" for x in np.asarray(values, dtype=float).ravel()
    )
