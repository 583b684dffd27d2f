"""Where the time of a first call goes: import, load, compile, solve.

Run: ``python -m benchmarks.bench_startup [--robots puma560,ur5,iiwa14,panda]
[--runs 5] [--commands fk,ik,ik-ur5,ik-iiwa14,ik-panda,help] [--skip-first]``.

Two tables, each from fresh Python processes (what a user's first call pays):

* the first ``ik.analytic`` per arm family, in a new process per arm: the CPU
  time [s] (user + system) and the wall time [s] of ``import workbench.ik``,
  of ``load_robot``, of the first call (on an empty Numba cache: Numba's
  import and the compile; on a warm one: Numba's import and loading the
  compiled kernels from the cache) and of the second call (the solve itself),
  once with an empty cache (``NUMBA_CACHE_DIR`` a new temporary folder) and
  once with that folder warm. A first solve runs as Python while a thread
  compiles its kernels (``_compiled.compile_in_background``): the last column,
  not in the total, is the wait for that thread after the second call (CPU
  times are the process's, that thread's included);
* the command line, warm: ``workbench fk``, ``workbench ik`` (six and seven
  axes) and ``workbench --help`` against ``python -c "import pinocchio,
  numpy"`` (the floor of any command), run in turn A B A B ..., with the CPU
  and wall time [s] of each process and the ratios A/B pair by pair (their
  medians are quoted: a shared machine changes speed between runs, a pair
  shares the moment).

The machine reference, ``sum(range(1000))`` [µs of CPU], is printed with each
row (as :mod:`benchmarks.bench_ik_closed_form` does): on a loaded machine it
grows, and the CPU times with it. Every process reads the bytecode of what it
imports, as an installed package does (``PYTHONDONTWRITEBYTECODE`` is dropped
from the children's environment; the warm-up run writes what is missing):
without it each import compiles its source again, a second or more.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

#: The child process of one first call (``--child NAME``) prints this JSON.
_STAGES = ("import", "load", "first call", "solve")
#: ... and the stage after them: the wait for the background compile.
_BACKGROUND = "background"

#: The environment of every child: bytecode read and written (module docs).
_ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}

#: Warm command lines, against the floor of any command.
_FLOOR = [sys.executable, "-c", "import pinocchio, numpy"]
_WORKBENCH = [sys.executable, "-m", "workbench"]
_POSE = ["--xyz-quat-wxyz", "0.4", "0.1", "0.3", "0", "1", "0", "0"]
_COMMANDS = {
    "fk": ("workbench fk --robot puma560",
           [*_WORKBENCH, "fk", "--robot", "puma560",
            "--deg", "10", "20", "30", "40", "50", "60"]),
    "ik": ("workbench ik --robot puma560",
           [*_WORKBENCH, "ik", "--robot", "puma560", *_POSE]),
    "ik-ur5": ("workbench ik --robot ur5",
               [*_WORKBENCH, "ik", "--robot", "ur5", *_POSE]),
    "ik-iiwa14": ("workbench ik --robot iiwa14",
                  [*_WORKBENCH, "ik", "--robot", "iiwa14", *_POSE]),
    "ik-panda": ("workbench ik --robot panda",
                 [*_WORKBENCH, "ik", "--robot", "panda", *_POSE]),
    "help": ("workbench --help", [*_WORKBENCH, "--help"]),
}  # fmt: skip


def _child(name: str) -> None:
    """One first call of ``ik.analytic`` on arm ``name``; prints its stages [s]."""
    times: dict[str, tuple[float, float]] = {}  # stage: (CPU, wall)
    start = time.process_time(), time.perf_counter()

    def lap(stage: str) -> None:
        nonlocal start
        now = time.process_time(), time.perf_counter()
        times[stage] = (now[0] - start[0], now[1] - start[1])
        start = time.process_time(), time.perf_counter()

    import numpy as np

    from workbench import load_robot
    from workbench.ik import analytic

    lap("import")
    robot = load_robot(name)
    lap("load")
    rng = np.random.default_rng(0)
    lower, upper = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    q0 = lower + (upper - lower) * rng.uniform(0.2, 0.8, robot.nq)
    target = robot.fk(q0, robot.tool_frame)
    for stage in ("first call", "solve"):
        start = time.process_time(), time.perf_counter()
        solutions = analytic(robot, target, q_previous=q0)
        lap(stage)
    from workbench._compiled import wait_for_background

    wait_for_background()
    lap(_BACKGROUND)
    if not len(solutions):
        raise SystemExit(f"{name}: no branch reaches a reachable pose")
    print(json.dumps(times))


def _first_call(name: str, cache: str) -> dict[str, tuple[float, float]]:
    """The stages (CPU, wall) [s] of a first call in a new process, with ``cache``."""
    env = dict(_ENV, NUMBA_CACHE_DIR=cache, WORKBENCH_PROGRESS="0")
    out = subprocess.run(
        [sys.executable, "-m", "benchmarks.bench_startup", "--child", name],
        env=env,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return json.loads(out.splitlines()[-1])


def _times_of(command: list[str]) -> tuple[float, float]:
    """CPU time [s] (user + system) and wall time [s] of one run of ``command``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True, env=_ENV)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall


