"""Base placement: task poses, screening against a map, exact verification, CLI."""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path
from typing import ClassVar

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from workbench import ik, load_robot
from workbench.cli import main
from workbench.collision import Obstacle, Scene
from workbench.errors import InputError
from workbench.trajectory.csv_io import JointTrajectorySamples, write_trajectory_csv
from workbench.workspace._placement_screen import CandidateLattice, Screening
from workbench.workspace.grid import default_bounds
from workbench.workspace.measures import singularity_margin
from workbench.workspace.placement import (
    PlacementInfeasibleError,
    base_transform,
    follow_path,
    place_base,
)
from workbench.workspace.placement_check import PATH_STEP_MAX, PlacementEvaluator
from workbench.workspace.placement_region import default_region
from workbench.workspace.task_map import build_task_map
from workbench.workspace.task_poses import (
    TASK_QUAT_NORM_TOL,
    TaskPoseFileError,
    matrices_from_xyz_quat_xyzw,
    read_task_poses,
    task_poses_from_trajectory,
)

#: Agreement of the exact verification with an independent computation.
RTOL_DET = 1e-9
#: The map's margins are float32: the screening's and NumPy's differ by rounding.
RTOL_FLOAT32 = 1e-6
#: The map's singularity factors of the best branch.
FACTORS = ("shoulder", "elbow", "wrist")
ATOL_EXACT = 1e-12
#: The known base pose the tasks are made from (on the test lattices).
BASE = (0.3, -0.2, 0.0, math.radians(40.0))
#: Coarse lattice around BASE: 0.1 m, 20° yaw steps (40° is on it).
REGION = (0.1, 0.5, -0.4, 0.0)
RESOLUTION = 0.1
YAW_STEP = math.radians(20.0)


def _task(robot, rng, count=12, base=BASE):
    """FK of random in-limit configurations, seen from ``base`` in the world."""
    q = rng.uniform(robot.lower, robot.upper, size=(count, robot.nq))
    world = base_transform(*base)
    return np.array([world @ robot.fk(x).homogeneous for x in q]), q


@pytest.fixture(scope="module")
def coarse_map(puma):
    """A coarse map of the PUMA (10 cm, 64 orientations) over all heights."""
    return build_task_map(puma, [-1.5, 1.5], resolution=0.1, orientations=64)


def _write_task_csv(path: Path, poses: np.ndarray) -> Path:
    lines = ["x,y,z,qx,qy,qz,qw"]
    for pose in poses:
        quat = pin.Quaternion(pose[:3, :3]).coeffs()
        lines.append(",".join(repr(float(v)) for v in [*pose[:3, 3], *quat]))
    path.write_text("\n".join(lines) + "\n")
    return path


def test_known_base_is_found_and_verified_exactly(puma, rng, coarse_map):
    task, _ = _task(puma, rng)
    found = place_base(
        puma,
        task,
        region=REGION,
        yaw_step=YAW_STEP,
        resolution=RESOLUTION,
        map=coarse_map,
        top=1000,
    )
    assert all(p.all_reachable and p.missed == 0 for p in found)
    keys = {(round(p.x, 9), round(p.y, 9), round(p.yaw, 9)) for p in found}
    assert (BASE[0], BASE[1], round(BASE[3], 9)) in keys
    ranks = [p.rank_key() for p in found]
    assert ranks == sorted(ranks)


def _exact_reference(robot, task, row):
    """Missed poses and worst best-branch |det J| with ik.analytic and Pinocchio's J."""
    inverse = np.linalg.inv(base_transform(*row))
    missed, worst = 0, math.inf
    for pose in task:
        try:
            solutions = ik.analytic(robot, inverse @ pose)
        except ik.UnreachableError:
            solutions = []
        dets = [
            abs(np.linalg.det(robot.jacobian(s.q)))
            for s in solutions
            if s.within_limits
        ]
        if dets:
            worst = min(worst, max(dets))
        else:
            missed += 1
    return missed, worst


