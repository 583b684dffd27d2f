"""Joint trajectories as CSV files: ``t,q1..qn,qd1..qdn,qdd1..qddn`` (SI units).

Written by ``workbench plan``, ``workbench fishcut`` and ``workbench demo``, read
by ``workbench view``, ``export`` and ``report`` and the singularity analysis along a
path. Line 1 is the header; line 2, ``# samples=K``, states the sample count, so
a reader refuses a file that lost rows (:func:`read_trajectory_csv`). A file
without that line (written by hand, or before the line existed) is read as it is:
it cannot be checked for missing rows. Files are written all at once
(:mod:`workbench.atomic_files`).
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from workbench.atomic_files import atomic_file
from workbench.errors import DimensionError, InputError
from workbench.validation import iter_data_rows, read_csv_file

#: Most samples (rows) of a trajectory the workbench writes or reads.
MAX_SAMPLES = 1_000_000
#: Line 2 of a trajectory file: its sample count.
_COUNT_LINE = re.compile(r"#\s*samples\s*=\s*(\d+)\s*")

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
    """Write samples to ``path``, all at once (full float precision).

    Line 1 is the header, line 2 ``# samples=K``, then one row per sample.

    Raises:
        DimensionError: If q, qd, qdd do not have one row per time.
        InputError: If ``path`` cannot be written or there are more than
            :data:`MAX_SAMPLES` samples.
    """
    t, q, qd, qdd = samples.t, samples.q, samples.qd, samples.qdd
    if not (q.shape == qd.shape == qdd.shape == (t.shape[0], q.shape[1])):
        raise DimensionError("q, qd, qdd", (t.shape[0], q.shape[1]), qd.shape)
    check_sample_count(t.shape[0], f"trajectory {path}")
    table = np.column_stack([t, q, qd, qdd])
    with atomic_file(path) as tmp, tmp.open("w", newline="", encoding="utf-8") as out:
        writer = csv.writer(out)
        writer.writerow(header(q.shape[1]))
        out.write(f"# samples={t.shape[0]}\r\n")
        writer.writerows([repr(float(x)) for x in row] for row in table)


def check_sample_count(count: int, what: str) -> None:
    """Refuse more than :data:`MAX_SAMPLES` samples.

    Raises:
        InputError: Naming ``what`` and the maximum.
    """
    if count > MAX_SAMPLES:
        raise InputError(
            f"{what}: {count} samples, at most {MAX_SAMPLES} (lower the rate or "
            "the duration)"
        )


def read_trajectory_csv(
    path: str | Path, nq: int | None = None
) -> JointTrajectorySamples:
    """Read a trajectory CSV file.

    Args:
        path: File written by :func:`write_trajectory_csv` (or by hand).
        nq: Expected joint count (e.g. ``robot.nq``); None accepts any.

    Raises:
        TrajectoryFileError: If the file is missing, the header is wrong, a row
            has the wrong number of fields, a value is not a finite number,
            the times do not increase, or the count of line 2 (``# samples=K``)
            differs from the rows (a truncated file); the message names the line.
    """
    path = Path(path)
    rows = read_csv_file(path, TrajectoryFileError, "trajectory")
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
    stated = _stated_count(rows, path)
    values = []
    for line, row in iter_data_rows(rows):
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
    if stated is not None and stated != len(values):
        raise TrajectoryFileError(
            f"{path}: line 2 states {stated} samples, the file has {len(values)} "
            "(truncated or edited)"
        )
    check_sample_count(len(values), str(path))
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


def _stated_count(rows: list[list[str]], path: Path) -> int | None:
    """The K of line 2 (``# samples=K``), or None for a file without the line."""
    if len(rows) < 2 or not rows[1] or not rows[1][0].lstrip().startswith("#"):
        return None
    match = _COUNT_LINE.fullmatch(",".join(rows[1]).strip())
    if match is None:
        raise TrajectoryFileError(
            f"{path}, line 2: expected '# samples=K', got {','.join(rows[1])[:80]!r}"
        )
    return int(match.group(1))
