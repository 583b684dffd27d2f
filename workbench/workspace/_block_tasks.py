"""What a worker runs for a map build: one block, from a small picklable job.

:class:`BlockJob` holds what every task of one build needs (the robot as a
:class:`~workbench.workspace.robot_spec.RobotSpec`, the grid, the store's
path); Dask sends it once to each worker. :func:`compute_block` evaluates a
block of voxels and writes it into the store (data, then the block's flag);
:func:`sample_task` returns the grid poses a block of random configurations
hits, for the build to fold in.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from workbench.errors import InputError
from workbench.workspace.grid import PoseGrid
from workbench.workspace.measures import evaluate_block
from workbench.workspace.redundant import evaluate_redundant_block
from workbench.workspace.robot_spec import (
    RobotSpec,
    load_spec_checker,
    load_spec_robot,
)
from workbench.workspace.sampled import sample_block
from workbench.workspace.store import BlockWriter

#: Configurations per block (one task) of a sampled map.
SAMPLES_PER_BLOCK = 1 << 18
#: Seed of a sampled map's generators (``default_rng([seed, block])``).
SAMPLE_SEED = 0


@dataclass(frozen=True, slots=True)
class BlockJob:
    """What every block task needs (sent once to each worker)."""

    spec: RobotSpec
    grid: PoseGrid
    path: str
    token: str  # unique to one build_map call
    block_voxels: int
    scene_json: str | None = None
    samples: int = 0
    redundancy_samples: int = 0  # K of a seven-axis map, 0 for the others


def compute_block(job: BlockJob, block: int) -> None:
    """Evaluate voxel block ``block`` and write it (data, then its flag).

    A seven-axis map (``redundancy_samples`` > 0) in closed form at K values
    of the redundancy parameter (:mod:`workbench.workspace.redundant`).
    """
    robot = load_spec_robot(job.spec)
    start = block * job.block_voxels
    stop = min(start + job.block_voxels, job.grid.voxel_count)
    if job.redundancy_samples:
        data = evaluate_redundant_block(
            robot, job.grid, start, stop, count=job.redundancy_samples
        )
        _get_writer(job.path, job.token).write(block, start, data)
        return
    checker = None
    if job.scene_json is not None:
        checker = load_spec_checker(job.spec, job.scene_json)
    # the per-pose arrays are this thread's buffers: stored before its next block
    data = evaluate_block(robot, job.grid, start, stop, checker=checker, reuse=True)
    _get_writer(job.path, job.token).write(block, start, data)


@functools.lru_cache(maxsize=4)
def _get_writer(path: str, token: str) -> BlockWriter:
    """The writer of a build's store, opened once per worker process.

    Raises:
        InputError: If the store is not there (a worker on another file system).
    """
    if not Path(path).is_dir():
        raise InputError(
            f"a worker cannot see the map being built at {path}: the workers "
            "of a cluster must share its file system, at the same path"
        )
    return BlockWriter(path)


def sample_task(job: BlockJob, block: int) -> tuple[np.ndarray, np.ndarray]:
    """The grid poses hit by sample block ``block`` and their manipulability."""
    count = min(SAMPLES_PER_BLOCK, job.samples - block * SAMPLES_PER_BLOCK)
    robot = load_spec_robot(job.spec)
    return sample_block(robot, job.grid, block, count, SAMPLE_SEED)
