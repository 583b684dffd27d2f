"""A real Dask cluster on localhost for the tests: a scheduler and one-thread workers.

The processes are the ``dask scheduler`` and ``dask worker`` commands of the
test's environment, found through a scheduler file, each in its own process
group, stopped (SIGTERM, then SIGKILL) when the context ends.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

DASK = [str(Path(sys.executable).parent / "dask")]
LOCAL = ["--host", "127.0.0.1", "--no-dashboard"]
SCHEDULER = [*DASK, "scheduler", "--port", "0"]
WORKER = [*DASK, "worker", *LOCAL, "--nthreads", "1", "--no-nanny"]
#: Seconds to wait for the cluster's processes to start, and to stop.
CLUSTER_START = 60.0
STOP_GRACE = 3.0


@contextmanager
def start_cluster(folder: Path, workers: int = 2) -> Iterator[str]:
    """Address of a local Dask cluster of ``workers`` one-thread workers."""
    scheduler_file = folder / "scheduler.json"
    common = {"cwd": folder, "start_new_session": True, "stderr": subprocess.DEVNULL}
    processes = [
        subprocess.Popen(
            [
                *DASK,
                "scheduler",
                "--port",
                "0",
                "--scheduler-file",
                str(scheduler_file),
            ],
            stdout=subprocess.DEVNULL,
            **common,
        )
    ]
    try:
        for _ in range(workers):
            processes.append(
                subprocess.Popen(
                    [*WORKER, "--scheduler-file", str(scheduler_file)],
                    stdout=subprocess.DEVNULL,
                    **common,
                )
            )
        yield _wait_for_workers(scheduler_file, workers)
    finally:
        _stop(processes)


def _stop(processes: list[subprocess.Popen]) -> None:
    """SIGTERM to each process group, SIGKILL to those still there after a while."""
    for process in processes:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGTERM)
    deadline = time.monotonic() + STOP_GRACE
    for process in processes:
        try:
            process.wait(timeout=max(deadline - time.monotonic(), 0.01))
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()


def _wait_for_workers(scheduler_file: Path, count: int) -> str:
    from distributed import Client

    deadline = time.monotonic() + CLUSTER_START
    while not scheduler_file.exists():
        if time.monotonic() > deadline:
            raise TimeoutError("the Dask scheduler did not start")
        time.sleep(0.05)
    address = json.loads(scheduler_file.read_text())["address"]
    with Client(address, timeout=CLUSTER_START) as client:
        client.wait_for_workers(count, timeout=CLUSTER_START)
    return address
