"""Trajectory CSV files: one plain dialect, its record, round trips, named errors."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from workbench.errors import DimensionError, InputError
from workbench.trajectory.csv_io import (
    MAX_SAMPLES,
    JointTrajectorySamples,
    TrajectoryFileError,
    check_sample_count,
    header,
    read_trajectory_csv,
    record_path,
    write_trajectory_csv,
)


def _samples(rng, k: int = 5, n: int = 6) -> JointTrajectorySamples:
    return JointTrajectorySamples(
        t=np.linspace(0.0, 1.0, k),
        q=rng.normal(size=(k, n)),
        qd=rng.normal(size=(k, n)),
        qdd=rng.normal(size=(k, n)),
    )


def test_round_trip_is_exact(tmp_path: Path, rng) -> None:
    samples = _samples(rng)
    write_trajectory_csv(tmp_path / "t.csv", samples)
    back = read_trajectory_csv(tmp_path / "t.csv", nq=6)
    for name in ("t", "q", "qd", "qdd"):
        np.testing.assert_array_equal(getattr(back, name), getattr(samples, name))
    first = (tmp_path / "t.csv").read_text().splitlines()[0]
    assert first.startswith("t,q1,q2") and first.endswith("qdd5,qdd6")


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("", "empty file"),
        ("time,q1,qd1,qdd1\n0,0,0,0\n", "line 1: header must be"),
        ("t,q1,qd1,qdd1\n0,0,0\n", "line 2: 3 fields, expected 4"),
        ("t,q1,qd1,qdd1\n0,0,0,0\n1,x,0,0\n", "line 3: not a number"),
        ("t,q1,qd1,qdd1\n0,nan,0,0\n", "line 2: NaN or infinite"),
        (
            "t,q1,qd1,qdd1\n0,0,0,0\n1,0,0,0\n1,0,0,0\n",
            "line 4: time 1.0 does not increase",
        ),
        ("t,q1,qd1,qdd1\n", "no samples"),
    ],
)
def test_malformed_files_name_the_line(
    tmp_path: Path, text: str, fragment: str
) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(TrajectoryFileError) as info:
        read_trajectory_csv(path)
    assert fragment in str(info.value)


def test_wrong_joint_count_and_missing_file(tmp_path: Path, rng) -> None:
    write_trajectory_csv(tmp_path / "t.csv", _samples(rng, n=2))
    with pytest.raises(
        TrajectoryFileError, match="the file has 2 joints, the robot has 6"
    ):
        read_trajectory_csv(tmp_path / "t.csv", nq=6)
    with pytest.raises(TrajectoryFileError, match="cannot read trajectory"):
        read_trajectory_csv(tmp_path / "none.csv")


def test_plain_readers_read_it_with_no_options(tmp_path: Path, rng) -> None:
    samples = _samples(rng, k=7, n=3)
    path = tmp_path / "t.csv"
    write_trajectory_csv(path, samples, joint_names=["a", "b", "c"])
    table = np.column_stack([samples.t, samples.q, samples.qd, samples.qdd])
    frame = pd.read_csv(path)
    assert list(frame.columns) == header(3) and len(frame) == 7
    assert frame["t"].dtype == np.float64 and not frame.isna().any().any()
    np.testing.assert_array_equal(frame.to_numpy(), table)
    np.testing.assert_array_equal(frame["t"].diff().to_numpy()[1:], np.diff(samples.t))
    with path.open(newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 7 and list(rows[0]) == header(3)
    assert [float(r["q2"]) for r in rows] == samples.q[:, 1].tolist()
    np.testing.assert_array_equal(np.loadtxt(path, delimiter=",", skiprows=1), table)
    entry = json.loads(record_path(path).read_text())
    assert entry["samples"] == 7 and entry["joint_names"] == ["a", "b", "c"]
    assert (entry["t_first"], entry["t_last"]) == (0.0, 1.0)
    assert entry["columns"] == header(3)


def test_a_file_that_differs_from_its_record_is_refused(tmp_path: Path, rng) -> None:
    path = tmp_path / "t.csv"
    write_trajectory_csv(path, _samples(rng, k=7))
    lines = path.read_text().splitlines(keepends=True)
    for cut in (len(lines) - 1, 3):  # a whole row lost; rows cut at a line end
        path.write_text("".join(lines[:cut]))
        with pytest.raises(
            TrajectoryFileError, match=r"its record t\.csv\.json states 7"
        ):
            read_trajectory_csv(path)
    fields = lines[3].split(",")
    edited = [*lines[:3], ",".join([fields[0], "0.5", *fields[2:]]), *lines[4:]]
    path.write_text("".join(edited))
    with pytest.raises(TrajectoryFileError, match="edited since it was written"):
        read_trajectory_csv(path)
    with pytest.raises(TrajectoryFileError, match=r"delete t\.csv\.json to read it"):
        read_trajectory_csv(path)
    record_path(path).unlink()  # no record: read as it is
    assert read_trajectory_csv(path).t.size == 7
    record_path(path).write_text("{not json")
    with pytest.raises(
        TrajectoryFileError, match=r"record t\.csv\.json cannot be read"
    ):
        read_trajectory_csv(path)
    record_path(path).write_text('{"format": "something else"}')
    with pytest.raises(TrajectoryFileError, match="is not the record of a trajectory"):
        read_trajectory_csv(path)


@settings(max_examples=25, deadline=None)
@given(cut=st.integers(1, 10_000))
def test_any_truncation_is_refused(tmp_path_factory, cut: int) -> None:
    path = tmp_path_factory.mktemp("cut") / "t.csv"
    samples = _samples(np.random.default_rng(cut), k=9)
    write_trajectory_csv(path, samples)
    data = path.read_bytes()
    path.write_bytes(data[: cut % len(data)])
    with pytest.raises(TrajectoryFileError):
        read_trajectory_csv(path)


def test_files_of_the_earlier_dialect_are_still_read_and_checked(
    tmp_path: Path, rng
) -> None:
    path = tmp_path / "t.csv"
    samples = _samples(rng, k=7)
    table = np.column_stack([samples.t, samples.q, samples.qd, samples.qdd])
    body = ["".join(",".join(repr(float(x)) for x in row) + "\n") for row in table]
    lines = [",".join(header(6)) + "\n", "# samples=7\n", *body]
    path.write_text("".join(lines))
    np.testing.assert_array_equal(read_trajectory_csv(path).q, samples.q)
    for cut in (len(lines) - 1, 3):
        path.write_text("".join(lines[:cut]))
        with pytest.raises(TrajectoryFileError, match="line 2 states 7 samples"):
            read_trajectory_csv(path)
    path.write_text("".join(lines[:1] + lines[2:5]))  # no count line: read as is
    assert read_trajectory_csv(path).t.size == 3
    path.write_text("".join([lines[0], "# samples=seven\n", *lines[2:]]))
    with pytest.raises(TrajectoryFileError, match="line 2: expected '# samples=K'"):
        read_trajectory_csv(path)


def test_a_failed_write_leaves_the_old_file(tmp_path: Path, rng) -> None:
    path = tmp_path / "t.csv"
    path.write_text("old")
    bad = JointTrajectorySamples(
        t=np.zeros(2), q=np.zeros((2, 6)), qd=np.zeros((3, 6)), qdd=np.zeros((2, 6))
    )
    with pytest.raises(DimensionError):
        write_trajectory_csv(path, bad)
    assert path.read_text() == "old" and sorted(tmp_path.iterdir()) == [path]
    with pytest.raises(DimensionError):
        write_trajectory_csv(path, _samples(rng), joint_names=["a"])
    assert path.read_text() == "old" and sorted(tmp_path.iterdir()) == [path]


def test_too_many_samples_are_refused() -> None:
    check_sample_count(MAX_SAMPLES, "fine")
    with pytest.raises(InputError, match=f"at most {MAX_SAMPLES}"):
        check_sample_count(MAX_SAMPLES + 1, "--rate")


@pytest.mark.parametrize("field", ["1_0", "\u0661\u0660", "\uff11\uff10"])
def test_numbers_are_plain_ascii_as_pandas_reads_them(
    tmp_path: Path, field: str
) -> None:
    path = tmp_path / "t.csv"
    path.write_text(f"t,q1,qd1,qdd1\n0,0,0,0\n1,{field},0,0\n", encoding="utf-8")
    with pytest.raises(TrajectoryFileError, match="line 3: not a number"):
        read_trajectory_csv(path)
    assert not pd.api.types.is_numeric_dtype(pd.read_csv(path)["q1"])  # pandas too
