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


@pytest.mark.slow
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


# -- pick and place as tool poses (closed form; seven-axis arms at a redundancy value)
PICK_POSE = ["0.5", "0.1", "0.3", "0", "1", "0", "0"]  # [m], tool z down
PLACE_POSE = ["0.4", "-0.3", "0.4", "0", "1", "0", "0"]
POSES = ("--pick-xyz-quat-wxyz", *PICK_POSE, "--place-xyz-quat-wxyz", *PLACE_POSE)
#: FK of the planned ends against the typed poses [m, 1].
ATOL_POSE = 1e-12


def _plan_poses(capsys, robot: str, *extra: str):
    code, out, err = run(
        capsys, "plan", "pick-place", "--robot", robot, *POSES, "--duration", "6",
        "--no-collision", "--json", *extra,
    )  # fmt: skip
    return code, json.loads(out) if out else None, err


def _check_ends(name: str, result: dict) -> None:
    import pinocchio as pin

    from workbench import load_robot
    from workbench.poses import rotation_from_quat_wxyz

    robot = load_robot(name)
    for q, typed in ((result["q_pick"], PICK_POSE), (result["q_place"], PLACE_POSE)):
        x = np.array(typed, dtype=float)
        pose = robot.fk(np.array(q))
        target = pin.SE3(rotation_from_quat_wxyz(x[3:]), x[:3])
        np.testing.assert_allclose(pose.translation, target.translation, atol=ATOL_POSE)
        np.testing.assert_allclose(pose.rotation, target.rotation, atol=ATOL_POSE)
        assert np.all((q >= robot.lower) & (q <= robot.upper))


def test_seven_axis_poses_at_a_given_redundancy(capsys) -> None:
    from workbench import ik, load_robot

    code, result, _ = _plan_poses(capsys, "iiwa14", "--redundancy", "1.5")
    assert code == 0 and result["branch"] == "shoulder-pos/elbow-pos/wrist-pos"
    assert result["redundancy"] == {
        "parameter": "arm angle", "source": "given", "criterion": None,
        "pick": 1.5, "place": 1.5,
    }  # fmt: skip
    _check_ends("iiwa14", result)
    iiwa = load_robot("iiwa14")
    for key in ("q_pick", "q_place"):  # the closed form at ψ = 1.5 exactly
        value = ik.get_solver(iiwa).parameter_of(np.array(result[key]))
        assert value == pytest.approx(1.5, abs=1e-9)


@pytest.mark.slow
def test_seven_axis_poses_at_chosen_values_on_one_branch(capsys) -> None:
    code, result, _ = _plan_poses(capsys, "panda", "--criterion", "manipulability")
    assert code == 0
    redundancy = result["redundancy"]
    assert redundancy["source"] == "chosen"
    assert redundancy["criterion"] == "manipulability"
    assert redundancy["parameter"] == "q7"
    assert result["q_pick"][6] == redundancy["pick"]  # q7 is the parameter
    assert result["q_place"][6] == redundancy["place"]
    _check_ends("panda", result)


def test_six_axis_poses_on_one_branch(capsys) -> None:
    code, result, _ = _plan_poses(capsys, "ur5")
    assert code == 0 and result["redundancy"] is None
    _check_ends("ur5", result)
    from workbench import ik, load_robot

    ur5 = load_robot("ur5")
    for key in ("q_pick", "q_place"):  # both ends on the one branch reported
        q = np.array(result[key])
        solutions = ik.analytic(ur5, ur5.fk(q), q_previous=q)
        assert ik.nearest(solutions, q).branch == result["branch"]


def test_joint_values_report_their_redundancy(capsys) -> None:
    pick = ["0", "-30", "0", "-120", "0", "90", "45"]
    place = ["60", "10", "20", "-90", "30", "120", "0"]
    code, out, _ = run(
        capsys, "plan", "pick-place", "--robot", "panda", "--pick-deg", *pick,
        "--place-deg", *place, "--duration", "3", "--json", "--no-collision",
    )  # fmt: skip
    result = json.loads(out)
    assert code == 0 and result["branch"] is None
    assert result["redundancy"]["source"] == "configuration"
    assert result["redundancy"]["pick"] == pytest.approx(np.deg2rad(45), abs=1e-15)


