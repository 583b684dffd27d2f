"""``workbench plan pick-place``: Angeles' normal-spline pick-and-place trajectory."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from workbench.atomic_files import atomic_files, check_outputs
from workbench.cli._collision import (
    add_collision_arguments,
    check_pick_and_place_path,
    get_collision_keys,
    print_collision_summary,
    report_collision_error,
)
from workbench.cli._common import (
    add_json_flag,
    add_limit_arguments,
    add_robot_argument,
    bounded_float,
    bounded_int,
    finite_float,
    get_input_paths,
    load_robot_from_args,
    print_json,
    q_from_degrees,
)
from workbench.errors import InputError
from workbench.trajectory import minimum_duration, pick_and_place
from workbench.trajectory.csv_io import check_sample_count, write_trajectory_csv
from workbench.trajectory.normal_spline import DEFAULT_N_POINTS, MIN_N_POINTS

EXIT_INFEASIBLE = 3
DEFAULT_RATE_HZ = 100.0
#: Largest ``--rate`` [Hz] (duration × rate is bounded by ``MAX_SAMPLES`` too).
MAX_RATE_HZ = 100_000.0
#: Largest ``--duration`` [s] (about 11.6 days).
MAX_DURATION = 1e6
#: Largest ``--n-points`` (knots of the normal spline).
MAX_N_POINTS = 100_000


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``plan`` command and its ``pick-place`` subcommand."""
    parser = commands.add_parser(
        "plan",
        help="plan trajectories",
        description="Plan joint trajectories.",
    )
    kinds = parser.add_subparsers(dest="plan_kind", metavar="KIND", required=True)
    pick = kinds.add_parser(
        "pick-place",
        help="Angeles et al. (1988) normal-spline pick-and-place trajectory",
        description="Rest-to-rest joint trajectory from the pick to the place "
        "configuration along Angeles' normal spline; checks position, speed and "
        "acceleration limits exactly, reports the minimum duration and the "
        "clearance to the scene and between the links (proven between samples). "
        "Exit code 3 (after printing the result) when a limit is violated or two "
        "bodies touch.",
    )
    add_robot_argument(pick)
    add_limit_arguments(pick)
    pick.add_argument(
        "--pick-deg",
        nargs="+",
        type=finite_float,
        required=True,
        metavar="Q",
        help="pick configuration [deg]",
    )
    pick.add_argument(
        "--place-deg",
        nargs="+",
        type=finite_float,
        required=True,
        metavar="Q",
        help="place configuration [deg]",
    )
    pick.add_argument(
        "--duration",
        type=bounded_float(MAX_DURATION, "s"),
        required=True,
        help=f"duration T [s], > 0, at most {MAX_DURATION:g}",
    )
    pick.add_argument(
        "--rate",
        type=bounded_float(MAX_RATE_HZ, "Hz"),
        default=DEFAULT_RATE_HZ,
        metavar="HZ",
        help=f"sample rate of --csv and of the collision check [Hz] (default "
        f"{DEFAULT_RATE_HZ:g}, at most {MAX_RATE_HZ:g})",
    )
    pick.add_argument(
        "--n-points",
        type=bounded_int(MIN_N_POINTS, MAX_N_POINTS),
        default=DEFAULT_N_POINTS,
        metavar="N",
        help=f"knots of the normal spline (default {DEFAULT_N_POINTS}, as the paper; "
        f"{MIN_N_POINTS}..{MAX_N_POINTS})",
    )
    pick.add_argument(
        "--csv", type=Path, metavar="FILE", help="write t,q..,qd..,qdd.. (SI units)"
    )
    pick.add_argument(
        "--plot", type=Path, metavar="FILE.png", help="plot q, qd, qdd with limits"
    )
    add_collision_arguments(
        pick,
        "Angeles' pedestal and pick table for puma560, the pedestal for other DH "
        "models, else none (self-collision only)",
    )
    add_json_flag(pick)
    pick.set_defaults(
        run=run_pick_place,
        progress_message="plan: planning the trajectory and checking every limit…",
    )


