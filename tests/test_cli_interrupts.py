"""Ctrl-C and kill -9 at random moments never leave a half-written file.

``workbench demo``, ``workbench plan --csv``, ``workspace view`` and
``workspace report`` run as processes and are stopped by SIGINT or SIGKILL
after a random delay, with some outputs existing beforehand: every output is
then absent, the old one or complete, SIGINT exits 130 without a traceback, and
the demo's forked worker ends with it. ``workspace map`` stopped by SIGINT
leaves no map (or the whole one) and a partial folder that the same command
resumes to a map bitwise equal to an uninterrupted build.
``python -m tests.run_cli_robustness`` runs hundreds of interrupts per command.
"""

from __future__ import annotations

import functools
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tests._interrupts import (
    Tally,
    interrupt_map_once,
    interrupt_once,
    map_reference,
    run_reference,
)

pytestmark = [pytest.mark.subprocess, pytest.mark.slow]

INTERRUPTS = 10  # per command: the suite stays fast
MAX_DELAY = 2.0  # [s] the commands take 3-6 s; most runs are stopped midway
#: [s] Python's own start (interpreter, site, compiling ``workbench/__init__``
#: where no bytecode is written) precedes any workbench code: a SIGINT there is
#: Python's KeyboardInterrupt (docs/interface.md, exit codes). The smallest
#: delay is this or, on a loaded machine, 3 × the start of ``python -c pass``
#: measured here (:func:`_min_delay`).
MIN_DELAY = 0.15


@functools.cache
def _min_delay() -> float:
    """The first moment a SIGINT is sent [s]: after Python's own start."""
    starts = []
    for _ in range(3):
        begin = time.perf_counter()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        starts.append(time.perf_counter() - begin)
    return max(MIN_DELAY, 3.0 * max(starts))


#: Per workspace command: each interrupt of ``workspace map`` is followed by
#: the run that resumes it (about 4 s in all).
WORKSPACE_INTERRUPTS = 2
#: [s] ``view`` and ``report`` of a small map take 1.5-3 s, ``map`` 3.5 s.
WORKSPACE_MAX_DELAY = {"workspace view": 1.8, "workspace report": 2.5, "map": 3.0}


@pytest.mark.parametrize("name", ["demo", "plan"])
def test_interrupted_runs_leave_whole_files(name: str, tmp_path: Path) -> None:
    if name == "demo":
        reference = run_reference(name, tmp_path)
    else:  # a trajectory CSV is checked by its reader, not against a reference
        reference = {"out/big.csv": b""}
    tally = _interrupt_repeatedly(name, tmp_path, reference, 7, INTERRUPTS, MAX_DELAY)
    assert tally.orphans == 0
    assert tally.exits[130] + tally.exits[-9] > 0  # some runs were stopped midway


@pytest.mark.parametrize("name", ["workspace view", "workspace report"])
def test_interrupted_workspace_pages_are_whole_or_old(
    name: str, tmp_path: Path
) -> None:
    reference = run_reference(name, tmp_path)
    delay = WORKSPACE_MAX_DELAY[name]
    _interrupt_repeatedly(name, tmp_path, reference, 11, WORKSPACE_INTERRUPTS, delay)


def _interrupt_repeatedly(
    name: str,
    tmp_path: Path,
    reference: dict[str, bytes],
    seed: int,
    count: int,
    max_delay: float,
) -> Tally:
    """Interrupt ``count`` runs of ``name``: no half file, no traceback."""
    rng = np.random.default_rng(seed)
    tally = Tally()
    for _ in range(count):
        interrupt_once(
            name, tmp_path, reference, rng, tally, max_delay=max_delay,
            min_delay=_min_delay(),
        )  # fmt: skip
    assert tally.problems == []
    assert tally.files["truncated"] == 0 and tally.tracebacks == 0
    assert tally.stderr_lines_over_one == 0
    assert set(tally.exits) <= {0, 130, -9}
    return tally


def test_interrupted_map_resumes_to_the_same_bits(tmp_path: Path) -> None:
    reference = map_reference(tmp_path)
    rng = np.random.default_rng(5)
    tally = Tally()
    for _ in range(WORKSPACE_INTERRUPTS):
        interrupt_map_once(
            tmp_path,
            reference,
            rng,
            tally,
            max_delay=WORKSPACE_MAX_DELAY["map"],
            min_delay=_min_delay(),
            kill=signal.SIGINT,
        )
    assert tally.problems == []
    assert tally.files["truncated"] == 0 and tally.tracebacks == 0
    assert tally.stderr_lines_over_one == 0
    assert tally.files["resumed equal"] == WORKSPACE_INTERRUPTS
    assert set(tally.exits) <= {0, 130} and tally.exits[130] > 0


#: A ``workbench`` command whose run is interrupted while Zarr's event loop has
#: tasks pending (as a ``workspace`` command reading or writing a map).
_PENDING_ZARR_TASKS = """
import asyncio
import sys
import time

import zarr.core.sync

from workbench.cli import fk, main


async def pending() -> None:
    await asyncio.sleep(3600)


def interrupted(args) -> int:
    for _ in range(20):
        asyncio.run_coroutine_threadsafe(pending(), zarr.core.sync._get_loop())
    raise KeyboardInterrupt


fk.run = interrupted
sys.exit(main(["fk", "--robot", "puma560", "--rad", "0"]))
"""


def test_interrupt_with_pending_zarr_tasks_prints_nothing(tmp_path: Path) -> None:
    script = tmp_path / "workbench"  # the name makes it the workbench command
    script.write_text(_PENDING_ZARR_TASKS)
    done = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, check=False
    )
    assert (done.returncode, done.stderr) == (130, "")
