"""Closed-form IK of seven-axis arms: speed and agreement, workbench vs peers.

Run from the repository root: ``python -m benchmarks.bench_seven_axis
[--poses N] [--agreement M] [--quick]``.

Speed, per robot (``panda``: Franka, parameter q7; ``iiwa14``: SRS, parameter
the arm angle ψ), one core, CPU time of this process:

* single pose: median time of one call from Python that returns every branch
  for one value of the parameter (ours: ``ik.analytic(..., redundancy=v)``;
  frankik: ``ik_full``, at most four branches within the Panda's limits;
  EAIK: ``IK`` of the 6R arm that locking joint 7 at q7 leaves, a robot
  built once per value; ``ik.numeric``: one solution, no parameter);
* batch: poses per second (ours: ``analytic_batch`` with one value per pose;
  frankik and EAIK have no batch call with a value per pose: a Python loop).

Agreement (``--agreement`` random poses, FK of random configurations within
the limits, and random parameter values):

* Panda: every exact answer of frankik's ``ik_full`` (FK residual ≤ 1e-9) is
  among our branches (joint difference mod 2π ≤ 1e-9; an answer farther away
  is counted, then polished by Newton at its q7 and compared again: frankik
  reaches the pose less exactly than we do); our FK residual; the branches
  within the limits that frankik leaves out;
* iiwa14: every solution that a multi-start Gauss-Newton finds on
  [pose error; ψ(q) − ψ*] (16 random starts per pose) is among our branches;
* both: ``analytic(fk(q), redundancy=solver.parameter_of(q))`` contains q.

frankik's ``fk`` gives the pose of the Franka Hand's TCP (our tool frame
``panda_hand_tcp``), but its ``ik`` and ``ik_full`` take the flange pose
``O_T_EE`` (``panda_link8``): the target handed to them is the TCP pose times
the inverse of the hand's offset (``docs/seven-axis.md``).
"""

from __future__ import annotations

import argparse
import importlib
import math
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from benchmarks.bench_ik_closed_form import _chain, _median_us, _rate, _reference_us
from workbench import Robot, load_robot
from workbench.ik import analytic, analytic_batch, get_solver, numeric

Bench = Callable[[Robot, int, bool], "dict[str, float] | str"]

#: A joint difference (mod 2π) below this [rad] is the same solution.
SAME_SOLUTION_TOL = 1e-9

#: The Franka Hand's TCP in the flange frame ``panda_link8``: 45° about z and
#: 0.1034 m along z (libfranka's default end effector; frankik's
#: ``FrankaHandTCPOffset`` prints the rotation rounded to 0.707).
_HAND = np.array(
    [
        [math.sqrt(0.5), math.sqrt(0.5), 0.0, 0.0],
        [-math.sqrt(0.5), math.sqrt(0.5), 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.1034],
        [0.0, 0.0, 0.0, 1.0],
    ]
)


def _problem(robot: Robot, count: int, seed: int = 0):
    """``count`` in-limit configurations, their tool poses and parameters."""
    rng = np.random.default_rng(seed)
    qs = rng.uniform(robot.lower, robot.upper, size=(count, robot.nq))
    poses = np.array([robot.fk(q).homogeneous for q in qs])
    return qs, poses, np.asarray(get_solver(robot).parameter_of(qs))


