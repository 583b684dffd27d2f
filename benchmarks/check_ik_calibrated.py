"""Completeness of the closed form on calibrated arms, measured: a table.

Run: ``python -m benchmarks.check_ik_calibrated [--samples N] [--poses P]``.

The arms of ``benchmarks/_calibrated_models.py`` (a UR5 and a PUMA 560 with
calibration deltas, the iiwa 14 0.436 mm off axis, a calibrated Panda at held
q7). Per arm, for N random in-limit configurations: the largest FK residual
of every branch by Pinocchio [m, rad]; the configurations whose generating q
is not among the branches (to 1e-9 rad), how many of them are near a
singularity (``least_singular`` below 0.02: the tool Jacobian, [J; ∇ψ] for
an SRS arm at held ψ) and how
many the solve flags (``ik.SolveFlag``); the poses with a non-zero solve
byte. Then a 100-start ``ik.numeric_batch`` search at P poses: the solutions
it finds outside the branches (to 1e-6 rad), and at how many poses, flagged
or not. ``tests/test_ik_calibrated.py`` asserts the same (``slow`` tests);
this prints the numbers.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks._calibrated_models import (
    calibrated_arm,
    fk_residuals,
    least_singular,
    wrapped,
)
from workbench import Robot
from workbench.ik import get_solver, get_structure, numeric_batch

ARMS = ("ur5", "puma560", "iiwa14", "panda")
#: The tolerances of ``tests/test_ik_calibrated.py``.
ATOL_SAME_Q = 1e-9
ATOL_NUMERIC_Q = 1e-6
NEAR_SINGULAR = 0.02


def _solve(robot: Robot, targets: np.ndarray, values):
    events = np.empty(len(targets), dtype=np.uint8)
    q_all, valid = get_solver(robot).solve_batch(
        targets, redundancy=values, solve_flags=events
    )
    return q_all, valid, events


def round_trip(robot: Robot, samples: int) -> dict[str, object]:
    """The generating q among the branches, residuals, misses and their reasons."""
    solver = get_solver(robot)
    rng = np.random.default_rng(1)
    qs = rng.uniform(robot.lower, robot.upper, (samples, robot.nq))
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    values = None if robot.nq == 6 else np.asarray(solver.parameter_of(qs))
    start = time.perf_counter()
    q_all, valid, events = _solve(robot, targets, values)
    seconds = time.perf_counter() - start
    rows = np.nonzero(valid)
    residual = fk_residuals(robot, q_all[rows], targets[rows[0]]).max(axis=0)
    gaps = wrapped(q_all - qs[:, None, :]).max(axis=2)
    gaps[~valid] = np.inf
    missed = np.flatnonzero(gaps.min(axis=1) > ATOL_SAME_Q)
    sigmas = [least_singular(robot, qs[i]) for i in missed]
    near = sum(s < NEAR_SINGULAR for s in sigmas)
    flagged = int(np.count_nonzero(events[missed]))
    both = sum(
        s < NEAR_SINGULAR and events[i] != 0
        for s, i in zip(sigmas, missed, strict=True)
    )
    return {
        "samples": samples,
        "residual_m": residual[0],
        "residual_rad": residual[1],
        "missed": len(missed),
        "near_singular": near,
        "flagged": flagged,
        "near_and_flagged": both,
        "largest_sigma_of_a_miss": max(sigmas, default=0.0),
        "flagged_poses": int(np.count_nonzero(events)),
        "batch_poses_per_s": samples / seconds,
    }


def numerical_search(robot: Robot, poses: int, starts: int) -> dict[str, object]:
    """``numeric_batch`` from ``starts`` random starts at ``poses`` poses."""
    solver = get_solver(robot)
    rng = np.random.default_rng(4)
    qs = rng.uniform(robot.lower, robot.upper, size=(poses, robot.nq))
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    begin = rng.uniform(robot.lower, robot.upper, (poses * starts, robot.nq))
    repeated = np.repeat(targets, starts, axis=0)
    found = numeric_batch(robot, repeated, begin, rng=7)
    ok = np.flatnonzero(found.success)
    q_num = found.q[ok]
    if robot.nq == 6:
        q_all, valid, events = _solve(robot, targets, None)
        q_all, valid = q_all[ok // starts], valid[ok // starts]
        events = events[ok // starts]
    else:  # each solution at its own value of the parameter
        q_all, valid, events = _solve(
            robot, repeated[ok], np.asarray(solver.parameter_of(q_num))
        )
    gaps = wrapped(q_all - q_num[:, None, :]).max(axis=2)
    gaps[~valid] = np.inf
    outside = np.flatnonzero(gaps.min(axis=1) > ATOL_NUMERIC_Q)
    at = np.unique(ok[outside] // starts)
    unflagged = np.unique(ok[outside[events[outside] == 0]] // starts)
    return {
        "converged": f"{ok.size}/{len(repeated)}",
        "outside": len(outside),
        "outside_poses": len(at),
        "unflagged_poses": len(unflagged),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--poses", type=int, default=200)
    parser.add_argument("--starts", type=int, default=100)
    parser.add_argument("--robots", default=",".join(ARMS))
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="calibrated-"))
    for name in args.robots.split(","):
        robot = calibrated_arm(name, folder)
        deviation = get_structure(robot).deviation.describe()
        print(f"{name}: {get_structure(robot).family}, deviation {deviation}")
        print(f"  round trip: {round_trip(robot, args.samples)}")
        if args.poses:
            print(f"  search:     {numerical_search(robot, args.poses, args.starts)}")


if __name__ == "__main__":
    main()