@pytest.mark.parametrize("name", ["puma560", "ur5"])
def test_exact_verification_matches_analytic_per_pose(name, rng):
    robot = load_robot(name)
    task, _ = _task(robot, rng, count=10)
    rows = np.array([BASE, (0.5, 0.1, 0.0, 1.0), (0.0, 0.0, 0.3, -2.0), (0.9, 0, 0, 0)])
    placements = PlacementEvaluator(robot, task, None, False).evaluate(rows)
    for row, placement in zip(rows, placements, strict=True):
        missed, worst = _exact_reference(robot, task, row)
        assert placement.missed == missed
        assert placement.all_reachable == (missed == 0)
        if math.isfinite(worst):
            np.testing.assert_allclose(
                placement.min_dexterity, worst, rtol=RTOL_DET, atol=0
            )
    assert placements[0].all_reachable


def test_screening_matches_nearest_grid_lookup(puma, rng, coarse_map):
    """The compiled lookup against the grid's own voxel and orientation indices."""
    task, _ = _task(puma, rng, count=6)
    lattice = CandidateLattice.make(REGION, 0.05, YAW_STEP, RESOLUTION)
    screening = Screening(coarse_map.grid, coarse_map.__getitem__, task, lattice)
    screening.rank(prune=False)
    grid = coarse_map.grid
    dexterity = coarse_map["dexterity"]
    for flat in rng.choice(math.prod(lattice.shape), size=25, replace=False):
        x, y, z, yaw = lattice.rows(np.array([flat]))[0]
        in_base = np.linalg.inv(base_transform(x, y, z, yaw)) @ task
        voxel = grid.voxel_index(in_base[:, :3, 3])
        quat = np.array([pin.Quaternion(p[:3, :3]).coeffs() for p in in_base])
        orientation = grid.orientation_index(quat)
        values = np.where(voxel >= 0, dexterity[voxel, orientation], np.nan)
        k, rest = divmod(int(flat), lattice.shape[1] * lattice.shape[2])
        assert screening.missed[k, rest] == np.count_nonzero(np.isnan(values))
        if not np.isnan(values).all():
            assert screening.worst_dexterity[k, rest] == np.nanmin(values)
            factors = [coarse_map[n][voxel, orientation] for n in FACTORS]
            margin = np.where(voxel >= 0, singularity_margin(*factors), np.nan)
            np.testing.assert_allclose(
                screening.worst_margin[k, rest],
                np.nanmin(margin[~np.isnan(values)]),
                rtol=RTOL_FLOAT32,
                atol=0,
            )


def test_nothing_reaches_raises_infeasible(puma, rng, coarse_map):
    task, _ = _task(puma, rng, count=5)
    with pytest.raises(PlacementInfeasibleError, match="misses 5 of 5") as info:
        place_base(
            puma,
            task,
            region=(5.0, 5.2, 5.0, 5.2),
            yaw_step=YAW_STEP,
            resolution=RESOLUTION,
            map=coarse_map,
        )
    assert info.value.best is not None and info.value.best.missed == 5


def test_mounts_are_each_verified(puma, rng):
    task, _ = _task(puma, rng, count=8)
    found = place_base(puma, task, mounts=[BASE, (3.0, 0.0, 0.0, 0.0)], top=5)
    assert len(found) == 1
    assert (found[0].x, found[0].y, found[0].yaw) == (BASE[0], BASE[1], BASE[3])


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"region": (1.0, 0.0, 0.0, 1.0)}, "max below min"),
        ({"region": (0, 1, 0, 1), "top": 0}, "top must be"),
        ({"region": (0, 1, 0, 1), "mounts": [BASE]}, "not both"),
        ({"region": (0, 1, 0, 1), "resolution": 0.0}, "resolution"),
    ],
)
def test_bad_arguments_raise_input_error(puma, rng, kwargs, message):
    task, _ = _task(puma, rng, count=2)
    with pytest.raises(InputError, match=message):
        place_base(puma, task, **kwargs)


