"""OMPL's planners through the compiled checker: ``plan(..., planner="ompl:NAME")``.

Every planner of :data:`OMPL_PLANNERS` on the Puma's wall (the planner tests'
problem) and the first-solution ones on a MotionBenchMaker Panda problem
(``tests/data/motionbenchmaker``), each path certified on the spheres and
checked on the exact meshes; the optimal planners' paths against
RRT-Connect's; seeds; errors.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import workbench as wb
from benchmarks._motionbenchmaker import ACCELERATION_LIMITS
from workbench.collision import read_scene
from workbench.collision.scene import Obstacle, Scene
from workbench.errors import InputError
from workbench.motion import (
    OMPL_PLANNERS,
    OPTIMAL_PLANNERS,
    PLANNERS,
    SphereChecker,
    plan,
    read_request,
    spherize,
)
from workbench.paper_data import ANGELES_PICK_Q_DEG, ANGELES_PLACE_Q_DEG

pytest.importorskip("ompl")

MBM = Path(__file__).parent / "data" / "motionbenchmaker" / "panda"
PICK, PLACE = np.radians(ANGELES_PICK_Q_DEG), np.radians(ANGELES_PLACE_Q_DEG)
#: Budget [s] of a first-solution planner (it stops at its first path).
FIRST_SOLUTION_BUDGET = 10.0
#: Budget [s] of an optimal planner (it runs to the end of it).
OPTIMAL_BUDGET = 1.0
#: Optimal planners that stop when their batch of samples is done.
BATCH_PLANNERS = ("FMT", "BFMT")
#: Relative excess [-] allowed over RRT-Connect's shortened path length.
LENGTH_RTOL = 0.05
FIRST_SOLUTION = [name for name in OMPL_PLANNERS if name not in OPTIMAL_PLANNERS]
#: Not on the Panda problem: plain RRT extends toward the goal from the node
#: nearest to it, which from seed 0 stays behind the table (no path in 10 s).
ON_THE_PANDA = [name for name in FIRST_SOLUTION if name != "RRT"]


def _budget(name: str) -> float:
    if name in OPTIMAL_PLANNERS and name not in BATCH_PLANNERS:
        return OPTIMAL_BUDGET
    return FIRST_SOLUTION_BUDGET


def _length(path: np.ndarray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))


@pytest.fixture(scope="module")
def puma() -> wb.Robot:
    return wb.load_robot("puma560").with_limits(acceleration_limit=np.full(6, 4.0))


@pytest.fixture(scope="module")
def puma_spheres(puma: wb.Robot):
    return spherize(puma)


@pytest.fixture(scope="module")
def wall(puma: wb.Robot) -> Scene:
    """A 10 cm box on the straight joint path from the pick to the place."""
    middle = puma.fk(0.5 * (PICK + PLACE)).translation
    box = Obstacle("wall", "box", (0.1, 0.1, 0.1), pin.SE3(np.eye(3), middle))
    return Scene("wall", (box,))


@pytest.fixture(scope="module")
def panda_problem():
    robot = wb.load_robot(MBM / "panda.urdf").with_limits(
        acceleration_limit=ACCELERATION_LIMITS["panda"]
    )
    scene = read_scene(MBM / "table_pick_scene0001.yaml")
    start, goal = read_request(MBM / "table_pick_request0001.yaml", robot)
    return robot, spherize(robot), scene, start, goal


def _assert_certified_and_exact(result, spheres, scene, start, goal) -> None:
    assert result.solved and result.reason is None, result.detail
    assert result.clearance is not None and result.clearance.collision_free
    assert result.clearance.lower_bound > 0 and result.min_clearance > 0
    np.testing.assert_array_equal(result.waypoints[0], start)
    np.testing.assert_array_equal(result.waypoints[-1], goal)
    checker = SphereChecker(spheres, scene, **_allowance(result, spheres, scene))
    for a, b in zip(result.waypoints[:-1], result.waypoints[1:], strict=True):
        assert checker.is_segment_free(a, b)


def _allowance(result, spheres, scene) -> dict[str, np.ndarray]:
    """The allowances plan() used, from ``result.allowances``."""
    checker = SphereChecker(spheres, scene)
    links, obstacles = checker.links, [o.name for o in scene.obstacles]
    pairs = list(checker.pairs)
    allowance = np.zeros(len(links) + len(pairs))
    by_obstacle = np.zeros((len(links), len(obstacles)))
    for a, b, metres in result.allowances:
        if (a, b) in pairs:
            allowance[len(links) + pairs.index((a, b))] = metres
        else:
            by_obstacle[links.index(a), obstacles.index(b)] = metres
    return {"allowance": allowance, "obstacle_allowance": by_obstacle}


def test_the_planners_are_offered_and_exist_in_the_wheel() -> None:
    from ompl import geometric

    assert set(OPTIMAL_PLANNERS) < set(OMPL_PLANNERS)
    assert PLANNERS == ("rrtconnect", *(f"ompl:{n}" for n in OMPL_PLANNERS))
    for name in OMPL_PLANNERS:
        assert callable(getattr(geometric, name))


@pytest.mark.parametrize("name", OMPL_PLANNERS)
def test_every_planner_goes_around_the_wall(puma, puma_spheres, wall, name) -> None:
    result = plan(
        puma,
        wall,
        PICK,
        PLACE,
        planner=f"ompl:{name}",
        time_limit=_budget(name),
        spheres=puma_spheres,
    )
    _assert_certified_and_exact(result, puma_spheres, wall, PICK, PLACE)
    assert result.iterations > 0  # the vertices of the planner's graph


@pytest.mark.parametrize("name", ON_THE_PANDA)
def test_first_solution_planners_solve_a_motionbenchmaker_problem(
    panda_problem, name
) -> None:
    robot, spheres, scene, start, goal = panda_problem
    result = plan(
        robot,
        scene,
        start,
        goal,
        planner=f"ompl:{name}",
        time_limit=FIRST_SOLUTION_BUDGET,
        spheres=spheres,
    )
    _assert_certified_and_exact(result, spheres, scene, start, goal)
    assert result.planning_time < FIRST_SOLUTION_BUDGET  # it stopped at a path


def test_a_goal_set_reaches_one_of_its_goals(puma, puma_spheres, wall) -> None:
    goals = np.array([PLACE, 0.5 * (PICK + PLACE) + 0.6])
    goals = np.clip(goals, puma.lower, puma.upper)
    result = plan(
        puma,
        wall,
        PICK,
        goals,
        planner="ompl:RRTConnect",
        time_limit=FIRST_SOLUTION_BUDGET,
        spheres=puma_spheres,
    )
    assert result.solved
    assert any(np.array_equal(result.waypoints[-1], q) for q in goals)


def test_optimal_planners_are_no_longer_than_rrtconnect(
    puma, puma_spheres, wall
) -> None:
    """After the same shortcuts; in 0.5-1 s behind the Python callback their raw
    paths are not shorter than RRT-Connect's greedy one on this problem."""

    def length(name: str) -> float:
        result = plan(
            puma,
            wall,
            PICK,
            PLACE,
            planner=f"ompl:{name}",
            time_limit=_budget(name),
            spheres=puma_spheres,
            verify=False,
        )
        assert result.solved, (name, result.detail)
        return result.path_length

    first = length("RRTConnect")
    for name in OPTIMAL_PLANNERS:
        assert length(name) <= (1.0 + LENGTH_RTOL) * first, name


