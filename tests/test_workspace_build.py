"""Map builds: bitwise the same on 1 worker, 2 workers and a Dask cluster; resumable.

The cluster is real: a ``dask scheduler`` and two ``dask worker`` processes
(one thread each) on localhost, found through a scheduler file, stopped at
the end of the module. A build stopped midway (an injected failure, SIGKILL,
SIGINT) is finished by the same call, computing only the missing blocks, and
equals the uninterrupted map bit for bit.
"""

from __future__ import annotations

import fcntl
import json
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import zarr

from tests._dask_cluster import start_cluster
from tests.conftest import run_cli
from workbench import Robot, _dask, load_robot
from workbench.collision import Obstacle, Scene
from workbench.errors import InputError
from workbench.workspace import (
    _block_tasks,
    _sampled_fold,
    make_pose_grid,
)
from workbench.workspace.build import SAMPLES_PER_BLOCK, build_map
from workbench.workspace.grid import PoseGrid
from workbench.workspace.robot_spec import (
    get_robot_spec,
    load_spec_checker,
    load_spec_robot,
)
from workbench.workspace.store import get_partial_path, open_map

#: A coarse exact grid: dozens of blocks, a fraction of a second.
RESOLUTION = 0.2  # [m]
ORIENTATIONS = 24
BLOCK_VOXELS = 32
#: A sampled map of a few blocks (the last one shorter).
SAMPLES = 3 * SAMPLES_PER_BLOCK // 2 + 1000


def _arrays(path: Path) -> dict[str, bytes]:
    """Every array of a map as bytes (NaN bit patterns included)."""
    group = zarr.open_group(path, mode="r")
    return {name: group[name][...].tobytes() for name in group.array_keys()}


def _attributes(path: Path) -> dict:
    return zarr.open_group(path, mode="r").attrs.asdict()


def _same_map(a: Path, b: Path) -> None:
    first, second = _arrays(a), _arrays(b)
    assert first.keys() == second.keys()
    for name in first:
        assert first[name] == second[name], name
    assert _attributes(a) == _attributes(b)


@pytest.fixture(scope="module")
def puma() -> Robot:
    return load_robot("puma560")


@pytest.fixture(scope="module")
def grid(puma: Robot) -> PoseGrid:
    return make_pose_grid(puma, resolution=RESOLUTION, orientations=ORIENTATIONS)


@pytest.fixture(scope="module")
def panda() -> Robot:
    return load_robot("panda")


@pytest.fixture(scope="module")
def panda_grid(panda: Robot) -> PoseGrid:
    return make_pose_grid(panda, resolution=0.25, orientations=8)


@pytest.fixture(scope="module")
def reference(
    tmp_path_factory: pytest.TempPathFactory, puma: Robot, grid: PoseGrid
) -> Path:
    """The map built once, on one worker, without interruption."""
    path = tmp_path_factory.mktemp("reference") / "puma.zarr"
    build_map(puma, grid, path, workers=1, block_voxels=BLOCK_VOXELS)
    return path


