"""Closed-form IK of the PUMA 560: workbench vs peers, all eight branches.

Run: ``python benchmarks/bench_ik_closed_form.py [--poses N] [--quick]``.

* single pose: median time of one call from Python that returns all eight
  branches (ours: ``analytic``; Robotics Toolbox: eight ``ikine_a`` calls, one
  per configuration string, since it returns one branch per call);
* batch: poses per second, all eight branches each (ours: ``analytic_batch``;
  RTB: ``ikine_a`` on an (N, 4, 4) array, once per configuration string).

Times are CPU time of this process (``time.process_time``), so that other
jobs on a shared machine inflate them less than wall time would; a reference
loop, ``sum(range(1000))``, is timed the same way to calibrate the machine.

Peers are optional: a missing one is reported and skipped. Each peer solves
its own PUMA 560 model (RTB's DH table differs from ours in d1, d3, α signs);
every tool's answers are checked against its own forward kinematics, so the
timings compare equal work.
"""

from __future__ import annotations

import argparse
import importlib
import statistics
import time
import warnings
from collections.abc import Callable

import numpy as np

from workbench import load_robot
from workbench.ik.closed_form import analytic, analytic_batch

_RTB_CONFIGS = tuple(a + e + w for a in "rl" for e in "ud" for w in "nf")


def _median_us(call: Callable[[], object], *, repeat: int, number: int) -> float:
    call()  # warm up
    times = []
    for _ in range(repeat):
        start = time.process_time()
        for _ in range(number):
            call()
        times.append((time.process_time() - start) / number)
    return statistics.median(times) * 1e6


def _rate(call: Callable[[], object], count: int, repeat: int) -> float:
    call()
    best = min(_timed(call) for _ in range(repeat))
    return count / best


def _timed(call: Callable[[], object]) -> float:
    start = time.process_time()
    call()
    return time.process_time() - start


def bench_workbench(poses: int, quick: bool) -> dict[str, float]:
    robot = load_robot("puma560")
    rng = np.random.default_rng(0)
    qs = rng.uniform(robot.lower, robot.upper, size=(2000, 6))
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    single = [robot.fk(q) for q in qs[:50]]
    q_batch, valid = analytic_batch(robot, targets)
    assert valid.all()
    worst = max(
        float(np.abs(robot.fk(q).homogeneous - t).max())
        for t, qq in zip(targets[:200], q_batch[:200], strict=True)
        for q in qq
    )
    assert worst < 1e-9, worst
    cycle = iter(range(10**9))
    one = _median_us(
        lambda: analytic(robot, single[next(cycle) % 50]),
        repeat=7 if quick else 25,
        number=200,
    )
    big = np.tile(targets, (max(poses // len(targets), 1), 1, 1))
    rate = _rate(lambda: analytic_batch(robot, big), len(big), 3 if quick else 7)
    return {"single_us": one, "batch_poses_per_s": rate, "fk_max_error": worst}


def bench_rtb(poses: int, quick: bool) -> dict[str, float] | str:
    try:
        rtb = importlib.import_module("roboticstoolbox")
    except ImportError as err:
        return f"not importable ({err})"
    warnings.filterwarnings("ignore")
    peer = rtb.models.DH.Puma560()
    rng = np.random.default_rng(0)
    qs = rng.uniform(peer.qlim[0], peer.qlim[1], size=(200, 6))
    targets = [peer.fkine(q).A for q in qs]

    def all_branches(target: np.ndarray) -> list[object]:
        return [peer.ikine_a(target, config=c) for c in _RTB_CONFIGS]

    assert all(s.success for s in all_branches(targets[0]))
    cycle = iter(range(10**9))
    one = _median_us(
        lambda: all_branches(targets[next(cycle) % 200]),
        repeat=3 if quick else 7,
        number=10,
    )
    count = min(poses, 500 if quick else 2000)
    batch = np.array([targets[i % 200] for i in range(count)])
    rate = _rate(
        lambda: [peer.ikine_a(batch, config=c) for c in _RTB_CONFIGS], count, 1
    )
    return {"single_us": one, "batch_poses_per_s": rate}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=1_000_000, help="batch size")
    parser.add_argument("--quick", action="store_true", help="fewer repeats")
    args = parser.parse_args()
    ours = bench_workbench(args.poses, args.quick)
    rows = [("workbench analytic / analytic_batch", ours)]
    missing = []
    for name, bench in (("Robotics Toolbox Puma560.ikine_a x8", bench_rtb),):
        result = bench(args.poses, args.quick)
        if isinstance(result, str):
            missing.append(f"{name}: {result}")
        else:
            rows.append((name, result))
    reference = _median_us(lambda: sum(range(1000)), repeat=15, number=2000)
    print("Closed-form PUMA 560 IK, all 8 branches per pose, one core, CPU time")
    print(f"machine reference: sum(range(1000)) = {reference:.1f} µs")
    print(f"{'solver':40s} {'single [µs]':>12s} {'ratio':>7s} {'batch [poses/s]':>16s} "
          f"{'ratio':>7s}")  # fmt: skip
    for name, r in rows:
        print(
            f"{name:40s} {r['single_us']:12.1f} "
            f"{r['single_us'] / ours['single_us']:6.1f}x "
            f"{r['batch_poses_per_s']:16,.0f} "
            f"{ours['batch_poses_per_s'] / r['batch_poses_per_s']:6.1f}x"
        )
    print("ratio: time relative to the workbench (single), workbench speed-up (batch)")
    print(f"workbench max |FK(q) - target| over 200 poses x 8 branches: "
          f"{ours['fk_max_error']:.1e}")  # fmt: skip
    for line in missing:
        print(f"skipped {line}")


if __name__ == "__main__":
    main()
