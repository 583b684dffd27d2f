"""Speed of the normal spline and pick-and-place sampling; toppra / ruckig beside it.

Run: ``python benchmarks/bench_trajectory.py`` (toppra and ruckig are optional,
``pip install -e .[bench]``). Times are the best of several repeats on this
machine; targets (issue 5): synthesis of N = 10⁶ knots <= 0.2 s, sampling 10 s
at 1 kHz for 6 joints <= 1 ms. No assertion: the script prints and exits 0.

The peers solve a different problem (time-optimal parametrisation, jerk-limited
online generation), so two kinds of numbers are printed: planning and sampling
times, and the motion durations each method reaches under the same limits on
the Table III motion (speed 1 / 2 rad/s from the model; acceleration 2 rad/s²
and jerk 20 rad/s³ are assumed for the comparison, the paper gives none).
"""

from __future__ import annotations

import importlib.util
import time
from collections.abc import Callable

import numpy as np

from workbench import load_robot, paper_data, trajectory

N_LARGE = 1_000_000
RATE_HZ = 1000.0
DURATION = paper_data.ANGELES_DURATION
ACCELERATION = 2.0  # [rad/s²], assumed for the comparison
JERK = 20.0  # [rad/s³], assumed for ruckig


def best_of(
    fn: Callable[[], object],
    repeat: int,
    number: int = 1,
    clock: Callable[[], float] = time.perf_counter,
) -> float:
    """Best time of ``fn`` [s] per call over ``repeat`` rounds of ``number`` calls."""
    best = np.inf
    for _ in range(repeat):
        start = clock()
        for _ in range(number):
            fn()
        best = min(best, (clock() - start) / number)
    return best


def wall_and_cpu(fn: Callable[[], object], repeat: int, number: int = 1) -> str:
    """``best wall / best CPU`` time of one call, formatted in ms or us.

    On a shared machine the wall time includes waiting for a core; the CPU
    time (``time.process_time``) does not, so the targets are read on it.
    """
    wall = best_of(fn, repeat, number)
    cpu = best_of(fn, repeat, number, time.process_time)
    if wall >= 1e-3:
        return f"{wall * 1e3:8.2f} ms wall, {cpu * 1e3:8.2f} ms CPU"
    return f"{wall * 1e6:8.2f} us wall, {cpu * 1e6:8.2f} us CPU"


def main() -> None:
    robot = load_robot("puma560")
    q0 = np.deg2rad(paper_data.ANGELES_PICK_Q_DEG)
    q1 = np.deg2rad(paper_data.ANGELES_PLACE_Q_DEG)
    t = np.arange(int(DURATION * RATE_HZ) + 1) / RATE_HZ

    traj = trajectory.pick_and_place(robot, q0, q1, DURATION)
    plan = best_of(lambda: trajectory.pick_and_place(robot, q0, q1, DURATION), 20, 50)
    sample = best_of(lambda: traj.sample(t), repeat=20, number=50)
    print("workbench (normal spline); best of repeats")
    synth = wall_and_cpu(lambda: trajectory.compute_normal_spline(N_LARGE), 7)
    print(f"  synthesis N = 10^6       {synth}   (target <= 200 ms)")
    synth40 = wall_and_cpu(lambda: trajectory.compute_normal_spline(40), 20, 100)
    print(f"  synthesis N = 40         {synth40}")
    plan_s = wall_and_cpu(
        lambda: trajectory.pick_and_place(robot, q0, q1, DURATION), 20, 50
    )
    print(f"  pick_and_place (N = 40)  {plan_s}   (spline memoised)")
    sample_s = wall_and_cpu(lambda: traj.sample(t), 30, 50)
    print(f"  sample {t.size} x 6      {sample_s}   (target <= 1 ms)")
    check = wall_and_cpu(traj.check_limits, 20, 50)
    print(f"  exact limit check        {check}")

    limited = robot.with_limits(acceleration_limit=np.full(6, ACCELERATION))
    t_spline = trajectory.minimum_duration(limited, q0, q1)
    t_opt = trajectory.compute_time_optimal_duration(limited, q0, q1)
    print(f"\nTable III motion, speed limits + {ACCELERATION} rad/s² (durations)")
    print(f"  normal spline minimum duration   {t_spline:8.4f} s")
    ratio = t_spline / t_opt
    print(f"  time-optimal, closed form        {t_opt:8.4f} s   ratio {ratio:.3f}")

    if importlib.util.find_spec("toppra"):
        import toppra  # noqa: F401  (import cost kept out of the timing)

        t_toppra = trajectory.compute_toppra_duration(limited, q0, q1)
        solve = best_of(
            lambda: trajectory.compute_toppra_duration(limited, q0, q1), repeat=5
        )
        print(
            f"  toppra (1001 grid points)        {t_toppra:8.4f} s   ratio "
            f"{t_spline / t_toppra:.3f}; solve {solve * 1e3:.1f} ms = "
            f"{solve / plan:.0f}x pick_and_place"
        )
    else:
        print("  toppra: not installed (pip install toppra)")

    if importlib.util.find_spec("ruckig"):
        from ruckig import InputParameter, Ruckig, Synchronization, Trajectory

        inp = InputParameter(6)
        inp.current_position = q0.tolist()
        inp.target_position = q1.tolist()
        inp.max_velocity = robot.velocity_limit.tolist()
        inp.max_acceleration = [ACCELERATION] * 6
        inp.max_jerk = [JERK] * 6
        inp.synchronization = Synchronization.Phase  # straight joint path
        otg, rtraj = Ruckig(6), Trajectory(6)
        otg.calculate(inp, rtraj)
        solve = best_of(lambda: otg.calculate(inp, rtraj), repeat=20, number=50)
        t_r = np.arange(int(rtraj.duration * RATE_HZ) + 1) / RATE_HZ
        at_time = rtraj.at_time
        rsample = best_of(lambda: [at_time(x) for x in t_r], repeat=3)
        per = rsample / t_r.size
        ours = sample / t.size
        print(
            f"  ruckig (jerk {JERK} rad/s³)      {rtraj.duration:8.4f} s   ratio "
            f"{t_spline / rtraj.duration:.3f}; solve {solve * 1e6:.1f} us "
            f"({solve / plan:.2f}x pick_and_place), sampling {per * 1e6:.2f} us "
            f"per point in Python ({per / ours:.0f}x ours)"
        )
    else:
        print("  ruckig: not installed (pip install ruckig)")


if __name__ == "__main__":
    main()
