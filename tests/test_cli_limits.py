"""Command-line options of the robot model: limits, package folders, joint values."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import run_cli as run
from tests.test_model_checks import write_packaged_arm
from workbench import load_robot
from workbench.model.catalog import get_own_urdf_dir
from workbench.trajectory import minimum_duration

ATOL_EXACT = 1e-12
PICK = ["0"] * 6
PLACE = ["90", "10", "10", "10", "10", "10"]
PLAN = ("plan", "pick-place", "--robot", "puma560", "--no-collision", "--json")


def _plan(capsys, *options: str, duration: str = "10") -> tuple[int, dict, str]:
    code, out, err = run(
        capsys,
        *PLAN,
        "--pick-deg",
        *PICK,
        "--place-deg",
        *PLACE,
        "--duration",
        duration,
        *options,
    )
    return code, json.loads(out) if out else {}, err


def test_plan_takes_one_limit_for_every_joint(capsys, puma) -> None:
    code, result, err = _plan(capsys, "--velocity-limit", "0.5")
    limited = puma.with_limits(velocity_limit=0.5)
    q0, q1 = np.zeros(6), np.deg2rad([float(x) for x in PLACE])
    assert (code, err) == (0, "")
    np.testing.assert_allclose(
        result["min_duration"], minimum_duration(limited, q0, q1), rtol=0, atol=0
    )
    assert result["min_duration"] != minimum_duration(puma, q0, q1)


def test_plan_limits_per_joint_are_checked(capsys) -> None:
    accelerations = ["0.01", "5", "5", "5", "5", "5"]
    code, result, err = _plan(capsys, "--acceleration-limit", *accelerations)
    assert code == 3
    found = {(v["joint"], v["kind"], abs(v["limit"])) for v in result["violations"]}
    assert found == {("joint1", "acceleration", 0.01)}  # at its peak and its trough
    assert err.count("\n") == 1 and "joint1 acceleration" in err


@pytest.mark.parametrize(
    ("option", "values", "message"),
    [
        ("--velocity-limit", ["0"], "--velocity-limit: must be > 0, got '0'"),
        ("--velocity-limit", ["-1"], "must be > 0, got '-1'"),
        ("--acceleration-limit", ["nan"], "not a finite number: 'nan'"),
        ("--acceleration-limit", ["inf"], "not a finite number: 'inf'"),
        ("--velocity-limit", ["fast"], "not a number: 'fast'"),
        (
            "--velocity-limit",
            ["1", "2"],
            "--velocity-limit takes 1 value (every joint) or 6 (one per joint of "
            "puma560: joint1, joint2, joint3, joint4, joint5, joint6), got 2",
        ),
    ],
)
def test_bad_limits_exit_2_with_one_line(capsys, option, values, message) -> None:
    code, result, err = _plan(capsys, option, *values)
    assert (code, result) == (2, {})
    assert err.count("\n") == 1 and message in err


def test_fishcut_plans_within_the_given_speed_limit(capsys) -> None:
    code, out, err = run(
        capsys, "fishcut", "--no-collision", "--velocity-limit", "0.05"
    )
    assert code == 3 and out == ""
    assert err.count("\n") == 1 and "outside [-0.05, 0.05]" in err
    code, _, err = run(capsys, "fishcut", "--velocity-limit", "1", "1")
    assert code == 2 and "takes 1 value (every joint) or 6" in err


def test_export_limits_only_with_fishcut(capsys, tmp_path: Path) -> None:
    out = str(tmp_path / "x.csv")
    args = ("export", "--format", "csv", "--out", out, "--pick-place")
    code, _, err = run(capsys, *args, "--velocity-limit", "1")
    assert code == 2 and "applies to --fishcut" in err
    assert not Path(out).exists()


def test_zero_velocity_is_no_limit_in_plan(capsys, tmp_path: Path) -> None:
    text = (get_own_urdf_dir() / "puma560.urdf").read_text()
    start = text.index('velocity="', text.index('name="joint1"'))
    end = text.index('"', start + len('velocity="'))
    path = tmp_path / "v0.urdf"
    path.write_text(text[:start] + 'velocity="0' + text[end:])
    code, out, err = run(
        capsys,
        "plan",
        "pick-place",
        "--robot",
        str(path),
        "--no-collision",
        "--json",
        "--pick-deg",
        *PICK,
        "--place-deg",
        *PLACE,
        "--duration",
        "0.2",
    )
    result = json.loads(out)
    # joint1 moves 90° without a speed limit; joint2..6 (10° each) bind instead
    robot = load_robot(path)
    assert robot.velocity_limit[0] == np.inf
    assert (
        0.0
        < result["min_duration"]
        == minimum_duration(robot, np.zeros(6), np.deg2rad([float(x) for x in PLACE]))
    )
    assert "joint1" not in {v["joint"] for v in result["violations"]}
    assert code == 3 and "RuntimeWarning" not in err


# --- joint values -------------------------------------------------------------


def test_fk_takes_one_angle_per_continuous_joint(capsys) -> None:
    angles = ["0", "180", "180", "0", "180", "-30"]
    code, out, err = run(capsys, "fk", "--robot", "kinova", "--deg", *angles, "--json")
    assert (code, err) == (0, "")
    result = json.loads(out)
    kinova = load_robot("kinova")
    q = kinova.q_from_joint_values(np.deg2rad([float(a) for a in angles]))
    np.testing.assert_allclose(result["q"], q, rtol=0, atol=0)
    np.testing.assert_allclose(
        np.rad2deg(result["joint_values"]), [float(a) for a in angles], atol=1e-12
    )
    np.testing.assert_allclose(
        result["position"], kinova.fk(q).translation, rtol=0, atol=ATOL_EXACT
    )
    # Pinocchio's q (9 values, cos/sin pairs) still works with --rad
    code, out, _ = run(
        capsys, "fk", "--robot", "kinova", "--rad", *map(str, q), "--json"
    )
    assert code == 0 and json.loads(out)["position"] == result["position"]


def test_fk_refuses_q_in_degrees_for_continuous_joints(capsys) -> None:
    code, _, err = run(capsys, "fk", "--robot", "kinova", "--deg", *["0"] * 9)
    assert code == 2 and err.count("\n") == 1
    assert "--deg takes one angle per joint (6 for kinova)" in err


def test_fk_names_the_mimic_joints_on_a_wrong_count(capsys, tmp_path) -> None:
    text = (get_own_urdf_dir() / "puma560.urdf").read_text()
    end = text.index("</joint>", text.index('<joint name="joint6"'))
    path = tmp_path / "mimic.urdf"
    path.write_text(text[:end] + '<mimic joint="joint4"/>' + text[end:])
    code, _, err = run(capsys, "fk", "--robot", str(path), "--rad", *["0"] * 6)
    assert code == 2 and err.count("\n") == 1
    assert "joint values (joint6 follows joint4) must have shape (5,)" in err


def test_a_zero_axis_exits_2(capsys, tmp_path) -> None:
    text = (get_own_urdf_dir() / "puma560.urdf").read_text()
    start = text.index("<axis", text.index('<joint name="joint2"'))
    end = text.index("/>", start)
    path = tmp_path / "zero.urdf"
    path.write_text(text[:start] + '<axis xyz="0 0 0"' + text[end:])
    code, out, err = run(capsys, "fk", "--robot", str(path), "--rad", *["0"] * 6)
    assert (code, out) == (2, "")
    assert err.count("\n") == 1 and "joint 'joint2' has a zero-length axis" in err


# --- package folders ----------------------------------------------------------


def test_package_dir_and_ros_package_path(capsys, tmp_path, monkeypatch) -> None:
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    monkeypatch.delenv("AMENT_PREFIX_PATH", raising=False)
    urdf, packages = write_packaged_arm(tmp_path)
    srdf = ("urdf", "srdf", "--robot", str(urdf))
    code, out, err = run(capsys, *srdf)
    assert (code, out) == (2, "") and "package://mypkg" in err
    code, out, err = run(
        capsys, *srdf, "--package-dir", "/nowhere", "--package-dir", str(packages)
    )
    assert code == 2 and "package folder not found: /nowhere" in err
    code, with_option, err = run(capsys, *srdf, "--package-dir", str(packages))
    assert (code, err) == (0, "") and 'link1="m1" link2="m2"' in with_option
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(packages))
    code, with_variable, err = run(capsys, *srdf)
    assert (code, err, with_variable) == (0, "", with_option)
