"""Closed-form IK of any arm: workbench vs peers, all eight branches.

Run: ``python benchmarks/bench_ik_closed_form.py [--poses N] [--quick]
[--robots puma560,ur5,kuka-kr6-r700]``.

* single pose: median time of one call from Python that returns all eight
  branches (ours: ``analytic``; Robotics Toolbox: eight ``ikine_a`` calls, one
  per configuration string, since it returns one branch per call; EAIK:
  ``IK``; ik-geo: ``get_ik``; ``ik.numeric``: one solution only);
* batch: poses per second, all eight branches each (ours: ``analytic_batch``;
  RTB: ``ikine_a`` on an (N, 4, 4) array, once per configuration string;
  EAIK: ``IK_batched`` with one worker thread, i.e. per core; ik-geo has no
  batch call: a Python loop of ``get_ik``).

Times are CPU time of this process (``time.process_time``), so that other
jobs on a shared machine inflate them less than wall time would; a reference
loop, ``sum(range(1000))``, is timed the same way to calibrate the machine.

Peers are optional (the ``bench`` extra): a missing one is reported and
skipped. RTB solves its own PUMA 560 model (its DH table differs from ours in
d1, d3, α signs); EAIK and ik-geo get the same chain as ours, read from the
model's joint axes (for ik-geo with the points on axes that meet moved to
where they meet, the form its solvers assume). Every tool's answers are
checked against forward kinematics; a peer whose answers miss the pose is
reported, not timed.
"""

from __future__ import annotations

import argparse
import importlib
import math
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


def _chain(robot):
    """Axes H (n, 3), offsets P (n + 1, 3) and the tool rotation at q = 0."""
    import pinocchio as pin

    from workbench.ik.structure import axis_lines

    directions, points = axis_lines(robot)
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, np.zeros(robot.nq))
    tool = data.oMf[robot.tool_frame_id]
    offsets = np.diff(np.vstack([np.zeros(3), points, tool.translation]), axis=0)
    return directions, offsets, tool.rotation


def _problem(name: str, count: int = 2000):
    robot = load_robot(name)
    rng = np.random.default_rng(0)
    qs = rng.uniform(robot.lower, robot.upper, size=(count, 6))
    return robot, np.array([robot.fk(q).homogeneous for q in qs])