@pytest.fixture(scope="module")
def cluster(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """Address of a local Dask cluster: a scheduler and two one-thread workers."""
    with start_cluster(tmp_path_factory.mktemp("cluster"), workers=2) as address:
        yield address


@pytest.mark.slow
@pytest.mark.subprocess
def test_exact_map_is_bitwise_the_same_on_1_2_workers_and_a_cluster(
    puma, grid, reference, cluster, tmp_path
) -> None:
    progress: list[tuple[int, int]] = []
    two = build_map(
        puma,
        grid,
        tmp_path / "two.zarr",
        workers=2,
        block_voxels=BLOCK_VOXELS,
        progress=lambda done, total: progress.append((done, total)),
    )
    _same_map(reference, tmp_path / "two.zarr")
    total = two.blocks
    assert total == -(-grid.voxel_count // BLOCK_VOXELS) > 10
    assert progress == [(k, total) for k in range(total + 1)]
    on_cluster = build_map(
        puma, grid, tmp_path / "cluster.zarr", scheduler=cluster, block_voxels=32
    )
    _same_map(reference, tmp_path / "cluster.zarr")
    assert on_cluster.blocks_computed == total
    assert on_cluster.poses == grid.pose_count
    assert 0.1 < on_cluster.reachable_fraction < 0.6
    assert not get_partial_path(tmp_path / "cluster.zarr").exists()


@pytest.mark.subprocess
def test_the_command_on_a_cluster_makes_the_same_map(
    capsys, reference, cluster, tmp_path
) -> None:
    path = tmp_path / "cli.zarr"
    code, out, err = run_cli(
        capsys,
        "workspace",
        "map",
        "--robot",
        "puma560",
        "--resolution",
        str(RESOLUTION),
        "--orientations",
        str(ORIENTATIONS),
        "--block-voxels",
        str(BLOCK_VOXELS),
        "--scheduler",
        cluster,
        "--out",
        str(path),
        "--json",
    )
    assert (code, err) == (0, "")
    assert json.loads(out)["blocks_computed"] == json.loads(out)["blocks"]
    _same_map(reference, path)


@pytest.mark.slow
@pytest.mark.subprocess
def test_sampled_map_is_bitwise_the_same_on_1_2_workers_and_a_cluster(
    panda, panda_grid, cluster, tmp_path
) -> None:
    maps = {}
    for name, where in (("one", {"workers": 1}), ("two", {"workers": 2})):
        maps[name] = build_map(
            panda, panda_grid, tmp_path / f"{name}.zarr", samples=SAMPLES, **where
        )
    maps["cluster"] = build_map(
        panda, panda_grid, tmp_path / "cluster.zarr", samples=SAMPLES, scheduler=cluster
    )
    for name in ("two", "cluster"):
        _same_map(tmp_path / "one.zarr", tmp_path / f"{name}.zarr")
    summary = maps["one"]
    assert summary.sampled and summary.samples == SAMPLES and summary.blocks == 2
    atlas = open_map(tmp_path / "one.zarr")
    assert atlas.sampled and atlas.attrs["family"] == "franka"  # sampled on request
    assert atlas.attrs["sampling"] == {
        "samples_per_block": SAMPLES_PER_BLOCK,
        "seed": 0,
    }
    hit = atlas["reached"]
    assert set(np.unique(hit)) <= {0, 1} and hit.any()
    assert np.array_equal(hit == 1, ~np.isnan(atlas["dexterity"]))
    np.testing.assert_array_equal(
        atlas["reachability"], hit.mean(axis=1, dtype=np.float64).astype(np.float32)
    )
    assert summary.reachable_fraction == pytest.approx(hit.mean(), rel=1e-12)


def _failing_after(function, count: int):
    """``function`` for its first ``count`` calls, then a RuntimeError."""
    calls = []

    def failing(*args, **kwargs):
        calls.append(None)
        if len(calls) > count:
            raise RuntimeError("injected failure")
        return function(*args, **kwargs)

    return failing


def test_a_failed_build_resumes_with_the_missing_blocks_only(
    puma, grid, reference, tmp_path, monkeypatch, caplog
) -> None:
    path = tmp_path / "resumed.zarr"
    real = _block_tasks.evaluate_block
    monkeypatch.setattr(_block_tasks, "evaluate_block", _failing_after(real, 5))
    caplog.set_level("INFO", logger="workbench.workspace.build")
    with pytest.raises(RuntimeError, match="injected"):
        build_map(puma, grid, path, workers=1, block_voxels=BLOCK_VOXELS)
    partial = get_partial_path(path)
    assert not path.exists() and partial.is_dir()
    assert "5 of" in caplog.text and "the same command resumes" in caplog.text
    with pytest.raises(InputError, match="unfinished map build"):
        open_map(partial)
    stray = partial / "dexterity" / "c" / "0" / f"0.{'ab' * 16}.partial"
    stray.parent.mkdir(parents=True, exist_ok=True)
    stray.write_bytes(b"half a chunk")  # what a writer killed mid-chunk leaves
    monkeypatch.setattr(_block_tasks, "evaluate_block", real)
    progress: list[tuple[int, int]] = []
    summary = build_map(
        puma,
        grid,
        path,
        workers=2,
        block_voxels=BLOCK_VOXELS,
        progress=lambda done, total: progress.append((done, total)),
    )
    assert summary.blocks_computed == summary.blocks - 5
    assert progress[0] == (5, summary.blocks) and len(progress) == summary.blocks - 4
    assert not partial.exists() and not list(path.rglob("*.partial"))
    _same_map(reference, path)


@pytest.mark.slow
def test_a_sampled_build_resumes_and_equals_the_uninterrupted_one(
    panda, panda_grid, tmp_path, monkeypatch
) -> None:
    samples = SAMPLES_PER_BLOCK + 7  # 2 blocks, the last of 7 samples
    build_map(panda, panda_grid, tmp_path / "whole.zarr", samples=samples, workers=1)
    real = _block_tasks.sample_block
    monkeypatch.setattr(_sampled_fold, "SAVE_INTERVAL", 0.0)  # save after each block
    monkeypatch.setattr(_block_tasks, "sample_block", _failing_after(real, 1))
    path = tmp_path / "resumed.zarr"
    with pytest.raises(RuntimeError, match="injected"):
        build_map(panda, panda_grid, path, samples=samples, workers=1)
    done = zarr.open_group(get_partial_path(path))["done"][...]
    assert sorted(done.tolist()) == [0, 1]  # the first block run was saved
    monkeypatch.setattr(_block_tasks, "sample_block", real)
    summary = build_map(panda, panda_grid, path, samples=samples, workers=1)
    assert summary.blocks_computed == 1
    _same_map(tmp_path / "whole.zarr", path)


def _cli(*argv: str) -> list[str]:
    return [sys.executable, "-m", "workbench", "-q", "workspace", "map", *argv]


CLI_MAP = ["--robot", "puma560", "--resolution", "0.1", "--orientations", "64"]
CLI_MAP += ["--block-voxels", "32", "--workers", "1"]


@pytest.fixture(scope="module")
def cli_reference(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The command's map, built without interruption."""
    path = tmp_path_factory.mktemp("cli") / "whole.zarr"
    subprocess.run(_cli(*CLI_MAP, "--out", str(path)), check=True, timeout=300)
    return path


def _wait_for_blocks(partial: Path, count: int, process: subprocess.Popen) -> int:
    """Wait until ``count`` blocks are flagged done; returns how many there are."""
    deadline = time.monotonic() + 120.0
    while time.monotonic() < deadline:
        flags = partial / "done" / "c"
        # A chunk being written is a ``*.partial`` sibling until it is renamed.
        done = (
            sum(not f.name.endswith(".partial") for f in flags.iterdir())
            if flags.is_dir()
            else 0
        )
        if done >= count:
            return done
        if process.poll() is not None:
            raise AssertionError(f"the build ended first (exit {process.returncode})")
        time.sleep(0.01)
    raise TimeoutError("no block done")


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("stop", [signal.SIGKILL, signal.SIGINT])
def test_a_killed_command_resumes_to_the_same_map(
    stop, cli_reference, tmp_path
) -> None:
    path = tmp_path / "map.zarr"
    process = subprocess.Popen(
        _cli(*CLI_MAP, "--out", str(path)),
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    _wait_for_blocks(get_partial_path(path), 3, process)
    process.send_signal(stop)
    _, err = process.communicate(timeout=60)
    assert process.returncode == (-9 if stop == signal.SIGKILL else 130)
    assert "Traceback" not in err
    assert not path.exists()
    done = int(np.sum(zarr.open_group(get_partial_path(path))["done"][...] == 1))
    assert done >= 3
    again = subprocess.run(
        _cli(*CLI_MAP, "--out", str(path), "--json"),
        capture_output=True,
        text=True,
        check=True,
        timeout=300,
    )
    summary = json.loads(again.stdout)
    assert summary["blocks_computed"] == summary["blocks"] - done
    assert not get_partial_path(path).exists() and not list(path.rglob("*.partial"))
    _same_map(cli_reference, path)


def test_refusals(puma, grid, reference, tmp_path, monkeypatch) -> None:
    with pytest.raises(InputError, match="already exists"):
        build_map(puma, grid, reference, workers=1, block_voxels=BLOCK_VOXELS)
    with pytest.raises(InputError, match="workers or a scheduler, not both"):
        build_map(puma, grid, tmp_path / "m.zarr", workers=1, scheduler="tcp://x:1")
    for bad in (0, True, 1.5):
        with pytest.raises(InputError, match="workers must be a positive integer"):
            build_map(puma, grid, tmp_path / "m.zarr", workers=bad)
    with pytest.raises(InputError, match="block_voxels must be a positive"):
        build_map(puma, grid, tmp_path / "m.zarr", block_voxels=0)
    scene = Scene("box", (Obstacle("b", "box", (0.1, 0.1, 0.1), _pose()),))
    with pytest.raises(InputError, match="a sampled map checks no collisions"):
        build_map(puma, grid, tmp_path / "m.zarr", samples=10, scene=scene)
    monkeypatch.setattr(_dask, "CONNECT_TIMEOUT", 0.5)
    with pytest.raises(InputError, match="cannot reach the Dask scheduler"):
        build_map(puma, grid, tmp_path / "m.zarr", scheduler="tcp://127.0.0.1:9")


def _pose():
    import pinocchio as pin

    return pin.SE3(np.eye(3), np.array([0.5, 0.0, 0.0]))


def test_a_partial_build_of_another_map_or_in_use_is_refused(
    puma, grid, tmp_path, monkeypatch
) -> None:
    path = tmp_path / "m.zarr"
    real = _block_tasks.evaluate_block
    monkeypatch.setattr(_block_tasks, "evaluate_block", _failing_after(real, 0))
    with pytest.raises(RuntimeError):
        build_map(puma, grid, path, workers=1, block_voxels=BLOCK_VOXELS)
    monkeypatch.setattr(_block_tasks, "evaluate_block", real)
    other = make_pose_grid(puma, resolution=RESOLUTION, orientations=ORIENTATIONS + 1)
    with pytest.raises(InputError, match=r"another map \(orientation_set differ\)"):
        build_map(puma, other, path, workers=1, block_voxels=BLOCK_VOXELS)
    with pytest.raises(InputError, match="block_voxels differ"):
        build_map(puma, grid, path, workers=1, block_voxels=BLOCK_VOXELS + 1)
    lock = tmp_path / ".m.zarr.partial.lock"
    with lock.open("w") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        with pytest.raises(InputError, match="being built by another process"):
            build_map(puma, grid, path, workers=1, block_voxels=BLOCK_VOXELS)
    build_map(puma, grid, path, workers=1, block_voxels=BLOCK_VOXELS)
    assert not lock.exists() and open_map(path).attrs["robot"] == "puma560"


def test_a_scene_map_is_the_same_on_1_and_2_workers(puma, tmp_path) -> None:
    small = make_pose_grid(
        puma,
        resolution=0.3,
        orientations=4,
        bounds=[[0.2, -0.3, -0.3], [0.8, 0.3, 0.3]],
    )
    scene = Scene("box", (Obstacle("b", "box", (0.2, 0.2, 0.2), _pose()),))
    for workers in (1, 2):
        build_map(
            puma, small, tmp_path / f"{workers}.zarr", workers=workers, scene=scene
        )
    _same_map(tmp_path / "1.zarr", tmp_path / "2.zarr")
    atlas = open_map(tmp_path / "1.zarr")
    assert "collision_free" in atlas.names
    assert atlas.attrs["scene"]["objects"][0]["name"] == "b"
    free, usable = atlas["collision_free"], atlas["branches"]
    assert np.all(free <= usable) and np.any(free < usable)


def test_robot_spec_loads_the_same_robot_and_refuses_another(puma) -> None:
    spec = get_robot_spec(puma)
    assert spec.name == "puma560" and spec.tool_frame == puma.tool_frame
    again = load_spec_robot(spec)
    assert again is load_spec_robot(spec)  # once per thread
    assert np.array_equal(again.lower, puma.lower)
    from_path = get_robot_spec(load_robot(str(puma.urdf_path)))
    assert Path(from_path.name).is_absolute()
    assert from_path.urdf_sha256 == spec.urdf_sha256
    other = type(spec)(**{**_fields(spec), "urdf_sha256": "0" * 64})
    with pytest.raises(InputError, match="is not the build's"):
        load_spec_robot(other)
    limits = type(spec)(**{**_fields(spec), "upper": (1.0,) * 6})
    with pytest.raises(InputError, match=r"joint limits .* differ"):
        load_spec_robot(limits)
    scene = Scene("box", (Obstacle("b", "box", (0.2, 0.2, 0.2), _pose()),))
    from workbench.workspace.robot_spec import get_scene_json

    checker = load_spec_checker(spec, get_scene_json(scene))
    assert checker is load_spec_checker(spec, get_scene_json(scene))
    assert checker.scene.obstacles[0].name == "b"


def _fields(spec) -> dict:
    return {name: getattr(spec, name) for name in spec.__slots__}
