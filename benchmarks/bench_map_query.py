"""Map queries with the integrity checks against Zarr's plain reads, in one run.

Run from the repository root: ``python -m benchmarks.bench_map_query
[--quick]``. A PUMA 560 map (10 cm voxels × 512 orientations, 256 voxels a
block: 39 chunks per array) is built once; then, interleaved round by round on
the same poses:

* ``checked``: ``WorkspaceMap.query`` of an open map: the chunks the poses
  touch read, each checked against its digest (:mod:`workbench.workspace.manifest`);
* ``plain``: the same query reading through Zarr, unchecked
  (``array.vindex[rows, cols]`` of every array: the reader before the checks);
* ``open``: ``open_map`` (the schema, the manifest, every array's metadata
  and a ``stat`` of every chunk file) against ``zarr.open_group`` with the
  attribute reads of the old open;
* ``verify``: ``verify_map`` of the whole map (every chunk read, digested,
  range-checked; the grid re-derived), once.

Poses: N random tool poses in the reach box (N = 1, 100, 10,000: one chunk,
a few, all). Times are the median of the rounds, wall clock; ratio = checked /
plain (the goal of the integrity change: ≤ 1.2).
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import zarr

from workbench import load_robot
from workbench.workspace import build_map, make_pose_grid, open_map, verify_map
from workbench.workspace.map_query import query_map
from workbench.workspace.orientations import rotations_from_quat_xyzw
from workbench.workspace.store import open_group_checked, read_array


def _poses(grid, count: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    low, high = grid.bounds
    quat = rng.normal(size=(count, 4))
    quat /= np.linalg.norm(quat, axis=1)[:, None]
    poses = np.tile(np.eye(4), (count, 1, 1))
    poses[:, :3, :3] = rotations_from_quat_xyzw(quat)
    poses[:, :3, 3] = rng.uniform(low, high, size=(count, 3))
    return poses


def _plain_query(path: Path, grid) -> Callable[[np.ndarray], object]:
    group = zarr.open_group(path, mode="r")
    names = [n for n in group.array_keys() if n not in ("positions", "orientations")]

    def gather(name, rows, cols):
        array = group[name]
        return array.vindex[rows, cols] if cols is not None else array.vindex[rows]

    return lambda poses: query_map(gather, names, grid, poses)


def _plain_open(path: Path) -> object:
    group = open_group_checked(path)  # the format, schema and array checks
    return read_array(group, "done")


def _median(call: Callable[[], object], number: int) -> float:
    start = time.perf_counter()
    for _ in range(number):
        call()
    return (time.perf_counter() - start) / number


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer rounds")
    args = parser.parse_args(argv)
    rounds = 5 if args.quick else 15
    robot = load_robot("puma560")
    grid = make_pose_grid(robot, resolution=0.1, orientations=512)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "puma.zarr"
        build_map(robot, grid, path, block_voxels=256)
        atlas = open_map(path)
        plain = _plain_query(path, atlas.grid)
        sizes = (1, 100, 10_000)
        poses = {n: _poses(grid, n, seed=n) for n in sizes}
        for n in sizes:  # the same answers
            a, b = atlas.query(poses[n]), plain(poses[n])
            for field in ("branches", "reached", "dexterity", "limit_margin"):
                np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
        times: dict[str, list[float]] = {}
        for _ in range(rounds):
            for n in sizes:
                number = 200 if n == 1 else 20 if n == 100 else 3
                for name, call in (
                    (f"checked {n}", lambda n=n: atlas.query(poses[n])),
                    (f"plain {n}", lambda n=n: plain(poses[n])),
                ):
                    times.setdefault(name, []).append(_median(call, number))
            for name, call in (
                ("open checked", lambda: open_map(path)),
                ("open plain", lambda: _plain_open(path)),
            ):
                times.setdefault(name, []).append(_median(call, 20))
        start = time.perf_counter()
        check = verify_map(path)
        verify_seconds = time.perf_counter() - start
    median = {name: statistics.median(values) for name, values in times.items()}
    print(
        f"map: {grid.voxel_count} voxels × {grid.orientation_count} orientations, "
        f"{check.chunks} chunks ({check.chunks_stored} stored, "
        f"{check.bytes / 1e6:.1f} MB); {rounds} rounds"
    )
    print("| what | checked [ms] | plain Zarr [ms] | checked / plain |")
    print("|---|---:|---:|---:|")
    for n in sizes:
        a, b = median[f"checked {n}"], median[f"plain {n}"]
        print(f"| query, {n} poses | {a * 1e3:.3f} | {b * 1e3:.3f} | {a / b:.2f} |")
    a, b = median["open checked"], median["open plain"]
    print(f"| open | {a * 1e3:.3f} | {b * 1e3:.3f} | {a / b:.2f} |")
    print(
        f"verify_map, whole map: {verify_seconds:.2f} s "
        f"({check.values / verify_seconds / 1e6:.1f} M values/s)"
    )


if __name__ == "__main__":
    main()
