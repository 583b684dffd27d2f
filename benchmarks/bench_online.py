"""Planning-cycle latency of the online planner, against the same loop on peers.

    python benchmarks/bench_online.py [--seed N] [--robots NAME,...]

One run of Kang's fish-cutting program with the workbench planner (after an
untimed warm-up run) times every planning cycle (react to the last touch,
Cartesian command, closed-form IK with continuity, joint rates), and reports
the cycles that planned a motion (a primitive began or changed stage, or
reacted to a touch) apart from the others. The same run's Cartesian commands
are then replayed through the same loop built on Robotics Toolbox for Python
(``Puma560.ikine_a`` with Kang's θ4 flip rule, ``jacob0``, the same DLS
inverse), and ruckig's
per-cycle ``update`` is timed against the workbench's per-cycle Cartesian
command. Peers are optional: a missing one is reported and skipped.

Then the same program on each arm of ``--robots`` (default the PUMA and the
two seven-axis arms, ``iiwa14`` and ``panda``, each in its scaled cell, the
default redundancy policy ``keep``): median and p99 of the planning cycle
over the run, and on a seven-axis arm apart for the cycles that moved the
redundancy parameter (a policy move, or the differential command near a
singularity of the closed form) and the others. Timings depend on the
machine; nothing here is asserted.
"""

from __future__ import annotations

import argparse
import math
import time
import timeit

import numpy as np
import pinocchio as pin

from workbench import ik, load_robot
from workbench.planning import OnlinePlanner
from workbench.tasks import (
    FishCuttingSetup,
    SimulatedFish,
    get_cell_scale,
    run_fish_cutting,
)
from workbench.tasks.fish_program import KANG_BASE_HEIGHT, build_program

clock = time.perf_counter


def stats(us: np.ndarray) -> tuple[float, float]:
    return float(np.median(us)), float(np.percentile(us, 99))


def wrist_commands(run, setup: FishCuttingSetup):
    """Wrist-centre poses (base frame) and twists (base axes) of each cycle."""
    lift = np.array([0.0, 0.0, KANG_BASE_HEIGHT])
    poses, twists = [], []
    for p, v, rotation, omega in zip(
        run.position[1:],
        run.velocity[1:],
        run.rotation[1:],
        run.angular_velocity[1:],
        strict=True,
    ):
        lever = -rotation[:, 2] * setup.tool_length  # tip -> wrist centre
        poses.append(pin.SE3(rotation, p + lever - lift))
        twists.append(np.concatenate([v + np.cross(omega, lever), omega]))
    return poses, twists


def time_cartesian_command(robot, fish, setup) -> np.ndarray:
    """The workbench loop again, timing the Cartesian command of each cycle alone."""
    planner = OnlinePlanner(
        robot,
        np.zeros(6),
        setup.limits,
        planning_rate=setup.planning_rate,
        servo_rate=setup.servo_rate,
        transform_tip_to_tool=pin.SE3(np.eye(3), np.array([0, 0, setup.tool_length])),
        transform_base_to_world=pin.SE3(np.eye(3), np.array([0, 0, KANG_BASE_HEIGHT])),
    )
    home = pin.SE3(planner.state.rotation, planner.state.position)
    planner.append(*build_program(fish, setup, home))
    command_us, contact = [], None
    while not planner.done:
        planner.notify(contact)
        planner.step()
        t_next = planner.t + planner.period
        start = clock()
        planner.active.sample(t_next)  # what the next step will command
        command_us.append((clock() - start) * 1e6)
        contact = fish.get_contact(planner.state.position)
    return np.array(command_us)


def bench_rtb(poses, twists):
    try:
        import roboticstoolbox as rtb
        from spatialmath import SE3
    except ImportError as err:  # optional peer
        print(f"Robotics Toolbox for Python not importable ({err}); skipped")
        return None
    puma = rtb.models.DH.Puma560()  # its base frame is Kang's world frame (d1)
    lift = np.eye(4)
    lift[2, 3] = KANG_BASE_HEIGHT
    config, q_prev = None, None
    latency = []
    for pose, twist in zip(poses, twists, strict=True):
        start = clock()
        target = SE3(lift @ pose.homogeneous, check=False)
        if config is None:  # the branch nearest the start, once
            candidates = {
                c: puma.ikine_a(target, config=c).q
                for c in ("lun", "luf", "ldn", "ldf", "run", "ruf", "rdn", "rdf")
            }
            config = min(candidates, key=lambda c: np.abs(candidates[c][3:]).sum())
        q = puma.ikine_a(target, config=config).q
        if (
            q_prev is not None
            and abs(math.remainder(q[3] - q_prev[3], 2 * math.pi)) > 2
        ):
            config = config[:2] + ("f" if config[2] == "n" else "n")  # Kang's rule
            q = puma.ikine_a(target, config=config).q
        jacobian = puma.jacob0(q)
        qd = ik.dls_inverse(jacobian) @ twist
        latency.append((clock() - start) * 1e6)
        q_prev = q
    assert qd.shape == (6,)
    return np.array(latency)


