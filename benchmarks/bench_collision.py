"""Clearance along Angeles' Table III pick-and-place: workbench vs raw Pinocchio/coal.

    python benchmarks/bench_collision.py [--repeat N]

The path: the normal-spline trajectory of Table III (T = 10 s) at 1000 samples,
checked for self-collision and against Angeles' scene (pedestal, pick table):
the same checked pairs everywhere. Timed, best of ``--repeat`` runs:

* ``check_path`` (straight lines between samples, and the spline with its exact
  peak speeds and accelerations): minimum clearance, where, every contact
  interval, and a proof that nothing is missed between the samples;
* raw Pinocchio from Python: ``pin.computeDistances`` at every sample (all
  pairs), then the minimum: distances at the samples only, no bound;
* raw coal from Python: ``pin.updateGeometryPlacements``, then
  ``coal.distance`` pair by pair at every sample.

The target of issue 14 is <= 50 ms for the first line. Timings depend on the
machine (a reference loop is printed); nothing is asserted.
"""

from __future__ import annotations

import argparse
import time
import timeit

import coal
import numpy as np
import pinocchio as pin

from workbench import load_robot, paper_data
from workbench.collision import CollisionChecker, check_path, get_angeles_scene
from workbench.trajectory import pick_and_place

clock = time.perf_counter
SAMPLES = 1000


def best_ms(function, repeat: int) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeat):
        start = clock()
        result = function()
        times.append(clock() - start)
    return 1e3 * min(times), result


def raw_pinocchio(robot, checker, q: np.ndarray) -> float:
    model, data = robot.model, robot.model.createData()
    geometry = checker.geometry_model
    geometry_data = pin.GeometryData(geometry)
    best = np.inf
    for qk in q:
        pin.computeDistances(model, data, geometry, geometry_data, qk)
        best = min(best, min(r.min_distance for r in geometry_data.distanceResults))
    return best


def raw_coal(robot, checker, q: np.ndarray) -> float:
    model, data = robot.model, robot.model.createData()
    geometry = checker.geometry_model
    geometry_data = pin.GeometryData(geometry)
    objects = geometry.geometryObjects
    pairs = [
        (objects[p.first].geometry, p.first, objects[p.second].geometry, p.second)
        for p in geometry.collisionPairs
    ]
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    best = np.inf
    for qk in q:
        pin.updateGeometryPlacements(model, data, geometry, geometry_data, qk)
        placements = [
            coal.Transform3s(m.rotation, m.translation) for m in geometry_data.oMg
        ]
        for a, i, b, j in pairs:
            result.clear()
            d = coal.distance(a, placements[i], b, placements[j], request, result)
            best = min(best, d)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    robot = load_robot("puma560")
    checker = CollisionChecker(robot, get_angeles_scene(robot))
    traj = pick_and_place(
        robot,
        np.deg2rad(paper_data.ANGELES_PICK_Q_DEG),
        np.deg2rad(paper_data.ANGELES_PLACE_Q_DEG),
        paper_data.ANGELES_DURATION,
    )
    t = np.linspace(0.0, traj.duration, SAMPLES)
    q = traj.sample(t)[0]
    peaks = [traj.get_extrema(order) for order in (1, 2)]
    speed, acceleration = (np.maximum(-e.minimum, e.maximum) for e in peaks)

    def spline():
        return check_path(
            checker,
            t,
            q,
            sample=lambda s: traj.sample(s)[0],
            max_joint_speed=speed,
            max_joint_acceleration=acceleration,
        )

    rows = [
        (
            "workbench check_path, lines between samples",
            lambda: check_path(checker, t, q),
        ),
        ("workbench check_path, spline, peak speed + acc", spline),
        (
            "raw pin.computeDistances loop (samples)",
            lambda: raw_pinocchio(robot, checker, q),
        ),
        ("raw coal.distance per pair (samples)", lambda: raw_coal(robot, checker, q)),
    ]
    reference_us = (
        1e6 * min(timeit.repeat("sum(range(1000))", number=1000, repeat=5)) / 1000
    )
    print(
        f"Table III pick-and-place, {SAMPLES} samples, {len(checker.pairs)} pairs "
        f"(self + pedestal + pick table), best of {args.repeat}"
    )
    print(f"reference loop sum(range(1000)): {reference_us:.1f} µs")
    timings = []
    for label, function in rows:
        ms, result = best_ms(function, args.repeat)
        value = result if isinstance(result, float) else result.min_clearance
        timings.append(ms)
        extra = ""
        if not isinstance(result, float):
            extra = (
                f", {result.evaluations} pair distances, {len(result.contacts)} "
                f"contacts, bound {result.lower_bound:.4f} m"
            )
        print(
            f"  {label:<46} {ms:8.2f} ms  x{ms / timings[0]:5.2f}  "
            f"min {value:.6f} m{extra}"
        )
    print(
        f"target <= 50 ms: {'met' if timings[0] <= 50.0 else 'NOT met'} "
        f"({timings[0]:.1f} ms)"
    )


if __name__ == "__main__":
    main()