def test_default_region_is_the_task_extent_widened_by_the_reach(puma, rng):
    task, _ = _task(puma, rng, count=5)
    region = default_region(puma, task, resolution=RESOLUTION)
    box = default_bounds(puma)
    reach = 0.5 * float(np.max(box[1, :2] - box[0, :2]))
    low, high = task[:, :2, 3].min(axis=0), task[:, :2, 3].max(axis=0)
    xmin, xmax, ymin, ymax = region
    assert xmin <= low[0] - reach and xmax >= high[0] + reach
    assert ymin <= low[1] - reach and ymax >= high[1] + reach
    assert max(xmax - high[0], low[0] - xmin) - reach < RESOLUTION
    for edge in region:  # on multiples of the resolution: the origin is a candidate
        assert abs(edge / RESOLUTION - round(edge / RESOLUTION)) < 1e-9
    rows = np.concatenate([task[:, :3, 3], np.tile([0, 0, 0, 1.0], (5, 1))], axis=1)
    assert default_region(puma, rows, resolution=RESOLUTION) == region


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"resolution": 0.0}, "resolution must be a finite number > 0"),
        ({"resolution": math.nan}, "resolution must be a finite number > 0"),
        ({"resolution": True}, "resolution must be a finite number > 0"),
    ],
)
def test_default_region_refuses_a_bad_resolution(puma, kwargs, message):
    with pytest.raises(InputError, match=message):
        default_region(puma, np.eye(4)[None], **kwargs)


def test_default_region_refuses_malformed_targets(puma):
    with pytest.raises(InputError, match="shape"):
        default_region(puma, np.zeros((2, 3)), resolution=RESOLUTION)


def test_place_base_without_a_region_searches_the_default_region(puma, rng, coarse_map):
    task, _ = _task(puma, rng, count=6)
    options = {"resolution": 0.2, "yaw_step": YAW_STEP, "map": coarse_map, "top": 3}
    region = default_region(puma, task, resolution=0.2)
    found = place_base(puma, task, **options)
    assert [p.as_dict() for p in found] == [
        p.as_dict() for p in place_base(puma, task, region=region, **options)
    ]


def test_map_of_another_robot_is_refused(puma, rng, coarse_map):
    class Other:
        grid = coarse_map.grid
        attrs: ClassVar = {"robot": "ur5", "tool_frame": "tool0", "sampled": False}

        def __getitem__(self, name):
            return coarse_map[name]

    task, _ = _task(puma, rng, count=2)
    with pytest.raises(InputError, match="map is of robot 'ur5'"):
        place_base(puma, task, region=REGION, map=Other())


def test_scene_in_the_world_frame(puma, rng):
    """An obstacle far away changes nothing; one enclosing the arm blocks every pose."""
    task, _ = _task(puma, rng, count=4)
    (free,) = place_base(puma, task, mounts=[BASE])
    far = Scene(
        "far",
        (
            Obstacle(
                "far",
                "box",
                (0.2, 0.2, 0.2),
                pin.SE3(np.eye(3), np.array([5.0, 5.0, 0.0])),
            ),
        ),
    )
    (same,) = place_base(puma, task, mounts=[BASE], scene=far)
    assert same == free
    world = pin.SE3(np.eye(3), np.array([BASE[0], BASE[1], 0.3]))
    cage = Scene("cage", (Obstacle("cage", "box", (3.0, 3.0, 3.0), world),))
    with pytest.raises(PlacementInfeasibleError, match="misses 4 of 4"):
        place_base(puma, task, mounts=[BASE], scene=cage)
    # a box at the world origin: around the arm's first links if it were in the
    # base frame, 2 m from a base at x = 2 m in the world frame
    at_origin = pin.SE3(np.eye(3), np.zeros(3))
    box = Scene("box", (Obstacle("box", "box", (0.3, 0.3, 0.3), at_origin),))
    away = (2.0, 0.0, 0.0, 0.0)
    task, _ = _task(puma, rng, count=4, base=away)
    (moved,) = place_base(puma, task, mounts=[away], scene=box)
    assert moved.all_reachable
    with pytest.raises(PlacementInfeasibleError, match="misses 4 of 4"):
        # the same task seen from a base at the origin: the box is around it
        shifted = np.linalg.inv(base_transform(*away)) @ task
        place_base(puma, shifted, mounts=[(0.0, 0.0, 0.0, 0.0)], scene=box)


# -- paths --------------------------------------------------------------------
def _trajectory(q_start, q_end, count=60):
    s = np.linspace(0.0, 1.0, count)[:, None]
    q = q_start + s * (q_end - q_start)
    zeros = np.zeros_like(q)
    return JointTrajectorySamples(np.linspace(0.0, 1.0, count), q, zeros, zeros)


