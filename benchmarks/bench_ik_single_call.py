"""Where the time of one closed-form call goes, against the peers' one call.

Run: ``python -m benchmarks.bench_ik_single_call [--quick]
[--robots puma560,ur5,iiwa14,panda]``.

For each arm, one pose at a time (50 poses from random in-limit
configurations, cycled), the median CPU time [µs] of:

* the whole call, ``ik.analytic(robot, pose)`` (every branch; seven-axis arms
  at the pose's own value of the redundancy parameter), and the same call
  followed by reading every solution's ``q`` (what a caller that looks at
  every branch pays);
* its stages, each timed alone: finding the robot's solver
  (``ik.get_solver``), checking the target (the solver's fast path: a float64
  (4, 4) array), allocating the outputs (two ``numpy.empty``), the compiled
  kernel (called directly), and building the result: one
  ``ik.Solutions`` (today) against one ``IKSolution`` record per reaching
  branch, built at once (the result before ``Solutions``, rebuilt here as the
  reference row);
* the peers' one call on the same poses: EAIK ``IK`` (6R, and the Panda with
  joint 7 locked at q7 = 0.3 rad, as every Panda pose here), frankik
  ``ik_full`` (Panda), set up as in :mod:`benchmarks.bench_ik_closed_form` and
  :mod:`benchmarks.bench_seven_axis` (which check their answers).

Every row is timed in the same interleaved rounds (one batch of calls of
each row per round, the median over rounds), so that ours and the peers'
see the same load of a shared machine. A row's time has the empty call's time
(a lambda returning None) taken off, and a result row the allocation of its
``q`` (the kernel's output): the stages then add up to about the whole call
(the difference is the Python code of ``analytic`` and ``Solver.solve``
between them). Peers are optional (the ``bench`` extra): a missing one is
reported and skipped.
"""

from __future__ import annotations

import argparse
import importlib
import statistics
import time
from collections.abc import Callable

import numpy as np

from benchmarks import bench_ik_closed_form, bench_seven_axis
from benchmarks.bench_ik_closed_form import _reference_us
from workbench import load_robot
from workbench.ik import IKSolution, Solutions, analytic, get_solver
from workbench.model.robot import Robot

_FLOAT64 = np.dtype(np.float64)
_UINT8 = np.dtype(np.uint8)
#: The value [rad] at which the Panda's peers lock joint 7 (our q7).
_LOCKED_Q7 = 0.3
#: The rows that are ours (the others are peers).
_OURS = ("call", "call + read every q", "get_solver", "target check",
         "outputs (2 numpy.empty)", "kernel", "result: one Solutions")  # fmt: skip


def _timed_rounds(
    calls: dict[str, Callable[[], object]], *, rounds: int, number: int
) -> dict[str, float]:
    """Median CPU time [µs] of each call, timed in interleaved rounds.

    Every round times ``number`` calls of each entry in turn, so that every
    row (ours and the peers') sees the same load of a shared machine.
    """
    for call in calls.values():
        call()  # warm up
    samples: dict[str, list[float]] = {name: [] for name in calls}
    for _ in range(rounds):
        for name, call in calls.items():
            start = time.process_time()
            for _ in range(number):
                call()
            samples[name].append((time.process_time() - start) / number * 1e6)
    return {name: statistics.median(values) for name, values in samples.items()}


def _eaik_call(robot: Robot, poses: list[np.ndarray], locked: float | None):
    """EAIK's one call on the same poses (its chain read from the model)."""
    try:
        hp = importlib.import_module("eaik.IK_HP")
    except ImportError as err:
        return f"not importable ({err})"
    directions, offsets, rotation0 = bench_ik_closed_form._chain(robot)
    if locked is None:
        peer = hp.HPRobot(directions, offsets)
    else:
        peer = hp.HPRobot(directions, offsets, fixed_axes=[(6, locked)])
    shifted = [pose.copy() for pose in poses]
    for pose in shifted:
        pose[:3, :3] = pose[:3, :3] @ rotation0.T
    cycle = iter(range(10**12))
    return lambda: peer.IK(shifted[next(cycle) % len(shifted)])


def _frankik_call(robot: Robot, qs: np.ndarray, poses: list[np.ndarray]):
    """frankik's ``ik_full`` on the same poses (flange poses, q7 given)."""
    try:
        frankik = importlib.import_module("frankik")
    except ImportError as err:
        return f"not importable ({err})"
    flanges = [pose @ np.linalg.inv(bench_seven_axis._HAND) for pose in poses]
    cycle = iter(range(10**12))

    def one() -> object:
        k = next(cycle) % len(flanges)
        return frankik.ik_full(flanges[k], qs[k], qs[k, 6])

    return one


