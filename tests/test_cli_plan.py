"""``workbench plan pick-place``: JSON, CSV, plot, exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import run_cli as run
from workbench import paper_data
from workbench.cli import EXIT_BAD_INPUT, EXIT_INFEASIBLE
from workbench.trajectory.csv_io import read_trajectory_csv

PICK = [str(x) for x in paper_data.ANGELES_PICK_Q_DEG]
PLACE = [str(x) for x in paper_data.ANGELES_PLACE_Q_DEG]
BASE = ("plan", "pick-place", "--robot", "puma560", "--pick-deg", *PICK)


def test_table3_json_csv_and_plot(capsys, tmp_path: Path) -> None:
    csv, png = tmp_path / "t.csv", tmp_path / "t.png"
    code, out, err = run(
        capsys,
        *BASE,
        "--place-deg",
        *PLACE,
        "--duration",
        "10",
        "--rate",
        "50",
        "--csv",
        str(csv),
        "--plot",
        str(png),
        "--no-collision",  # the paper's scene collides: tests/test_cli_collision.py
        "--json",
    )
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert result["duration"] == 10.0 and result["violations"] == []
    assert result["min_duration"] == pytest.approx(7.3304, abs=1e-4)
    samples = read_trajectory_csv(csv, nq=6)
    assert samples.t.size == 501 and samples.t[-1] == 10.0
    np.testing.assert_allclose(
        samples.q[[0, -1]],
        np.deg2rad([paper_data.ANGELES_PICK_Q_DEG, paper_data.ANGELES_PLACE_Q_DEG]),
        rtol=0,
        atol=1e-12,
    )
    np.testing.assert_allclose(samples.qd[[0, -1]], 0.0, rtol=0, atol=1e-12)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_below_minimum_prints_json_and_exits_3(capsys) -> None:
    code, out, err = run(
        capsys, *BASE, "--place-deg", *PLACE, "--duration", "7", "--json"
    )
    assert code == EXIT_INFEASIBLE
    result = json.loads(out)
    (violation,) = result["violations"]
    assert violation == {
        "joint": "joint3",
        "t": 3.5,
        "value": pytest.approx(-1.0472, abs=1e-4),
        "limit": -1.0,
        "kind": "velocity",
    }
    assert (
        err.count("\n") == 1 and "joint joint3 velocity" in err and "t = 3.5 s" in err
    )


def test_at_exactly_the_minimum_duration_no_violation(capsys) -> None:
    _, out, _ = run(capsys, *BASE, "--place-deg", *PLACE, "--duration", "7", "--json")
    t_min = json.loads(out)["min_duration"]
    code, out, err = run(
        capsys,
        *BASE,
        "--place-deg",
        *PLACE,
        "--duration",
        repr(t_min),
        "--no-collision",
        "--json",
    )
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert result["violations"] == []
    assert max(result["peak_velocity"]) == pytest.approx(1.0, rel=1e-12)


def test_human_output(capsys) -> None:
    code, out, _ = run(
        capsys, *BASE, "--place-deg", *PLACE, "--duration", "10", "--no-collision"
    )
    assert code == 0
    assert "collision check skipped" in out
    assert "minimum 7.3304 s" in out and "within every" in out and "joint3" in out


def test_panda(capsys) -> None:
    code, out, _ = run(
        capsys,
        "plan",
        "pick-place",
        "--robot",
        "panda",
        "--pick-deg",
        *["0", "-30", "0", "-120", "0", "90", "45"],
        "--place-deg",
        *["60", "10", "20", "-90", "30", "120", "0"],
        "--duration",
        "3",
        "--json",
    )
    assert code == 0 and len(json.loads(out)["peak_velocity"]) == 7


@pytest.mark.parametrize(
    ("duration", "place", "fragment"),
    [
        ("0", PLACE, "--duration: must be > 0 and at most 1e+06 s"),
        ("-2", PLACE, "--duration: must be > 0 and at most 1e+06 s"),
        ("nan", PLACE, "not a finite number"),
        ("10", PLACE[:5], "6 values expected, 5 given"),
        ("10", [*PLACE[:5], "nan"], "not a finite number"),
        ("10", [*PLACE[:5], "x"], "not a number"),
    ],
)
def test_bad_input_exits_2(capsys, duration, place, fragment) -> None:
    code, out, err = run(capsys, *BASE, "--place-deg", *place, "--duration", duration)
    assert code == EXIT_BAD_INPUT and out == ""
    assert err.count("\n") == 1 and fragment in err, err


def test_bad_rate_exits_2(capsys) -> None:
    code, _, err = run(
        capsys, *BASE, "--place-deg", *PLACE, "--duration", "1", "--rate", "0"
    )
    assert code == EXIT_BAD_INPUT and "--rate: must be > 0 and at most 100000 Hz" in err


def test_missing_subcommand_exits_2(capsys) -> None:
    code, _, err = run(capsys, "plan")
    assert code == EXIT_BAD_INPUT and "KIND" in err
