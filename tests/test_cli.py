"""The command line: fk, urdf from-dh, demo; exit codes and one-line errors."""

from __future__ import annotations

import contextlib
import io
import json
import re
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import run_cli as run
from workbench import paper_data
from workbench.cli import EXIT_BAD_INPUT, main
from workbench.demo import run as demo_module
from workbench.demo.summary_text import format_demo_summary
from workbench.model.catalog import get_own_urdf_dir

# Table II is printed to two decimals: a computed value matches when it rounds to it.
PRINTED_DECIMALS = 2
ATOL_PRINTED = 1e-9  # printed values converted mm -> m -> mm are not bit-exact


@pytest.mark.parametrize(
    ("q_deg", "printed"),
    [
        (paper_data.ANGELES_PICK_Q_DEG, paper_data.ANGELES_PICK_ANGELES7),
        (paper_data.ANGELES_PLACE_Q_DEG, paper_data.ANGELES_PLACE_ANGELES7),
    ],
)
def test_fk_json_reproduces_table2(capsys, q_deg, printed) -> None:
    code, out, err = run(
        capsys, "fk", "--robot", "puma560", "--deg", *map(str, q_deg), "--json"
    )
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert set(result) >= {
        "robot",
        "frame",
        "q",
        "position",
        "rotation",
        "quat_wxyz",
        "angeles7",
    }
    assert result["frame"] == "wrist_center"
    computed = np.array(result["angeles7"]) * [1, 1, 1, 1, 1e3, 1e3, 1e3]
    expected = printed * [1, 1, 1, 1, 1e3, 1e3, 1e3]
    np.testing.assert_allclose(
        np.round(computed, PRINTED_DECIMALS), expected, rtol=0, atol=ATOL_PRINTED
    )
    np.testing.assert_allclose(result["q"], np.deg2rad(q_deg), rtol=0, atol=1e-15)


def test_fk_human_output_and_radians(capsys) -> None:
    code, out, _ = run(capsys, "fk", "--robot", "puma560-kang", "--rad", *["0"] * 6)
    assert code == 0
    assert "position" in out and "452.100" in out and "angeles7" in out


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (("fk", "--robot", "puma56", "--deg", "0"), "valid names: "),
        (("fk", "--robot", "puma560", "--deg", "0", "0"), "6 values expected, 2 given"),
        (
            ("fk", "--robot", "puma560", "--deg", *["0"] * 5, "nan"),
            "not a finite number",
        ),
        (("fk", "--robot", "puma560", "--deg", *["0"] * 5, "abc"), "not a number"),
        (("fk", "--robot", "puma560", *["0"] * 6), "one of the arguments --deg --rad"),
        (("fk", "--robot", "nowhere/arm.urdf", "--rad", "0"), "URDF file not found"),
        (
            ("urdf", "from-dh", "missing.json", "--out", "x.urdf"),
            "cannot read DH table",
        ),
    ],
)
def test_bad_input_exits_2_with_one_line(capsys, argv, fragment) -> None:
    code, out, err = run(capsys, *argv)
    assert code == EXIT_BAD_INPUT
    assert out == ""
    assert err.count("\n") == 1 and fragment in err, err


def test_malformed_urdf_exits_2(capsys, tmp_path: Path) -> None:
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link", encoding="utf-8")
    code, _, err = run(capsys, "fk", "--robot", str(bad), "--rad", "0")
    assert code == EXIT_BAD_INPUT and "malformed URDF" in err and err.count("\n") == 1


def test_malformed_dh_table_exits_2(capsys, tmp_path: Path) -> None:
    table = tmp_path / "t.json"
    table.write_text('{"name": "x", "joints": [{"alpha": 0}]}', encoding="utf-8")
    code, _, err = run(
        capsys, "urdf", "from-dh", str(table), "--out", str(tmp_path / "x")
    )
    assert code == EXIT_BAD_INPUT and "missing key(s) a, d" in err
    assert not (tmp_path / "x").exists()


def test_urdf_from_dh_regenerates_the_committed_file(capsys, tmp_path: Path) -> None:
    out_file = tmp_path / "puma560.urdf"
    table = get_own_urdf_dir() / "puma560.dh.json"
    code, out, _ = run(
        capsys, "urdf", "from-dh", str(table), "--out", str(out_file), "--json"
    )
    assert code == 0
    assert json.loads(out) == {
        "robot": "puma560",
        "joints": 6,
        "tool_frame": "wrist_center",
        "out": str(out_file),
    }
    assert out_file.read_text() == (get_own_urdf_dir() / "puma560.urdf").read_text()


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory) -> tuple[Path, dict]:
    """``workbench demo --json`` run once: (output folder, printed summary).

    The text mode prints the same summary formatted (``format_demo_summary``), so
    the other demo tests check that wiring with this summary instead of a second
    run.
    """
    out = tmp_path_factory.mktemp("demo")
    printed, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(err):
        code = main(["demo", "--out", str(out), "--json"])
    assert code == 0, err.getvalue()
    return out, json.loads(printed.getvalue())