def measure(
    name: str, robot: Robot, quick: bool
) -> tuple[dict[str, float], dict[str, str]]:
    """The medians [µs] of the call, its stages and the peers (module docs).

    Returns:
        The medians by row, and the peers that could not be timed, with why.
    """
    solver = get_solver(robot)
    rng = np.random.default_rng(0)
    qs = rng.uniform(robot.lower, robot.upper, size=(50, robot.nq))
    if name == "panda":  # the peers lock joint 7 at one value
        qs[:, 6] = _LOCKED_Q7
    poses = [robot.fk(q).homogeneous for q in qs]
    values = [
        None if solver.parameter is None else float(solver.parameter_of(q)) for q in qs
    ]
    cycle = iter(range(10**12))

    def whole() -> object:
        k = next(cycle) % 50
        return analytic(robot, poses[k], redundancy=values[k])

    def read_all() -> object:
        k = next(cycle) % 50
        return [s.q for s in analytic(robot, poses[k], redundancy=values[k])]

    pose, value = poses[0], values[0]
    analytic(robot, pose, redundancy=value)  # compiles, binds the compiled entry
    kernel, geometry, prev = solver._solve_pose, solver.geometry, np.empty(0)
    count, nq = len(solver.branches), solver.nq
    q, flags = np.empty((count, nq)), np.empty(count, dtype=np.uint8)
    if value is None:
        run_kernel = lambda: kernel(geometry, pose, prev, q, flags, True)  # noqa: E731
    else:
        run_kernel = lambda: kernel(geometry, pose, value, prev, q, flags, True)  # noqa: E731
    run_kernel()
    labels, reached = solver.branches, int(np.count_nonzero(flags))

    def records() -> object:  # the result before Solutions: one record per branch
        rows = np.empty((count, nq))
        rows.setflags(write=False)
        return [
            IKSolution((rows, i, bits, labels, value))
            for i, bits in zip(range(count), flags.tolist(), strict=True)
            if bits
        ]

    calls: dict[str, Callable[[], object]] = {
        "empty call": lambda: None,
        "call": whole,
        "call + read every q": read_all,
        "get_solver": lambda: get_solver(robot),
        "target check": lambda: (
            pose.__class__ is np.ndarray
            and pose.shape == (4, 4)
            and pose.dtype is _FLOAT64
        ),
        "outputs (2 numpy.empty)": lambda: (
            np.empty((count, nq)),
            np.empty(count, _UINT8),
        ),
        "kernel": run_kernel,
        "one numpy.empty (q)": lambda: np.empty((count, nq)),
        "result: one Solutions": lambda: Solutions.from_arrays(
            np.empty((count, nq)), flags, labels, value
        ),
        f"result before: {reached} IKSolution records": records,
    }
    skipped: dict[str, str] = {}
    peers: dict[str, object] = {}
    if nq == 6:
        peers["EAIK IK"] = _eaik_call(robot, poses, None)
    elif name == "panda":
        peers["frankik ik_full"] = _frankik_call(robot, qs, poses)
        peers["EAIK IK, joint 7 locked"] = _eaik_call(robot, poses, _LOCKED_Q7)
    for peer, call in peers.items():
        if isinstance(call, str):
            skipped[peer] = call
        else:
            calls[peer] = call  # type: ignore[assignment]
    rounds, number = (9, 1000) if quick else (31, 2000)
    medians = _timed_rounds(calls, rounds=rounds, number=number)
    empty = medians.pop("empty call")
    allocation = medians.pop("one numpy.empty (q)") - empty
    for row in medians:
        medians[row] -= empty
    medians["result: one Solutions"] -= allocation  # its q is the kernel's
    medians[f"result before: {reached} IKSolution records"] -= allocation
    return medians, skipped


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--robots", default="puma560,ur5,iiwa14,panda")
    args = parser.parse_args()
    print(f"machine reference: sum(range(1000)) = {_reference_us():.1f} µs (CPU time)")
    for name in args.robots.split(","):
        robot = load_robot(name)
        start = time.process_time()
        medians, skipped = measure(name, robot, args.quick)
        call = medians["call"]
        print(
            f"\n{name}: one pose, every branch, one core, CPU time "
            f"(machine reference now {_reference_us():.1f} µs)"
        )
        print(f"{'':44s} {'[µs]':>7s} {'of the call':>12s}")
        for row, value in medians.items():
            if row in _OURS:
                share = f"{value / call:11.0%}"
            elif row.startswith("result before"):
                today = medians["result: one Solutions"]
                share = f"{value / today:11.1f}x today's result"
            else:
                share = f"  peer / ours {value / call:.2f}x"
            print(f"{row:44s} {value:7.2f} {share}")
        for peer, why in skipped.items():
            print(f"{peer:44s} {'-':>7s}  ({why})")
        print(f"({time.process_time() - start:.0f} s)")


if __name__ == "__main__":
    main()
