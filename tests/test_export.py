"""``workbench export`` and ``workbench.export``: bags, URScript, the trajectory CSV."""

from __future__ import annotations

import csv
import importlib.metadata
import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from tests.conftest import run_cli as run
from workbench import InputError, load_robot
from workbench.cli import EXIT_BAD_INPUT
from workbench.export import (
    UR_JOINTS,
    generate_urscript,
    read_ros2_bag,
    resample_hermite,
    write_ros2_bag,
)
from workbench.trajectory import pick_and_place
from workbench.trajectory.csv_io import (
    JointTrajectorySamples,
    header,
    read_trajectory_csv,
    record_path,
    write_trajectory_csv,
)

ATOL_EXACT = 1e-12
NAMES = [f"joint{i}" for i in range(1, 7)]


@pytest.fixture(scope="module")
def ur5_csv(tmp_path_factory) -> Path:
    ur5 = load_robot("ur5")
    q0 = np.deg2rad([0.0, -90.0, 90.0, -90.0, -90.0, 0.0])
    q1 = np.deg2rad([90.0, -60.0, 60.0, -90.0, -90.0, 30.0])
    path = tmp_path_factory.mktemp("ur5") / "ur5.csv"
    write_trajectory_csv(path, pick_and_place(ur5, q0, q1, 2.0).sample_uniform(100.0))
    return path


def _same(a: JointTrajectorySamples, b: JointTrajectorySamples) -> None:
    for x, y in ((a.t, b.t), (a.q, b.q), (a.qd, b.qd), (a.qdd, b.qdd)):
        np.testing.assert_allclose(x, y, rtol=0, atol=ATOL_EXACT)


def test_bag_round_trip_from_the_cli(capsys, tmp_path: Path) -> None:
    bag, table = tmp_path / "bag", tmp_path / "pp.csv"
    code, out, err = run(
        capsys, "export", "--format", "ros2-bag", "--pick-place", "--out", str(bag),
        "--no-collision",
    )  # fmt: skip
    assert (code, err) == (0, "") and "1001 samples" in out
    assert sorted(p.suffix for p in bag.iterdir()) == [".mcap", ".yaml"]
    run(capsys, "plan", "pick-place", "--robot", "puma560", "--pick-deg", "0", "45",
        "200", "-100", "30", "10", "--place-deg", "150", "-100", "-10", "100", "-70",
        "170", "--duration", "10", "--csv", str(table), "--no-collision")  # fmt: skip
    back = read_ros2_bag(bag)
    assert back.joint_names == tuple(NAMES) and back.frame_id == "base"
    _same(back.samples, read_trajectory_csv(table, 6))


finite = st.floats(-10.0, 10.0, allow_nan=False)


@pytest.mark.slow
@given(
    steps=arrays(np.int64, 5, elements=st.integers(1, 10**9), unique=True),
    values=arrays(np.float64, (5, 3, 2), elements=finite),
)
def test_bag_round_trip_property(tmp_path_factory, steps, values) -> None:
    t = np.cumsum(steps) / 1e9  # times on the nanosecond grid of ROS durations
    samples = JointTrajectorySamples(
        t, values[:, :, 0], values[:, :, 1], -values[:, :, 0]
    )
    bag = tmp_path_factory.mktemp("bag") / "b"
    write_ros2_bag(bag, samples, ["a", "b", "c"], topic="/arm/trajectory")
    back = read_ros2_bag(bag, topic="/arm/trajectory")
    assert back.joint_names == ("a", "b", "c")
    _same(back.samples, samples)


@pytest.mark.parametrize("rate", [100, 125, 500, 1000])
def test_bag_times_come_back_to_the_bit(tmp_path: Path, rate: int) -> None:
    t = np.arange(1001) / rate  # as the workbench samples (4.56 came back 4.56...05)
    q = np.zeros((t.size, 1))
    write_ros2_bag(tmp_path / "b", JointTrajectorySamples(t, q, q, q), ["j"])
    back = read_ros2_bag(tmp_path / "b").samples.t
    assert np.array_equal(back, t), np.flatnonzero(back != t)[:5]


