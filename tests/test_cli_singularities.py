"""``workbench singularities`` and ``workbench report singularities``."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.conftest import run_cli as run
from workbench import load_robot
from workbench.cli import EXIT_BAD_INPUT
from workbench.singularities.conditions import (
    compute_conditions,
    compute_det_j_analytic,
)

ATOL_DEG_INPUT = 1e-9  # degrees typed with 10 decimals, converted to rad
REL_DET = 1e-9
SMALL_GRID = ["--grid", "40", "--svd-grid", "12"]
KEYS = {"robot", "det_j", "sigma_min", "manipulability", "condition_number", "near"}


@pytest.mark.parametrize(
    ("name", "q_deg"),
    [
        ("puma560-kang", [10.0, 30.0, 87.3083636611, -20.0, 0.0, 5.0]),  # two loci
        ("ur5", [20.0, -60.0, 45.0, 10.0, 30.0, -15.0]),
        ("iiwa14", [10.0, 40.0, -20.0, 60.0, 15.0, -30.0, 5.0]),
        ("panda", [0.0, -30.0, 0.0, -120.0, 0.0, 90.0, 45.0]),
    ],
)
def test_singularities_json_is_analyse_configuration_as_dict(
    capsys, name, q_deg
) -> None:
    """The command prints what the library computes, key for key."""
    from workbench.json_numbers import to_json_ready
    from workbench.singularities import analyse_configuration

    code, out, _ = run(
        capsys, "singularities", "--robot", name, "--deg", *map(str, q_deg), "--json"
    )
    assert code == 0
    analysis = analyse_configuration(load_robot(name), np.deg2rad(q_deg))
    assert json.loads(out) == json.loads(json.dumps(to_json_ready(analysis.as_dict())))
    assert analysis.q.flags.writeable is False
    assert (analysis.family is None) == (name in ("iiwa14", "panda"))
    assert (analysis.srs is None) == (name != "iiwa14")


def test_singularities_json_at_kang_elbow_singularity(capsys) -> None:
    q_deg = [10.0, 30.0, 87.3083636611, -20.0, 45.0, 5.0]
    code, out, err = run(
        capsys,
        "singularities",
        "--robot",
        "puma560-kang",
        "--deg",
        *map(str, q_deg),
        "--json",
    )
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert set(result) >= KEYS
    assert set(result["near"]) == {"shoulder", "elbow", "wrist"}
    robot = load_robot("puma560-kang")
    q = np.radians(q_deg)
    expected = compute_conditions(robot, q).as_dict()
    for kind, value in result["near"].items():
        assert value == pytest.approx(float(expected[kind]), abs=1e-12)
    assert abs(result["near"]["elbow"]) <= ATOL_DEG_INPUT
    assert result["near"]["wrist"] == pytest.approx(math.sin(math.radians(45.0)))
    assert result["singular"] == ["elbow"]
    assert result["det_j"] == pytest.approx(
        float(compute_det_j_analytic(robot, q)), rel=1e-6, abs=1e-12
    )
    assert result["sigma_min"] <= 1e-9


def test_singularities_json_generic_puma(capsys) -> None:
    q_text = ["0.1", "-0.7", "0.4", "0.2", "1.1", "0.3"]
    code, out, _ = run(
        capsys, "singularities", "--robot", "puma560", "--rad", *q_text, "--json"
    )
    result = json.loads(out)
    assert code == 0
    q = np.array([0.1, -0.7, 0.4, 0.2, 1.1, 0.3])
    expected = float(compute_det_j_analytic(load_robot("puma560"), q))
    assert result["det_j"] == pytest.approx(expected, rel=REL_DET)
    assert result["singular"] == []
    assert result["condition_number"] >= 1.0
    assert result["manipulability"] == pytest.approx(abs(expected), rel=REL_DET)


def test_singularities_text_output(capsys) -> None:
    code, out, err = run(
        capsys,
        "singularities",
        "--robot",
        "puma560-kang",
        "--deg",
        "0",
        "0",
        "0",
        "0",
        "0",
        "0",
    )
    assert (code, err) == (0, "")
    assert "near wrist" in out and "singular         wrist" in out


def test_singularities_json_ur5_wrist_direction(capsys) -> None:
    """θ5 = 0: the direction of the wrist singularity, a left null vector of J."""
    q = np.array([0.3, -1.1, 1.4, -0.6, 0.0, 0.8])
    code, out, err = run(
        capsys, "singularities", "--robot", "ur5", "--rad", *map(str, q), "--json"
    )
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert result["singular"] == ["wrist"]
    assert set(result["directions"]) == {"wrist"}
    d = result["directions"]["wrist"]
    assert d["reference"].startswith("wrist point")
    robot = load_robot("ur5")
    tool_jac = robot.jacobian(q)
    jac = tool_jac.copy()
    jac[:3] += np.cross(
        jac[3:].T, np.array(d["reference_point"]) - robot.fk(q).translation
    ).T
    for key, matrix in (("u", jac), ("u_tool", tool_jac)):
        u = np.array(d[key])
        assert u.shape == (6,)
        assert np.linalg.norm(u) == pytest.approx(1.0, abs=1e-12)
        assert np.linalg.norm(u @ matrix) <= 1e-9
    assert max(d["residual"], d["residual_tool"]) <= 1e-9
    assert np.linalg.norm(tool_jac @ np.array(d["self_motion"])) <= 1e-9
    code, out, _ = run(capsys, "singularities", "--robot", "ur5", "--rad", *map(str, q))
    assert code == 0 and "u wrist" in out and "self-motion v" in out


def test_singularities_no_directions_off_the_loci(capsys) -> None:
    q_text = ["0.3", "-1.1", "1.4", "-0.6", "0.9", "0.8"]
    code, out, _ = run(
        capsys, "singularities", "--robot", "ur5", "--rad", *q_text, "--json"
    )
    assert code == 0
    assert json.loads(out)["directions"] == {}


def test_singularities_of_a_non_puma_robot(capsys) -> None:
    q_text = ["0", "-40", "70", "10", "60", "0"]
    code, out, _ = run(
        capsys, "singularities", "--robot", "generic6r", "--deg", *q_text, "--json"
    )
    result = json.loads(out)
    assert code == 0
    assert result["near"] == {"shoulder": None, "elbow": None, "wrist": None}
    assert result["directions"] is None
    assert result["sigma_min"] > 0.0 and result["det_j"] is not None


def test_singularities_of_a_redundant_robot_has_null_det(capsys) -> None:
    code, out, _ = run(
        capsys, "singularities", "--robot", "panda", "--rad", *["0.3"] * 7, "--json"
    )
    assert code == 0
    result = json.loads(out)
    assert result["det_j"] is None and result["srs"] is None  # Franka: numeric only
    code, out, _ = run(
        capsys, "singularities", "--robot", "panda", "--rad", *["0.3"] * 7
    )
    assert code == 0 and "no analytic conditions for this arm" in out


def test_singularities_of_an_srs_arm(capsys) -> None:
    """iiwa14 with θ4 = 0 (elbow stretched): distances and det(J Jᵀ) both ways."""
    robot = load_robot("iiwa14")
    q_deg = [10.0, 30.0, 20.0, 0.0, 40.0, 50.0, 60.0]
    argv = ["singularities", "--robot", "iiwa14", "--deg", *map(str, q_deg)]
    code, out, _ = run(capsys, *argv, "--json")
    assert code == 0
    srs = json.loads(out)["srs"]
    assert set(srs["near"]) == {
        "elbow",
        "shoulder",
        "wrist",
        "shoulder_wrist",
        "arm_angle",
    }
    assert abs(srs["near"]["elbow"]) < 1e-12 and srs["det_jjt"] < 1e-24
    q = np.radians(q_deg)
    q[3] = 0.5  # off the elbow locus: det(J Jᵀ) both ways agree
    code, out, _ = run(
        capsys,
        "singularities",
        "--robot",
        "iiwa14",
        "--rad",
        *map(repr, q.tolist()),
        "--json",
    )
    srs = json.loads(out)["srs"]
    jacobian = robot.jacobian(q)
    expected = np.linalg.det(jacobian @ jacobian.T)
    assert srs["det_jjt"] == pytest.approx(expected, rel=1e-9, abs=0.0)
    assert srs["det_jjt_pinocchio"] == pytest.approx(expected, rel=1e-9, abs=0.0)
    code, out, _ = run(capsys, *argv)
    assert code == 0 and "near elbow" in out and "family           SRS" in out


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["--robot", "puma560", "--deg", "1", "2", "3"], "6 values expected, 3 given"),
        (
            ["--robot", "puma560", "--deg", "0", "0", "nan", "0", "0", "0"],
            "not a finite",
        ),
        (["--robot", "nope", "--deg", "0", "0", "0", "0", "0", "0"], "unknown robot"),
        (["--robot", "puma560", "0", "0", "0", "0", "0", "0"], "--deg"),
    ],
)
def test_singularities_bad_input(capsys, argv, fragment) -> None:
    code, out, err = run(capsys, "singularities", *argv, "--json")
    assert code == EXIT_BAD_INPUT
    assert out == ""
    assert fragment in err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_report_singularities_json(capsys, tmp_path, monkeypatch) -> None:
    from workbench import progress

    monkeypatch.setenv("WORKBENCH_PROGRESS", "1")  # the lines honour this (and -q)
    monkeypatch.setattr(progress, "PROGRESS_DELAY", 0.0)
    monkeypatch.setattr(progress, "COUNT_INTERVAL", 0.0)
    html = tmp_path / "kang.html"
    argv = ["--robot", "puma560-kang", "--out", str(html), *SMALL_GRID, "--json"]
    code, out, err = run(capsys, "report", "singularities", *argv)
    assert code == 0
    summary = json.loads(out)
    np.testing.assert_allclose(
        summary["elbow_theta3_deg"], [87.308, -92.692], rtol=0, atol=5e-4
    )
    assert summary["out"] == str(html)
    assert html.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    # the progress lines, on stderr: each map counted to its end
    assert "report singularities: det J map: 1600/1600 points (100%)" in err
    assert "report singularities: σmin map: 144/144 points (100%)" in err
    for off in (["-q"], []):
        monkeypatch.setenv("WORKBENCH_PROGRESS", "1" if off else "0")
        code, _, err = run(capsys, *off, "report", "singularities", *argv)
        assert code == 0 and "%" not in err


def test_report_singularities_text_and_no_progress(capsys, tmp_path) -> None:
    html = tmp_path / "angeles.html"
    argv = ["--robot", "puma560", "--out", str(html), *SMALL_GRID, "--no-progress"]
    code, out, err = run(capsys, "report", "singularities", *argv)
    assert (code, err) == (0, "")
    assert "+87.474, -92.526" in out


@pytest.mark.parametrize(
    ("extra", "fragment"),
    [
        (["--out", "/nonexistent-dir/x.html"], "/nonexistent-dir does not exist"),
        (
            ["--out", "OUT", "--trajectory", "/nonexistent.csv"],
            "cannot read trajectory",
        ),
        (["--out", "OUT", "--grid", "1"], "--grid: must be 2..4000"),
    ],
)
def test_report_bad_input(capsys, tmp_path, extra, fragment) -> None:
    extra = [str(tmp_path / "r.html") if a == "OUT" else a for a in extra]
    code, _, err = run(
        capsys, "report", "singularities", "--robot", "puma560", *extra, "--no-progress"
    )
    assert code == EXIT_BAD_INPUT
    assert fragment in err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("name", ["ur5", "kuka-kr6-r700"])
def test_singularities_of_any_closed_form_arm(capsys, name) -> None:
    """OPW and UR-type arms get the analytic classes; q5 at DH θ5 = 0 is wrist."""
    from workbench import load_robot
    from workbench.ik import get_structure

    structure = get_structure(load_robot(name))
    q5 = -structure.joint_sign[4] * structure.table.joints[4].theta_offset
    q = [0.3, -0.7, 1.2, 0.4, q5, 0.2]
    code, out, _ = run(
        capsys, "singularities", "--robot", name, "--rad", *map(repr, q), "--json"
    )
    result = json.loads(out)
    assert code == 0 and result["family"] == structure.family
    assert abs(result["near"]["wrist"]) < 1e-12 and "wrist" in result["singular"]
    assert abs(result["det_j"]) < 1e-12