def run_pick_place(args: argparse.Namespace) -> int:
    """Plan, check, write; returns the exit code (3 on a limit violation).

    The outputs are checked before any work and written together at the end
    (all or none, :func:`workbench.atomic_files.atomic_files`).
    """
    check_outputs([args.csv, args.plot], get_input_paths(args))
    if args.plot is not None:
        check_plot_format(args.plot)
    check_sample_count(
        int(args.duration * args.rate) + 1,
        f"--duration {args.duration:g} s at --rate {args.rate:g} Hz",
    )
    robot = load_robot_from_args(args)
    q_pick = q_from_degrees(robot, args.pick_deg)
    q_place = q_from_degrees(robot, args.place_deg)
    traj = pick_and_place(robot, q_pick, q_place, args.duration, n_points=args.n_points)
    t_min = minimum_duration(robot, q_pick, q_place, n_points=args.n_points)
    violations = traj.check_limits()
    scene, clearance = check_pick_and_place_path(robot, traj, args, args.rate)
    samples = traj.sample_uniform(args.rate) if args.csv else None
    outputs = [p for p in (args.csv, args.plot) if p is not None]
    with atomic_files(*outputs) as temps:
        staged = dict(zip(outputs, temps, strict=True))
        if samples is not None:
            write_trajectory_csv(staged[args.csv], samples)
        if args.plot:
            from workbench.plots.trajectory import plot_joint_trajectory

            plot_joint_trajectory(
                traj,
                staged[args.plot],
                title=f"{robot.name}: pick-and-place, T = {traj.duration:g} s "
                f"(minimum {t_min:.4g} s)",
            )
    speed = traj.get_extrema(1)
    acc = traj.get_extrema(2)
    result = {
        "robot": robot.name,
        "joint_names": robot.joint_names,
        "duration": traj.duration,
        "min_duration": t_min,
        "n_points": traj.spline.n_points,
        "amplitude": traj.spline.amplitude,
        "q_pick": traj.q_pick,
        "q_place": traj.q_place,
        "peak_velocity": np.maximum(np.abs(speed.minimum), np.abs(speed.maximum)),
        "peak_acceleration": np.maximum(np.abs(acc.minimum), np.abs(acc.maximum)),
        "violations": [v.as_dict() for v in violations],
        "csv": None if args.csv is None else str(args.csv),
        "samples": 0 if samples is None else int(samples.t.size),
        "plot": None if args.plot is None else str(args.plot),
        **get_collision_keys(scene, clearance),
    }
    if args.json:
        print_json(result)
    else:
        _print_human(robot, traj, result)
        print_collision_summary(clearance)
    if violations:
        more = f" (and {len(violations) - 1} more)" if len(violations) > 1 else ""
        print(f"workbench: error: {violations[0].message}{more}", file=sys.stderr)
        return EXIT_INFEASIBLE
    if report_collision_error(clearance):
        return EXIT_INFEASIBLE
    return 0


def check_plot_format(path: Path) -> None:
    """Refuse a figure file whose suffix Matplotlib cannot write.

    Raises:
        InputError: Listing the formats it can write.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    formats = FigureCanvasAgg(Figure()).get_supported_filetypes()
    if path.suffix.lstrip(".").lower() not in formats:
        raise InputError(
            f"--plot {path}: unknown figure format {path.suffix or '(none)'!r}; "
            f"use one of {', '.join('.' + f for f in sorted(formats))}"
        )


def _print_human(robot, traj, result: dict) -> None:
    print(
        f"{robot.name}: pick-and-place in T = {traj.duration:g} s "
        f"(minimum {result['min_duration']:.6g} s); normal spline N = "
        f"{traj.spline.n_points}, A = {traj.spline.amplitude:.6g}"
    )
    w = max(14, *(len(name) + 2 for name in robot.joint_names))
    print(
        f"{'joint':<{w}}{'pick':>9}{'place':>9}{'peak speed':>12}{'limit':>9}"
        f"{'peak acc':>11}{'limit':>9}"
    )
    print(
        f"{'':<{w}}{'[deg]':>9}{'[deg]':>9}{'[deg/s]':>12}{'[deg/s]':>9}"
        f"{'[deg/s²]':>11}{'[deg/s²]':>9}"
    )
    for i, name in enumerate(robot.joint_names):
        print(
            f"{name:<{w}}{np.rad2deg(traj.q_pick[i]):9.2f}"
            f"{np.rad2deg(traj.q_place[i]):9.2f}"
            f"{np.rad2deg(result['peak_velocity'][i]):12.3f}"
            f"{np.rad2deg(robot.velocity_limit[i]):9.2f}"
            f"{np.rad2deg(result['peak_acceleration'][i]):11.3f}"
            f"{np.rad2deg(robot.acceleration_limit[i]):9.2f}"
        )
    if result["violations"]:
        print(f"{len(result['violations'])} limit violation(s):")
        for v in traj.check_limits():
            print(f"  {v.message}")
    else:
        print("within every position, speed and acceleration limit")
    if result["csv"]:
        print(f"{result['samples']} samples written to {result['csv']}")
    if result["plot"]:
        print(f"plot written to {result['plot']}")
