"""benchmarks/bench_motion.py (and its _motionbenchmaker, _motion_peers) on tests/data.

The exact check of a trajectory (MotionBenchMaker's Panda, provenance in
``tests/data/motionbenchmaker``; the problem reader and the validity check are
the package's, tested in ``test_motion_batch.py``), the statistics and the
tables; VAMP and OMPL on one problem where they are installed.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from benchmarks._motion_peers import (
    WorkbenchPeer,
    check_polyline,
    check_trajectory,
    get_workbench_plan,
    path_length,
)
from benchmarks._motionbenchmaker import ACCELERATION_LIMITS, get_sdist
from benchmarks.bench_motion import format_tables, run_robot, summarise
from workbench import load_robot
from workbench.collision import CollisionChecker, Obstacle, Scene
from workbench.motion import Problem, find_problems, time_scale, verify_trajectory

DATA = Path(__file__).parent / "data" / "motionbenchmaker"
MBM_PANDA = DATA / "panda" / "panda.urdf"
#: Exact arithmetic of a few sums [rad].
ATOL_EXACT = 1e-12


@pytest.fixture(scope="module")
def panda():
    return load_robot(MBM_PANDA).with_limits(
        acceleration_limit=ACCELERATION_LIMITS["panda"]
    )


def _read(problem: Problem, robot):
    start, goal = problem.read_request(robot)
    return problem.scene, start, goal


def test_a_trajectory_is_checked_at_quarter_degree_steps(panda) -> None:
    (problem,) = find_problems(DATA / "panda", scenarios=["table_pick"])
    start = _read(problem, panda)[1]
    turn = np.zeros(panda.nq)
    turn[0] = np.deg2rad(40.0)  # the first joint only: within its limits
    trajectory = time_scale(panda, [start, start + turn])
    free = CollisionChecker(panda, Scene("empty"))
    report = check_trajectory(free, trajectory)
    assert report["samples"] >= 40.0 / 0.25
    assert report["contacts"] == 0 and report["verify_lower_bound"] > 0.0
    assert report["duration"] == trajectory.duration and report["verify_time"] > 0.0
    hand = panda.fk(start + turn / 2, "panda_hand")
    block = Obstacle("block", "box", (0.05, 0.05, 0.05), pin.SE3(hand))
    blocked = check_trajectory(
        CollisionChecker(panda, Scene("b", (block,))), trajectory
    )
    assert blocked["contacts"] >= 1 and blocked["verify_min_clearance"] < 0.0
    assert all(p.endswith(" – block") for p in blocked["contact_pairs"])


def test_path_length_sums_euclidean_segments() -> None:
    path = np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 5.0]])
    assert math.isclose(path_length(path), 6.0, abs_tol=ATOL_EXACT)


def _run(solved: bool, plan: float, simplify: float, length: float, **extra):
    return {
        "solved": solved,
        "planning_time": plan,
        "simplification_time": simplify,
        "length": length,
        "extra": extra,
    }


def _records() -> list[dict]:
    valid = {"valid": True, "where": "", "body_a": "a", "body_b": "b", "distance": 0.1}
    out = []
    for k in range(4):
        out.append(
            {
                "scenario": "cage" if k < 2 else "box",
                "index": k + 1,
                "valid": valid,
                "vamp_valid": True,
                "vamp": _run(True, 1e-4 * (k + 1), 1e-4, 2.0),
                "ompl": _run(k != 3, 1e-2 * (k + 1), 1e-3, 3.0),
            }
        )
    out.append(
        {
            "scenario": "box",
            "index": 9,
            "valid": {**valid, "valid": False, "where": "goal", "distance": -0.002},
            "vamp_valid": False,
        }
    )
    return out


def test_the_statistics_count_solved_problems_and_ratios() -> None:
    records = _records()
    vamp, ompl = summarise(records, "vamp"), summarise(records, "ompl")
    assert vamp is not None and ompl is not None
    assert (vamp["tried"], vamp["solved"]) == (4, 4)  # the invalid one: not tried
    assert (ompl["tried"], ompl["solved"]) == (4, 3)
    assert math.isclose(vamp["plan_median"], 2.5e-4, rel_tol=1e-12)
    assert math.isclose(ompl["plan_max"], 3e-2, rel_tol=1e-12)
    assert math.isclose(ompl["total_median"], 2.1e-2, rel_tol=1e-12)
    assert math.isclose(ompl["length_ratio"], 1.5, rel_tol=1e-12)
    assert summarise(records, "workbench") is None


def test_the_tables_list_the_counts_and_the_invalid_problem() -> None:
    text = format_tables(
        {"robot": "panda", "reference_us": [20.0, 21.0], "problems": _records()}, 1.0
    )
    assert "| cage | 2/2 | 2/2 | VAMP | 2/2 |" in text
    assert "| box | 2/3 | 2/3 | VAMP | 2/2 |" in text
    assert "| all | 4/5 | 4/5 | VAMP | 4/4 |" in text
    assert "| | | OMPL (Python callback) | 1/2 |" in text
    assert "| box | 9 | goal | a – b | -2.00 mm |" in text
    assert "20.0 µs before" in text


def test_an_sdist_with_another_hash_is_refused(tmp_path: Path) -> None:
    fake = tmp_path / "vamp_planner-0.6.4.tar.gz"
    fake.write_bytes(b"not the release")
    with pytest.raises(SystemExit, match="SHA-256"):
        get_sdist(tmp_path, fake)
    with pytest.raises(SystemExit, match="SHA-256"):
        get_sdist(tmp_path)  # the cached copy is checked too


def test_vamp_and_ompl_solve_a_table_pick_problem(panda) -> None:
    pytest.importorskip("vamp")
    pytest.importorskip("ompl")
    from benchmarks._motion_peers import OmplPeer, VampPeer

    (problem,) = find_problems(DATA / "panda", scenarios=["table_pick"])
    scene, start, goal = _read(problem, panda)
    vamp = VampPeer("panda")
    order = [panda.joint_names.index(j) for j in vamp.joint_names]
    qs, qg = start[order].tolist(), goal[order].tolist()
    env = vamp.environment(scene, problem.scenario)
    assert vamp.valid(qs, env) and vamp.valid(qg, env)
    for run in (vamp.run(qs, qg, env), OmplPeer(vamp, 1.0).run(qs, qg, env)):
        assert run.solved
        assert run.length >= float(np.linalg.norm(np.subtract(qg, qs))) - 1e-5
        assert run.planning_time > 0.0 and run.simplification_time >= 0.0


@pytest.mark.slow  # plans and checks paths on the exact meshes: seconds
def test_a_robot_runs_from_a_resources_folder(tmp_path: Path) -> None:
    """MotionBenchMaker's layout, the planners that are installed, the tables."""
    resources = tmp_path / "resources"
    shutil.copytree(
        DATA / "panda", resources / "panda", ignore=shutil.ignore_patterns("*.yaml")
    )
    for scenario in ("table_pick", "cage"):
        folder = resources / "panda" / "problems" / f"{scenario}_panda"
        folder.mkdir(parents=True)
        for kind in ("scene", "request"):
            source = DATA / "panda" / f"{scenario}_{kind}0001.yaml"
            shutil.copy(source, folder / f"{kind}0001.yaml")
    planners = [p for p in ("vamp", "ompl") if importlib.util.find_spec("vamp")]
    args = argparse.Namespace(
        scenarios=["table_pick", "cage"],
        limit=None,
        planners=[*planners, "workbench", "workbench-ompl"],
        time_limit=1.0,
        verify=["workbench", "vamp"],
    )
    result = run_robot("panda", resources, args)
    assert [(r["scenario"], r["valid"]["valid"]) for r in result["problems"]] == [
        ("table_pick", True),
        ("cage", True),
    ]
    for record in result["problems"]:
        for key in planners:
            assert record[key]["solved"]
        if planners:  # VAMP's path, checked on the exact meshes
            assert record["vamp"]["extra"]["samples"] >= 2
            assert "verify_lower_bound" in record["vamp"]["extra"]
        assert ("workbench" in record) == (get_workbench_plan() is not None)
        if importlib.util.find_spec("ompl"):  # OMPL's RRTConnect, our checker
            ours_ompl = record["workbench_ompl"]
            assert ours_ompl["planning_time"] > 0.0
            if ours_ompl["solved"]:
                assert ours_ompl["extra"]["contacts"] == 0
    text = format_tables(result, 1.0)
    assert "| all | 2/2 |" in text


