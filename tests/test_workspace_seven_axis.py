"""Workspace maps of seven-axis arms, in closed form at K values of ψ or q7.

The block measures are checked against a plain loop over the public
``ik.analytic`` at each value (an independent path: one pose, one value at a
time) and Pinocchio's Jacobian; maps are bitwise the same on 1 and 2
workers; K values nest in 3K; the command line says what "exact" means.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.conftest import run_cli
from workbench import InputError, ik, load_robot
from workbench.workspace import build_map, make_pose_grid, open_map
from workbench.workspace._reference import block_poses, limit_representatives
from workbench.workspace.redundant import (
    DEFAULT_REDUNDANCY_SAMPLES,
    MAX_REDUNDANCY_SAMPLES,
    REDUNDANT_POSE_KEYS,
    REDUNDANT_VOXEL_KEYS,
    evaluate_redundant_block,
    redundancy_values,
)

ROBOTS = ("iiwa14", "panda")
#: Cell centres computed two ways [rad].
ATOL_VALUES = 1e-12
#: float32 storage of a float64 measure (relative).
RTOL_FLOAT32 = 1e-6
#: A parameter value [rad] stored as float32 (|value| <= π).
ATOL_FLOAT32_VALUE = 4e-7
K = 5


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request):
    return load_robot(request.param)


@pytest.fixture(scope="module")
def grid(robot):
    return make_pose_grid(robot, resolution=0.3, orientations=6)


def test_values_are_cell_centres_of_the_range() -> None:
    values = redundancy_values((-np.pi, np.pi), 4)
    np.testing.assert_allclose(
        values,
        [-0.75 * np.pi, -0.25 * np.pi, 0.25 * np.pi, 0.75 * np.pi],
        atol=ATOL_VALUES,
    )
    three = redundancy_values((-2.0, 3.0), 3 * K)
    for value in redundancy_values((-2.0, 3.0), K):  # K's values among 3K's
        assert np.min(np.abs(three - value)) < ATOL_VALUES
    for bad in (0, MAX_REDUNDANCY_SAMPLES + 1, 2.5, True):
        with pytest.raises(InputError, match="redundancy samples"):
            redundancy_values((0.0, 1.0), bad)


def _reference(robot, grid, start, stop, count):
    """Per pose: branches reached, in limits, best margin, its q and value."""
    values = redundancy_values(ik.get_solver(robot).parameter_range, count)
    rows = []
    for pose in block_poses(grid, start, stop):
        reached, usable, best = set(), set(), (-np.inf, None, np.nan)
        for value in values:
            try:
                solutions = ik.analytic(robot, pose, redundancy=float(value))
            except ik.UnreachableError:
                continue
            for s in solutions:
                reached.add(s.branch)
                shifted, margin, within = limit_representatives(
                    s.q, robot.lower, robot.upper
                )
                if within:
                    usable.add(s.branch)
                    if margin > best[0]:
                        best = (float(margin), shifted, float(value))
        rows.append((len(reached), len(usable), *best))
    return rows


@pytest.mark.slow
def test_block_matches_a_loop_over_the_public_closed_form(robot, grid) -> None:
    start = grid.voxel_count // 2 - 6  # around the arm's middle: poses it reaches
    stop = start + 12
    out = evaluate_redundant_block(robot, grid, start, stop, count=K)
    assert set(out) == {*REDUNDANT_POSE_KEYS, *REDUNDANT_VOXEL_KEYS}
    flat = {key: out[key].reshape(-1) for key in REDUNDANT_POSE_KEYS}
    rows = _reference(robot, grid, start, stop, K)
    assert any(row[1] > 0 for row in rows), "the block reaches no pose: move it"
    for i, (reached, usable, margin, q, value) in enumerate(rows):
        assert flat["reached"][i] == reached
        assert flat["branches"][i] == usable
        if q is None:
            for key in ("dexterity", "limit_margin", "redundancy"):
                assert np.isnan(flat[key][i])
            continue
        jacobian = robot.jacobian(q)
        manipulability = np.sqrt(np.linalg.det(jacobian @ jacobian.T))
        np.testing.assert_allclose(
            flat["dexterity"][i], manipulability, rtol=RTOL_FLOAT32, atol=0
        )
        np.testing.assert_allclose(
            flat["limit_margin"][i], margin, rtol=RTOL_FLOAT32, atol=0
        )
        assert flat["redundancy"][i] == np.float32(value)


def test_more_values_reach_at_least_the_same_poses(robot, grid) -> None:
    start = grid.voxel_count // 2 - 20
    few = evaluate_redundant_block(robot, grid, start, start + 40, count=K)
    many = evaluate_redundant_block(robot, grid, start, start + 40, count=3 * K)
    assert few["branches"].any()
    assert np.all(many["branches"] >= few["branches"])
    assert np.all(many["reached"] >= few["reached"])


def _arrays(path) -> dict[str, bytes]:
    opened = open_map(path)
    return {name: opened[name].tobytes() for name in opened.names}


@pytest.mark.slow
def test_map_is_bitwise_the_same_on_1_and_2_workers(robot, grid, tmp_path) -> None:
    one = build_map(robot, grid, tmp_path / "one.zarr", workers=1, block_voxels=16)
    two = build_map(robot, grid, tmp_path / "two.zarr", workers=2, block_voxels=16)
    assert (
        one.redundancy_samples == two.redundancy_samples == DEFAULT_REDUNDANCY_SAMPLES
    )
    assert not one.sampled and one.reachable_fraction > 0.0
    assert _arrays(tmp_path / "one.zarr") == _arrays(tmp_path / "two.zarr")
    attrs = open_map(tmp_path / "one.zarr").attrs
    solver = ik.get_solver(robot)
    assert attrs["family"] == solver.family.name
    assert attrs["redundancy"]["parameter"] == solver.parameter
    assert attrs["redundancy"]["samples"] == DEFAULT_REDUNDANCY_SAMPLES
    np.testing.assert_array_equal(
        attrs["redundancy"]["values"],
        redundancy_values(solver.parameter_range, DEFAULT_REDUNDANCY_SAMPLES),
    )


def test_sampled_stays_an_option_and_k_is_refused_elsewhere(tmp_path) -> None:
    panda = load_robot("panda")
    grid = make_pose_grid(panda, resolution=0.4, orientations=2)
    summary = build_map(panda, grid, tmp_path / "s.zarr", samples=5000, workers=1)
    assert summary.sampled and summary.redundancy_samples is None
    with pytest.raises(InputError, match="not for a sampled map"):
        build_map(panda, grid, tmp_path / "x.zarr", samples=10, redundancy_samples=3)
    puma = load_robot("puma560")
    with pytest.raises(InputError, match="no seven-axis family"):
        build_map(
            puma,
            make_pose_grid(puma, resolution=0.4, orientations=2),
            tmp_path / "y.zarr",
            redundancy_samples=3,
        )


@pytest.mark.slow
def test_command_line_says_what_exact_means(capsys, tmp_path) -> None:
    out = tmp_path / "iiwa.zarr"
    argv = ["workspace", "map", "--robot", "iiwa14", "--resolution", "0.4"]
    argv += ["--orientations", "2", "--workers", "1", "--redundancy-samples", "3"]
    code, text, err = run_cli(capsys, *argv, "--out", str(out))
    assert code == 0, err
    assert "exact at 3 values of the redundancy parameter" in text
    code, text, _ = run_cli(capsys, *argv, "--out", str(tmp_path / "j.zarr"), "--json")
    assert code == 0 and json.loads(text)["redundancy_samples"] == 3
    code, text, _ = run_cli(
        capsys, "workspace", "report", str(out), "--out", str(tmp_path / "r.html")
    )
    assert code == 0
    page = (tmp_path / "r.html").read_text()
    assert "exact</b> map at 3 values of the arm angle" in page
    assert "6 × 7 Jacobian of a seven-axis arm" in page


@pytest.mark.slow
@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--robot", "puma560", "--redundancy-samples", "3"], "no seven-axis family"),
        (
            ["--robot", "panda", "--samples", "9", "--redundancy-samples", "3"],
            "sampled",
        ),
        (["--robot", "panda", "--redundancy-samples", "0"], "must be 1..4096"),
    ],
)
def test_command_line_refusals_exit_2(capsys, tmp_path, argv, message) -> None:
    code, _, err = run_cli(
        capsys, "workspace", "map", *argv, "--out", str(tmp_path / "m.zarr")
    )
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1


def test_base_placement_says_it_needs_a_closed_form(capsys, tmp_path) -> None:
    """An arm of no family is refused in one line (seven-axis arms are placed:
    ``tests/test_workspace_placement_seven_axis.py``)."""
    targets = tmp_path / "targets.csv"
    targets.write_text("x,y,z,qx,qy,qz,qw\n0.5,0.1,0.4,1,0,0,0\n", encoding="utf-8")
    code, out, err = run_cli(
        capsys, "workspace", "place", "--robot", "generic6r", "--targets", str(targets)
    )
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert "robot 'generic6r' has no closed-form IK" in err


@pytest.mark.slow
def test_a_pose_reached_at_the_values_is_feasible_and_its_value_inside(
    robot, grid
) -> None:
    """Sound: a reached pose has a feasible interval holding its best value."""
    start = grid.voxel_count // 2 - 6
    out = evaluate_redundant_block(robot, grid, start, start + 12, count=K)
    poses = block_poses(grid, start, start + 12)
    branches = out["branches"].reshape(-1)
    values = out["redundancy"].reshape(-1)
    assert branches.any()
    for pose, usable, value in zip(poses, branches, values, strict=True):
        feasible = ik.get_solver(robot).feasible(pose)
        if not usable:
            continue
        assert feasible.union, "reached at a value, yet feasible for none"
        assert any(
            lo - ATOL_FLOAT32_VALUE <= value <= hi + ATOL_FLOAT32_VALUE
            for lo, hi in feasible.union
        )


def test_query_gives_the_best_value_and_it_reaches_the_grid_pose(robot, grid, tmp_path):
    """MapQuery.redundancy: the closed form at that value reaches the grid pose."""
    build_map(robot, grid, tmp_path / "m.zarr", workers=1, block_voxels=64)
    atlas = open_map(tmp_path / "m.zarr")
    reached = np.argwhere(atlas["branches"] > 0)[:5]
    poses = np.array([grid.pose(int(v), int(o)) for v, o in reached])
    query = atlas.query(poses)
    assert np.all(np.isfinite(query.redundancy))
    values = atlas.attrs["redundancy"]["values"]
    for pose, value in zip(poses, query.redundancy, strict=True):
        nearest = float(values[int(np.argmin(np.abs(np.array(values) - value)))])
        assert abs(nearest - value) <= ATOL_FLOAT32_VALUE  # one of the K values
        solutions = ik.analytic(robot, pose, redundancy=nearest)
        assert any(s.within_limits for s in solutions)
    six = load_robot("puma560")
    six_grid = make_pose_grid(six, resolution=0.5, orientations=2)
    build_map(six, six_grid, tmp_path / "p.zarr", workers=1)
    assert np.all(np.isnan(open_map(tmp_path / "p.zarr").query(poses[:1]).redundancy))


@pytest.mark.slow
def test_a_stopped_build_resumes_to_the_same_bits_and_refuses_another_k(
    robot, grid, tmp_path, monkeypatch
) -> None:
    from workbench.workspace import _block_tasks
    from workbench.workspace.store import get_partial_path

    whole = tmp_path / "whole.zarr"
    build_map(robot, grid, whole, workers=1, block_voxels=16, redundancy_samples=K)
    real = _block_tasks.evaluate_redundant_block
    calls: list[int] = []

    def failing(*args, **kwargs):
        calls.append(1)
        if len(calls) > 2:
            raise RuntimeError("injected failure")
        return real(*args, **kwargs)

    monkeypatch.setattr(_block_tasks, "evaluate_redundant_block", failing)
    path = tmp_path / "resumed.zarr"
    with pytest.raises(RuntimeError, match="injected"):
        build_map(robot, grid, path, workers=1, block_voxels=16, redundancy_samples=K)
    assert get_partial_path(path).is_dir()
    monkeypatch.setattr(_block_tasks, "evaluate_redundant_block", real)
    with pytest.raises(InputError, match="redundancy"):  # another K: another map
        build_map(robot, grid, path, workers=1, block_voxels=16, redundancy_samples=3)
    summary = build_map(
        robot, grid, path, workers=2, block_voxels=16, redundancy_samples=K
    )
    assert summary.blocks_computed == summary.blocks - 2
    assert _arrays(whole) == _arrays(path)