def bench_ruckig(run, setup, cycles: int):
    try:
        from ruckig import InputParameter, OutputParameter, Result, Ruckig
    except ImportError as err:
        print(f"ruckig not importable ({err}); skipped")
        return None
    goals = [p for p, v in zip(run.position, run.velocity, strict=True) if not v.any()]
    otg = Ruckig(6, 1.0 / setup.planning_rate)
    inp, out = InputParameter(6), OutputParameter(6)
    inp.current_position = [*run.position[0], 0.0, 0.0, 0.0]
    inp.max_velocity = [setup.max_velocity] * 3 + [setup.max_angular_velocity] * 3
    inp.max_acceleration = [setup.max_acceleration] * 3 + [
        setup.max_angular_acceleration
    ] * 3
    inp.max_jerk = [50.0] * 6
    goal = 1
    inp.target_position = [*goals[goal % len(goals)], 0.0, 0.0, 0.0]
    latency = []
    for _ in range(cycles):
        start = clock()
        result = otg.update(inp, out)
        out.pass_to_input(inp)
        latency.append((clock() - start) * 1e6)
        if result == Result.Finished:  # next goal: an online target change
            goal += 1
            inp.target_position = [*goals[goal % len(goals)], 0.0, 0.0, 0.0]
    return np.array(latency)


def bench_robots(names: list[str], seed: int) -> None:
    """The fish-cutting run's planning cycle on each arm, in its scaled cell."""
    print(
        f"{'robot':14s} {'cycles':>7s} {'median µs':>10s} {'p99 µs':>10s} "
        f"{'max µs':>10s}   {'moved':>6s} {'median':>8s} {'p99':>8s}   "
        f"{'kept':>6s} {'median':>8s} {'p99':>8s}"
    )
    for name in names:
        robot = load_robot(name)
        run_fish_cutting(robot, SimulatedFish(seed=seed).scaled(get_cell_scale(robot)))
        run = run_fish_cutting(
            robot, SimulatedFish(seed=seed).scaled(get_cell_scale(robot))
        )
        us = run.latency_us
        med, p99 = stats(us)
        line = f"{name:14s} {len(us):7d} {med:10.1f} {p99:10.1f} {us.max():10.1f}"
        if run.redundancy_parameter is not None:
            moved = np.diff(run.redundancy) != 0.0
            for part in (us[moved], us[~moved]):
                part_med, part_p99 = stats(part)
                line += f"   {len(part):6d} {part_med:8.1f} {part_p99:8.1f}"
        print(line)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--robots",
        default="puma560-kang,iiwa14,panda",
        help="comma-separated arms for the per-robot table",
    )
    args = parser.parse_args()
    robot = load_robot("puma560-kang")
    fish, setup = SimulatedFish(seed=args.seed), FishCuttingSetup()
    loop = min(timeit.repeat("sum(range(1000))", number=2000, repeat=5)) / 2000 * 1e6
    print(f"machine: sum(range(1000)) takes {loop:.1f} µs in this Python")

    # a first run loads the compiled code (Numba cache) and warms the caches;
    # the second is timed
    run_fish_cutting(robot, SimulatedFish(seed=args.seed), setup)
    run = run_fish_cutting(robot, fish, setup)
    ours = run.latency_us
    command_us = time_cartesian_command(robot, fish, setup)
    poses, twists = wrist_commands(run, setup)
    ik_us = []
    for pose, q_prev in zip(poses, run.q[:-1], strict=True):
        start = clock()
        ik.analytic(robot, pose, q_previous=q_prev)
        ik_us.append((clock() - start) * 1e6)

    rows = [
        ("workbench: whole planning cycle", ours, None),
        ("  ik.analytic alone (8 branches, public API)", np.array(ik_us), None),
        ("  of which the Cartesian command", command_us, None),
    ]
    rtb_us = bench_rtb(poses, twists)
    if rtb_us is not None:
        rows.append(("RTB loop: ikine_a + jacob0 + DLS", rtb_us, ours))
    ruckig_us = bench_ruckig(run, setup, len(ours))
    if ruckig_us is not None:
        rows.append(("ruckig update, 6 DoF (vs our command)", ruckig_us, command_us))
    print(f"{len(ours)} planning cycles of the fish-cutting program (seed {args.seed})")
    print(f"{'':42s} {'median µs':>10s} {'p99 µs':>10s} {'peer/ours':>10s}")
    for name, us, reference in rows:
        med, p99 = stats(us)
        ratio = "" if reference is None else f"{med / stats(reference)[0]:10.1f}"
        print(f"{name:42s} {med:10.1f} {p99:10.1f} {ratio}")
    replanned = run.replanned
    print(f"{'':42s} {'count':>10s} {'median µs':>10s} {'p99 µs':>10s} {'max µs':>10s}")
    for name, us in (
        ("workbench: cycles that planned a motion", ours[replanned]),
        ("workbench: the other cycles", ours[~replanned]),
    ):
        med, p99 = stats(us)
        print(f"{name:42s} {len(us):10d} {med:10.1f} {p99:10.1f} {us.max():10.1f}")
    print("targets: workbench cycle median <= 30 µs, p99 <= 100 µs")
    print()
    print("the fish-cutting program per arm (its scaled cell, redundancy policy keep)")
    bench_robots(args.robots.split(","), args.seed)


if __name__ == "__main__":
    main()