def test_the_tables_say_why_a_valid_problem_is_unsolved() -> None:
    records = _records()
    records[0]["vamp_valid"] = False  # VAMP's spheres disagree with the meshes
    records[0]["ompl"] = _run(False, 1e-6, math.nan, math.nan)
    text = format_tables(
        {"robot": "ur5", "reference_us": [20.0, 21.0], "problems": records}, 1.0
    )
    assert "| cage | 1 | 100.00 mm | a – b | True |" in text
    assert (
        "| OMPL (Python callback) | cage | 1 | start or goal invalid for VAMP's "
        "spheres |" in text
    )
    assert "| OMPL (Python callback) | box | 4 | no path after 40 ms |" in text


def test_a_polyline_is_checked_at_quarter_degree_steps(panda) -> None:
    (problem,) = find_problems(DATA / "panda", scenarios=["table_pick"])
    start = _read(problem, panda)[1]
    turn = np.zeros(panda.nq)
    turn[0] = np.deg2rad(20.0)
    path = np.array([start, start + turn, start + 2 * turn])
    free = check_polyline(CollisionChecker(panda, Scene("empty")), path)
    assert free["samples"] == 2 * 80 + 1  # 20° in steps of 0.25°
    assert free["contacts"] == 0 and free["verify_lower_bound"] > 0.0
    hand = panda.fk(start + 1.5 * turn, "panda_hand")
    block = Obstacle("block", "box", (0.05, 0.05, 0.05), pin.SE3(hand))
    blocked = check_polyline(CollisionChecker(panda, Scene("b", (block,))), path)
    assert blocked["contacts"] >= 1 and blocked["verify_min_clearance"] < 0.0
    assert all(p.endswith(" – block") for p in blocked["contact_pairs"])


