"""Build a workspace map: blocks computed as Dask tasks into a Zarr store.

:func:`build_map` splits the work into blocks. For an arm with a closed form,
a block is ``block_voxels`` voxels × every orientation: one Dask task
evaluates its poses (:func:`~workbench.workspace.measures.evaluate_block`) and
writes them into its own chunk of every array, then the block's ``done`` flag.
A block's bits depend on the block only, so the map is bitwise the same on one
worker, many workers or a cluster.

Seven-axis arms of the SRS and Franka families get the same blocks, each pose
solved in closed form at K values of the redundancy parameter
(:mod:`workbench.workspace.redundant`). Arms without a closed form get a
sampled map (:mod:`workbench.workspace.sampled`): a block is
:data:`SAMPLES_PER_BLOCK` random configurations, drawn from
``default_rng([seed, block])``; each task returns the grid poses its samples
hit and their manipulability, which this process folds into the map (hit flag
and maximum: the same bits in any order), saving it as it goes
(:mod:`._sampled_fold`). Workers run :mod:`._block_tasks`.

Whole or nothing, and resumable: the map is written in ``MAP.zarr.partial``
and renamed ``MAP.zarr`` when every block is done (:mod:`._partial`). A
build that stops (Ctrl-C, an error, ``kill -9``) leaves the partial folder;
the same call again checks that it is a build of the same map (robot, URDF,
limits, grid, orientations, scene, blocks, sampling, versions) and computes
only the blocks not marked done (a sampled map folds a block twice at worst,
which a maximum ignores).
"""

from __future__ import annotations

import logging
import math
import os
import time
import uuid
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from workbench._dask import check_scheduler
from workbench.atomic_files import check_output
from workbench.collision import Scene
from workbench.errors import InputError
from workbench.ik import Family, get_family, get_solver
from workbench.model.robot import Robot
from workbench.workspace._block_runner import run_tasks
from workbench.workspace._block_tasks import SAMPLES_PER_BLOCK, BlockJob, compute_block
from workbench.workspace._partial import (
    check_same_build,
    finish,
    locked,
    map_attributes,
)
from workbench.workspace._sampled_fold import SAMPLED_KEYS, run_sampled
from workbench.workspace.grid import DEFAULT_BLOCK_VOXELS, PoseGrid
from workbench.workspace.measures import POSE_KEYS, VOXEL_KEYS, get_core_count
from workbench.workspace.redundant import (
    DEFAULT_REDUNDANCY_SAMPLES,
    REDUNDANT_POSE_KEYS,
    REDUNDANT_VOXEL_KEYS,
    redundancy_values,
)
from workbench.workspace.robot_spec import get_robot_spec, get_scene_json
from workbench.workspace.sampled import check_samplable
from workbench.workspace.store import (
    ARRAYS,
    DONE,
    create_store,
    get_block_count,
    get_partial_path,
    open_group_checked,
    read_array,
)

logger = logging.getLogger(__name__)

#: Configurations of a sampled map when none is given.
DEFAULT_SAMPLES = 10_000_000
#: ``progress(done, total)``: blocks done so far (those of an earlier run
#: included) and in all.
ProgressCallback = Callable[[int, int], None]


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
        redundancy_samples: K, the values of the redundancy parameter each
            pose of a seven-axis exact map is solved at (else None).
        reachable_fraction: Fraction of the V · O poses with a usable branch
            (of a sampled map: hit by a sample).
        seconds: Wall time of the build [s].
        poses_per_second: Poses (of a sampled map: samples) computed by this
            run, per second [1/s].
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
    redundancy_samples: int | None
    reachable_fraction: float
    seconds: float
    poses_per_second: float
    store: str
    blocks: int
    blocks_computed: int

    def as_dict(self) -> dict[str, Any]:
        """The summary as a JSON-ready dict."""
        return asdict(self)


