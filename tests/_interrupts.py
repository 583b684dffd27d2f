"""Stop ``workbench demo`` and ``workbench plan --csv`` at random moments.

Used by ``tests/test_cli_interrupts.py`` (a few interrupts in the suite) and by
``tests/run_cli_robustness.py`` (hundreds per command, with a table). Each
interrupt starts the command as a process in a folder where some outputs
already exist (old contents) and others do not, sends SIGINT or SIGKILL after a
random delay, and sorts every output into absent, old, complete or truncated
(anything else). A complete file is one a reader accepts whole: a trajectory
CSV with its sample count, JSON that parses, text equal to a finished run's.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tests._cli_fuzz import PLAN
from workbench.atomic_files import get_temporaries
from workbench.errors import InputError
from workbench.trajectory.csv_io import read_trajectory_csv, record_path

OLD = b"old output, from an earlier run\n"
#: Seconds a forked worker may take to end after its parent was killed.
ORPHAN_GRACE = 1.0

#: argv (run in the command's folder) and the files it writes there.
COMMANDS: dict[str, tuple[list[str], tuple[str, ...]]] = {
    "demo": (
        ["demo", "--out", "out", "--no-plots"],
        (
            "out/table2.md",
            "out/pick_and_place.csv",
            "out/puma560.srdf",
            "out/fishcut.csv",
            "out/summary.json",
        ),
    ),
    "plan": (
        [*PLAN, "--rate", "20000", "--csv", "out/big.csv", "--no-collision"],
        ("out/big.csv",),
    ),
    "workspace view": (
        ["workspace", "view", "map.zarr", "--html", "out/v.html"],
        ("out/v.html",),
    ),
    "workspace report": (
        ["workspace", "report", "map.zarr", "--out", "out/r.html"],
        ("out/r.html",),
    ),
}
#: ``workspace map`` of a coarse grid in many small blocks (a few seconds on
#: one thread): stopped midway, it leaves ``out/m.zarr.partial``.
WORKSPACE_MAP = [
    *"workspace map --robot puma560 --resolution 0.15 --orientations 8".split(),
    *("--block-voxels", "16", "--workers", "1", "--out", "out/m.zarr"),
]
#: ``workspace map`` of a small map, for the view and report (``map.zarr``).
SMALL_MAP = [
    *"workspace map --robot puma560 --resolution 0.4 --orientations 8".split(),
    *("--workers", "1", "--out"),
]


@dataclass
class Tally:
    """Counts over many interrupts of one command."""

    runs: int = 0
    files: Counter[str] = field(default_factory=Counter)  # absent/old/complete/...
    exits: Counter[int] = field(default_factory=Counter)
    signals: Counter[str] = field(default_factory=Counter)  # SIGINT, SIGKILL sent
    tracebacks: int = 0
    stderr_lines_over_one: int = 0
    orphans: int = 0  # forked workers alive ORPHAN_GRACE s after the kill
    leftover_temporaries: int = 0  # after SIGKILL; removed by the next run
    problems: list[str] = field(default_factory=list)


def _is_complete(path: Path, reference: bytes) -> bool:
    data = path.read_bytes()
    if path.suffix == ".csv":
        try:
            read_trajectory_csv(path)
        except InputError:
            return False
        return record_path(path).exists()  # checked against it when read
    if path.suffix == ".html":  # a page ends with its closing tag
        return data.rstrip().endswith(b"</html>")
    if path.suffix == ".json":
        try:
            json.loads(data)
        except ValueError:
            return False
        return True
    return data == reference


def classify(path: Path, reference: bytes) -> str:
    """``absent``, ``old``, ``complete`` or ``truncated`` (anything else)."""
    if not path.exists():
        return "absent"
    if path.read_bytes() == OLD:
        return "old"
    return "complete" if _is_complete(path, reference) else "truncated"


def _children(pid: int) -> list[int]:
    try:
        tasks = Path(f"/proc/{pid}/task").iterdir()
        return [
            int(c) for task in tasks for c in (task / "children").read_text().split()
        ]
    except OSError:
        return []


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def take_sigint() -> None:
    """In the child, before exec: SIGINT acts (not ignored as by ``nohup cmd &``)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def run_reference(name: str, folder: Path) -> dict[str, bytes]:
    """Run the command to its end once; the bytes of every output."""
    argv, outputs = COMMANDS[name]
    (folder / "out").mkdir(parents=True, exist_ok=True)
    if name.startswith("workspace") and not (folder / "map.zarr").exists():
        _run_to_end([*SMALL_MAP, "map.zarr"], folder)
    subprocess.run(
        [sys.executable, "-m", "workbench", "-q", *argv],
        cwd=folder,
        capture_output=True,
        check=False,
    )
    return {p: (folder / p).read_bytes() for p in outputs}