def _own_branch(robot, pose, q):
    """Index of the closed-form branch of ``pose`` that is ``q``."""
    (label,) = {
        s.branch
        for s in ik.analytic(robot, pose)
        if np.allclose(s.q, q, atol=1e-9, rtol=0)
    }
    return ik.BRANCHES.index(label)


def _chain_inputs(robot, task):
    """q (K, 8, 6) within-limit representatives, usable (K, 8), |det J| (K, 8)."""
    q, valid = ik.analytic_batch(robot, task.poses)
    wraps = np.asarray(robot.upper) - np.asarray(robot.lower) >= 2 * math.pi
    det = np.where(valid, 1.0, np.nan)
    return np.where(valid[..., None], q, np.nan), valid, det, wraps


def test_trajectory_path_is_followed_by_its_own_branch(puma):
    q_start = np.array([0.2, -0.6, 0.4, 0.3, 0.8, -0.2])
    q_end = np.array([0.9, -0.3, 0.7, -0.4, 1.2, 0.5])
    task = task_poses_from_trajectory(puma, _trajectory(q_start, q_end))
    assert task.ordered
    (found,) = place_base(puma, task, mounts=[(0.0, 0.0, 0.0, 0.0)])
    assert found.all_reachable and found.branch is not None
    assert "->" not in found.branch  # no singularity on the way: one label
    q, valid, det, wraps = _chain_inputs(puma, task)
    own = _own_branch(puma, task.poses[0], q_start)
    only_own = valid & (np.arange(8) == own)
    result = follow_path(q, only_own, det, wraps)
    assert result is not None and set(result[1].tolist()) == {own}


