"""Speed of the polyline time scaling, and its durations against the optimum.

Run: ``python benchmarks/bench_time_scale.py`` (TOPP-RA is optional, ``pip install
-e .[bench]``). Prints, for the Panda (the Franka datasheet's acceleration
limits), the best wall and CPU time of :func:`workbench.motion.time_scale` on a
5-waypoint path, of ``sample`` at 1000 instants and ``sample_uniform`` at 1 kHz;
then the ratio of the duration to the time-optimal one along the same polylines
(:func:`workbench.motion.time_optimal_duration`) over random polylines of the
four catalog arms, and TOPP-RA's duration on the first of them beside the
closed form. No assertion: the script prints and exits 0.
"""

from __future__ import annotations

import importlib.util
import itertools
import math
import time
from collections.abc import Callable

import numpy as np

from workbench import load_robot
from workbench.motion import WORST_RATIO, time_optimal_duration, time_scale
from workbench.trajectory import compute_toppra_duration

#: Acceleration limits [rad/s²] given to the catalog arms (their URDFs have none).
ACCELERATION_LIMITS = {
    "puma560": [4.0, 4.0, 4.0, 8.0, 8.0, 8.0],
    "ur5": [8.0] * 6,
    "panda": [15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0],
    "iiwa14": [10.0] * 7,
}
POLYLINES = 2000  # per arm
SCALES = ((1.0, 1.0), (0.5, 0.3), (0.1, 0.01))  # (velocity, acceleration)


def best_of(fn: Callable[[], object], repeat: int, number: int, clock) -> float:
    """Best time of one call [s] over ``repeat`` rounds of ``number`` calls."""
    best = math.inf
    for _ in range(repeat):
        start = clock()
        for _ in range(number):
            fn()
        best = min(best, (clock() - start) / number)
    return best


def timed(label: str, fn: Callable[[], object], number: int) -> None:
    wall = best_of(fn, 7, number, time.perf_counter)
    cpu = best_of(fn, 7, number, time.process_time)
    print(f"{label:44s} {wall * 1e6:9.1f} us wall {cpu * 1e6:9.1f} us CPU")


def polyline(robot, rng: np.random.Generator, count: int) -> np.ndarray:
    """Waypoints within the limits, steps of 1 mrad to 3 rad (log-uniform)."""
    points = [rng.uniform(robot.lower, robot.upper)]
    while len(points) < count:
        direction = rng.normal(size=robot.nq)
        length = 10.0 ** rng.uniform(-3.0, math.log10(3.0))
        step = direction / np.linalg.norm(direction) * length
        points.append(np.clip(points[-1] + step, robot.lower, robot.upper))
    return np.array(points)


def main() -> None:
    robots = {
        name: load_robot(name).with_limits(acceleration_limit=limits)
        for name, limits in ACCELERATION_LIMITS.items()
    }
    panda = robots["panda"]
    path = polyline(panda, np.random.default_rng(0), 5)
    traj = time_scale(panda, path)
    t = np.linspace(0.0, traj.duration, 1000)
    print(f"panda, 5 waypoints, duration {traj.duration:.4f} s")
    timed("time_scale", lambda: time_scale(panda, path), 200)
    timed("sample, 1000 instants", lambda: traj.sample(t), 200)
    timed("sample_uniform, 1 kHz", lambda: traj.sample_uniform(1000.0), 200)
    timed("time_optimal_duration", lambda: time_optimal_duration(panda, path), 200)
    print(f"\nratio to the optimum (stated worst case {WORST_RATIO:.6f})")
    for name, robot in robots.items():
        rng = np.random.default_rng(1)
        ratios = []
        for k, (v, a) in itertools.product(range(POLYLINES), SCALES):
            points = polyline(robot, rng, 2 + k % 5)
            scales = {"velocity_scale": v, "acceleration_scale": a}
            duration = time_scale(robot, points, **scales).duration
            ratios.append(duration / time_optimal_duration(robot, points, **scales))
        r = np.array(ratios)
        print(
            f"{name:8s} {r.size:5d} polylines: min {r.min():.6f} median "
            f"{np.median(r):.6f} max {r.max():.16f}"
        )
    if importlib.util.find_spec("toppra") is None:
        print("\ntoppra not installed: no TOPP-RA comparison")
        return
    segments = list(itertools.pairwise(path))
    toppra = sum(compute_toppra_duration(panda, a, b) for a, b in segments)
    optimum = time_optimal_duration(panda, path)
    print(
        f"\npanda path: TOPP-RA {toppra:.6f} s, closed form {optimum:.6f} s "
        f"(relative {toppra / optimum - 1.0:+.2e}), time_scale {traj.duration:.6f} s "
        f"(ratio to TOPP-RA {traj.duration / toppra:.4f})"
    )


if __name__ == "__main__":
    main()
