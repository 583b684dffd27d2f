"""MotionBenchMaker problem sets and many motions: found, judged, planned, summarised.

The problems are MotionBenchMaker's own (``tests/data/motionbenchmaker``,
provenance there), read from the flat folder, from a ``problems.tar.bz2`` in
MotionBenchMaker's layout written here from them, and from a tarball laid out
as the ``vamp-planner`` sdist; the robot is MotionBenchMaker's Panda (its
meshes and SRDF). The cluster test runs a real Dask scheduler and two workers.
"""

from __future__ import annotations

import io
import math
import tarfile
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from tests._dask_cluster import start_cluster
from workbench import load_robot
from workbench.collision import CollisionChecker, Obstacle, Scene
from workbench.errors import InputError
from workbench.motion import (
    Problem,
    ProblemResult,
    Validity,
    check_validity,
    find_problems,
    plan,
    plan_many,
    run_problem,
    run_problems,
    summarise,
)

DATA = Path(__file__).parent / "data" / "motionbenchmaker"
#: The Franka datasheet's acceleration limits [rad/s²] (the URDF has none).
PANDA_ACCELERATION = (15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0)
#: Copies of one problem, as several indices of MotionBenchMaker's layout.
INDICES = (2, 1, 10)
#: Joint-space agreement of two runs of the same seed [rad].
ATOL_SAME_RUN = 1e-12


@pytest.fixture(scope="module")
def panda():
    return load_robot(DATA / "panda" / "panda.urdf").with_limits(
        acceleration_limit=PANDA_ACCELERATION
    )


def _add(archive: tarfile.TarFile, name: str, data: bytes) -> None:
    info = tarfile.TarInfo(name)
    info.size = len(data)
    archive.addfile(info, io.BytesIO(data))


def _problems_tarball(robot: str, scenarios: dict[str, str]) -> bytes:
    """``problems.tar.bz2`` of MotionBenchMaker's layout: ``problems/<s>_<robot>/``.

    ``scenarios`` maps a scenario to the flat file of ``tests/data`` it copies
    (at every index of :data:`INDICES`).
    """
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:bz2") as archive:
        for scenario, origin in scenarios.items():
            for index in INDICES:
                for kind in ("scene", "request"):
                    data = (DATA / robot / f"{origin}_{kind}0001.yaml").read_bytes()
                    name = f"problems/{scenario}_{robot}/{kind}{index:04d}.yaml"
                    _add(archive, name, data)
    return buffer.getvalue()