def test_bag_times_round_to_nanoseconds(tmp_path: Path) -> None:
    t = np.array([0.0, 1.0 / 3.0])
    q = np.zeros((2, 1))
    write_ros2_bag(tmp_path / "b", JointTrajectorySamples(t, q, q, q), ["j"])
    back = read_ros2_bag(tmp_path / "b").samples.t
    assert back[1] == 333_333_333 / 1e9 and abs(back[1] - t[1]) <= 0.5e-9


def test_bag_errors(tmp_path: Path) -> None:
    s = JointTrajectorySamples(
        np.zeros(1), np.zeros((1, 2)), np.zeros((1, 2)), np.zeros((1, 2))
    )
    with pytest.raises(InputError, match="unique"):
        write_ros2_bag(tmp_path / "b", s, ["a", "a"])
    with pytest.raises(InputError, match="shape"):
        write_ros2_bag(tmp_path / "b", s, ["a"])
    for topic in ("", "//x", "1abc", "a b"):
        with pytest.raises(InputError, match="not a ROS 2 topic"):
            write_ros2_bag(tmp_path / "b", s, ["a", "b"], topic=topic)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(InputError, match="cannot read bag"):
        read_ros2_bag(tmp_path / "none")


def test_missing_rosbags_names_this_distribution_and_its_extra(
    tmp_path: Path, monkeypatch
) -> None:
    """The hint installs this project's ``export`` extra, not a namesake on PyPI."""
    monkeypatch.setitem(sys.modules, "rosbags.rosbag2", None)  # import fails
    s = JointTrajectorySamples(np.zeros(1), *(np.zeros((1, 1)),) * 3)
    with pytest.raises(InputError) as error:
        write_ros2_bag(tmp_path / "b", s, ["a"])
    message = str(error.value)
    assert "\n" not in message
    requirement = re.search(r'pip install "([^"\[]+)\[(\w+)\]"', message)
    assert requirement is not None, message
    metadata = importlib.metadata.metadata(requirement.group(1))
    assert metadata["Name"] == "kinematics-workbench"
    assert requirement.group(2) in metadata.get_all("Provides-Extra")
    extra = requirement.group(2)
    assert any(
        r.startswith("rosbags") and r.replace('"', "'").endswith(f"extra == '{extra}'")
        for r in metadata.get_all("Requires-Dist")
    )


