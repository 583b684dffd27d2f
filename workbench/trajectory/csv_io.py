"""Joint trajectories as CSV files: ``t,q1..qn,qd1..qdn,qdd1..qddn`` (SI units).

Written by ``workbench plan``, ``fishcut``, ``export --format csv`` and ``demo``,
read by ``workbench view``, ``export`` and ``report`` and the singularity
analysis along a path. One plain dialect: line 1 is the header, then one row per
sample, every float at full precision (``repr``), nothing else, so that
``pandas.read_csv(path)``, ``csv.DictReader`` and ``numpy.loadtxt(path,
delimiter=",", skiprows=1)`` read it with no options.

What the file cannot hold without breaking those readers is in its *record*, a
JSON file beside it (:func:`record_path`: ``traj.csv`` → ``traj.csv.json``),
written together with it (:func:`workbench.atomic_files.atomic_files`): the
sample count, the first and last times, the joint names when known and the
SHA-256 of the CSV's bytes. :func:`read_trajectory_csv` refuses a file that
does not match its record (truncated, or edited since it was written; deleting
the record reads the file as it is). A file without a record (written by hand,
or by another program) is read as it is. Files of the earlier dialect, whose
line 2 is ``# samples=K``, are still read and checked against that line.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.atomic_files import atomic_files
from workbench.errors import DimensionError, InputError
from workbench.validation import iter_data_rows, parse_float, read_csv_file

#: Most samples (rows) of a trajectory the workbench writes or reads.
MAX_SAMPLES = 1_000_000
#: What a record's ``format`` says.
RECORD_FORMAT = "workbench trajectory CSV"
#: Line 2 of a trajectory file of the earlier dialect: its sample count.
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


def record_path(path: str | Path) -> Path:
    """The record of a trajectory CSV: the file's name with ``.json`` appended."""
    path = Path(path)
    return path.with_name(path.name + ".json")


def get_output_paths(path: str | Path) -> list[Path]:
    """The files :func:`write_trajectory_csv` writes: the CSV and its record."""
    return [Path(path), record_path(path)]


def write_trajectory_csv(
    path: str | Path,
    samples: JointTrajectorySamples,
    *,
    joint_names: Sequence[str] | None = None,
    record: str | Path | None = None,
) -> None:
    """Write samples to ``path`` and its record, all at once (full precision).

    Args:
        path: The CSV file: the header, then one row per sample.
        samples: The trajectory.
        joint_names: The robot's joint names, kept in the record (e.g.
            ``robot.joint_names``); None keeps none.
        record: Where the record goes when the caller stages the files itself
            (``path`` and ``record`` then temporary files of one
            :func:`~workbench.atomic_files.atomic_files` block, of the targets
            :func:`get_output_paths`); None writes both to ``path`` and
            :func:`record_path` of it, all at once.

    Raises:
        DimensionError: If q, qd, qdd do not have one row per time, or the
            names do not match the joints.
        InputError: If ``path`` cannot be written, or there are more than
            :data:`MAX_SAMPLES` samples.
    """
    t, q, qd, qdd = samples.t, samples.q, samples.qd, samples.qdd
    if not (q.shape == qd.shape == qdd.shape == (t.shape[0], q.shape[1])):
        raise DimensionError("q, qd, qdd", (t.shape[0], q.shape[1]), qd.shape)
    names = None if joint_names is None else [str(n) for n in joint_names]
    if names is not None and len(names) != q.shape[1]:
        raise DimensionError("joint_names", (q.shape[1],), (len(names),))
    check_sample_count(t.shape[0], f"trajectory {path}")
    stream = io.StringIO(newline="")
    writer = csv.writer(stream)
    writer.writerow(header(q.shape[1]))
    table = np.column_stack([t, q, qd, qdd])
    writer.writerows([repr(float(x)) for x in row] for row in table)
    data = stream.getvalue().encode("utf-8")
    entry = {
        "format": RECORD_FORMAT,
        "version": 1,
        "columns": header(q.shape[1]),
        "samples": int(t.shape[0]),
        "t_first": float(t[0]) if t.size else None,
        "t_last": float(t[-1]) if t.size else None,
        "joint_names": names,
        "sha256": hashlib.sha256(data).hexdigest(),
    }
    text = json.dumps(entry, indent=2) + "\n"
    if record is not None:
        Path(path).write_bytes(data)
        Path(record).write_text(text, encoding="utf-8")
        return
    with atomic_files(path, record_path(path)) as (tmp, tmp_record):
        tmp.write_bytes(data)
        tmp_record.write_text(text, encoding="utf-8")


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
            the times do not increase, or the file does not match its record
            (:func:`record_path`; truncated or edited since it was written) or,
            in the earlier dialect, the count of its line 2 (``# samples=K``);
            the message names the line or the record.
    """
    path = Path(path)
    rows = read_csv_file(path, TrajectoryFileError, "trajectory")
    entry = _read_record(path)
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
            numbers = [parse_float(field.strip()) for field in row]
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
    if entry is not None:
        _check_record(path, entry, len(values), columns)
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


def _read_record(path: Path) -> dict[str, Any] | None:
    """The record beside ``path`` (:func:`record_path`), or None if there is none.

    Raises:
        TrajectoryFileError: If the record cannot be read or is not one.
    """
    where = record_path(path)
    if not where.exists():
        return None
    try:
        entry = json.loads(where.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as err:
        raise TrajectoryFileError(
            f"{path}: its record {where.name} cannot be read ({err}); delete it "
            "to read the file as it is"
        ) from None
    keys = ("format", "samples", "sha256", "columns")
    if (
        not isinstance(entry, dict)
        or entry.get("format") != RECORD_FORMAT
        or not all(k in entry for k in keys)
        or not isinstance(entry["samples"], int)
        or not isinstance(entry["sha256"], str)
    ):
        raise TrajectoryFileError(
            f"{path}: {where.name} is not the record of a trajectory CSV (format "
            f"{RECORD_FORMAT!r}, keys {', '.join(keys)}); delete it to read the "
            "file as it is"
        )
    return entry


def _check_record(
    path: Path, entry: dict[str, Any], count: int, columns: list[str]
) -> None:
    """Refuse ``path`` if it is not the file its record describes.

    Raises:
        TrajectoryFileError: Saying how it differs (rows, columns, bytes).
    """
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    if digest == entry["sha256"]:
        return
    hint = f"delete {record_path(path).name} to read it as it is"
    if count != entry["samples"]:
        raise TrajectoryFileError(
            f"{path}: {count} samples, its record {record_path(path).name} states "
            f"{entry['samples']} (truncated or edited; {hint})"
        )
    if columns != entry["columns"]:
        raise TrajectoryFileError(
            f"{path}: its columns differ from those of its record "
            f"{record_path(path).name} (edited; {hint})"
        )
    raise TrajectoryFileError(
        f"{path}: edited since it was written (its SHA-256 differs from that of "
        f"its record {record_path(path).name}; {hint})"
    )


def _stated_count(rows: list[list[str]], path: Path) -> int | None:
    """The K of line 2 (``# samples=K``, the earlier dialect), or None."""
    if len(rows) < 2 or not rows[1] or not rows[1][0].lstrip().startswith("#"):
        return None
    match = _COUNT_LINE.fullmatch(",".join(rows[1]).strip())
    if match is None:
        raise TrajectoryFileError(
            f"{path}, line 2: expected '# samples=K', got {','.join(rows[1])[:80]!r}"
        )
    return int(match.group(1))
