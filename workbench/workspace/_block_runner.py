"""Run the block tasks of a map build on Dask: local threads or a cluster.

Each task computes one block and writes it into the store itself (data, then
its ``done`` flag), so the coordinator only counts finished tasks. Locally the
tasks run on Dask's threaded scheduler in this process: the compiled kernels
release the GIL (Numba ``nogil``), so threads run in parallel without a second
import, compile or copy of the grid. With a scheduler address they run on that
cluster through :func:`workbench._dask.connect` (the grid is scattered once to
every worker; the map's folder must be on a file system every worker shares).
"""

from __future__ import annotations

import logging
import uuid
from collections.abc import Callable, Sequence
from typing import Any

from workbench._dask import connect

logger = logging.getLogger(__name__)

#: ``task(shared, index)`` computes and stores item ``index``; ``shared`` is the
#: large read-only argument (the grid), sent once to each worker.
Task = Callable[[Any, int], Any]
#: Called once per finished item with its result, in the coordinating thread.
OnDone = Callable[[int, Any], None]


def run_tasks(
    task: Task,
    shared: Any,
    items: Sequence[int],
    *,
    on_done: OnDone,
    workers: int,
    scheduler: str | None = None,
) -> None:
    """Run ``task(shared, i)`` for every ``i`` of ``items``, in any order.

    Args:
        task: A picklable function (module level) of ``(shared, index)``.
        shared: Its first argument, the same for every item.
        items: The indices to run.
        on_done: Called in this thread after each item, with its result.
        workers: Threads of the local run (ignored with ``scheduler``).
        scheduler: Address of a Dask scheduler (``tcp://HOST:PORT``), or
            None for local threads.

    Raises:
        InputError: If the scheduler cannot be reached or has no worker.
        Exception: The first exception a task raised (the others are
            cancelled).
    """
    if not items:
        return
    if scheduler is None:
        _run_threads(task, shared, items, on_done, workers)
    else:
        _run_cluster(task, shared, items, on_done, scheduler)


def _run_threads(
    task: Task, shared: Any, items: Sequence[int], on_done: OnDone, workers: int
) -> None:
    """Dask's threaded scheduler in this process; ``on_done`` from its callbacks."""
    import dask
    from dask.callbacks import Callback

    prefix = f"workspace-block-{uuid.uuid4().hex}"
    keys = {f"{prefix}-{i}": i for i in items}
    results: dict[int, Any] = {}  # handed over, then dropped: none piles up

    def run(i: int) -> None:
        results[i] = task(shared, i)

    class _Finished(Callback):
        def _posttask(
            self, key: Any, result: Any, dsk: Any, state: Any, worker: Any
        ) -> None:
            if key in keys:
                on_done(keys[key], results.pop(keys[key]))

    tasks = [dask.delayed(run, pure=False)(i, dask_key_name=k) for k, i in keys.items()]
    with _Finished():
        dask.compute(*tasks, scheduler="threads", num_workers=workers)


def _run_cluster(
    task: Task, shared: Any, items: Sequence[int], on_done: OnDone, address: str
) -> None:
    """A Dask cluster: one future per item, ``on_done`` as they complete."""
    from distributed import as_completed

    with connect(address) as client:
        handle = client.scatter(shared, broadcast=True, hash=False)
        prefix = f"workspace-block-{uuid.uuid4().hex}"
        futures = {
            client.submit(task, handle, i, key=f"{prefix}-{i}", pure=False): i
            for i in items
        }
        try:
            for future in as_completed(futures, loop=client.loop):
                on_done(futures[future], future.result())
        finally:
            client.cancel(list(futures))
