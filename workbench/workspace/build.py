"""Build a workspace map: blocks of voxels computed as Dask tasks into a Zarr store.

:func:`build_map` splits the grid into blocks of ``block_voxels`` voxels; each
block is one Dask task that evaluates every pose of its voxels
(:func:`~workbench.workspace.measures.evaluate_block`) and writes them into
its own chunk of every array, then the block's ``done`` flag. A block's bits
depend on the block only, so the map is bitwise the same on one worker, many
workers or a cluster.

Whole or nothing, and resumable: the map is written in ``MAP.zarr.partial``
(:func:`~workbench.workspace.store.get_partial_path`) and renamed ``MAP.zarr``
when every block is done. A build that stops (Ctrl-C, a crash, ``kill -9``)
leaves the partial folder; the same call again finds it, checks that it is a
build of the same map (robot, URDF, limits, grid, orientations, scene,
blocks, versions) and computes only the blocks not marked done. A partial
folder of another map is refused with a message saying so.

Arms without a closed form get a sampled map (:mod:`workbench.workspace.sampled`).
"""

from __future__ import annotations

import contextlib
import fcntl
import importlib.metadata
import json
import logging
import math
import os
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

import workbench
from workbench.atomic_files import check_output, move_folder_into_place
from workbench.collision import Scene
from workbench.errors import InputError, WorkbenchError
from workbench.ik import UnsupportedRobotError, get_closed_form
from workbench.model.robot import Robot
from workbench.singularities.conditions import ELBOW_TOL, SHOULDER_TOL, WRIST_TOL
from workbench.workspace._block_runner import run_tasks
from workbench.workspace.grid import PoseGrid
from workbench.workspace.measures import POSE_KEYS, VOXEL_KEYS, evaluate_block
from workbench.workspace.robot_spec import (
    RobotSpec,
    get_robot_spec,
    get_scene_json,
    load_spec_checker,
    load_spec_robot,
)
from workbench.workspace.store import (
    FORMAT,
    FORMAT_VERSION,
    create_store,
    get_attributes,
    get_block_count,
    get_partial_path,
    open_group_checked,
    read_array,
    read_done,
    write_block,
)

logger = logging.getLogger(__name__)

#: Voxels per block (one task, one chunk of every array): 256 voxels × 512
#: orientations is 131,072 poses, a quarter second of one core.
DEFAULT_BLOCK_VOXELS = 256
#: ``progress(done, total)``: blocks done so far (those of an earlier run
#: included) and in all.
ProgressCallback = Callable[[int, int], None]

_VERSIONED = ("workbench", "pinocchio", "numpy", "numba", "zarr", "dask")


@dataclass(frozen=True, slots=True)
class MapSummary:
    """What a build made (the keys of ``workbench workspace map --json``).

    Attributes:
        robot: Robot name (or URDF path).
        voxels: V, voxels of the grid.
        orientations: O, orientations per voxel.
        poses: V · O.
        sampled: Whether the map was sampled (no closed form).
        samples: Configurations sampled (None for an exact map).
        reachable_fraction: Fraction of the V · O poses with a usable branch.
        seconds: Wall time of the build [s].
        poses_per_second: Poses (samples of a sampled map) computed by this
            run per second [1/s].
        store: Path of the map folder.
        blocks: Blocks of the build.
        blocks_computed: Blocks computed by this run (fewer when resumed).
    """

    robot: str
    voxels: int
    orientations: int
    poses: int
    sampled: bool
    samples: int | None
    reachable_fraction: float
    seconds: float
    poses_per_second: float
    store: str
    blocks: int
    blocks_computed: int

    def as_dict(self) -> dict[str, Any]:
        """The summary as a JSON-ready dict."""
        return asdict(self)


@dataclass(frozen=True, slots=True)
class _BlockJob:
    """What every block task needs (sent once to each worker)."""

    spec: RobotSpec
    grid: PoseGrid
    scene_json: str | None
    path: str
    block_voxels: int


def _compute_block(job: _BlockJob, block: int) -> int:
    """Evaluate block ``block`` and write it (data, then its flag); returns it."""
    robot = load_spec_robot(job.spec)
    checker = (
        None if job.scene_json is None else load_spec_checker(job.spec, job.scene_json)
    )
    start = block * job.block_voxels
    stop = min(start + job.block_voxels, job.grid.voxel_count)
    if not Path(job.path).is_dir():
        raise InputError(
            f"a worker cannot see the map being built at {job.path}: the workers "
            "of a cluster must share its file system, at the same path"
        )
    write_block(
        job.path,
        block,
        start,
        evaluate_block(robot, job.grid, start, stop, checker=checker),
    )
    return block


