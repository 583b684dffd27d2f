"""Workspace atlas: map build, base placement, accuracy, joint-space map, peers.

Run from the repository root: ``python -m benchmarks.bench_workspace [--part
map|place|accuracy|joint|peers ...] [--quick] [--rm4d DIR]``. One run of each
part, wall time (the builds use threads); the reference loop of the other
benchmarks (``sum(range(1000))``, CPU time) calibrates the machine.

* ``map``: ``build_map`` of puma560 and ur5, 5 cm voxels × 512 orientations
  (limits and singularity measures) with 1 and 2 workers: seconds, poses/s
  and the speed-up.
* ``place``: ``place_base``, 800 task poses (a task around a known base),
  2 × 2 m region at 2 cm, 10° yaw steps.
* ``accuracy``: 10,000 held-out poses, half the tool poses of random in-limit
  configurations, half random poses in the reach box. Truth: the closed form
  (``ik.analytic_batch``) and the joint limits (some 2π representative of each
  angle within them), computed here independently of the map. Answers: the
  exact map at the nearest grid pose (``WorkspaceMap.query``) and a sampled
  map (random configurations → FK → binned, ``workspace.sampled``) drawn for
  as long as the exact map took to build. False-positive rate = wrong
  "reachable" among the unreachable poses, false-negative rate = wrong
  "unreachable" among the reachable ones. Then 10,000 grid poses checked
  exactly against the stored counts (the exact map must have no error there).
* ``joint``: ``compute_joint_space_map``, 10⁶ configurations, 1 and 2 threads.
* ``peers`` (optional, the ``bench`` extra): scikit-robot's
  ``ReachabilityMap`` (random joint samples, position voxels and approach
  bins), RM4D's ``ReachabilityMap4D`` (ICRA 2025; not on PyPI: ``--rm4d DIR``
  names a checkout's folder holding its ``rm4d`` package, imported without
  its ``__init__`` so that pybullet is not needed; our FK feeds its
  construction loop, which is what RM4D's ``JointSpaceConstructor`` does with
  pybullet's), compas_fab's ``ReachabilityMap`` (ur5, its analytic
  ``UR5Kinematics``). Build time and agreement with our map.
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import sys
import tempfile
import time
import types
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.bench_ik_closed_form import _reference_us
from workbench import Robot, load_robot
from workbench.ik import analytic_batch, compute_tool_poses
from workbench.workspace import compute_joint_space_map, make_pose_grid
from workbench.workspace.build import build_map
from workbench.workspace.orientations import (
    quat_xyzw_from_rotations,
    rotations_from_quat_xyzw,
)
from workbench.workspace.placement import base_transform, place_base
from workbench.workspace.sampled import accumulate, sample_block
from workbench.workspace.store import open_map

ROBOTS = ("puma560", "ur5")
PARTS = ("map", "place", "accuracy", "joint", "peers")
TAU = 2.0 * math.pi


def _sizes(quick: bool) -> dict[str, Any]:
    """The benchmark's sizes; ``quick``: a smoke test of every part in seconds."""
    if quick:
        return {
            "resolution": 0.15,
            "orientations": 64,
            "tasks": 50,
            "place_res": 0.1,
            "held_out": 1000,
            "grid_checks": 1000,
            "joint": 100_000,
            "peer_samples": 20_000,
            "peer_poses": 500,
        }
    return {
        "resolution": 0.05,
        "orientations": 512,
        "tasks": 800,
        "place_res": 0.02,
        "held_out": 10_000,
        "grid_checks": 10_000,
        "joint": 1_000_000,
        "peer_samples": 1_000_000,
        "peer_poses": 5_000,
    }


def _timed(call: Callable[[], Any]) -> tuple[Any, float]:
    start = time.perf_counter()
    result = call()
    return result, time.perf_counter() - start


# --- truth ------------------------------------------------------------------------