def _paired(command: list[str], runs: int) -> dict[str, float]:
    """Medians of ``command`` (A) and of the floor (B), run in turn A B A B ...

    Keys ``cpu_a``, ``cpu_b``, ``wall_a``, ``wall_b`` [s] and the medians of
    the ratios pair by pair, ``cpu_ratio`` and ``wall_ratio``.
    """
    _times_of(command), _times_of(_FLOOR)  # warm up (bytecode, Numba cache, disk)
    pairs = [(_times_of(command), _times_of(_FLOOR)) for _ in range(runs)]
    out = {}
    for k, kind in enumerate(("cpu", "wall")):
        out[f"{kind}_a"] = statistics.median(a[k] for a, _ in pairs)
        out[f"{kind}_b"] = statistics.median(b[k] for _, b in pairs)
        out[f"{kind}_ratio"] = statistics.median(a[k] / b[k] for a, b in pairs)
    return out


def main() -> None:
    """Print both tables (module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default="puma560,ur5,iiwa14,panda")
    parser.add_argument("--runs", type=int, default=5, help="pairs per command")
    parser.add_argument("--commands", default=",".join(_COMMANDS))
    parser.add_argument("--skip-first", action="store_true", help="no first calls")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        _child(args.child)
        return
    from benchmarks.bench_ik_closed_form import _reference_us  # imports workbench

    if not args.skip_first:
        print("first ik.analytic per arm, new process, CPU / wall [s]")
        header = "".join(f"{stage:>14}" for stage in _STAGES)
        print(
            f"{'robot':<10}{'cache':<7}{header}{'total':>14}{_BACKGROUND:>14}"
            f"{'ref [µs]':>10}"
        )
        for name in args.robots.split(","):
            with tempfile.TemporaryDirectory(prefix="numba-cache-") as cache:
                for label in ("empty", "warm"):
                    times = _first_call(name, cache)
                    reference = _reference_us()
                    cells = "".join(
                        f"{times[stage][0]:7.3f}/{times[stage][1]:<6.3f}"
                        for stage in _STAGES
                    )
                    cpu = sum(times[stage][0] for stage in _STAGES)
                    wall = sum(times[stage][1] for stage in _STAGES)
                    behind = times[_BACKGROUND]
                    print(
                        f"{name:<10}{label:<7}{cells}{cpu:7.3f}/{wall:<6.3f}"
                        f"{behind[0]:7.3f}/{behind[1]:<6.3f}{reference:10.1f}"
                    )
        print()
    print(
        f"warm command line, per process, medians of {args.runs} pairs A B A B ...; "
        "B: python -c 'import pinocchio, numpy'"
    )
    print(
        f"{'command A':<30}{'CPU A':>7}{'CPU B':>7}{'A/B':>6}"
        f"{'wall A':>8}{'wall B':>7}{'A/B':>6}{'ref [µs]':>10}"
    )
    for key in args.commands.split(","):
        label, command = _COMMANDS[key]
        m = _paired(command, args.runs)
        print(
            f"{label:<30}{m['cpu_a']:7.3f}{m['cpu_b']:7.3f}{m['cpu_ratio']:6.2f}"
            f"{m['wall_a']:8.3f}{m['wall_b']:7.3f}{m['wall_ratio']:6.2f}"
            f"{_reference_us():10.1f}"
        )


if __name__ == "__main__":
    main()
