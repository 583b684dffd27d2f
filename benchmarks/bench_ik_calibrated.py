"""Closed-form IK of calibrated arms: workbench vs peers, in one run.

Run: ``python -m benchmarks.bench_ik_calibrated [--poses N] [--quick]``.

The arms (``benchmarks/_calibrated_models.py``): a UR5 and a PUMA 560 with
calibration deltas on every joint origin (1e-4…1e-3 rad, 0.1…1 mm), the iiwa
14 with its joint 2 and 4 origins 0.436 mm off axis (ROS-Industrial's URDF) and
a calibrated Panda. Per arm, over random in-limit configurations:

* ours on the calibrated model: single pose (``ik.analytic``, every branch
  carried to the model; seven axes at the configuration's own parameter): the
  mean over 100 poses (median of the repeats), the median and 99th-percentile
  pose (2000 poses one call each: the regular poses, and the tail of poses
  near a singularity that take the complete search), and batch (``analytic_batch``,
  poses per second, one core); the same on the catalog's exact arm (the
  closed form alone, for scale), and the ratios;
* ``ik.numeric`` on the calibrated model (one solution per call);
* EAIK on the calibrated model if it takes it (it decomposes only chains of
  exact structure: it refuses these), else on the exact arm, and frankik
  (the Panda's geometry is built in: the exact arm only): said in the table.

Times are CPU time of this process; the reference loop ``sum(range(1000))`` is
timed the same way to calibrate the machine.
"""

from __future__ import annotations

import argparse
import importlib
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks import bench_ik_closed_form as six
from benchmarks import bench_seven_axis as seven
from benchmarks._calibrated_models import calibrated_urdf, off_axis_iiwa
from workbench import Robot, load_robot
from workbench.ik import analytic, analytic_batch, get_solver, get_structure, numeric

#: The arms: catalog name and how the calibrated copy is made.
ARMS = ("ur5", "puma560", "iiwa14", "panda")


def _calibrated(name: str, folder: Path) -> Robot:
    return off_axis_iiwa(folder) if name == "iiwa14" else calibrated_urdf(name, folder)


def _problem(robot: Robot, count: int):
    rng = np.random.default_rng(0)
    qs = rng.uniform(robot.lower, robot.upper, size=(count, robot.nq))
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    values = qs[:, 6].copy() if robot.nq == 7 else None
    if robot.nq == 7:
        values = np.asarray(get_solver(robot).parameter_of(qs))
    return targets, values


def bench_ours(robot: Robot, poses: int, quick: bool) -> dict[str, float]:
    """Single pose [µs] and batch [poses/s] of the closed form on ``robot``."""
    targets, values = _problem(robot, 2000)
    cycle = iter(range(10**9))

    def one() -> object:
        i = next(cycle) % 2000
        if values is None:
            return analytic(robot, targets[i])
        return analytic(robot, targets[i], redundancy=float(values[i]))

    def safe() -> object:
        try:
            return one()
        except Exception:  # a pose out of the model's reach (counted as a solve)
            return None

    single = six._median_us(safe, repeat=5 if quick else 15, number=100)
    each = np.empty(len(targets))
    for i in range(len(targets)):  # one call per pose: the median pose
        start = time.perf_counter()
        safe()
        each[i] = time.perf_counter() - start
    reps = max(poses // len(targets), 1)
    big = np.tile(targets, (reps, 1, 1))
    if values is None:
        rate = six._rate(
            lambda: analytic_batch(robot, big), len(big), 2 if quick else 5
        )
    else:
        big_values = np.tile(values, reps)
        rate = six._rate(
            lambda: analytic_batch(robot, big, redundancy=big_values),
            len(big),
            2 if quick else 5,
        )
    return {
        "single_us": single,
        "median_us": float(np.median(each)) * 1e6,
        "p99_us": float(np.percentile(each, 99)) * 1e6,
        "batch_poses_per_s": rate,
    }


def bench_numeric(robot: Robot, quick: bool) -> dict[str, float]:
    targets, _ = _problem(robot, 100)
    cycle = iter(range(10**9))
    one = six._median_us(
        lambda: numeric(robot, targets[next(cycle) % 100], rng=0),
        repeat=3 if quick else 7,
        number=10,
    )
    return {"single_us": one, "batch_poses_per_s": 1e6 / one}


def bench_eaik_on(robot: Robot, name: str, poses: int, quick: bool):
    """EAIK on the calibrated model, else (it refuses it) on the exact arm."""
    try:
        hp = importlib.import_module("eaik.IK_HP")
    except ImportError as err:
        return f"not importable ({err})", ""
    if robot.nq == 6:
        directions, offsets, _ = six._chain(robot)
        peer = hp.HPRobot(directions, offsets)
        if peer.hasKnownDecomposition():
            return six.bench_eaik(name, poses, quick), "calibrated model"
        return six.bench_eaik(name, poses, quick), "exact arm (refuses the calibrated)"
    exact = load_robot(name)
    return seven.bench_eaik(exact, poses, quick), "exact arm, joint 7 locked"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=100_000)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--robots", default=",".join(ARMS))
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="calibrated-"))
    print(f"reference loop sum(range(1000)): {six._reference_us():.2f} µs")
    for name in args.robots.split(","):
        robot = _calibrated(name, folder)
        deviation = get_structure(robot).deviation.describe()
        print(
            f"\n{name} calibrated: {get_structure(robot).family}, deviation {deviation}"
        )
        print(f"  reference loop {six._reference_us():.2f} µs")
        rows: list[tuple[str, object, str]] = [
            ("ours, calibrated model", bench_ours(robot, args.poses, args.quick), ""),
            (
                "ours, exact arm",
                bench_ours(load_robot(name), args.poses, args.quick),
                "",
            ),
            ("ik.numeric, calibrated model", bench_numeric(robot, args.quick), ""),
        ]
        eaik, where = bench_eaik_on(robot, name, args.poses, args.quick)
        rows.append(("EAIK", eaik, where))
        if name == "panda":
            rows.append(
                ("frankik", seven.bench_frankik(load_robot(name), args.poses,
                                                args.quick), "exact arm")
            )  # fmt: skip
        print(
            f"  {'tool':<30} {'single pose [µs]':>17} {'median pose [µs]':>17} "
            f"{'p99 pose [µs]':>14} {'batch [poses/s]':>16}  on"
        )
        exact = rows[1][1]
        for tool, result, on in rows:
            if isinstance(result, str):
                print(f"  {tool:<30} {result}")
                continue
            assert isinstance(result, dict)
            median = result.get("median_us")
            shown = f"{median:>17.2f}" if median is not None else f"{'':>17}"
            tail = result.get("p99_us")
            shown += f" {tail:>14.1f}" if tail is not None else f" {'':>14}"
            print(
                f"  {tool:<30} {result['single_us']:>17.2f} {shown} "
                f"{result['batch_poses_per_s']:>16,.0f}  {on}"
            )
        ours = rows[0][1]
        assert isinstance(ours, dict) and isinstance(exact, dict)
        print(
            f"  ratios, calibrated / exact arm: single "
            f"{ours['single_us'] / exact['single_us']:.1f}x, batch "
            f"{exact['batch_poses_per_s'] / ours['batch_poses_per_s']:.0f}x slower"
        )


if __name__ == "__main__":
    main()