def bench_any(name: str, poses: int, quick: bool) -> dict[str, float]:
    """Ours on any robot: single pose and batch, every answer checked."""
    robot, targets = _problem(name)
    q_batch, valid = analytic_batch(robot, targets)
    worst = max(
        float(np.abs(robot.fk(q).homogeneous - t).max())
        for t, qq, ok in zip(targets[:200], q_batch[:200], valid[:200], strict=True)
        for q in qq[ok]
    )
    assert worst < 1e-9, worst
    cycle = iter(range(10**9))
    one = _median_us(
        lambda: analytic(robot, targets[next(cycle) % 2000]),
        repeat=7 if quick else 25,
        number=200,
    )
    big = np.tile(targets, (max(poses // len(targets), 1), 1, 1))
    rate = _rate(lambda: analytic_batch(robot, big), len(big), 3 if quick else 7)
    return {"single_us": one, "batch_poses_per_s": rate, "fk_max_error": worst}


def bench_eaik(name: str, poses: int, quick: bool) -> dict[str, float] | str:
    try:
        hp = importlib.import_module("eaik.IK_HP")
    except ImportError as err:
        return f"not importable ({err})"
    robot, targets = _problem(name)
    directions, offsets, rotation0 = _chain(robot)
    peer = hp.HPRobot(directions, offsets)
    shifted = targets.copy()
    shifted[:, :3, :3] = targets[:, :3, :3] @ rotation0.T
    worst = 0.0
    for target, pose in zip(targets[:200], shifted[:200], strict=True):
        solution = peer.IK(pose)
        exact = ~np.asarray(solution.is_LS, dtype=bool)
        for q in np.asarray(solution.Q)[exact]:
            worst = max(worst, float(np.abs(robot.fk(q).homogeneous - target).max()))
    if worst > 1e-9:
        return f"answers miss the pose (max |FK(q) - target| = {worst:.2g})"
    cycle = iter(range(10**9))
    one = _median_us(
        lambda: peer.IK(shifted[next(cycle) % 2000]),
        repeat=7 if quick else 25,
        number=200,
    )
    count = min(poses, 20_000 if quick else 100_000)
    batch = [shifted[i % 2000] for i in range(count)]
    rate = _rate(lambda: peer.IK_batched(batch, 1), count, 1 if quick else 3)
    return {"single_us": one, "batch_poses_per_s": rate}


def _ik_geo_chain(robot, family: str):
    """``_chain`` in ik-geo's form: points on axes that meet at their meeting point.

    ik-geo's solvers take the offsets between axes that meet to be zero:
    ``spherical_two_parallel`` (OPW) never reads p45 and p56, so the points on
    axes 4, 5, 6 must be the wrist centre; ``three_parallel_two_intersecting``
    (UR) adds p56 to p45 as if q5 did not turn it, so the points on axes 5 and 6
    must be where they meet. ``axis_lines`` gives each axis's point nearest the
    base origin instead, hence the move.
    """
    directions, offsets, rotation0 = _chain(robot)
    points = np.cumsum(offsets, axis=0)  # points on axes 1-6, then the tool
    k = 3 if family == "opw" else 4  # first of the axes that meet
    a, u, b, v = points[k], directions[k], points[k + 1], directions[k + 1]
    s = np.linalg.lstsq(np.column_stack([u, -v]), b - a, rcond=None)[0][0]
    points[k:6] = a + s * u
    return directions, np.diff(points, axis=0, prepend=0.0), rotation0


def _ik_geo_peer(ik_geo, robot):
    """ik-geo's solver of the robot's chain (:func:`_ik_geo_chain`), rotation at 0."""
    from workbench.ik.structure import get_structure

    family = get_structure(robot).family
    directions, offsets, rotation0 = _ik_geo_chain(robot, family)
    make = (
        ik_geo.Robot.three_parallel_two_intersecting
        if family == "ur"
        else ik_geo.Robot.spherical_two_parallel
    )
    return make(directions, offsets), rotation0


def bench_ik_geo(name: str, poses: int, quick: bool) -> dict[str, float] | str:
    try:
        ik_geo = importlib.import_module("ik_geo")
    except ImportError as err:
        return f"not importable ({err})"
    robot, targets = _problem(name)
    peer, rotation0 = _ik_geo_peer(ik_geo, robot)
    # get_ik reads R[j] as column j (its bindings: rotation[(i, j)] = R[j][i])
    rotations = np.swapaxes(targets[:, :3, :3] @ rotation0.T, 1, 2).copy()
    translations = targets[:, :3, 3].copy()
    worst, exact = 0.0, 0
    for target, rotation, translation in zip(
        targets[:200], rotations[:200], translations[:200], strict=True
    ):
        for q, is_ls in peer.get_ik(rotation, translation):
            if not is_ls:
                exact += 1
                error = np.abs(robot.fk(np.array(q)).homogeneous - target).max()
                worst = max(worst, float(error))
    if worst > 1e-9 or exact == 0:
        return f"answers miss the pose (max |FK(q) - target| = {worst:.2g})"
    cycle = iter(range(10**9))

    def one_pose() -> object:
        i = next(cycle) % 2000
        return peer.get_ik(rotations[i], translations[i])

    one = _median_us(one_pose, repeat=7 if quick else 25, number=200)
    count = min(poses, 20_000 if quick else 100_000)

    def loop() -> None:  # no batch API: one get_ik call per pose
        for i in range(count):
            peer.get_ik(rotations[i % 2000], translations[i % 2000])

    rate = _rate(loop, count, 1 if quick else 3)
    return {"single_us": one, "batch_poses_per_s": rate}


def bench_numeric(name: str, poses: int, quick: bool) -> dict[str, float] | str:
    from workbench.ik import numeric

    robot, targets = _problem(name, 100)
    cycle = iter(range(10**9))
    one = _median_us(
        lambda: numeric(robot, targets[next(cycle) % 100], rng=0),
        repeat=3 if quick else 7,
        number=10,
    )
    return {"single_us": one, "batch_poses_per_s": 1e6 / one}


def _print_table(title: str, rows, ours) -> None:
    print(title)
    print(f"{'solver':44s} {'single [µs]':>12s} {'ratio':>7s} {'batch [poses/s]':>16s} "
          f"{'ratio':>7s}")  # fmt: skip
    for name, r in rows:
        batch = r["batch_poses_per_s"]
        speedup = ours["batch_poses_per_s"] / batch if batch == batch else math.nan
        print(
            f"{name:44s} {r['single_us']:12.1f} "
            f"{r['single_us'] / ours['single_us']:6.1f}x "
            f"{batch:16,.0f} {speedup:6.1f}x"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=1_000_000, help="batch size")
    parser.add_argument("--quick", action="store_true", help="fewer repeats")
    parser.add_argument(
        "--robots",
        default="puma560,ur5,kuka-kr6-r700",
        help="comma-separated models for the peers EAIK, ik-geo, ik.numeric",
    )
    args = parser.parse_args()
    reference = _reference_us()
    print(f"machine reference: sum(range(1000)) = {reference:.1f} µs (CPU time)")
    print("ratio: time relative to the workbench (single), workbench speed-up "
          "(batch); ik.numeric gives one branch, batch = 1 / single")  # fmt: skip
    missing = []
    for name in args.robots.split(","):
        ours = bench_any(name, args.poses, args.quick)
        rows = [("workbench analytic / analytic_batch", ours)]
        peers = (
            ("EAIK IK / IK_batched (1 thread)", bench_eaik),
            ("ik-geo get_ik (batch: Python loop)", bench_ik_geo),
            ("workbench ik.numeric (1 branch)", bench_numeric),
        )
        if name == "puma560":
            peers = (("Robotics Toolbox Puma560.ikine_a x8", _bench_rtb_any), *peers)
        for label, bench in peers:
            result = bench(name, args.poses, args.quick)
            if isinstance(result, str):
                missing.append(f"{label} on {name}: {result}")
            else:
                rows.append((label, result))
        _print_table(
            f"\n{name}: closed-form IK, all branches per pose, one core, CPU time "
            f"(machine reference now {_reference_us():.1f} µs)",
            rows,
            ours,
        )
        print(f"workbench max |FK(q) - target|, 200 poses x every branch: "
              f"{ours['fk_max_error']:.1e}")  # fmt: skip
    for line in missing:
        print(f"skipped {line}")


def _reference_us() -> float:
    """The reference loop's median [µs]: the machine's speed at this moment.

    Printed with each robot too, as shared machines change speed within a run.
    """
    return _median_us(lambda: sum(range(1000)), repeat=15, number=2000)


def _bench_rtb_any(name: str, poses: int, quick: bool) -> dict[str, float] | str:
    return bench_rtb(poses, quick)


if __name__ == "__main__":
    main()