@dataclass
class _Plan:
    """What ``motion.plan`` returns, as far as the benchmark reads it."""

    solved: bool
    reason: str | None
    waypoints: np.ndarray
    trajectory: object
    planning_time: float
    smoothing_time: float
    verification_time: float
    min_clearance: float
    clearance: object
    iterations: int
    detail: str = ""


def test_the_workbench_column_reads_a_plan_and_its_exact_check(panda) -> None:
    (problem,) = find_problems(DATA / "panda", scenarios=["table_pick"])
    scene, start, _ = _read(problem, panda)
    turn = np.zeros(panda.nq)
    turn[0] = np.deg2rad(10.0)
    waypoints = np.array([start, start + turn])
    trajectory = time_scale(panda, waypoints)
    checker = CollisionChecker(panda, scene)
    report = verify_trajectory(checker, trajectory)
    calls = []

    def plan(robot, scene_, q0, goal, *, seed, time_limit, verify):
        calls.append((seed, time_limit, verify))
        own = report if len(calls) == 1 else None  # then: checked by the bench
        return _Plan(True, None, waypoints, trajectory, 1e-3, 2e-4, 0.5, 0.01, own, 7)

    peer = WorkbenchPeer(plan, 0.5)
    first = peer.run(panda, scene, checker, start, start + turn, seed=3)
    second = peer.run(panda, scene, checker, start, start + turn, seed=3)
    assert calls[0] == (3, 0.5, True)
    assert first.solved and first.total_time == 1e-3 + 2e-4
    assert math.isclose(first.length, np.deg2rad(10.0), rel_tol=1e-12)
    assert first.extra["verify_time"] == 0.5  # the plan's own check, not redone
    assert second.extra["verify_time"] != 0.5
    for run in (first, second):
        assert run.extra["contacts"] == 0
        assert run.extra["samples"] == report.samples

    def refused(robot, scene_, q0, goal, *, seed, time_limit, verify):
        return _Plan(False, "time limit", np.zeros((0, 7)), None, 0.5, 0.0, 0.0,
                     math.nan, None, 99, "no connection")  # fmt: skip

    lost = WorkbenchPeer(refused, 0.5).run(panda, scene, checker, start, start, 0)
    assert not lost.solved and lost.extra["status"] == "time limit"
    assert "contacts" not in lost.extra