def test_urscript_for_a_ur5(capsys, tmp_path: Path, ur5_csv: Path) -> None:
    script = tmp_path / "ur5.script"
    code, _, err = run(capsys, "export", "--format", "urscript", "--robot", "ur5",
                       "--trajectory", str(ur5_csv), "--out", str(script),
                       "--servo-rate", "125")  # fmt: skip
    assert (code, err) == (0, "")
    text = script.read_text()
    commands = re.findall(r"servoj\(\[([^\]]*)\], t=([0-9.]+)", text)
    assert len(commands) == 2 * 125 + 1 and {c[1] for c in commands} == {"0.008"}
    first = np.array([float(x) for x in commands[0][0].split(",")])
    last = np.array([float(x) for x in commands[-1][0].split(",")])
    samples = read_trajectory_csv(ur5_csv, 6)
    np.testing.assert_allclose(first, samples.q[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(last, samples.q[-1], rtol=0, atol=1e-9)
    assert text.startswith("def workbench_trajectory():") and "movej(" in text
    assert text.rstrip().endswith("workbench_trajectory()")


def test_hermite_resampling_passes_through_the_samples(ur5_csv: Path) -> None:
    samples = read_trajectory_csv(ur5_csv, 6)
    fine = resample_hermite(samples, 500.0)  # 5 servo steps per 100 Hz sample
    np.testing.assert_allclose(fine[::5], samples.q, rtol=0, atol=ATOL_EXACT)
    ur5 = load_robot("ur5")
    q0 = np.deg2rad([0.0, -90.0, 90.0, -90.0, -90.0, 0.0])
    q1 = np.deg2rad([90.0, -60.0, 60.0, -90.0, -90.0, 30.0])
    exact = pick_and_place(ur5, q0, q1, 2.0).sample(np.arange(len(fine)) / 500.0)[0]
    assert np.max(np.abs(fine - exact)) < 1e-6  # cubic pieces: Hermite is exact


def test_urscript_refuses_other_arms(capsys, tmp_path: Path) -> None:
    out = tmp_path / "puma.script"
    code, stdout, err = run(
        capsys, "export", "--format", "urscript", "--pick-place", "--out", str(out)
    )
    assert code == EXIT_BAD_INPUT and stdout == "" and err.count("\n") == 1
    assert "Universal Robots arms only" in err and "joint1" in err
    assert not out.exists()
    with pytest.raises(InputError, match="shoulder_pan_joint"):
        generate_urscript(read_trajectory_csv, NAMES)  # type: ignore[arg-type]


def test_csv_is_the_one_trajectory_dialect(
    capsys, tmp_path: Path, ur5_csv: Path
) -> None:
    out = tmp_path / "exported.csv"
    code, _, _ = run(capsys, "export", "--format", "csv", "--robot", "ur5",
                     "--trajectory", str(ur5_csv), "--out", str(out))  # fmt: skip
    assert code == 0
    with out.open(newline="") as stream:
        rows = list(csv.reader(stream))
    assert rows[0] == header(6)  # the columns of every trajectory CSV
    table = np.array(rows[1:], dtype=float)
    samples = read_trajectory_csv(ur5_csv, 6)
    np.testing.assert_array_equal(
        table, np.column_stack([samples.t, samples.q, samples.qd, samples.qdd])
    )
    entry = json.loads(record_path(out).read_text())
    assert entry["joint_names"] == list(UR_JOINTS)
    assert entry["samples"] == samples.t.size
    again = read_trajectory_csv(out, 6)
    np.testing.assert_array_equal(again.q, samples.q)


@pytest.mark.parametrize("fmt", ["ros2-bag", "urscript", "csv"])
def test_bad_inputs_exit_2_and_write_nothing(capsys, tmp_path: Path, fmt) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text("t,q1,qd1,qdd1\n0,1,2\n", encoding="utf-8")
    out = tmp_path / "out"
    for argv in (
        ("--trajectory", str(bad), "--out", str(out)),
        ("--trajectory", str(tmp_path / "missing.csv"), "--out", str(out)),
        ("--pick-place", "--out", str(tmp_path / "no" / "dir" / "out")),
    ):
        robot = ("--robot", "ur5") if fmt == "urscript" else ()
        code, stdout, err = run(capsys, "export", "--format", fmt, *robot, *argv)
        assert code == EXIT_BAD_INPUT and stdout == "" and err.count("\n") == 1
        assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv"]


def test_existing_bag_is_not_replaced(capsys, tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    bag.mkdir()
    code, _, err = run(
        capsys, "export", "--format", "ros2-bag", "--pick-place", "--out", str(bag)
    )
    assert code == EXIT_BAD_INPUT and "already exists" in err
    assert list(bag.iterdir()) == []


def test_failed_write_leaves_nothing(monkeypatch, tmp_path: Path) -> None:
    s = JointTrajectorySamples(
        np.array([0.0, 1.0]), np.zeros((2, 6)), np.zeros((2, 6)), np.zeros((2, 6))
    )

    def broken(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Path, "write_text", broken)  # the record, after the CSV
    with pytest.raises(InputError, match="No space left"):
        write_trajectory_csv(tmp_path / "x.csv", s, joint_names=NAMES)
    assert list(tmp_path.iterdir()) == []


def test_json_output(capsys, tmp_path: Path) -> None:
    out = tmp_path / "pp.csv"
    code, stdout, _ = run(capsys, "export", "--format", "csv", "--pick-place",
                          "--out", str(out), "--json", "--no-collision")  # fmt: skip
    result = json.loads(stdout)
    assert code == 0 and result["samples"] == 1001 and result["duration"] == 10.0
    assert result["joint_names"] == NAMES and result["format"] == "csv"
