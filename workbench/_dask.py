"""A Dask cluster as the jobs of the library reach it: address check, client, timeouts.

Shared by the map builds (:mod:`workbench.workspace`) and the batch planning of
:mod:`workbench.motion`: :func:`check_scheduler` refuses a bad address within
a few seconds (Dask itself retries the connection for a long while), and
:func:`connect` opens a :class:`distributed.Client` that has a worker, or
refuses with an :class:`~workbench.errors.InputError` saying which of the two
failed.
"""

from __future__ import annotations

import asyncio
import re
import socket
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from workbench.errors import InputError

#: Seconds to wait for a scheduler to answer (an address with no scheduler
#: fails after this long: Dask retries the connection until then).
CONNECT_TIMEOUT = 10.0
#: Seconds the check of a scheduler address waits for its answer (connect, then
#: Dask's handshake), so that a bad address is refused within a few seconds.
PROBE_TIMEOUT = 2.0
#: Seconds to wait for the first worker of a scheduler that answered.
WORKER_TIMEOUT = 30.0
#: ``[tcp://]HOST:PORT`` (HOST a name, an IPv4 address or a bracketed IPv6 one).
_ADDRESS = re.compile(
    r"(?:tcp://)?(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):(?P<port>\d{1,5})"
)


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


@contextmanager
def connect(address: str) -> Iterator[Any]:
    """A :class:`distributed.Client` of the scheduler at ``address`` with a worker.

    Waits :data:`CONNECT_TIMEOUT` for the scheduler, then
    :data:`WORKER_TIMEOUT` for its first worker; the client is closed on exit.

    Raises:
        InputError: If the scheduler cannot be reached or has no worker.
    """
    from distributed import Client

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
        yield client