@pytest.fixture(scope="module")
def tarball(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("mbm") / "problems.tar.bz2"
    path.write_bytes(
        _problems_tarball("panda", {"cage": "cage", "table_pick": "table_pick"})
    )
    return path


def test_the_flat_folder_reads_in_motionbenchmakers_scenario_order() -> None:
    problems = find_problems(DATA / "panda")
    assert [(p.robot_name, p.scenario, p.index) for p in problems] == [
        ("panda", "table_pick", 1),
        ("panda", "bookshelf_thin", 1),
        ("panda", "cage", 1),
    ]
    assert all(
        p.request_path.endswith(f"{p.scenario}_request0001.yaml") for p in problems
    )
    ur5 = find_problems(DATA / "ur5", scenarios=["box", "bookshelf_tall"])
    assert [p.scenario for p in ur5] == ["box", "bookshelf_tall"]
    (cage,) = find_problems(DATA / "panda", robot_name="panda", scenarios=["cage"])
    assert [o.name for o in cage.scene.obstacles] and cage.request["start_state"]


def test_a_problems_tarball_reads_by_index_with_a_limit(tarball: Path) -> None:
    problems = find_problems(tarball, scenarios=["table_pick", "cage"])
    assert [(p.scenario, p.index) for p in problems] == [
        ("table_pick", 1),
        ("table_pick", 2),
        ("table_pick", 10),
        ("cage", 1),
        ("cage", 2),
        ("cage", 10),
    ]
    assert (
        problems[0].scene_path == f"{tarball}:problems/table_pick_panda/scene0001.yaml"
    )
    limited = find_problems(tarball, limit=1)
    assert [(p.scenario, p.index) for p in limited] == [("table_pick", 1), ("cage", 1)]
    flat = find_problems(DATA / "panda", scenarios=["cage"])[0]
    assert limited[1].request == flat.request
    assert [o.name for o in limited[1].scene.obstacles] == [
        o.name for o in flat.scene.obstacles
    ]


def test_the_unpacked_folder_reads_as_the_tarball(tarball: Path, tmp_path) -> None:
    with tarfile.open(tarball) as archive:
        archive.extractall(tmp_path, filter="data")
    (tmp_path / "problems" / "cage_panda" / "request0010.yaml").unlink()  # skipped
    problems = find_problems(tmp_path / "problems", limit=5)
    assert [(p.scenario, p.index) for p in problems] == [
        ("table_pick", 1),
        ("table_pick", 2),
        ("table_pick", 10),
        ("cage", 1),
        ("cage", 2),
    ]


def test_an_sdist_of_two_robots_needs_the_robots_name(tmp_path: Path) -> None:
    sdist = tmp_path / "vamp_planner-0.6.4.tar.gz"
    with tarfile.open(sdist, mode="w:gz") as archive:
        for robot, scenarios in (
            ("panda", {"table_pick": "table_pick"}),
            ("ur5", {"box": "box", "bookshelf_tall": "bookshelf_tall"}),
        ):
            data = _problems_tarball(robot, scenarios)
            _add(
                archive, f"vamp_planner-0.6.4/resources/{robot}/problems.tar.bz2", data
            )
        _add(archive, "vamp_planner-0.6.4/README.md", b"not a problem")
    with pytest.raises(
        InputError, match="holds problems of panda, ur5: name the robot"
    ):
        find_problems(sdist)
    ur5 = find_problems(sdist, robot_name="ur5", limit=2)
    assert [(p.robot_name, p.scenario, p.index) for p in ur5] == [
        ("ur5", "box", 1),
        ("ur5", "box", 2),
        ("ur5", "bookshelf_tall", 1),
        ("ur5", "bookshelf_tall", 2),
    ]
    assert [p.scenario for p in find_problems(sdist, robot_name="panda")] == [
        "table_pick"
    ] * len(INDICES)


def test_refusals(tmp_path: Path, tarball: Path) -> None:
    with pytest.raises(InputError, match="no such problem set"):
        find_problems(tmp_path / "missing.tar.bz2")
    with pytest.raises(InputError, match="no MotionBenchMaker problem"):
        find_problems(tmp_path)
    (tmp_path / "junk.tar.bz2").write_bytes(b"not a tarball")
    with pytest.raises(InputError, match="not a problem archive"):
        find_problems(tmp_path / "junk.tar.bz2")
    with pytest.raises(InputError, match="no problem for robot 'ur5'; it has panda"):
        find_problems(tarball, robot_name="ur5")
    with pytest.raises(InputError, match="no panda problem of scenario box; it has "
                       "table_pick, cage"):  # fmt: skip
        find_problems(tarball, scenarios=["box"])
    for bad in (0, True, 1.5):
        with pytest.raises(InputError, match="limit must be a positive integer"):
            find_problems(tarball, limit=bad)
    broken = tmp_path / "broken" / "panda"
    broken.mkdir(parents=True)
    (broken / "box_scene0001.yaml").write_text("world: [unclosed\n")
    (broken / "box_request0001.yaml").write_text("{}\n")
    with pytest.raises(InputError, match="not valid YAML"):
        find_problems(broken)


@pytest.mark.parametrize("scenario", ["table_pick", "bookshelf_thin", "cage"])
def test_the_panda_problems_are_valid_with_their_closest_pair(panda, scenario) -> None:
    (problem,) = find_problems(DATA / "panda", scenarios=[scenario])
    start, goal = problem.read_request(panda)
    checker = CollisionChecker(panda, problem.scene)
    validity = check_validity(panda, problem)
    assert validity.valid and validity.where == ""
    smallest = min(
        float(np.min(checker.compute_distances(start))),
        float(np.min(checker.compute_distances(goal))),
    )
    assert validity.distance == smallest > 0.0
    assert (validity.body_a, validity.body_b) in checker.body_pairs
    assert check_validity(panda, problem, checker=checker) == validity


def _blocked(panda, problem: Problem, end: str) -> Problem:
    """The problem with a box on the hand at its start or goal."""
    q = problem.read_request(panda)._asdict()[end]
    block = Obstacle(
        "block", "box", (0.05, 0.05, 0.05), pin.SE3(panda.fk(q, "panda_hand"))
    )
    scene = Scene("blocked", (*problem.scene.obstacles, block))
    return Problem(
        problem.robot_name, problem.scenario, problem.index, scene, problem.request,
        problem.scene_path, problem.request_path,
    )  # fmt: skip


def test_an_invalid_problem_is_judged_and_not_planned(panda) -> None:
    (problem,) = find_problems(DATA / "panda", scenarios=["table_pick"])
    validity = check_validity(panda, _blocked(panda, problem, "goal"))
    assert not validity.valid and validity.where == "goal"
    assert validity.body_b == "block" and validity.body_a.startswith("panda_")
    assert validity.distance < 0.0
    result = run_problem(panda, _blocked(panda, problem, "start"))
    assert result.validity.where == "start" and not result.solved
    assert result.reason == "invalid: start in collision"
    assert result.detail.endswith("touches block at the start")
    assert result.planning_time == 0.0 and result.contacts is None
    assert math.isnan(result.path_length)


def test_a_problem_is_planned_and_proven_free_on_the_exact_meshes(panda) -> None:
    (problem,) = find_problems(DATA / "panda", scenarios=["table_pick"])
    result = run_problem(panda, problem, seed=3, time_limit=5.0)
    assert isinstance(result, ProblemResult) and result.solved is True
    assert result.reason is None and result.contacts == 0 and result.seed == 3
    assert result.min_clearance > 0.0 and result.duration > 0.0
    assert result.verification_time > 0.0 and result.planning_time > 0.0
    assert result.total_time == result.planning_time + result.smoothing_time
    start, goal = problem.read_request(panda)
    direct = plan(panda, problem.scene, start, goal, seed=3, time_limit=5.0)
    assert result.path_length == pytest.approx(direct.path_length, abs=ATOL_SAME_RUN)
    posed = run_problem(
        panda, problem, seed=3, time_limit=5.0, pose_goal=True, verify=False
    )
    assert posed.solved and posed.contacts is None and math.isnan(posed.min_clearance)


def test_plan_many_is_plan_of_each_request_in_order(panda) -> None:
    problems = find_problems(DATA / "panda", scenarios=["bookshelf_thin", "table_pick"])
    requests = [(p.scene, *p.read_request(panda)) for p in problems]
    seen = []
    plans = plan_many(
        panda, requests, seed=5, time_limit=5.0, verify=False,
        progress=lambda done, total: seen.append((done, total)),
    )  # fmt: skip
    assert seen == [(1, 2), (2, 2)]
    for (scene, start, goal), got in zip(requests, plans, strict=True):
        alone = plan(panda, scene, start, goal, seed=5, time_limit=5.0, verify=False)
        assert got.solved and alone.solved
        np.testing.assert_allclose(got.waypoints, alone.waypoints, atol=ATOL_SAME_RUN)
    with pytest.raises(InputError, match="request 0 must be a"):
        plan_many(panda, [(None, requests[0][1])])


def _result(
    scenario: str, valid: bool, solved: bool, t: float, contacts
) -> ProblemResult:
    validity = Validity(
        valid, "" if valid else "start", "a", "b", 0.01 if valid else -0.01
    )
    return ProblemResult(
        scenario, 1, validity, solved, None if solved else "time limit", "",
        0.0, t, t / 10, 2 * t, 0, 1.0, 1.0, contacts, 0.01, 0,
    )  # fmt: skip


def test_summarise_counts_and_times_per_scenario_then_all() -> None:
    results = [
        _result("box", True, True, 1.0, 0),
        _result("box", True, True, 3.0, 2),
        _result("box", False, False, 0.0, None),
        _result("cage", True, False, 1.0, None),
        _result("cage", True, True, 5.0, 0),
    ]
    box, cage, every = summarise(results)
    assert (box.scenario, box.problems, box.valid, box.solved) == ("box", 3, 2, 2)
    assert box.planning_median == pytest.approx(2.0, abs=ATOL_SAME_RUN)
    assert box.planning_p95 == pytest.approx(2.9, abs=ATOL_SAME_RUN)
    assert box.planning_max == 3.0
    assert box.total_median == pytest.approx(2.2, abs=ATOL_SAME_RUN)
    assert box.verification_median == pytest.approx(4.0, abs=ATOL_SAME_RUN)
    assert (box.verified, box.with_contacts, box.contacts) == (2, 1, 2)
    assert (cage.valid, cage.solved, cage.planning_median) == (2, 1, 5.0)
    assert (every.scenario, every.problems, every.valid, every.solved) == (
        "all",
        5,
        4,
        3,
    )
    assert every.planning_median == 3.0
    (empty,) = summarise([_result("x", True, False, 1.0, None)][:0])
    assert empty.problems == 0 and math.isnan(empty.planning_median)


def test_a_bad_scheduler_is_refused_before_any_plan(panda) -> None:
    problems = find_problems(DATA / "panda", scenarios=["table_pick"])
    with pytest.raises(InputError, match="is not tcp://HOST:PORT"):
        run_problems(panda, problems, scheduler="nowhere")
    with pytest.raises(InputError, match="cannot reach the Dask scheduler"):
        run_problems(panda, problems, scheduler="tcp://127.0.0.1:9")


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_dask_cluster_gives_the_results_of_this_process(
    panda, tarball, tmp_path
) -> None:
    problems = find_problems(tarball, scenarios=["table_pick"])
    problems += find_problems(DATA / "panda", scenarios=["bookshelf_thin"])
    options = {"seed": 2, "time_limit": 5.0, "verify": False}
    here = run_problems(panda, problems, **options)
    with start_cluster(tmp_path, workers=2) as address:
        seen = []
        there = run_problems(
            panda, problems, **options, scheduler=address,
            progress=lambda done, total: seen.append((done, total)),
        )  # fmt: skip
        requests = [(p.scene, *p.read_request(panda)) for p in problems[-2:]]
        plans = plan_many(panda, requests, **options, scheduler=address)
    assert sorted(seen) == [(k, len(problems)) for k in range(1, len(problems) + 1)]
    assert [(r.scenario, r.index) for r in there] == [
        (p.scenario, p.index) for p in problems
    ]
    for a, b in zip(here, there, strict=True):
        assert a.solved and b.solved and a.validity == b.validity
        assert b.path_length == pytest.approx(a.path_length, abs=ATOL_SAME_RUN)
        assert b.iterations == a.iterations
    for (scene, start, goal), got in zip(requests, plans, strict=True):
        alone = plan(panda, scene, start, goal, **options)
        np.testing.assert_allclose(got.waypoints, alone.waypoints, atol=ATOL_SAME_RUN)