@pytest.mark.parametrize(
    ("robot", "args", "code", "fragment"),
    [
        ("ur5", [*POSES, "--redundancy", "1"], EXIT_BAD_INPUT, "no redundancy"),
        ("ur5", [*POSES, "--criterion", "manipulability"], EXIT_BAD_INPUT,
         "no redundancy"),
        ("iiwa14", [*POSES, "--redundancy", "1", "--criterion", "limit_margin"],
         EXIT_BAD_INPUT, "not with --redundancy"),
        ("panda", ["--pick-deg", *["0"] * 7, "--place-deg", *["0"] * 7,
                   "--redundancy", "1"], EXIT_BAD_INPUT, "fix the redundancy"),
        ("panda", ["--pick-deg", *["0"] * 7, "--place-xyz-quat-wxyz", *PLACE_POSE],
         EXIT_BAD_INPUT, "both as joint values"),
        ("iiwa14", ["--pick-xyz-quat-wxyz", *PICK_POSE[:3], "0", "0", "0", "0",
                    "--place-xyz-quat-wxyz", *PLACE_POSE], EXIT_BAD_INPUT,
         "--pick-xyz-quat-wxyz"),
        ("iiwa14", [*POSES, "--redundancy", "0.5"], EXIT_INFEASIBLE,
         "no IK solution within the joint limits"),
        ("iiwa14", ["--pick-xyz-quat-wxyz", "3", *PICK_POSE[1:],
                    "--place-xyz-quat-wxyz", *PLACE_POSE], EXIT_INFEASIBLE,
         "out of reach"),
    ],
)  # fmt: skip
def test_pose_options_exit_codes(capsys, robot, args, code, fragment) -> None:
    result = run(
        capsys, "plan", "pick-place", "--robot", robot, *args, "--duration", "6",
        "--no-collision",
    )  # fmt: skip
    assert result[0] == code and fragment in result[2], result[2]


def _bare_ur5(tmp_path: Path, *, zero_velocity: tuple[int, ...]) -> Path:
    """The catalog ur5 without <collision> elements, some velocity="0" (no limit)."""
    import re

    from workbench import load_robot

    text = load_robot("ur5").description  # mesh paths resolved
    text = re.sub(r"<collision>.*?</collision>", "", text, flags=re.S)
    limits = list(re.finditer(r'velocity="[^"]*"', text))
    for index in sorted(zero_velocity, reverse=True):
        match = limits[index]
        text = text[: match.start()] + 'velocity="0"' + text[match.end() :]
    path = tmp_path / "bare_ur5.urdf"
    path.write_text(text)
    return path


def test_an_arm_without_collision_geometry_or_limits_is_told_so(
    capsys, tmp_path: Path
) -> None:
    urdf = _bare_ur5(tmp_path, zero_velocity=(1, 4))
    args = ("plan", "pick-place", "--robot", str(urdf), "--pick-deg", *["0"] * 6)
    args += ("--place-deg", "10", "20", "30", "0", "0", "0", "--duration", "5")
    code, out, err = run(capsys, *args)
    assert (code, err) == (0, "")
    assert "no collision geometry in the URDF: collision check not possible" in out
    assert "--no-collision" not in out
    joints = [f"{j}_joint" for j in ("shoulder_lift", "wrist_2")]
    assert (
        f"note: the model gives no velocity limit for {', '.join(joints)}; no "
        "acceleration limit for any joint: the minimum duration respects the "
        "known limits only"
    ) in out
    code, out, err = run(capsys, *args, "--json")
    result = json.loads(out)
    assert result["collision_skipped"] == "no collision geometry in the URDF"
    assert result["unknown_limits"]["velocity"] == joints
    assert len(result["unknown_limits"]["acceleration"]) == 6
    code, out, err = run(capsys, *args, "--no-collision", "--json")
    assert json.loads(out)["collision_skipped"] == "--no-collision"


def test_no_known_limit_says_no_minimum_is_known(capsys, tmp_path: Path) -> None:
    urdf = _bare_ur5(tmp_path, zero_velocity=tuple(range(6)))
    args = ("plan", "pick-place", "--robot", str(urdf), "--pick-deg", *["0"] * 6)
    args += ("--place-deg", "10", "20", "30", "0", "0", "0", "--duration", "5")
    code, out, err = run(capsys, *args)
    assert (code, err) == (0, "")
    assert (
        "note: the model gives no velocity limit for any joint; no acceleration "
        "limit for any joint: no minimum duration is known (0 s stands for none)"
    ) in out
    assert "(minimum 0 s)" in out
