"""Trajectory CSV files: round trip and line-numbered errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from workbench.errors import DimensionError, InputError
from workbench.trajectory.csv_io import (
    MAX_SAMPLES,
    JointTrajectorySamples,
    TrajectoryFileError,
    check_sample_count,
    read_trajectory_csv,
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


def test_line_2_states_the_count_and_a_lost_row_is_refused(tmp_path: Path, rng) -> None:
    path = tmp_path / "t.csv"
    write_trajectory_csv(path, _samples(rng, k=7))
    lines = path.read_text().splitlines(keepends=True)
    assert lines[1] == "# samples=7\n"
    for cut in (len(lines) - 1, 3):  # a whole row lost; rows cut at a line end
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


def test_too_many_samples_are_refused() -> None:
    check_sample_count(MAX_SAMPLES, "fine")
    with pytest.raises(InputError, match=f"at most {MAX_SAMPLES}"):
        check_sample_count(MAX_SAMPLES + 1, "--rate")