def test_path_through_a_wrist_singularity_changes_label_without_a_flip(puma):
    """θ5 crosses 0: the motion goes from one wrist twin's label to the other's."""
    q_start = np.array([0.2, -0.6, 0.4, 0.3, 0.4, -0.2])
    q_end = np.array([0.4, -0.5, 0.5, 0.5, -0.4, 0.2])
    task = task_poses_from_trajectory(puma, _trajectory(q_start, q_end))
    q, valid, det, wraps = _chain_inputs(puma, task)
    own = _own_branch(puma, task.poses[0], q_start)
    twins = valid & (np.arange(8) // 2 == own // 2)
    result = follow_path(q, twins, det, wraps)
    assert result is not None
    labels = result[1]
    assert labels[0] == own and labels[-1] == own ^ 1  # the other twin's label
    along = q[np.arange(len(labels)), labels]
    np.testing.assert_allclose(along, _trajectory(q_start, q_end).q, rtol=0, atol=1e-9)
    # kept to one label, the arm would have to flip (θ4, θ6 by π): no chain
    assert follow_path(q, valid & (np.arange(8) == own), det, wraps) is None
    (found,) = place_base(puma, task, mounts=[(0.0, 0.0, 0.0, 0.0)])
    assert found.all_reachable


def test_path_that_no_branch_follows_is_infeasible(puma):
    """A path that jumps (two far-apart halves): no branch follows it."""
    q_start = np.array([0.2, -0.6, 0.4, 0.3, 0.8, -0.2])
    q_far = np.array([2.0, -0.3, 0.7, -0.4, 1.2, 0.5])
    samples = _trajectory(q_start, q_start, count=5)
    jump = JointTrajectorySamples(
        np.arange(10.0),
        np.vstack([samples.q, np.tile(q_far, (5, 1))]),
        np.zeros((10, 6)),
        np.zeros((10, 6)),
    )
    task = task_poses_from_trajectory(puma, jump)
    with pytest.raises(PlacementInfeasibleError, match="no branch follows"):
        place_base(puma, task, mounts=[(0.0, 0.0, 0.0, 0.0)])
    (found,) = place_base(puma, task, mounts=[(0.0, 0.0, 0.0, 0.0)], path=False)
    assert found.all_reachable


def test_follow_path_steps_and_limits():
    """A step beyond PATH_STEP_MAX breaks a chain; wrapping only where limits allow."""
    q = np.zeros((4, 2, 6))
    q[:, 0, 3] = [3.0, 3.1, -3.1, -3.0]  # crosses ±π
    q[:, 1, 3] = [3.0, 3.1, 3.2, 3.3]  # the same motion, unwrapped
    usable = np.ones((4, 2), dtype=bool)
    dexterity = np.array([[1.0, 0.5]] * 4)
    wraps = np.zeros(6, dtype=bool)
    best, chain = follow_path(q, usable, dexterity, wraps)
    assert chain.tolist() == [0, 0, 1, 1] and best == 0.5  # 3.1 -> 3.2 steps 0.1
    usable[2:, 1] = False  # only the wrapped representatives remain
    assert follow_path(q, usable, dexterity, wraps) is None
    wraps[3] = True  # a joint free to turn past ±π
    best, chain = follow_path(q, usable, dexterity, wraps)
    assert chain.tolist() == [0, 0, 0, 0] and best == 1.0
    jump = np.zeros((2, 1, 6))
    jump[1, 0, 0] = 1.01 * PATH_STEP_MAX
    assert follow_path(jump, np.ones((2, 1), bool), np.ones((2, 1)), wraps) is None


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_follow_path_is_the_best_chain(seed):
    """Against every chain of a small path (K = 4 samples, S = 3 solutions)."""
    gen = np.random.default_rng(seed)
    q = gen.uniform(-math.pi, math.pi, size=(4, 3, 2))
    q[1:] = q[:-1] + gen.normal(0.0, 0.6, size=(3, 3, 2))  # some steps join
    usable = gen.random((4, 3)) < 0.8
    dexterity = gen.random((4, 3))
    wraps = np.array([True, False])
    best = -math.inf
    for chain in itertools.product(range(3), repeat=4):
        steps = np.diff(q[np.arange(4), chain], axis=0)
        steps[:, 0] = np.remainder(steps[:, 0] + math.pi, 2 * math.pi) - math.pi
        if all(usable[k, s] for k, s in enumerate(chain)) and np.all(
            np.abs(steps) <= PATH_STEP_MAX
        ):
            best = max(best, min(dexterity[k, s] for k, s in enumerate(chain)))
    found = follow_path(q, usable, dexterity, wraps)
    if best == -math.inf:
        assert found is None
    else:
        assert found is not None and found[0] == best
        chain = found[1]
        assert min(dexterity[k, s] for k, s in enumerate(chain)) == best


# -- task-pose files ----------------------------------------------------------
@settings(max_examples=25, deadline=None)
@given(
    st.lists(
        st.tuples(
            *[st.floats(-2.0, 2.0) for _ in range(3)],
            *[st.floats(-1.0, 1.0) for _ in range(4)],
        ),
        min_size=1,
        max_size=5,
    )
)
def test_task_csv_round_trip(tmp_path_factory, rows):
    values = np.array(rows, dtype=np.float64)
    norms = np.linalg.norm(values[:, 3:], axis=1)
    values = values[norms > 0.1]
    if not len(values):
        return
    values[:, 3:] /= np.linalg.norm(values[:, 3:], axis=1, keepdims=True)
    poses = matrices_from_xyz_quat_xyzw(values)
    path = _write_task_csv(tmp_path_factory.mktemp("csv") / "task.csv", poses)
    task = read_task_poses(path)
    np.testing.assert_allclose(task.poses, poses, rtol=0, atol=ATOL_EXACT)
    for pose, row in zip(task.poses, values, strict=True):
        expected = pin.Quaternion(row[6], *row[3:6]).toRotationMatrix()
        np.testing.assert_allclose(pose[:3, :3], expected, rtol=0, atol=ATOL_EXACT)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("x,y,z,qw,qx,qy,qz\n0,0,0,1,0,0,0\n", "line 1: header"),
        ("x,y,z,qx,qy,qz,qw\n0,0,0,0,0,0\n", "line 2: 6 fields"),
        ("x,y,z,qx,qy,qz,qw\n0,0,0,0,0,0,1\n0,nan,0,0,0,0,1\n", "line 3: NaN"),
        ("x,y,z,qx,qy,qz,qw\n0,0,0,0,0,0,1.001\n", "line 2: quaternion"),
        ("x,y,z,qx,qy,qz,qw\n0,a,0,0,0,0,1\n", "line 2: not a number"),
        ("x,y,z,qx,qy,qz,qw\n", "no task pose"),
        ("", "empty file"),
    ],
)
def test_bad_task_csv(tmp_path, text, message):
    path = tmp_path / "task.csv"
    path.write_text(text)
    with pytest.raises(TaskPoseFileError, match=message):
        read_task_poses(path)


