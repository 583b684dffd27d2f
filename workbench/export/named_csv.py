"""Joint trajectories as CSV files whose header names the joints and the units.

Header: ``t [s]``, then ``<joint> [rad]`` for every joint, ``<joint> velocity
[rad/s]``, ``<joint> acceleration [rad/s^2]``; one row per sample, every float
written with full precision (``repr``), so the file reads back exactly.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from workbench.atomic_files import atomic_file
from workbench.errors import DimensionError, InputError
from workbench.trajectory.csv_io import JointTrajectorySamples


def get_named_header(joint_names: list[str]) -> list[str]:
    """Column names with units for these joints."""
    return (
        ["t [s]"]
        + [f"{n} [rad]" for n in joint_names]
        + [f"{n} velocity [rad/s]" for n in joint_names]
        + [f"{n} acceleration [rad/s^2]" for n in joint_names]
    )


def write_named_csv(
    path: str | Path, samples: JointTrajectorySamples, joint_names: list[str]
) -> Path:
    """Write the samples with a named header (all at once).

    Raises:
        DimensionError: If the names do not match the columns.
        InputError: If a name holds a comma or a newline, or the file cannot
            be written.
    """
    names = list(joint_names)
    if len(names) != samples.nq:
        raise DimensionError("joint_names", (samples.nq,), (len(names),))
    if any(("," in n) or ("\n" in n) for n in names):
        raise InputError(f"joint names must not hold commas or newlines: {names}")
    table = np.column_stack([samples.t, samples.q, samples.qd, samples.qdd])
    with atomic_file(path) as tmp:
        with tmp.open("w", newline="", encoding="utf-8") as stream:
            writer = csv.writer(stream)
            writer.writerow(get_named_header(names))
            writer.writerows([repr(float(x)) for x in row] for row in table)
    return Path(path)


__all__ = ["get_named_header", "write_named_csv"]