def build_map(
    robot: Robot,
    grid: PoseGrid,
    path: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    scene: Scene | None = None,
    samples: int | None = None,
    block_voxels: int = DEFAULT_BLOCK_VOXELS,
    progress: ProgressCallback | None = None,
) -> MapSummary:
    """Compute the workspace map of ``robot`` over ``grid`` into ``path``.

    Args:
        robot: The arm; the grid is in its base frame.
        grid: The pose grid (:func:`~workbench.workspace.grid.make_pose_grid`).
        path: The map folder to create (``MAP.zarr``); must not exist.
        workers: Local threads (default: every core of this machine).
        scheduler: Address of a running Dask scheduler (``tcp://HOST:PORT``)
            to compute on instead; ``path`` must be on a file system every
            worker shares, at the same path.
        scene: Obstacles: then ``collision_free`` is counted and the best
            branch must be collision-free.
        samples: Sample this many configurations instead of solving in
            closed form (a sampled map); default: exact for arms with a
            closed form, sampled otherwise.
        block_voxels: Voxels per block (task and chunk).
        progress: Called with ``(done, total)`` blocks as they finish.

    Returns:
        The summary (also the CLI's JSON).

    Raises:
        InputError: On a bad argument, an existing ``path``, a partial build
            of another map at ``path``'s partial folder, a partial folder in
            use by another build, or an unreachable scheduler.
    """
    begin = time.perf_counter()
    path = Path(path).absolute()
    count = _check_arguments(workers, scheduler, samples, block_voxels)
    check_output(path, folder=True)
    spec = get_robot_spec(robot)
    scene_json = None if scene is None else get_scene_json(scene)
    family = _get_family(robot)
    if samples is not None or family is None:
        raise InputError(
            f"{robot.name} has no closed form: sampled maps are not available yet"
        )
    attrs = _map_attributes(robot, spec, grid, family, scene, block_voxels)
    partial = get_partial_path(path)
    total = get_block_count(grid.voxel_count, block_voxels)
    names = [k for k in (*POSE_KEYS, *VOXEL_KEYS) if k != "collision_free" or scene]
    with _locked(partial):
        check_output(path, folder=True)  # not made by another build meanwhile
        if partial.exists():
            _check_same_build(partial, attrs)
        else:
            create_store(
                partial, grid, names=names, block_voxels=block_voxels, attrs=attrs
            )
        done = read_done(partial)
        todo = [int(b) for b in np.flatnonzero(~done)]
        finished = total - len(todo)
        if progress is not None:
            progress(finished, total)

        def on_done(block: int, result: Any) -> None:
            nonlocal finished
            finished += 1
            if progress is not None:
                progress(finished, total)

        job = _BlockJob(spec, grid, scene_json, str(partial), block_voxels)
        try:
            run_tasks(
                _compute_block,
                job,
                todo,
                on_done=on_done,
                workers=count,
                scheduler=scheduler,
            )
        except BaseException:
            logger.warning(
                "map build stopped with %d of %d blocks done; they are kept in %s "
                "and the same command resumes the build",
                int(read_done(partial).sum()),
                total,
                partial,
            )
            raise
        reachable = _finish(partial, path, total)
    seconds = time.perf_counter() - begin
    computed = len(todo)
    poses = grid.pose_count
    computed_poses = (
        sum(min(block_voxels, grid.voxel_count - b * block_voxels) for b in todo)
        * grid.orientation_count
    )
    return MapSummary(
        robot=robot.name,
        voxels=grid.voxel_count,
        orientations=grid.orientation_count,
        poses=poses,
        sampled=False,
        samples=None,
        reachable_fraction=reachable,
        seconds=seconds,
        poses_per_second=computed_poses / seconds if seconds > 0 else math.inf,
        store=str(path),
        blocks=total,
        blocks_computed=computed,
    )


def _check_arguments(
    workers: int | None,
    scheduler: str | None,
    samples: int | None,
    block_voxels: int,
) -> int:
    """Validate the options; returns the local thread count."""
    if workers is not None and scheduler is not None:
        raise InputError("give workers or a scheduler, not both")
    for name, value in (
        ("workers", workers),
        ("samples", samples),
        ("block_voxels", block_voxels),
    ):
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, int | np.integer):
            raise InputError(f"{name} must be a positive integer, got {value!r}")
        if value < 1:
            raise InputError(f"{name} must be a positive integer, got {value}")
    if scheduler is not None and not isinstance(scheduler, str):
        raise InputError(f"scheduler must be an address string, got {scheduler!r}")
    return int(workers) if workers is not None else get_core_count()