def test_quaternion_within_tolerance_is_normalised(tmp_path):
    q = 1.0 + 0.5 * TASK_QUAT_NORM_TOL
    path = tmp_path / "task.csv"
    path.write_text(f"x,y,z,qx,qy,qz,qw\n0.1,0.2,0.3,0,0,0,{q!r}\n")
    np.testing.assert_allclose(
        read_task_poses(path).poses[0, :3, :3], np.eye(3), rtol=0, atol=ATOL_EXACT
    )


# -- command line -------------------------------------------------------------
@pytest.mark.slow
def test_cli_place_json(puma, rng, tmp_path, capsys):
    task, _ = _task(puma, rng, count=6)
    path = _write_task_csv(tmp_path / "task.csv", task)
    code = main([
        "workspace", "place", "--robot", "puma560", "--targets", str(path),
        "--region", *map(str, REGION), "--resolution", "0.1", "--yaw-step", "20",
        "--top", "3", "--json",
    ])  # fmt: skip
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    assert out["poses"] == 6 and out["path"] is False
    assert 1 <= len(out["placements"]) <= 3
    keys = {"x", "y", "z", "yaw", "all_reachable", "min_dexterity",
            "min_singularity_margin", "branch", "missed", "redundancy"}  # fmt: skip
    assert all(set(p) == keys and p["all_reachable"] for p in out["placements"])


def test_cli_place_default_region_is_python_place_base_default(
    puma, rng, tmp_path, capsys
):
    """Without --region, the command and place_base without a region agree."""
    task, _ = _task(puma, rng, count=4)
    path = _write_task_csv(tmp_path / "task.csv", task)
    code = main([
        "workspace", "place", "--robot", "puma560", "--targets", str(path),
        "--resolution", "0.25", "--yaw-step", "45", "--top", "2", "--json",
    ])  # fmt: skip
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    poses = read_task_poses(path)
    assert out["region"] == list(default_region(puma, poses, resolution=0.25))
    python = place_base(puma, poses, resolution=0.25, yaw_step=math.pi / 4, top=2)
    assert out["placements"] == [p.as_dict() for p in python]


@pytest.mark.slow
def test_cli_place_nothing_reaches_exits_3(puma, rng, tmp_path, capsys):
    task, _ = _task(puma, rng, count=3)
    path = _write_task_csv(tmp_path / "task.csv", task)
    code = main([
        "workspace", "place", "--robot", "puma560", "--targets", str(path),
        "--region", "6", "6.2", "6", "6.2", "--resolution", "0.1", "--json",
    ])  # fmt: skip
    assert code == 3
    out = json.loads(capsys.readouterr().out)
    assert out["feasible"] is False and "misses 3 of 3" in out["error"]


@pytest.mark.parametrize(
    "text",
    ["x,y,z\n0,0,0\n", "x,y,z,qx,qy,qz,qw\n0,0,0,0,0,0,2\n", "x,y,z,qx,qy,qz,qw\n"],
)
def test_cli_place_bad_csv_exits_2_one_line(tmp_path, capsys, text):
    path = tmp_path / "task.csv"
    path.write_text(text)
    code = main(["workspace", "place", "--robot", "puma560", "--targets", str(path)])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0]


def test_cli_place_trajectory(puma, tmp_path, capsys):
    q_start = np.array([0.2, -0.6, 0.4, 0.3, 0.8, -0.2])
    q_end = np.array([0.9, -0.3, 0.7, -0.4, 1.2, 0.5])
    path = tmp_path / "path.csv"
    write_trajectory_csv(path, _trajectory(q_start, q_end, count=20))
    code = main([
        "workspace", "place", "--robot", "puma560", "--trajectory", str(path),
        "--region", "-0.1", "0.1", "-0.1", "0.1", "--resolution", "0.1",
        "--yaw-step", "90", "--json",
    ])  # fmt: skip
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    assert out["path"] is True
    assert out["placements"] and all(p["branch"] for p in out["placements"])