def exact_counts(robot: Robot, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form branches reaching each pose (N,), and of those within the limits.

    A branch is within the limits when every angle has a representative
    ``q + 2πk`` in ``[lower, upper]``: the smallest one above ``lower`` is
    below ``upper``.
    """
    q, valid = analytic_batch(robot, poses)
    with np.errstate(invalid="ignore"):
        lowest = q + TAU * np.ceil((robot.lower - q) / TAU)
        within = valid & np.all(lowest <= robot.upper, axis=-1)
    return valid.sum(axis=1), within.sum(axis=1)


def _fk_poses(robot: Robot, q: np.ndarray) -> np.ndarray:
    """(N, 4, 4) tool poses in the base frame (compiled chain kinematics)."""
    rotations, positions, _ = compute_tool_poses(robot, q)
    poses = np.zeros((len(q), 4, 4))
    poses[:, :3, :3], poses[:, :3, 3], poses[:, 3, 3] = rotations, positions, 1.0
    return poses


def held_out_poses(robot: Robot, grid: Any, count: int, seed: int) -> np.ndarray:
    """Half tool poses of random in-limit configurations, half random box poses."""
    rng = np.random.default_rng(seed)
    half = count // 2
    q = rng.uniform(robot.lower, robot.upper, size=(half, robot.nq))
    box = np.empty((count - half, 4, 4))
    box[:] = np.eye(4)
    box[:, :3, 3] = rng.uniform(grid.bounds[0], grid.bounds[1], (count - half, 3))
    quat = rng.normal(size=(count - half, 4))
    box[:, :3, :3] = rotations_from_quat_xyzw(
        quat / np.linalg.norm(quat, axis=1)[:, None]
    )
    return np.concatenate([_fk_poses(robot, q), box])


def error_rates(truth: np.ndarray, said: np.ndarray) -> tuple[float, float]:
    """(false-positive rate, false-negative rate) of ``said`` against ``truth``."""
    fp = float(np.mean(said[~truth])) if (~truth).any() else math.nan
    fn = float(np.mean(~said[truth])) if truth.any() else math.nan
    return fp, fn


# --- parts ------------------------------------------------------------------------


def bench_map(robot: Robot, grid: Any, folder: Path) -> dict[int, Any]:
    """build_map with 1 and 2 workers; returns the summaries by worker count."""
    small = make_pose_grid(robot, resolution=0.3, orientations=8)
    build_map(robot, small, folder / f"{robot.name}-warm-up.zarr", workers=2)
    out = {}
    for workers in (1, 2):
        path = folder / f"{robot.name}-{workers}.zarr"
        out[workers] = build_map(robot, grid, path, workers=workers)
    return out


def bench_place(robot: Robot, sizes: dict[str, Any]) -> dict[str, Any]:
    """place_base on a task around a known base (x 0.3, y -0.2, yaw 30°)."""
    rng = np.random.default_rng(11)
    mid = 0.5 * (robot.lower + robot.upper)
    span = np.minimum(0.35, 0.5 * (robot.upper - robot.lower))
    q = rng.uniform(mid - span, mid + span, size=(sizes["tasks"], robot.nq))
    world = base_transform(0.3, -0.2, 0.0, math.radians(30.0)) @ _fk_poses(robot, q)
    placements, seconds = _timed(
        lambda: place_base(
            robot,
            world,
            region=(-1.0, 1.0, -1.0, 1.0),
            height=0.0,
            yaw_step=math.radians(10.0),
            resolution=sizes["place_res"],
            top=10,
        )
    )
    best = placements[0]
    return {
        "seconds": seconds,
        "found": len(placements),
        "best": best,
        "tasks": len(world),
    }


def sampled_map(
    robot: Robot, grid: Any, budget: float, workers: int = 2
) -> tuple[np.ndarray, int, float]:
    """A sampled map drawn for ``budget`` seconds: hit flags (V·O,), samples, seconds.

    Blocks of 2**16 configurations (``sample_block``) on ``workers`` threads,
    folded in with ``accumulate``, until the budget is spent.
    """
    per_block = 1 << 16
    hit = np.zeros(grid.pose_count, dtype=np.uint8)
    dexterity = np.full(grid.pose_count, np.nan, dtype=np.float32)
    start = time.perf_counter()
    block = 0
    with ThreadPoolExecutor(max_workers=workers) as pool:
        while time.perf_counter() - start < budget:
            blocks = range(block, block + workers)
            for cells, values in pool.map(
                lambda b: sample_block(robot, grid, b, per_block, 0), blocks
            ):
                accumulate(cells, values, hit, dexterity)
            block += workers
    return hit, block * per_block, time.perf_counter() - start


def bench_accuracy(
    robot: Robot, grid: Any, map_path: Path, budget: float, sizes: dict[str, Any]
) -> dict[str, Any]:
    the_map = open_map(map_path)
    poses = held_out_poses(robot, grid, sizes["held_out"], seed=5)
    _, within = exact_counts(robot, poses)
    truth = within > 0
    exact_said = the_map.query(poses).branches > 0
    hit, samples, seconds = sampled_map(robot, grid, budget)
    voxel = grid.voxel_index(poses[:, :3, 3])
    orientation = grid.orientation_index(quat_xyzw_from_rotations(poses[:, :3, :3]))
    inside = voxel >= 0
    sampled_said = np.zeros(len(poses), dtype=bool)
    cells = voxel[inside] * grid.orientation_count + orientation[inside]
    sampled_said[inside] = hit[cells] > 0
    half = len(poses) // 2
    rows = {}
    for label, part in (
        ("FK of in-limit q", slice(0, half)),
        ("random in reach box", slice(half, None)),
        ("all", slice(None)),
    ):
        rows[label] = {
            "count": len(truth[part]),
            "reachable": float(np.mean(truth[part])),
            "exact": error_rates(truth[part], exact_said[part]),
            "sampled": error_rates(truth[part], sampled_said[part]),
        }
    # Grid poses: the stored counts against the closed form, exactly.
    rng = np.random.default_rng(6)
    v = rng.integers(0, grid.voxel_count, sizes["grid_checks"])
    o = rng.integers(0, grid.orientation_count, sizes["grid_checks"])
    at_grid = np.empty((len(v), 4, 4))
    at_grid[:] = np.eye(4)
    at_grid[:, :3, :3], at_grid[:, :3, 3] = grid.rotations[o], grid.positions[v]
    reached, within_grid = exact_counts(robot, at_grid)
    stored_reached, stored_branches = the_map["reached"], the_map["branches"]
    return {
        "rows": rows,
        "samples": samples,
        "sampled_seconds": seconds,
        "sampled_coverage": float(np.mean(hit > 0)),
        "exact_coverage": float(np.mean(stored_branches > 0)),
        "grid_checked": len(v),
        "grid_branch_mismatches": int(np.sum(stored_branches[v, o] != within_grid)),
        "grid_reached_mismatches": int(np.sum(stored_reached[v, o] != reached)),
        "grid_answer_mismatches": int(
            np.sum((stored_branches[v, o] > 0) != (within_grid > 0))
        ),
    }


def bench_joint(robot: Robot, count: int) -> dict[int, tuple[Any, float]]:
    """The map with 1 and 2 threads: (map, CPU seconds of this process)."""
    compute_joint_space_map(robot, samples=1000)  # kernels loaded
    out = {}
    for workers in (1, 2):
        cpu = time.process_time()
        the_map = compute_joint_space_map(robot, samples=count, workers=workers)
        out[workers] = (the_map, time.process_time() - cpu)
    return out


# --- peers ------------------------------------------------------------------------


def _import_peer(*names: str) -> list[Any] | str:
    """The modules of a peer, or why they do not import."""
    try:
        return [importlib.import_module(name) for name in names]
    except ImportError as err:
        return f"not importable ({err})"


def _our_reachable_voxels(map_path: Path) -> np.ndarray:
    return np.asarray(open_map(map_path)["reachability"]) > 0


def bench_skrobot(robot: Robot, grid: Any, map_path: Path, samples: int) -> Any:
    modules = _import_peer(
        "skrobot.models.urdf",
        "skrobot.coordinates",
        "skrobot.kinematics.reachability_map",
    )
    if isinstance(modules, str):
        return modules
    urdf, coords, rmap_module = modules
    model = urdf.RobotModelFromURDF(urdf_file=str(robot.urdf_path))
    links = [j.child_link for j in model.joint_list if j.name in robot.joint_names]
    tool = coords.CascadedCoords(parent=getattr(model, robot.tool_frame), name="tool")
    rmap = rmap_module.ReachabilityMap(
        model, links, tool, voxel_size=grid.resolution, backend="numpy"
    )
    _, seconds = _timed(lambda: rmap.compute(n_samples=samples, seed=0, verbose=False))
    theirs = rmap.reachability > 0
    centres = rmap._origin + (np.argwhere(theirs) + 0.5) * rmap.voxel_size
    ours = _our_reachable_voxels(map_path)
    voxel = grid.voxel_index(centres)
    theirs_in_ours = float(np.mean((voxel >= 0) & ours[np.maximum(voxel, 0)]))
    cells = np.floor((grid.positions[ours] - rmap._origin) / rmap.voxel_size)
    cells = cells.astype(np.int64)
    inside = np.all((cells >= 0) & (cells < np.array(rmap._shape)), axis=1)
    said = np.zeros(len(cells), dtype=bool)
    said[inside] = theirs[tuple(cells[inside].T)]
    return {
        "what": "position voxels + 50 approach bins, random joint samples",
        "samples": samples,
        "seconds": seconds,
        "theirs_in_ours": theirs_in_ours,
        "ours_in_theirs": float(np.mean(said)),
    }


def _import_rm4d(folder: str | None) -> Any:
    """RM4D's map module, from a checkout's folder, without its package __init__."""
    if folder is None:
        try:
            return importlib.import_module("rm4d.reachability_map")
        except ImportError as err:
            return f"not importable ({err}); give --rm4d DIR (a checkout's folder)"
    package = types.ModuleType("rm4d")
    package.__path__ = [str(Path(folder) / "rm4d")]
    sys.modules["rm4d"] = package
    try:
        return importlib.import_module("rm4d.reachability_map")
    except ImportError as err:
        return f"not importable from {folder} ({err})"


def bench_rm4d(
    robot: Robot, grid: Any, map_path: Path, samples: int, folder: str | None
) -> Any:
    module = _import_rm4d(folder)
    if isinstance(module, str):
        return module
    # Its bins must tile its limits: n bins of res, shrunk by a rounding error
    # so that its ceil(range / res) is n. x*, y* span twice the reach.
    res, shrink = grid.resolution, 1.0 - 1e-12
    xy_bins = math.ceil(4.0 * float(np.max(np.abs(grid.bounds[:, :2]))) / res)
    z_low = float(grid.bounds[0, 2])
    z_bins = math.ceil((float(grid.bounds[1, 2]) - z_low) / res)
    half = 0.5 * xy_bins * res * shrink
    rmap = module.ReachabilityMap4D(
        xy_limits=[-half, half],
        z_limits=[z_low, z_low + z_bins * res * shrink],
        voxel_res=res,
        n_bins_theta=36,
    )
    rng = np.random.default_rng(0)
    q = rng.uniform(robot.lower, robot.upper, size=(samples, robot.nq))
    poses, fk_seconds = _timed(lambda: _fk_poses(robot, q))

    def construct() -> None:  # JointSpaceConstructor.sample, our FK
        for pose in poses:
            try:
                rmap.mark_reachable(rmap.get_indices_for_ee_pose(pose))
            except IndexError:
                pass

    _, seconds = _timed(construct)
    the_map = open_map(map_path)
    branches = np.asarray(the_map["branches"])
    v = rng.integers(0, grid.voxel_count, 20_000)
    o = rng.integers(0, grid.orientation_count, 20_000)
    ours = branches[v, o] > 0
    theirs = np.zeros(len(v), dtype=bool)
    for i, (vi, oi) in enumerate(zip(v, o, strict=True)):
        try:
            theirs[i] = rmap.is_reachable(
                rmap.get_indices_for_ee_pose(grid.pose(vi, oi))
            )
        except IndexError:
            pass
    return {
        "what": "4D map (z, tilt, base x*, y*), random joint samples",
        "samples": samples,
        "seconds": seconds,
        "fk_seconds": fk_seconds,
        "theirs_in_ours": float(np.mean(ours[theirs])) if theirs.any() else math.nan,
        "ours_in_theirs": float(np.mean(theirs[ours])) if ours.any() else math.nan,
    }


def bench_compas_fab(robot: Robot, grid: Any, map_path: Path, count: int) -> Any:
    if robot.name != "ur5":
        return "its analytic solvers are for UR, ABB IRB4600, Stäubli arms: ur5 only"
    modules = _import_peer(
        "compas.geometry", "compas_fab.robots", "compas_fab.backends"
    )
    if isinstance(modules, str):
        return modules
    compas_geometry, robots, backends = modules
    cell, state = robots.RobotCellLibrary.ur5(load_geometry=False)
    solver = backends.UR5Kinematics()
    planner = backends.AnalyticalKinematicsPlanner(solver)
    planner.set_robot_cell(cell)
    # Their flange frame is ours (tool0) up to a constant rotation B.
    flange = solver.forward([0.0] * 6)
    theirs0 = np.eye(4)
    theirs0[:3, 0], theirs0[:3, 1] = list(flange.xaxis), list(flange.yaxis)
    theirs0[:3, 2], theirs0[:3, 3] = (
        np.cross(theirs0[:3, 0], theirs0[:3, 1]),
        list(flange.point),
    )
    to_theirs = np.linalg.inv(
        np.linalg.inv(theirs0) @ robot.fk(np.zeros(6)).homogeneous
    )
    rng = np.random.default_rng(7)
    v = rng.integers(0, grid.voxel_count, count)
    o = rng.integers(0, grid.orientation_count, count)
    frames = []
    for vi, oi in zip(v, o, strict=True):
        t = grid.pose(vi, oi) @ to_theirs
        frames.append([compas_geometry.Frame(t[:3, 3], t[:3, 0], t[:3, 1])])
    rmap = robots.ReachabilityMap()
    _, seconds = _timed(
        lambda: rmap.calculate(
            iter(frames),
            planner,
            state,
            robots.TargetMode.ROBOT,
            {"check_collision": False, "keep_order": True},
        )
    )
    theirs = np.array(rmap.score) > 0
    the_map = open_map(map_path)
    reached = np.asarray(the_map["reached"])[v, o] > 0
    branches = np.asarray(the_map["branches"])[v, o] > 0
    return {
        "what": "IK per frame (UR5Kinematics), frames from a generator",
        "samples": count,
        "seconds": seconds,
        "agree_reached": float(np.mean(theirs == reached)),
        "agree_in_limits": float(np.mean(theirs == branches)),
    }


# --- printing ---------------------------------------------------------------------


def _print_map(name: str, grid: Any, summaries: dict[int, Any]) -> None:
    one, two = summaries[1], summaries[2]
    print(
        f"\n{name}: map build, {grid.resolution * 100:.0f} cm × "
        f"{grid.orientation_count} orientations = {grid.pose_count:,} poses "
        f"({grid.voxel_count:,} voxels), "
        f"reachable fraction {two.reachable_fraction:.4f}; {_load()}"
    )
    print(f"{'workers':>8s} {'seconds':>9s} {'poses/s':>14s} {'speed-up':>9s}")
    for workers, s in summaries.items():
        print(
            f"{workers:8d} {s.seconds:9.2f} {s.poses_per_second:14,.0f} "
            f"{one.seconds / s.seconds:8.2f}x"
        )


def _print_accuracy(name: str, result: dict[str, Any], budget: float) -> None:
    print(
        f"\n{name}: accuracy at held-out poses (truth: closed form + limits); "
        f"sampled map: {result['samples']:,} samples in "
        f"{result['sampled_seconds']:.1f} s (budget {budget:.1f} s, the exact build's)"
    )
    print(
        f"{'poses':22s} {'count':>6s} {'reachable':>9s} {'exact FP':>9s} "
        f"{'exact FN':>9s} {'sampled FP':>11s} {'sampled FN':>11s}"
    )
    for label, row in result["rows"].items():
        (efp, efn), (sfp, sfn) = row["exact"], row["sampled"]
        print(
            f"{label:22s} {row['count']:6d} {row['reachable']:9.3f} {efp:9.4f} "
            f"{efn:9.4f} {sfp:11.4f} {sfn:11.4f}"
        )
    print(
        f"grid poses reachable: exact map {result['exact_coverage']:.4f}, sampled map "
        f"{result['sampled_coverage']:.4f} (its hits); {result['grid_checked']:,} "
        f"grid poses checked exactly: {result['grid_answer_mismatches']} wrong "
        f"answers, {result['grid_branch_mismatches']} in-limit branch counts and "
        f"{result['grid_reached_mismatches']} reached counts differ"
    )


def _print_place(name: str, r: dict[str, Any], sizes: dict[str, Any]) -> None:
    best = r["best"]
    print(
        f"\n{name}: place_base, {r['tasks']} task poses, 2 × 2 m at "
        f"{sizes['place_res'] * 100:.0f} cm, 10° yaw: {r['seconds']:.2f} s, "
        f"{r['found']} verified placements; best x {best.x:.2f} m, y {best.y:.2f} m, "
        f"yaw {math.degrees(best.yaw):.0f}°, min dexterity {best.min_dexterity:.4g} "
        "m³ (task made around x 0.30, y -0.20, yaw 30°)"
    )


def _print_joint(name: str, maps: dict[int, tuple[Any, float]]) -> None:
    one = maps[1][0]
    near = one.near_singular_fraction()
    print(
        f"\n{name}: joint-space singularity map, {one.count:,} configurations "
        f"(σ_min, Π σ, det J = K s e w and its factors); near-singular fraction "
        f"{near if near is None else f'{near:.4f}'}"
    )
    print(
        f"{'threads':>8s} {'seconds':>9s} {'configs/s':>12s} {'speed-up':>9s} "
        f"{'CPU s':>7s}"
    )
    for workers, (m, cpu) in maps.items():
        print(
            f"{workers:8d} {m.seconds:9.2f} {m.count / m.seconds:12,.0f} "
            f"{one.seconds / m.seconds:8.2f}x {cpu:7.2f}"
        )


def _print_peers(name: str, rows: list[tuple[str, Any]], ours: Any) -> None:
    print(
        f"\n{name}: peers (ours: exact map, {ours.poses:,} poses in "
        f"{ours.seconds:.1f} s with 2 workers)"
    )
    for label, r in rows:
        if isinstance(r, str):
            print(f"  {label}: skipped, {r}")
            continue
        agreement = ", ".join(
            f"{k} {v:.3f}"
            for k, v in r.items()
            if k.startswith(("theirs", "ours", "agree"))
        )
        extra = f" (+ our FK {r['fk_seconds']:.1f} s)" if "fk_seconds" in r else ""
        print(
            f"  {label}: {r['what']}; {r['samples']:,} in {r['seconds']:.2f} s{extra} "
            f"= {r['samples'] / r['seconds']:,.0f}/s; {agreement}"
        )


def _load() -> str:
    """The machine's load (other processes share its cores: wall times suffer)."""
    one, five, _ = os.getloadavg()
    return (
        f"load average {one:.2f} (1 min), {five:.2f} (5 min) on {os.cpu_count()} cores"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--part",
        action="append",
        choices=PARTS,
        help="parts to run (repeat; default: all)",
    )
    parser.add_argument(
        "--quick", action="store_true", help="small sizes: a smoke test"
    )
    parser.add_argument("--robots", default=",".join(ROBOTS), help="comma-separated")
    parser.add_argument("--rm4d", default=None, help="folder of an RM4D checkout")
    args = parser.parse_args()
    parts = set(args.part or PARTS)
    sizes = _sizes(args.quick)
    print(
        f"machine reference: sum(range(1000)) = {_reference_us():.1f} µs (CPU time); "
        f"{_load()}"
    )
    with tempfile.TemporaryDirectory(prefix="bench-workspace-") as tmp:
        for name in args.robots.split(","):
            robot = load_robot(name)
            grid = make_pose_grid(
                robot,
                resolution=sizes["resolution"],
                orientations=sizes["orientations"],
            )
            needs_map = parts & {"map", "accuracy", "peers"}
            summaries: dict[int, Any] = {}
            if needs_map:
                if "map" in parts:
                    summaries = bench_map(robot, grid, Path(tmp))
                    _print_map(name, grid, summaries)
                else:
                    path = Path(tmp) / f"{name}-2.zarr"
                    summaries = {2: build_map(robot, grid, path, workers=2)}
            map_path = Path(tmp) / f"{name}-2.zarr"
            if "place" in parts:
                _print_place(name, bench_place(robot, sizes), sizes)
            if "accuracy" in parts:
                budget = summaries[2].seconds
                result = bench_accuracy(robot, grid, map_path, budget, sizes)
                _print_accuracy(name, result, budget)
            if "joint" in parts:
                _print_joint(name, bench_joint(robot, sizes["joint"]))
            if "peers" in parts:
                rows = [
                    (
                        "scikit-robot ReachabilityMap",
                        bench_skrobot(robot, grid, map_path, sizes["peer_samples"]),
                    ),
                    (
                        "RM4D ReachabilityMap4D",
                        bench_rm4d(
                            robot,
                            grid,
                            map_path,
                            sizes["peer_samples"],
                            args.rm4d,
                        ),
                    ),
                    (
                        "compas_fab ReachabilityMap",
                        bench_compas_fab(robot, grid, map_path, sizes["peer_poses"]),
                    ),
                ]
                _print_peers(name, rows, summaries[2])
    print(f"\nmachine reference now: {_reference_us():.1f} µs; {_load()}")


if __name__ == "__main__":
    main()