@pytest.mark.parametrize("name", ["RRTConnect", "RRT", "KPIECE1", "FMT"])
def test_a_seed_gives_the_same_path(puma, puma_spheres, wall, name) -> None:
    def waypoints(seed: int) -> np.ndarray:
        return plan(
            puma,
            wall,
            PICK,
            PLACE,
            planner=f"ompl:{name}",
            seed=seed,
            time_limit=FIRST_SOLUTION_BUDGET,
            spheres=puma_spheres,
            verify=False,
        ).waypoints

    first = waypoints(3)
    np.testing.assert_array_equal(first, waypoints(3))
    others = [waypoints(seed) for seed in (4, 5)]
    assert any(o.shape != first.shape or not np.array_equal(o, first) for o in others)


def test_unknown_planners_are_refused_with_the_names(puma, wall) -> None:
    with pytest.raises(InputError, match=r"unknown OMPL planner 'Nope'.*ompl:RRTstar"):
        plan(puma, wall, PICK, PLACE, planner="ompl:Nope")
    with pytest.raises(InputError, match="unknown planner 'RRTstar'; rrtconnect or"):
        plan(puma, wall, PICK, PLACE, planner="RRTstar")


def test_without_ompl_the_error_names_the_extra(puma, wall, monkeypatch) -> None:
    for module in [m for m in sys.modules if m == "ompl" or m.startswith("ompl.")]:
        monkeypatch.delitem(sys.modules, module)
    monkeypatch.setitem(sys.modules, "ompl", None)  # import ompl raises ImportError
    with pytest.raises(InputError, match=r"kinematics-workbench\[ompl\]"):
        plan(puma, wall, PICK, PLACE, planner="ompl:RRTConnect")
