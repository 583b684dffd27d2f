"""``workbench motion bench``: the table, JSON, exit codes, sources and refusals.

On MotionBenchMaker's Panda and problems of ``tests/data/motionbenchmaker``
(provenance there), read from the flat folder and from a ``problems.tar.bz2``
written from them.
"""

from __future__ import annotations

import json
import shutil
import tarfile
from pathlib import Path

import pytest

from tests.conftest import run_cli as run
from workbench.cli import EXIT_BAD_INPUT, EXIT_INFEASIBLE

DATA = Path(__file__).parent / "data" / "motionbenchmaker" / "panda"
ROBOT = (
    "--robot", str(DATA / "panda.urdf"),
    "--acceleration-limit", "15", "7.5", "10", "12.5", "15", "20", "20",
)  # fmt: skip
BENCH = ("motion", "bench")


def test_prints_the_table_per_scenario_and_exits_0(capsys) -> None:
    code, out, err = run(
        capsys, *BENCH, str(DATA), *ROBOT, "--scenario", "table_pick", "--seed", "4"
    )
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0] == (
        f"panda: 1 problems of {DATA}, rrtconnect, seed 4, time limit 1 s"
    )
    assert lines[1].split()[:3] == ["scenario", "valid", "solved"]
    row = lines[2].split()
    assert row[:3] == ["table_pick", "1/1", "1/1"]
    assert row[-3:] == ["0", "of", "1"]  # no contact on the exact meshes
    assert lines[3].split()[:3] == ["all", "1/1", "1/1"] and len(lines) == 4


def test_json_has_the_summary_and_each_problem(capsys) -> None:
    code, out, err = run(
        capsys, *BENCH, str(DATA), *ROBOT, "--scenario", "table_pick",
        "--scenario", "bookshelf_thin", "--no-verify", "--time-limit", "5", "--json",
    )  # fmt: skip
    assert code == 0, err
    keys = json.loads(out)
    assert keys["robot_name"] == "panda" and keys["all_solved"] is True
    assert keys["verified"] is False and keys["scheduler"] is None
    assert keys["planner"] == "rrtconnect"
    assert [s["scenario"] for s in keys["summary"]] == [
        "table_pick",
        "bookshelf_thin",
        "all",
    ]
    every = keys["summary"][-1]
    assert (every["problems"], every["valid"], every["solved"]) == (2, 2, 2)
    assert every["verified"] == 0 and every["verification_median"] is None
    first = keys["problems"][0]
    assert (first["scenario"], first["index"], first["solved"]) == (
        "table_pick",
        1,
        True,
    )
    assert first["validity"]["valid"] is True and first["contacts"] is None
    assert first["min_clearance"] is None  # NaN (not checked) as null
    assert first["planning_time"] > 0.0 and first["path_length"] > 0.0


def test_ompl_planners_run_the_set_through_the_same_checker(capsys) -> None:
    """``--planner ompl:RRTConnect``: solved, verified, named in the JSON."""
    pytest.importorskip("ompl")
    code, out, err = run(
        capsys, *BENCH, str(DATA), *ROBOT, "--scenario", "table_pick",
        "--planner", "ompl:RRTConnect", "--time-limit", "5", "--json",
    )  # fmt: skip
    assert code == 0, err
    keys = json.loads(out)
    assert keys["planner"] == "ompl:RRTConnect" and keys["all_solved"] is True
    every = keys["summary"][-1]
    assert (every["solved"], every["verified"], every["with_contacts"]) == (1, 1, 0)


def test_an_unsolved_valid_problem_exits_3(capsys, tmp_path: Path) -> None:
    archive = tmp_path / "problems.tar.bz2"
    with tarfile.open(archive, mode="w:bz2") as tar:
        for kind in ("scene", "request"):
            tar.add(
                DATA / f"bookshelf_thin_{kind}0001.yaml",
                f"problems/bookshelf_thin_panda/{kind}0007.yaml",
            )
    code, out, err = run(
        capsys, *BENCH, str(archive), *ROBOT, "--iteration-limit", "1", "--no-verify"
    )
    assert code == EXIT_INFEASIBLE
    assert "bookshelf_thin  1/1    0/1" in out
    assert "unsolved: bookshelf_thin 7: iteration limit" in out
    assert err.splitlines()[-1] == ("workbench: error: 1 of 1 valid problems unsolved")


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (("--scenario", "box"), "no panda problem of scenario box"),
        (("--limit", "0"), "--limit"),
        (("--scheduler", "nowhere"), "is not tcp://HOST:PORT"),
        (("--robot-name", "ur5"), "no problem for robot 'ur5'; it has panda"),
        (("--planner", "ompl:Nope"), "unknown planner 'ompl:Nope'"),
    ],
)
def test_bad_input_exits_2_with_one_line(capsys, argv, fragment) -> None:
    code, out, err = run(capsys, *BENCH, str(DATA), *ROBOT, *argv)
    assert (code, out) == (EXIT_BAD_INPUT, "") and fragment in err, err
    assert "Traceback" not in err


def test_a_robot_of_another_name_is_named_with_robot_name(capsys, tmp_path) -> None:
    robot = tmp_path / "franka"
    shutil.copytree(DATA, robot, ignore=shutil.ignore_patterns("*.yaml"))
    (robot / "panda.urdf").rename(robot / "franka.urdf")
    other = ("--robot", str(robot / "franka.urdf"), *ROBOT[2:])
    code, out, err = run(capsys, *BENCH, str(DATA), *other, "--scenario", "cage")
    assert (code, out) == (EXIT_BAD_INPUT, "")
    assert (
        "no problem for robot 'franka'; it has panda (name it with --robot-name)" in err
    )
    code, out, err = run(
        capsys, *BENCH, str(DATA), *other, "--robot-name", "panda",
        "--scenario", "table_pick", "--no-verify",
    )  # fmt: skip
    assert code == 0, err
    code, out, err = run(capsys, *BENCH, str(tmp_path / "none"), *ROBOT)
    assert (code, out) == (EXIT_BAD_INPUT, "") and "no such problem set" in err