class _Counter:
    """Counts finished blocks and reports them to a progress callback."""

    def __init__(self, done: int, total: int, progress: ProgressCallback | None):
        self.done, self.total, self._progress = done, total, progress
        self._report()

    def add(self, block: int, result: Any = None) -> None:
        self.done += 1
        self._report()

    def _report(self) -> None:
        if self._progress is not None:
            self._progress(self.done, self.total)


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
    redundancy_samples: int | None = None,
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
            branch must be collision-free (exact maps only).
        samples: Sample this many configurations instead of solving in
            closed form (a sampled map); default: exact for arms with a
            closed form, :data:`DEFAULT_SAMPLES` for the others.
        block_voxels: Voxels per block of an exact map, and per chunk.
        redundancy_samples: K of a seven-axis arm's exact map: each pose
            solved in closed form at K values of its redundancy parameter
            (:mod:`workbench.workspace.redundant`); default
            :data:`~workbench.workspace.redundant.DEFAULT_REDUNDANCY_SAMPLES`.
            Only for arms of the SRS or Franka family, without ``samples``.
        progress: Called with ``(done, total)`` blocks as they finish.

    Returns:
        The summary (also the CLI's JSON).

    Raises:
        InputError: On a bad argument, an existing ``path``, a partial build
            of another map in ``path``'s partial folder, a partial folder in
            use by another build, an unreachable scheduler, a scene with a
            sampled map, a scene with a seven-axis map, ``redundancy_samples``
            for another arm or with ``samples``.
    """
    begin = time.perf_counter()
    path = Path(path).absolute()
    threads = _check_arguments(workers, scheduler, samples, block_voxels)
    if scheduler is not None:
        scheduler = check_scheduler(scheduler)
    check_output(path, folder=True)
    family = get_family(robot)
    sampled = samples is not None or family is None
    if sampled and scene is not None:
        raise InputError(
            "a sampled map checks no collisions: a scene needs an exact map (an "
            "arm with a closed form, without samples)"
        )
    redundancy = _redundancy_attributes(robot, family, sampled, redundancy_samples)
    if redundancy is not None and scene is not None:
        raise InputError(
            "a seven-axis map checks no collisions: a scene needs a six-axis arm"
        )
    if sampled:
        check_samplable(robot)
    count = (samples or DEFAULT_SAMPLES) if sampled else 0
    spec = get_robot_spec(robot)
    attrs = map_attributes(
        robot,
        spec,
        grid,
        None if family is None else family.name,
        scene,
        block_voxels,
        count,
        redundancy,
    )
    if sampled:
        names = list(SAMPLED_KEYS)
        total = get_block_count(count, SAMPLES_PER_BLOCK)
    elif redundancy is not None:
        names = [*REDUNDANT_POSE_KEYS, *REDUNDANT_VOXEL_KEYS]
        total = get_block_count(grid.voxel_count, block_voxels)
    else:
        names = [k for k in (*POSE_KEYS, *VOXEL_KEYS) if k != "collision_free" or scene]
        total = get_block_count(grid.voxel_count, block_voxels)
    if not sampled:
        _check_memory(names, block_voxels, grid.orientation_count, threads, scheduler)
    partial = get_partial_path(path)
    with locked(partial):
        check_output(path, folder=True)  # not made by another build meanwhile
        if partial.exists():
            check_same_build(partial, attrs)
        else:
            create_store(
                partial,
                grid,
                names=names,
                block_voxels=block_voxels,
                attrs=attrs,
                blocks=total,
            )
        todo = [
            int(b)
            for b in np.flatnonzero(read_array(open_group_checked(partial), DONE) != 1)
        ]
        job = BlockJob(
            spec=spec,
            grid=grid,
            path=str(partial),
            token=uuid.uuid4().hex,
            block_voxels=block_voxels,
            scene_json=None if scene is None else get_scene_json(scene),
            samples=count,
            redundancy_samples=0 if redundancy is None else redundancy["samples"],
        )
        counter = _Counter(total - len(todo), total, progress)
        try:
            if sampled:
                run_sampled(job, todo, counter.add, threads, scheduler)
            else:
                run_tasks(
                    compute_block,
                    job,
                    todo,
                    on_done=counter.add,
                    workers=threads,
                    scheduler=scheduler,
                )
        except BaseException as err:
            # A Ctrl-C's one line tells how to resume; after an error, whose
            # line is the one on stderr, it is information (-v).
            stopped = isinstance(err, KeyboardInterrupt)
            logger.log(
                logging.WARNING if stopped else logging.INFO,
                "map build stopped with %d of %d blocks done; they are kept in %s "
                "and the same command resumes the build",
                counter.done,
                total,
                partial,
            )
            raise
        reachability = read_array(open_group_checked(partial), "reachability").astype(
            np.float64
        )
        finish(partial, path)
    seconds = time.perf_counter() - begin
    if sampled:
        computed = sum(
            min(SAMPLES_PER_BLOCK, count - b * SAMPLES_PER_BLOCK) for b in todo
        )
    else:
        voxels = sum(
            min(block_voxels, grid.voxel_count - b * block_voxels) for b in todo
        )
        computed = voxels * grid.orientation_count
    return MapSummary(
        robot=robot.name,
        voxels=grid.voxel_count,
        orientations=grid.orientation_count,
        poses=grid.pose_count,
        sampled=sampled,
        samples=count if sampled else None,
        redundancy_samples=None if redundancy is None else redundancy["samples"],
        reachable_fraction=float(np.sum(reachability) / reachability.size),
        seconds=seconds,
        poses_per_second=computed / seconds if seconds > 0 else math.inf,
        store=str(path),
        blocks=total,
        blocks_computed=len(todo),
    )


def _check_arguments(
    workers: int | None,
    scheduler: str | None,
    samples: int | None,
    block_voxels: int,
) -> int:
    """Validate the options; returns the number of local threads."""
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


def _check_memory(
    names: list[str],
    block_voxels: int,
    orientations: int,
    threads: int,
    scheduler: str | None,
) -> None:
    """Refuse blocks whose chunks alone exceed this machine's memory.

    Each task holds one chunk of every array, ``block_voxels`` rows of
    ``orientations`` poses (the last chunk padded to that length), besides
    the kernel's own buffers; local tasks run ``threads`` at a time. On a
    cluster one task's chunks are checked (its workers' memory is unknown
    here, this machine's is taken as a guide).

    Raises:
        InputError: Stating the bytes needed and the memory there is.
    """
    per_voxel = sum(
        np.dtype(ARRAYS[n].dtype).itemsize * (orientations if ARRAYS[n].per_pose else 1)
        for n in names
    )
    tasks = 1 if scheduler is not None else threads
    needed = per_voxel * block_voxels * tasks
    memory = _get_memory_bytes()
    if memory is not None and needed > memory:
        raise InputError(
            f"blocks of {block_voxels} voxels × {orientations} orientations need "
            f"at least {needed / 2**30:.3g} GiB ({tasks} at a time), more than the "
            f"{memory / 2**30:.3g} GiB of memory here; lower --block-voxels, "
            "--orientations or --workers"
        )


def _get_memory_bytes() -> int | None:
    """Physical memory of this machine [bytes], or None where unknown."""
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return None


def _redundancy_attributes(
    robot: Robot, family: Family | None, sampled: bool, count: int | None
) -> dict[str, Any] | None:
    """The ``redundancy`` attribute of a seven-axis exact map, else None.

    Raises:
        InputError: If ``count`` is given for a sampled map or an arm without
            a redundancy parameter, or is out of range.
    """
    seven_axis = family is not None and family.redundant
    if count is not None and (sampled or not seven_axis):
        what = "a sampled map" if sampled else f"{robot.name} (no seven-axis family)"
        raise InputError(
            "redundancy samples are the values of a seven-axis arm's redundancy "
            f"parameter (SRS or Franka family, exact map): not for {what}"
        )
    if sampled or not seven_axis:
        return None
    solver = get_solver(robot)
    if solver.parameter_range is None:  # (a seven-axis family has one)
        raise InputError(f"robot {robot.name!r} is no seven-axis arm")
    k = DEFAULT_REDUNDANCY_SAMPLES if count is None else count
    values = redundancy_values(solver.parameter_range, k)
    return {
        "parameter": solver.parameter,
        "range": [float(v) for v in solver.parameter_range],
        "samples": int(k),
        "values": values.tolist(),
    }