@pytest.mark.slow
def test_demo_reproduces_table2(demo_run) -> None:
    folder, summary = demo_run
    text = (folder / "summary.json").read_text()
    assert json.loads(text).keys() == summary.keys()  # (the file rounds floats)
    assert summary["table2_matches"] is True
    # Floats are stored with at most 9 significant digits, paper values as printed.
    for number in re.findall(r"-?\d+\.\d+(?:e[-+]?\d+)?", text):
        mantissa = number.lstrip("-").split("e")[0].replace(".", "").lstrip("0")
        assert len(mantissa) <= 9, number
    assert summary["table2"]["pick"]["printed"][4:] == [-94.07, 125.4, -470.55]
    assert (folder / "table2.md").is_file()
    figures = summary["pick_and_place"]["figures"]
    assert len(figures) == 7
    for path in figures.values():
        assert Path(path).read_bytes()[:4] == b"\x89PNG"
    assert (folder / "pick_and_place.csv").is_file()
    preview = Path(summary["pages"]["preview"]).read_text(encoding="utf-8")
    assert "<html" in preview.lower() and len(preview) > 100_000  # scene embedded
    report = Path(summary["pages"]["singularity_report"]).read_text(encoding="utf-8")
    assert report.count("data:image/png;base64,") >= 3
    fish = summary["fish_cutting"]
    assert fish["robot"] == "puma560-kang" and fish["wrist_flips"] == 0
    assert {e["kind"] for e in fish["events"]} == {"flesh", "bone"}
    assert (folder / "fishcut.csv").is_file()
    assert (folder / "fishcut.html").stat().st_size > 100_000


@pytest.mark.slow  # the demo_run fixture runs the whole demo
def test_demo_text_and_flags(capsys, monkeypatch, demo_run, tmp_path: Path) -> None:
    """Text mode prints the summary formatted; --no-plots reaches the demo."""
    _, summary = demo_run
    calls = []

    def recorded_demo(robot, out, *, plots):
        calls.append((robot.name, out, plots))
        return summary

    monkeypatch.setattr(demo_module, "run_demo", recorded_demo)
    code, out, _ = run(capsys, "demo", "--out", str(tmp_path))
    assert code == 0 and out == format_demo_summary(summary, tmp_path) + "\n"
    assert "match Table II" in out and "DO NOT" not in out
    assert "Pick and place (Sec. V), T = 10 s" in out and "minimum duration" in out
    assert "3D preview (open in a browser)" in out
    code, out, _ = run(capsys, "demo", "--out", str(tmp_path), "--json", "--no-plots")
    assert code == 0 and json.loads(out) == summary
    assert calls == [("puma560", tmp_path, True), ("puma560", tmp_path, False)]


def test_ik_falls_back_to_numerical_ik_for_other_arms(capsys) -> None:
    from workbench import load_robot

    q = np.array([0.1, -1.0, 1.0, 0.5, 0.3, 0.2])
    matrix = load_robot("generic6r").fk(q).homogeneous
    code, out, _ = run(
        capsys,
        "ik",
        "--robot",
        "generic6r",
        "--matrix",
        *map(str, matrix.ravel()),
        "--json",
    )
    assert code == 0
    result = json.loads(out)
    (solution,) = result["solutions"]
    assert result["solver"] == "numeric"
    assert solution["branch"] == "numeric" and solution["residual"] < 1e-9


def test_ik_gives_one_angle_per_continuous_joint(capsys) -> None:
    from workbench import load_robot

    robot = load_robot("kinova")  # three continuous joints: nq 9, six joints
    values = np.array([0.1, 2.0, 3.0, 0.4, 2.5, 0.6])
    matrix = robot.fk(robot.q_from_joint_values(values)).homogeneous
    code, out, _ = run(
        capsys,
        "ik",
        "--robot",
        "kinova",
        "--matrix",
        *map(str, matrix.ravel()),
        "--json",
    )
    assert code == 0
    (solution,) = json.loads(out)["solutions"]
    assert len(solution["q"]) == robot.nq
    joint_values = robot.joint_values_from_q(np.array(solution["q"]))
    np.testing.assert_allclose(solution["joint_values"], joint_values, atol=1e-12)
    np.testing.assert_allclose(solution["q_deg"], np.rad2deg(joint_values), atol=1e-9)


def test_ik_numerical_out_of_reach_exits_3(capsys) -> None:
    far = [
        "1",
        "0",
        "0",
        "3",
        "0",
        "1",
        "0",
        "0",
        "0",
        "0",
        "1",
        "0",
        "0",
        "0",
        "0",
        "1",
    ]
    code, _, err = run(capsys, "ik", "--robot", "generic6r", "--matrix", *far)
    assert code == 3 and "no solution" in err and err.count("\n") == 1
