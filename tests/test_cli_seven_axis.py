"""The command line on seven-axis arms: `ik --redundancy`, `ik --feasible`.

Every branch printed is checked against the library (``ik.analytic`` at the
same value) and against forward kinematics (its residual); the value chosen
without ``--redundancy`` is ``ik.choose_redundancy``'s; the intervals printed
are ``Solver.feasible``'s. Bad input exits 2 with one line, an
infeasible value 3 with the feasible intervals.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.conftest import run_cli as run
from workbench import ik, load_robot
from workbench.json_numbers import to_json_ready

#: Residual of a closed-form branch (FK against the target) [m, rad].
ATOL_RESIDUAL = 1e-9
#: A parameter value through the command line (text, degrees) and back [rad].
ATOL_VALUE = 1e-12
#: Configurations within the joint limits, one per robot [rad].
Q0 = {
    "iiwa14": np.array([0.06, 1.7, -1.9, 1.69, -1.0, -0.29, 1.8]),
    "panda": np.array([0.2, -0.4, 0.3, -2.0, 0.4, 1.8, 0.5]),
}
ROBOTS = tuple(Q0)


def _matrix(name: str) -> list[str]:
    return [repr(float(x)) for x in load_robot(name).fk(Q0[name]).homogeneous.ravel()]


def _ik(capsys, name: str, *options: str) -> tuple[int, str, str]:
    return run(capsys, "ik", "--robot", name, "--matrix", *_matrix(name), *options)


def _wrapped(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(np.angle(np.exp(1j * (a - b))))))


@pytest.mark.parametrize("name", ROBOTS)
def test_every_branch_at_the_given_value(capsys, name) -> None:
    robot = load_robot(name)
    value = float(ik.get_solver(robot).parameter_of(Q0[name]))
    code, out, err = _ik(capsys, name, "--redundancy", repr(value), "--all", "--json")
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert result["solver"] == "closed-form" and result["feasible"] is True
    redundancy = result["redundancy"]
    assert redundancy["source"] == "given" and redundancy["value"] == value
    assert redundancy["parameter"] == ik.get_solver(robot).parameter
    expected = ik.analytic(robot, robot.fk(Q0[name]), redundancy=value)
    assert [row["branch"] for row in result["solutions"]] == [
        s.branch for s in expected
    ]
    for row, solution in zip(result["solutions"], expected, strict=True):
        assert row["index"] == solution.index
        np.testing.assert_array_equal(row["q"], solution.q)
        for key in (
            "within_limits",
            "shoulder_singular",
            "elbow_singular",
            "wrist_singular",
            "parameter_singular",
        ):
            assert row[key] == getattr(solution, key)
        assert row["residual"] < ATOL_RESIDUAL
    # Q0 itself is one of them
    assert min(_wrapped(np.array(r["q"]), Q0[name]) for r in result["solutions"]) < 1e-9
    # without --all: the one ik.select chooses at that value
    code, out, err = _ik(capsys, name, "--redundancy", repr(value), "--json")
    (row,) = json.loads(out)["solutions"]
    choice = ik.select(robot, robot.fk(Q0[name]), redundancy=value)
    assert row["branch"] == choice.branch and row["q"] == to_json_ready(choice.q)


@pytest.mark.parametrize("name", ROBOTS)
def test_degrees_give_the_same_value(capsys, name) -> None:
    robot = load_robot(name)
    value = float(ik.get_solver(robot).parameter_of(Q0[name]))
    code, out, _ = _ik(
        capsys, name, "--redundancy", repr(math.degrees(value)), "--deg", "--json"
    )
    assert code == 0
    assert abs(json.loads(out)["redundancy"]["value"] - value) < ATOL_VALUE
    code, text, _ = _ik(
        capsys, name, "--redundancy", repr(math.degrees(value)), "--deg"
    )
    assert code == 0 and f"{math.degrees(value):.3f}°" in text and "(given)" in text


@pytest.mark.parametrize("name", ROBOTS)
def test_without_a_value_the_choice_is_said(capsys, name) -> None:
    robot = load_robot(name)
    choice = ik.choose_redundancy(robot, robot.fk(Q0[name]))
    code, out, _ = _ik(capsys, name, "--json")
    assert code == 0
    redundancy = json.loads(out)["redundancy"]
    assert redundancy["source"] == "chosen"
    assert redundancy["criterion"] == "limit_margin" == choice.criterion
    assert redundancy["value"] == choice.value and redundancy["score"] == choice.score
    code, text, _ = _ik(capsys, name)
    assert code == 0 and "(chosen: limit_margin" in text


def test_criterion_manipulability(capsys) -> None:
    robot = load_robot("iiwa14")
    choice = ik.choose_redundancy(
        robot, robot.fk(Q0["iiwa14"]), criterion="manipulability"
    )
    code, out, _ = _ik(capsys, "iiwa14", "--criterion", "manipulability", "--json")
    assert code == 0
    assert json.loads(out)["redundancy"]["value"] == choice.value


@pytest.mark.parametrize("name", ROBOTS)
def test_feasible_intervals_are_the_library_s(capsys, name) -> None:
    robot = load_robot(name)
    feasible = ik.get_solver(robot).feasible(robot.fk(Q0[name]))
    code, out, _ = _ik(capsys, name, "--feasible", "--json")
    assert code == 0
    printed = json.loads(out)["feasible_redundancy"]
    assert printed["parameter"] == feasible.parameter
    assert printed["range"] == list(feasible.range)
    assert printed["union"] == [list(i) for i in feasible.union]
    assert printed["circular"] is (name == "iiwa14")
    assert list(printed["branches"]) == list(feasible.branches)
    for label, intervals in zip(feasible.branches, feasible.intervals, strict=True):
        assert printed["branches"][label] == [list(i) for i in intervals]
    code, text, _ = _ik(capsys, name, "--feasible")
    assert code == 0 and f"feasible {feasible.parameter}: [" in text


def _gap(name: str) -> float:
    """A value of the parameter inside its range where no branch is within limits."""
    robot = load_robot(name)
    feasible = ik.get_solver(robot).feasible(robot.fk(Q0[name]))
    lo, hi = feasible.range
    edges = [lo, *(x for interval in feasible.union for x in interval), hi]
    gaps = [
        (a, b) for a, b in zip(edges[::2], edges[1::2], strict=True) if b - a > 0.02
    ]
    assert gaps, f"{name}: the test pose is feasible over the whole range"
    a, b = max(gaps, key=lambda g: g[1] - g[0])
    return 0.5 * (a + b)


@pytest.mark.parametrize("name", ROBOTS)
def test_infeasible_value_exits_3_with_the_intervals(capsys, name) -> None:
    robot = load_robot(name)
    parameter = ik.get_solver(robot).parameter
    value = _gap(name)
    code, out, err = _ik(capsys, name, "--redundancy", repr(value))
    assert code == 3 and out == ""
    assert len(err.strip().splitlines()) == 1
    assert f"feasible {parameter}" in err or "feasible" in err
    code, out, err = _ik(capsys, name, "--redundancy", repr(value), "--json")
    result = json.loads(out)
    assert code == 3 and result["feasible"] is False and "feasible" in result["error"]


def test_all_prints_branches_outside_the_limits(capsys) -> None:
    value = _gap("iiwa14")
    robot = load_robot("iiwa14")
    reached = ik.analytic(robot, robot.fk(Q0["iiwa14"]), redundancy=value)
    code, out, _ = _ik(capsys, "iiwa14", "--redundancy", repr(value), "--all", "--json")
    assert code == 0
    rows = json.loads(out)["solutions"]
    assert len(rows) == len(reached) and not any(r["within_limits"] for r in rows)


@pytest.mark.parametrize(
    "options",
    [
        ("--redundancy", "0.3"),
        ("--feasible",),
        ("--deg",),
        ("--criterion", "limit_margin"),
    ],
)
def test_redundancy_options_on_a_six_axis_arm_exit_2(capsys, options) -> None:
    matrix = [
        repr(float(x)) for x in load_robot("ur5").fk(np.zeros(6)).homogeneous.ravel()
    ]
    code, out, err = run(capsys, "ik", "--robot", "ur5", "--matrix", *matrix, *options)
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and "no redundancy" in err


def test_criterion_with_a_value_exits_2(capsys) -> None:
    code, _, err = _ik(
        capsys, "iiwa14", "--redundancy", "0.1", "--criterion", "manipulability"
    )
    assert code == 2 and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("value", ["1001", "-1e308", "57300"])
def test_huge_values_exit_2(capsys, value) -> None:
    unit = ["--deg"] if value == "57300" else []  # 57300° > 1000 rad
    code, out, err = _ik(capsys, "iiwa14", "--redundancy", value, *unit)
    assert code == 2 and out == "" and "at most 1000 rad" in err
