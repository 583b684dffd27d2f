"""Joint trajectories as CSV files: ``t,q1..qn,qd1..qdn,qdd1..qddn`` (SI units).

Written by ``workbench plan`` and ``workbench fishcut``, read by ``workbench view``
and the singularity analysis along a path.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from workbench.errors import DimensionError, InputError

FloatArray = npt.NDArray[np.float64]


class TrajectoryFileError(InputError):
    """A trajectory CSV file is missing or malformed (the message names the line)."""


@dataclass(frozen=True, slots=True)
class JointTrajectorySamples:
    """Samples of a joint trajectory.

    Attributes:
        t: Times, shape (K,) [s], strictly increasing.
        q: Positions, shape (K, n) [rad].
        qd: Velocities, shape (K, n) [rad/s].
        qdd: Accelerations, shape (K, n) [rad/s²].
    """

    t: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray

    @property
    def nq(self) -> int:
        """Number of joints."""
        return int(self.q.shape[1])


def header(nq: int) -> list[str]:
    """Column names for ``nq`` joints."""
    return (
        ["t"]
        + [f"q{i}" for i in range(1, nq + 1)]
        + [f"qd{i}" for i in range(1, nq + 1)]
        + [f"qdd{i}" for i in range(1, nq + 1)]
    )


def write_trajectory_csv(path: str | Path, samples: JointTrajectorySamples) -> None:
    """Write samples to ``path`` (full float precision)."""
    t, q, qd, qdd = samples.t, samples.q, samples.qd, samples.qdd
    if not (q.shape == qd.shape == qdd.shape == (t.shape[0], q.shape[1])):
        raise DimensionError("q, qd, qdd", (t.shape[0], q.shape[1]), qd.shape)
    table = np.column_stack([t, q, qd, qdd])
    with Path(path).open("w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream)
        writer.writerow(header(q.shape[1]))
        writer.writerows([repr(float(x)) for x in row] for row in table)


def read_trajectory_csv(
    path: str | Path, nq: int | None = None
) -> JointTrajectorySamples:
    """Read a trajectory CSV file.

    Args:
        path: File written by :func:`write_trajectory_csv` (or by hand).
        nq: Expected joint count (e.g. ``robot.nq``); None accepts any.

    Raises:
        TrajectoryFileError: If the file is missing, the header is wrong, a row
            has the wrong number of fields, a value is not a finite number, or
            the times do not increase; the message names the line.
    """
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as stream:
            rows = list(csv.reader(stream))
    except (OSError, UnicodeDecodeError) as err:
        raise TrajectoryFileError(f"cannot read trajectory {path}: {err}") from err
    if not rows:
        raise TrajectoryFileError(f"{path}: empty file (expected a header line)")
    columns = [c.strip() for c in rows[0]]
    n = (len(columns) - 1) // 3
    if n < 1 or columns != header(n):
        raise TrajectoryFileError(
            f"{path}, line 1: header must be t,q1..qn,qd1..qdn,qdd1..qddn, "
            f"got {','.join(columns)[:80]}"
        )
    if nq is not None and n != nq:
        raise TrajectoryFileError(
            f"{path}: the file has {n} joints, the robot has {nq}"
        )
    values = []
    for line, row in enumerate(rows[1:], start=2):
        if not row or all(not field.strip() for field in row):
            continue
        if len(row) != len(columns):
            raise TrajectoryFileError(
                f"{path}, line {line}: {len(row)} fields, expected {len(columns)}"
            )
        try:
            numbers = [float(field) for field in row]
        except ValueError:
            raise TrajectoryFileError(
                f"{path}, line {line}: not a number in {row}"
            ) from None
        if not all(math.isfinite(x) for x in numbers):
            raise TrajectoryFileError(f"{path}, line {line}: NaN or infinite value")
        values.append(numbers)
    if not values:
        raise TrajectoryFileError(f"{path}: no samples after the header")
    table = np.array(values)
    t = table[:, 0]
    bad = np.flatnonzero(np.diff(t) <= 0.0)
    if bad.size:
        raise TrajectoryFileError(
            f"{path}, line {bad[0] + 3}: time {t[bad[0] + 1]} does not increase"
        )
    return JointTrajectorySamples(
        t=t,
        q=table[:, 1 : 1 + n],
        qd=table[:, 1 + n : 1 + 2 * n],
        qdd=table[:, 1 + 2 * n :],
    )