def interrupt_once(
    name: str,
    folder: Path,
    reference: dict[str, bytes],
    rng: np.random.Generator,
    tally: Tally,
    *,
    max_delay: float,
    min_delay: float = 0.0,
) -> float:
    """One run of ``name`` in ``folder``, stopped after a random delay.

    Returns:
        The delay [s] between the start and the signal.
    """
    argv, outputs = COMMANDS[name]
    out = folder / "out"
    out.mkdir(parents=True, exist_ok=True)
    for rel in outputs:  # some outputs exist (old), the others do not
        path = folder / rel
        if rng.random() < 0.5:
            path.write_bytes(OLD)
        else:
            path.unlink(missing_ok=True)
    kill = signal.SIGKILL if rng.random() < 0.5 else signal.SIGINT
    process = subprocess.Popen(
        [sys.executable, "-m", "workbench", "-q", *argv],
        cwd=folder,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        preexec_fn=take_sigint,  # a background job (`cmd &`) inherits it ignored
    )
    delay = rng.uniform(min_delay, max_delay)
    time.sleep(delay)
    workers = _children(process.pid)
    process.send_signal(kill)
    _, err = process.communicate()
    stderr = err.decode(errors="replace")
    tally.runs += 1
    tally.exits[process.returncode] += 1
    tally.tracebacks += "Traceback" in stderr
    tally.stderr_lines_over_one += len(stderr.splitlines()) > 1
    deadline = time.monotonic() + ORPHAN_GRACE
    while any(_alive(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.02)
    orphans = [w for w in workers if _alive(w)]
    tally.orphans += len(orphans)
    for w in orphans:  # do not let them disturb the next run
        os.kill(w, signal.SIGKILL)
    for rel in outputs:
        kind = classify(folder / rel, reference[rel])
        tally.files[kind] += 1
        if kind == "truncated":
            tally.problems.append(f"{name}: {rel} truncated ({kill.name})")
        temporaries = get_temporaries(folder / rel)
        tally.leftover_temporaries += len(temporaries)
        if kill == signal.SIGINT and temporaries:
            tally.problems.append(f"{name}: temporary file of {rel} after SIGINT")
        for path, _ in temporaries:  # what the next write would remove
            path.unlink()
    tally.signals[kill.name] += 1
    expected = {signal.SIGINT: (130, 0), signal.SIGKILL: (-9, 0)}[kill]
    if process.returncode not in expected:
        tally.problems.append(
            f"{name}: exit {process.returncode} after {kill.name} at {delay:.3f} s: "
            f"{stderr[-200:]}"
        )
    return delay


def _run_to_end(argv: list[str], folder: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "workbench", "-q", *argv],
        cwd=folder,
        capture_output=True,
        check=False,
    )
    if done.returncode != 0:
        raise RuntimeError(f"{argv}: exit {done.returncode}: {done.stderr[-300:]!r}")


def read_map(path: Path) -> dict[str, bytes]:
    """The bytes of every array of the finished map at ``path`` and its attributes.

    Raises:
        InputError: If ``path`` is no finished map (:func:`open_map`).
    """
    from workbench.workspace.store import open_map

    workspace_map = open_map(path)
    arrays = {
        name: workspace_map[name].tobytes()
        for name in (*workspace_map.names, "positions", "orientations", "done")
    }
    attrs = {k: v for k, v in workspace_map.attrs.items() if k != "versions"}
    return {**arrays, "attrs": json.dumps(attrs, sort_keys=True).encode()}


def map_reference(folder: Path) -> dict[str, bytes]:
    """Build the map of :data:`WORKSPACE_MAP` uninterrupted once; :func:`read_map`."""
    (folder / "out").mkdir(parents=True, exist_ok=True)
    _run_to_end([*WORKSPACE_MAP[:-1], "ref.zarr"], folder)
    return read_map(folder / "ref.zarr")


def interrupt_map_once(
    folder: Path,
    reference: dict[str, bytes],
    rng: np.random.Generator,
    tally: Tally,
    *,
    max_delay: float,
    min_delay: float = 0.0,
    kill: signal.Signals | None = None,
) -> float:
    """Stop ``workspace map`` once (SIGINT or SIGKILL), then resume it to the end.

    The map is then absent (only ``out/m.zarr.partial``, possibly left by an
    earlier interrupt too) or complete and equal to ``reference``; the run
    that resumes it ends with a map bitwise equal to ``reference``. ``kill``
    None: SIGINT or SIGKILL drawn.

    Returns:
        The delay [s] between the start and the signal.
    """
    from workbench.errors import InputError

    out = folder / "out"
    out.mkdir(parents=True, exist_ok=True)
    target = out / "m.zarr"
    if target.exists():  # finished by the previous run: start again
        shutil.rmtree(target)
    if kill is None:
        kill = signal.SIGKILL if rng.random() < 0.5 else signal.SIGINT
    process = subprocess.Popen(
        [sys.executable, "-m", "workbench", "-q", *WORKSPACE_MAP],
        cwd=folder,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        preexec_fn=take_sigint,
    )
    delay = rng.uniform(min_delay, max_delay)
    time.sleep(delay)
    process.send_signal(kill)
    _, err = process.communicate()
    stderr = err.decode(errors="replace")
    tally.runs += 1
    tally.signals[kill.name] += 1
    tally.exits[process.returncode] += 1
    tally.tracebacks += "Traceback" in stderr
    tally.stderr_lines_over_one += len(stderr.splitlines()) > 1
    if "Traceback" in stderr or len(stderr.splitlines()) > 1:
        tally.problems.append(f"workspace map: {kill.name}: stderr {stderr[:300]}")
    expected = {signal.SIGINT: (130, 0), signal.SIGKILL: (-9, 0)}[kill]
    if process.returncode not in expected:
        tally.problems.append(
            f"workspace map: exit {process.returncode} after {kill.name} at "
            f"{delay:.3f} s: {stderr[-200:]}"
        )
    if not target.exists():
        tally.files["absent"] += 1
    else:
        try:
            same = read_map(target) == reference
        except InputError:
            same = False
        tally.files["complete" if same else "truncated"] += 1
        if not same:
            tally.problems.append(f"workspace map: {target} half-written ({kill.name})")
        shutil.rmtree(target)  # resume from the partial folder if any
    _run_to_end(WORKSPACE_MAP, folder)
    resumed = read_map(target) == reference
    tally.files["resumed equal" if resumed else "resumed different"] += 1
    if not resumed:
        tally.problems.append(f"workspace map: resumed after {kill.name} differs")
    if any(out.glob("*.partial")):
        tally.problems.append("workspace map: partial folder left after resuming")
    return delay
