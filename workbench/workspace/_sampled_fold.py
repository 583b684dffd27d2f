"""The coordinator's side of a sampled map: fold the blocks in, save, summarise.

Each sample task returns the grid poses its samples hit and their
manipulability; :func:`run_sampled` folds them into the map in memory (hit
flag and maximum, :func:`~workbench.workspace.sampled.accumulate`: the same
bits in any order), saves the arrays every :data:`SAVE_INTERVAL` seconds and
at the end, then the ``done`` flags of the blocks they hold, and finally the
per-voxel summaries. A block folded twice (saved, then run again after a
stop) changes nothing: a maximum is idempotent.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import zarr

from workbench.workspace._block_runner import run_tasks
from workbench.workspace._block_tasks import BlockJob, sample_task
from workbench.workspace._reference import summarise_voxels
from workbench.workspace.sampled import accumulate
from workbench.workspace.store import DONE, get_array, open_group_checked, read_array

#: Seconds between two saves of a sampled map's folded arrays.
SAVE_INTERVAL = 30.0
#: The arrays of a sampled map: the hit flag (as ``reached``), the largest
#: manipulability, and the per-voxel summaries of those.
SAMPLED_KEYS = (
    "reached",
    "dexterity",
    "reachability",
    "dexterity_best",
    "dexterity_median",
)
#: Voxels summarised at once at the end of a sampled build (bounds the memory).
_SUMMARY_VOXELS = 4096


def run_sampled(
    job: BlockJob,
    todo: list[int],
    on_block: Callable[[int], None],
    threads: int,
    scheduler: str | None,
) -> None:
    """Sample the blocks ``todo``, fold them in, save as they come; then summarise.

    Args:
        job: The build's job (``samples`` > 0).
        todo: Sample blocks not done yet.
        on_block: Called with each block once it is folded in.
        threads: Local threads (without ``scheduler``).
        scheduler: Address of a Dask scheduler, or None.
    """
    group = open_group_checked(job.path, mode="r+")
    hit = np.ascontiguousarray(read_array(group, "reached").reshape(-1))
    dexterity = np.ascontiguousarray(read_array(group, "dexterity").reshape(-1))
    folded: list[int] = []
    saved = time.monotonic()

    def save() -> None:
        nonlocal saved
        shape = (job.grid.voxel_count, job.grid.orientation_count)
        get_array(group, "reached")[...] = hit.reshape(shape)
        get_array(group, "dexterity")[...] = dexterity.reshape(shape)
        flags = get_array(group, DONE)
        for block in folded:
            flags[block] = 1
        folded.clear()
        saved = time.monotonic()

    def fold(block: int, result: tuple[np.ndarray, np.ndarray]) -> None:
        accumulate(*result, hit, dexterity)
        folded.append(block)
        if time.monotonic() - saved > SAVE_INTERVAL:
            save()
        on_block(block)

    try:
        run_tasks(
            sample_task, job, todo, on_done=fold, workers=threads, scheduler=scheduler
        )
    finally:
        if folded:
            save()
    _save_summaries(group, dexterity.reshape(job.grid.voxel_count, -1))


def _save_summaries(group: zarr.Group, dexterity: np.ndarray) -> None:
    """The per-voxel arrays of a sampled map from its (V, O) dexterity."""
    for start in range(0, len(dexterity), _SUMMARY_VOXELS):
        part = dexterity[start : start + _SUMMARY_VOXELS].astype(np.float64)
        summary = summarise_voxels(part, np.full(part.shape, np.nan))
        for name in SAMPLED_KEYS[2:]:
            get_array(group, name)[start : start + len(part)] = summary[name]
