"""Run the block tasks of a map build on Dask: local threads or a cluster.

Each task computes one block and writes it into the store itself (data, then
its ``done`` flag), so the coordinator only counts finished tasks. Locally the
tasks run on Dask's threaded scheduler in this process: the compiled kernels
release the GIL (Numba ``nogil``), so threads run in parallel without a second
import, compile or copy of the grid. With a scheduler address they run on that
cluster through :class:`distributed.Client` (the grid is scattered once to
every worker; the map's folder must be on a file system every worker shares).
"""

from __future__ import annotations

import asyncio
import logging
import re
import socket
import uuid
from collections.abc import Callable, Sequence
from typing import Any

from workbench.errors import InputError

logger = logging.getLogger(__name__)

#: Seconds to wait for a scheduler to answer (an address with no scheduler
#: fails after this long: Dask retries the connection until then).
CONNECT_TIMEOUT = 10.0
#: Seconds the check of a scheduler address waits for its answer (connect, then
#: Dask's handshake), so that a bad address is refused within a few seconds.
PROBE_TIMEOUT = 2.0
#: ``[tcp://]HOST:PORT`` (HOST a name, an IPv4 address or a bracketed IPv6 one).
_ADDRESS = re.compile(
    r"(?:tcp://)?(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):(?P<port>\d{1,5})"
)
#: Seconds to wait for the first worker of a scheduler that answered.
WORKER_TIMEOUT = 30.0

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


def check_scheduler(address: str) -> str:
    """Parse and probe a Dask scheduler address; returns it as ``tcp://HOST:PORT``.

    The address is parsed, connected to and asked who it is (Dask's
    ``identity``), each within :data:`PROBE_TIMEOUT`, so that a bad address is
    refused at once instead of after Dask's connection retries.

    Raises:
        InputError: If ``address`` is not ``[tcp://]HOST:PORT``, nothing
            listens there, or what answers is no Dask scheduler.
    """
    match = _ADDRESS.fullmatch(address) if isinstance(address, str) else None
    port = int(match["port"]) if match else 0
    if match is None or not 1 <= port <= 65535:
        raise InputError(
            f"scheduler address {address!r} is not tcp://HOST:PORT (PORT 1..65535), "
            "e.g. tcp://10.0.0.5:8786"
        )
    host = match["host"].strip("[]")
    normal = f"tcp://{match['host']}:{port}"
    try:
        socket.create_connection((host, port), timeout=PROBE_TIMEOUT).close()
    except OSError as err:
        reason = err.strerror or str(err) or type(err).__name__
        if isinstance(err, TimeoutError | socket.timeout):
            reason = f"no answer within {PROBE_TIMEOUT:g} s"
        raise InputError(
            f"cannot reach the Dask scheduler at {normal}: {reason}"
        ) from err
    try:
        reply = asyncio.run(asyncio.wait_for(_identity(normal), PROBE_TIMEOUT))
    except Exception as err:  # no Dask handshake in time, or a stranger's reply
        reply = {"error": " ".join(str(err).split()) or type(err).__name__}
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        raise InputError(
            f"{normal} answers but is no Dask scheduler (asked for its identity "
            f"within {PROBE_TIMEOUT:g} s)"
        )
    return normal


async def _identity(address: str) -> Any:
    """Dask's ``identity`` reply of the server at ``address`` (no time limit)."""
    from distributed.comm import connect

    comm = await connect(address, timeout=PROBE_TIMEOUT)
    try:
        await comm.write({"op": "identity"})
        return await comm.read()
    finally:
        comm.abort()


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
    from distributed import Client, as_completed

    try:
        client = Client(address, timeout=CONNECT_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError, ValueError, TypeError) as err:
        message = " ".join(str(err).split()) or type(err).__name__
        raise InputError(
            f"cannot reach the Dask scheduler at {address}: {message}"
        ) from err
    with client:
        try:
            client.wait_for_workers(1, timeout=WORKER_TIMEOUT)
        except TimeoutError as err:
            raise InputError(
                f"the Dask scheduler at {address} has no worker "
                f"(waited {WORKER_TIMEOUT:g} s)"
            ) from err
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