def _wrapped(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a − b| per joint, modulo 2π."""
    return np.abs(np.remainder(a - b + math.pi, 2.0 * math.pi) - math.pi)


def _fk_error(robot: Robot, q: np.ndarray, pose: np.ndarray) -> float:
    """Largest entry of |FK(q) − pose| (rotation entries and metres)."""
    return float(np.abs(robot.fk(q).homogeneous - pose).max())


# -- speed -------------------------------------------------------------------


def bench_ours(robot: Robot, poses: int, quick: bool) -> dict[str, float]:
    _, targets, values = _problem(robot, 2000)
    cycle = iter(range(10**9))

    def one() -> object:
        i = next(cycle) % 2000
        return analytic(robot, targets[i], redundancy=values[i])

    single = _median_us(one, repeat=7 if quick else 25, number=200)
    reps = max(poses // len(targets), 1)
    big, big_values = np.tile(targets, (reps, 1, 1)), np.tile(values, reps)
    rate = _rate(
        lambda: analytic_batch(robot, big, redundancy=big_values),
        len(big),
        3 if quick else 7,
    )
    return {"single_us": single, "batch_poses_per_s": rate}


def bench_frankik(robot: Robot, poses: int, quick: bool) -> dict[str, float] | str:
    try:
        frankik = importlib.import_module("frankik")
    except ImportError as err:
        return f"not importable ({err})"
    qs, targets, values = _problem(robot, 2000)
    flanges = targets @ np.linalg.inv(_HAND)
    cycle = iter(range(10**9))

    def one() -> object:
        i = next(cycle) % 2000
        return frankik.ik_full(flanges[i], qs[i], values[i])

    single = _median_us(one, repeat=7 if quick else 25, number=200)
    count = min(poses, 20_000 if quick else 200_000)

    def loop() -> None:
        for i in range(count):
            frankik.ik_full(flanges[i % 2000], qs[i % 2000], values[i % 2000])

    return {"single_us": single, "batch_poses_per_s": _rate(loop, count, 1)}


def _eaik_peer(robot: Robot, locked: int, value: float):
    """EAIK's solver of the 6R arm left by locking joint ``locked`` at ``value``."""
    hp = importlib.import_module("eaik.IK_HP")
    directions, offsets, rotation0 = _chain(robot)
    return hp.HPRobot(directions, offsets, fixed_axes=[(locked, value)]), rotation0


def bench_eaik(robot: Robot, poses: int, quick: bool) -> dict[str, float] | str:
    """EAIK on the Panda with joint 7 locked at one q7 (our parameter)."""
    try:
        importlib.import_module("eaik.IK_HP")
    except ImportError as err:
        return f"not importable ({err})"
    value = 0.3
    rng = np.random.default_rng(1)
    qs = rng.uniform(robot.lower, robot.upper, size=(2000, robot.nq))
    qs[:, 6] = value
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    peer, rotation0 = _eaik_peer(robot, 6, value)
    shifted = targets.copy()
    shifted[:, :3, :3] = targets[:, :3, :3] @ rotation0.T
    worst = 0.0
    for target, pose in zip(targets[:200], shifted[:200], strict=True):
        solution = peer.IK(pose)
        exact = ~np.asarray(solution.is_LS, dtype=bool)
        for q in np.asarray(solution.Q)[exact]:
            worst = max(worst, _fk_error(robot, q, target))
    if worst > 1e-9:
        return f"answers miss the pose (max |FK(q) - target| = {worst:.2g})"
    cycle = iter(range(10**9))
    single = _median_us(
        lambda: peer.IK(shifted[next(cycle) % 2000]),
        repeat=7 if quick else 25,
        number=200,
    )
    count = min(poses, 20_000 if quick else 100_000)
    batch = [shifted[i % 2000] for i in range(count)]
    rate = _rate(lambda: peer.IK_batched(batch, 1), count, 1)
    return {"single_us": single, "batch_poses_per_s": rate}


def bench_numeric(robot: Robot, poses: int, quick: bool) -> dict[str, float]:
    _, targets, _ = _problem(robot, 100)
    cycle = iter(range(10**9))
    single = _median_us(
        lambda: numeric(robot, targets[next(cycle) % 100], rng=0),
        repeat=3 if quick else 7,
        number=10,
    )
    return {"single_us": single, "batch_poses_per_s": 1e6 / single}


# -- agreement ---------------------------------------------------------------


def agreement_frankik(robot: Robot, count: int) -> dict[str, float] | str:
    """frankik's exact answers among ours, on random poses and q7 values."""
    try:
        frankik = importlib.import_module("frankik")
    except ImportError as err:
        return f"not importable ({err})"
    rng = np.random.default_rng(7)
    qs = rng.uniform(robot.lower, robot.upper, size=(count, 7))
    values = rng.uniform(robot.lower[6], robot.upper[6], size=count)
    qs[: count // 2, 6] = values[: count // 2]  # half: q7 of the pose's own q
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    values[: count // 2] = qs[: count // 2, 6]
    flanges = targets @ np.linalg.inv(_HAND)
    q_ours, valid = analytic_batch(robot, targets, redundancy=values)
    within = valid & np.all(
        (q_ours >= robot.lower - 1e-9) & (q_ours <= robot.upper + 1e-9), axis=2
    )
    theirs = missing = polished_missing = wrong = 0
    worst_match, worst_fk, worst_theirs = 0.0, 0.0, 0.0
    ours_only = 0
    for i in range(count):
        solutions = frankik.ik_full(flanges[i], qs[i], values[i])
        solutions = solutions[~np.isnan(solutions).any(axis=1)]
        matched = np.zeros(q_ours.shape[1], dtype=bool)
        for s in solutions:
            theirs += 1
            residual = _fk_error(robot, s, targets[i])
            if residual > 1e-9:
                wrong += 1
                continue
            worst_theirs = max(worst_theirs, residual)
            gaps = _wrapped(q_ours[i], s).max(axis=1)
            gaps[~valid[i]] = np.inf
            best = int(np.argmin(gaps))
            if gaps[best] > SAME_SOLUTION_TOL:
                missing += 1
                s = _polished(robot, pin.SE3(targets[i]), s)
                gaps = _wrapped(q_ours[i], s).max(axis=1)
                gaps[~valid[i]] = np.inf
                best = int(np.argmin(gaps))
                if gaps[best] > SAME_SOLUTION_TOL:
                    polished_missing += 1
                    continue
            matched[best] = True
            worst_match = max(worst_match, float(gaps[best]))
        ours_only += int((within[i] & ~matched).sum())
        for q in q_ours[i][valid[i]][:2]:
            worst_fk = max(worst_fk, _fk_error(robot, q, targets[i]))
    return {
        "poses": count,
        "frankik_solutions": theirs,
        "frankik_wrong": wrong,
        "frankik_worst_fk_residual": worst_theirs,
        "frankik_not_in_ours": missing,
        "not_in_ours_after_polish": polished_missing,
        "worst_match_rad": worst_match,
        "ours_within_limits_not_in_frankik": ours_only,
        "ours_fk_residual": worst_fk,
    }


def _polished(robot: Robot, pose: pin.SE3, q: np.ndarray) -> np.ndarray:
    """``q`` after three Newton steps on joints 1-6 (q7 fixed) towards ``pose``.

    frankik's answers reach the pose to 1e-12 … 1e-10 (ours to 1e-15); where
    the joints are ill-conditioned that is a joint difference of up to a few
    1e-8, so an answer not within 1e-9 of ours is polished before it counts
    as missing.
    """
    q = q.copy()
    for _ in range(3):
        placement = pose.actInv(robot.fk(q))
        jac = pin.Jlog6(placement) @ _local_jacobian(robot, q)[:, :6]
        q[:6] -= np.linalg.solve(jac, pin.log6(placement).vector)
    return q


def _constrained_newton(robot: Robot, pose: pin.SE3, psi: float, q: np.ndarray):
    """Gauss-Newton on [log6(pose⁻¹ FK(q)); ψ(q) − ψ*] from ``q`` (None: diverged)."""
    for _ in range(60):
        error = pin.log6(pose.actInv(robot.fk(q))).vector
        value = float(get_solver(robot).parameter_of(q))
        gap = math.remainder(value - psi, 2 * math.pi)
        if np.abs(error).max() < 1e-13 and abs(gap) < 1e-13:
            return q
        jac = pin.Jlog6(pose.actInv(robot.fk(q))) @ _local_jacobian(robot, q)
        row = np.empty(7)
        for k in range(7):
            step = np.zeros(7)
            step[k] = 1e-7
            up = float(get_solver(robot).parameter_of(q + step))
            down = float(get_solver(robot).parameter_of(q - step))
            row[k] = math.remainder(up - down, 2 * math.pi) / 2e-7
        system = np.vstack([jac, row])
        q = q - np.linalg.lstsq(system, np.append(error, gap), rcond=None)[0]
    return None


def _local_jacobian(robot: Robot, q: np.ndarray) -> np.ndarray:
    model, data = robot.model, robot.data
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    return pin.getFrameJacobian(model, data, robot.tool_frame_id, pin.LOCAL)


def agreement_multistart(robot: Robot, count: int, starts: int = 16) -> dict:
    """Solutions of a multi-start Gauss-Newton at the same ψ, among ours."""
    rng = np.random.default_rng(11)
    _, targets, values = _problem(robot, count, seed=11)
    found = missing = 0
    worst = 0.0
    for i in range(count):
        pose = pin.SE3(targets[i])
        ours = np.array(
            [s.q for s in analytic(robot, targets[i], redundancy=values[i])]
        )
        for _ in range(starts):
            q = _constrained_newton(
                robot, pose, values[i], rng.uniform(robot.lower, robot.upper)
            )
            if q is None:
                continue
            found += 1
            gap = float(_wrapped(ours, q).max(axis=1).min())
            if gap > 1e-7:  # converged to 1e-13 in the pose: same solution to 1e-9
                missing += 1
            else:
                worst = max(worst, gap)
    return {
        "poses": count,
        "numerical_solutions": found,
        "not_in_ours": missing,
        "worst_match_rad": worst,
    }


def round_trip(robot: Robot, count: int) -> dict[str, float]:
    """``analytic(fk(q), redundancy=solver.parameter_of(q))`` contains q."""
    qs, targets, values = _problem(robot, count, seed=3)
    q_all, valid = analytic_batch(robot, targets, redundancy=values)
    gaps = np.where(valid, _wrapped(q_all, qs[:, None, :]).max(axis=2), np.inf)
    return {"configurations": count, "worst_rad": float(gaps.min(axis=1).max())}


def _print_speed(name: str, rows, ours) -> None:
    print(f"\n{name}: every branch for one parameter value, one core, CPU time "
          f"(machine reference now {_reference_us():.1f} µs)")  # fmt: skip
    print(f"{'solver':46s} {'single [µs]':>12s} {'ratio':>7s} {'batch [poses/s]':>16s} "
          f"{'ratio':>7s}")  # fmt: skip
    for label, r in rows:
        batch = r["batch_poses_per_s"]
        print(
            f"{label:46s} {r['single_us']:12.1f} "
            f"{r['single_us'] / ours['single_us']:6.1f}x "
            f"{batch:16,.0f} {ours['batch_poses_per_s'] / batch:6.1f}x"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=1_000_000, help="batch size")
    parser.add_argument(
        "--agreement", type=int, default=10_000, help="poses of the agreement checks"
    )
    parser.add_argument("--quick", action="store_true", help="fewer repeats")
    args = parser.parse_args()
    print(f"machine reference: sum(range(1000)) = {_reference_us():.1f} µs (CPU time)")
    print("ratio: peer time relative to the workbench (single), workbench "
          "speed-up (batch); ik.numeric: one solution, batch = 1 / single")  # fmt: skip
    skipped: list[str] = []
    for name in ("panda", "iiwa14"):
        robot = load_robot(name)
        ours = bench_ours(robot, args.poses, args.quick)
        rows: list[tuple[str, dict[str, float]]] = [
            ("workbench analytic / analytic_batch", ours)
        ]
        peers: list[tuple[str, Bench]] = [
            ("workbench ik.numeric (1 solution)", bench_numeric)
        ]
        if name == "panda":
            peers = [
                ("frankik ik_full (batch: Python loop)", bench_frankik),
                ("EAIK IK / IK_batched, joint 7 locked", bench_eaik),
                *peers,
            ]
        for label, bench in peers:
            result = bench(robot, args.poses, args.quick)
            if isinstance(result, str):
                skipped.append(f"{label} on {name}: {result}")
            else:
                rows.append((label, result))
        _print_speed(name, rows, ours)
    print("\nagreement")
    panda, iiwa = load_robot("panda"), load_robot("iiwa14")
    result = agreement_frankik(panda, args.agreement)
    print(f"panda vs frankik ik_full: {result}")
    count = max(args.agreement // 100, 20)
    print(f"iiwa14 vs multi-start Gauss-Newton at the same ψ: "
          f"{agreement_multistart(iiwa, count)}")  # fmt: skip
    for robot in (panda, iiwa):
        print(f"{robot.name} round trip: {round_trip(robot, args.agreement)}")
    for line in skipped:
        print(f"skipped {line}")


if __name__ == "__main__":
    main()
