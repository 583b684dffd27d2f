"""Where the time of a first call goes: import, load, compile, solve.

Run: ``python -m benchmarks.bench_startup [--robots puma560,ur5,iiwa14,panda]
[--runs 5]``.

Two tables, each from fresh Python processes (what a user's first call pays):

* the first ``ik.analytic`` per arm family, in a new process per arm: the CPU
  time [s] of ``import workbench.ik``, of ``load_robot``, of the first call
  (on an empty Numba cache: the compile; on a warm one: loading the compiled
  kernels from the cache) and of the second call (the solve itself), once
  with an empty cache (``NUMBA_CACHE_DIR`` a new temporary folder) and once
  with that folder warm;
* the command line, warm: ``workbench fk`` and ``workbench ik`` against
  ``python -c "import pinocchio, numpy"`` (the floor of any command), run in
  turn A B A B ..., with the CPU time [s] of each process (user + system) and
  the ratio A/B pair by pair (its median is quoted: a shared machine changes
  speed between runs, a pair shares the moment).

The machine reference, ``sum(range(1000))`` [µs of CPU], is printed with each
table (as :mod:`benchmarks.bench_ik_closed_form` does).
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

#: Warm command lines, against the floor of any command.
_FLOOR = [sys.executable, "-c", "import pinocchio, numpy"]
_COMMANDS = {
    "workbench fk --robot puma560": [
        sys.executable, "-m", "workbench", "fk", "--robot", "puma560",
        "--deg", "10", "20", "30", "40", "50", "60",
    ],
    "workbench ik --robot puma560": [
        sys.executable, "-m", "workbench", "ik", "--robot", "puma560",
        "--xyz-quat-wxyz", "0.4", "0.1", "0.3", "0", "1", "0", "0",
    ],
    "workbench ik --robot ur5": [
        sys.executable, "-m", "workbench", "ik", "--robot", "ur5",
        "--xyz-quat-wxyz", "0.4", "0.1", "0.3", "0", "1", "0", "0",
    ],
}  # fmt: skip


def _child(name: str) -> None:
    """One first call of ``ik.analytic`` on arm ``name``; prints its stages [s]."""
    times = {}
    start = time.process_time()
    import numpy as np

    from workbench import load_robot
    from workbench.ik import analytic

    times["import"] = time.process_time() - start
    start = time.process_time()
    robot = load_robot(name)
    times["load"] = time.process_time() - start
    rng = np.random.default_rng(0)
    lower, upper = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    q0 = lower + (upper - lower) * rng.uniform(0.2, 0.8, robot.nq)
    target = robot.fk(q0, robot.tool_frame)
    for stage in ("first call", "solve"):
        start = time.process_time()
        solutions = analytic(robot, target, q_previous=q0)
        times[stage] = time.process_time() - start
    if not len(solutions):
        raise SystemExit(f"{name}: no branch reaches a reachable pose")
    print(json.dumps(times))


def _first_call(name: str, cache: str) -> dict[str, float]:
    """The stages [s] of a first call in a new process, with ``cache``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, WORKBENCH_PROGRESS="0")
    out = subprocess.run(
        [sys.executable, "-m", "benchmarks.bench_startup", "--child", name],
        env=env,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return json.loads(out.splitlines()[-1])


def _cpu_of(command: list[str]) -> float:
    """CPU time [s] (user + system) of one run of ``command``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(command, check=True, capture_output=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _paired(command: list[str], runs: int) -> tuple[float, float, float]:
    """Median CPU [s] of ``command`` and of the floor, and the median ratio."""
    _cpu_of(command), _cpu_of(_FLOOR)  # warm up (bytecode, Numba cache, disk)
    pairs = [(_cpu_of(command), _cpu_of(_FLOOR)) for _ in range(runs)]
    ratio = statistics.median(a / b for a, b in pairs)
    return (
        statistics.median(a for a, _ in pairs),
        statistics.median(b for _, b in pairs),
        ratio,
    )


def main() -> None:
    """Print both tables (module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default="puma560,ur5,iiwa14,panda")
    parser.add_argument("--runs", type=int, default=5, help="pairs per command")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        _child(args.child)
        return
    from benchmarks.bench_ik_closed_form import _reference_us  # imports workbench

    print(
        f"first ik.analytic per arm, new process, CPU [s] (machine reference: "
        f"sum(range(1000)) = {_reference_us():.1f} µs)"
    )
    header = "".join(f"{stage:>12}" for stage in _STAGES)
    print(f"{'robot':<10}{'cache':<8}{header}{'total':>10}")
    for name in args.robots.split(","):
        with tempfile.TemporaryDirectory(prefix="numba-cache-") as cache:
            for label in ("empty", "warm"):
                times = _first_call(name, cache)
                cells = "".join(f"{times[stage]:12.3f}" for stage in _STAGES)
                total = sum(times.values())
                print(f"{name:<10}{label:<8}{cells}{total:10.3f}")
    print(
        f"\nwarm command line, CPU [s] per process, {args.runs} pairs A B A B ... "
        f"(machine reference: {_reference_us():.1f} µs)"
    )
    print(f"{'command A':<32}{'A':>8}{'B: import pinocchio, numpy':>28}{'A/B':>8}")
    for label, command in _COMMANDS.items():
        a, b, ratio = _paired(command, args.runs)
        print(f"{label:<32}{a:8.3f}{b:28.3f}{ratio:8.2f}")


if __name__ == "__main__":
    main()