def get_core_count() -> int:
    """Cores this process may run on (the default number of local workers)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _get_family(robot: Robot) -> str | None:
    """``"opw"`` or ``"ur"`` for an arm with a closed form, else None."""
    try:
        return get_closed_form(robot).family
    except UnsupportedRobotError:
        return None


def _get_versions() -> dict[str, str]:
    versions = {}
    for name in _VERSIONED:
        if name == "workbench":
            versions[name] = workbench.__version__
            continue
        try:
            versions[name] = importlib.metadata.version(
                "pin" if name == "pinocchio" else name
            )
        except importlib.metadata.PackageNotFoundError:
            versions[name] = "unknown"
    return versions


def _json_ready(value: Any) -> Any:
    """NumPy values as builtins, exactly (no rounding), tuples as lists."""
    if isinstance(value, Mapping):
        return {str(k): _json_ready(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return _json_ready(value.tolist())
    if isinstance(value, list | tuple):
        return [_json_ready(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _map_attributes(
    robot: Robot,
    spec: RobotSpec,
    grid: PoseGrid,
    family: str | None,
    scene: Scene | None,
    block_voxels: int,
) -> dict[str, Any]:
    """The group attributes of a map (``docs/workspace.md`` lists them)."""
    attrs = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "robot": robot.name,
        "urdf_sha256": spec.urdf_sha256,
        "tool_frame": robot.tool_frame,
        "family": family,
        "joint_limits": {"lower": spec.lower, "upper": spec.upper},
        "sampled": False,
        "samples": None,
        "grid": {
            "origin": grid.origin,
            "resolution": grid.resolution,
            "shape": grid.shape,
            "bounds": grid.bounds,
        },
        "orientation_set": grid.orientation_set,
        "block_voxels": block_voxels,
        "tolerances": {
            "shoulder": SHOULDER_TOL,
            "elbow": ELBOW_TOL,
            "wrist": WRIST_TOL,
        },
        "scene": None if scene is None else scene.to_dict(),
        "versions": _get_versions(),
    }
    ready = _json_ready(attrs)
    return json.loads(json.dumps(ready, allow_nan=False))


def _check_same_build(partial: Path, attrs: Mapping[str, Any]) -> None:
    """Raise unless the partial folder is a build of the map ``attrs`` describe."""
    try:
        stored = get_attributes(open_group_checked(partial, mode="r"))
    except InputError as err:
        raise InputError(
            f"{partial} is in the way of this build and is not a partial map "
            f"of it ({err}); remove it to start again"
        ) from err
    differ = [key for key in attrs if stored.get(key) != attrs[key]]
    if differ:
        raise InputError(
            f"{partial} holds an unfinished build of another map ({', '.join(differ)} "
            "differ); run the command that started it to finish it, or remove it "
            "to start this one"
        )


@contextlib.contextmanager
def _locked(partial: Path) -> Iterator[None]:
    """Hold an exclusive lock on the parent folder's entry for ``partial``.

    The lock is a ``flock`` on a hidden lock file beside the partial folder
    (the operating system drops it when the process dies), so two builds of
    one map never write the same partial folder.
    """
    lock = partial.with_name(f".{partial.name}.lock")
    fd = _lock_file(lock, partial)
    try:
        yield
        lock.unlink(missing_ok=True)
    finally:
        os.close(fd)


def _lock_file(lock: Path, partial: Path) -> int:
    """Open and ``flock`` the lock file; its descriptor (retried if replaced)."""
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as err:
            raise InputError(f"cannot write {lock}: {err.strerror or err}") from err
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            os.close(fd)
            raise InputError(
                f"{partial} is being built by another process; wait for it or stop it"
            ) from err
        try:
            same = os.fstat(fd).st_ino == lock.stat().st_ino
        except FileNotFoundError:  # its holder removed it as we took it
            same = False
        if same:
            return fd
        os.close(fd)


def _finish(partial: Path, path: Path, total: int) -> float:
    """Check every block is done, rename the partial folder; reachable fraction."""
    group = open_group_checked(partial, mode="r")
    done = read_array(group, "done")
    if not np.all(done == 1):
        raise WorkbenchError(
            f"{partial}: {int(done.sum())} of {total} blocks done after the run"
        )
    reachability = read_array(group, "reachability").astype(np.float64)
    reachable = float(np.nansum(reachability) / reachability.size)
    if path.exists():
        raise InputError(f"cannot write {path}: it appeared during the build")
    try:
        move_folder_into_place(partial, path)
    except OSError as err:
        raise InputError(f"cannot write {path}: {err.strerror or err}") from err
    return reachable
