"""``workbench plan pick-place``: Angeles' normal-spline pick-and-place trajectory.

Pick and place are joint values, or tool poses solved together by
:func:`workbench.ik.pick_place_configurations` (:mod:`workbench.cli._plan_poses`;
seven-axis arms at ``--redundancy`` or a value chosen by ``--criterion``, as
``workbench ik``). With ``--avoid``, a spline that collides is replaced by a
motion planned around the scene (:func:`workbench.motion.plan_around`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from workbench.atomic_files import atomic_files, check_outputs
from workbench.cli._collision import (
    add_collision_arguments,
    check_pick_and_place_path,
    get_collision_error,
    get_collision_keys,
    get_skip_reason,
    print_collision_summary,
    report_collision_error,
)
from workbench.cli._common import (
    EXIT_INFEASIBLE,
    add_json_flag,
    add_limit_arguments,
    add_robot_argument,
    add_search_arguments,
    bounded_float,
    bounded_int,
    finite_float,
    get_input_paths,
    load_robot_from_args,
    print_json,
)
from workbench.cli._plan_poses import get_configurations
from workbench.cli._redundancy import add_redundancy_argument
from workbench.cli.ik import CRITERIA
from workbench.errors import InputError
from workbench.trajectory import (
    describe_unknown_limits,
    get_unknown_limits,
    minimum_duration,
    pick_and_place,
)
from workbench.trajectory.csv_io import (
    check_sample_count,
    get_output_paths,
    write_trajectory_csv,
)
from workbench.trajectory.normal_spline import DEFAULT_N_POINTS, MIN_N_POINTS

if TYPE_CHECKING:
    from workbench.collision import PathClearance, Scene
    from workbench.model.robot import Robot
    from workbench.motion import PlannedAround
    from workbench.trajectory import JointTrajectory

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
        "configuration along Angeles' normal spline (each given as joint values, "
        "or as a tool pose solved in closed form on one branch; seven-axis arms "
        "at --redundancy or a value chosen by --criterion); checks position, speed and "
        "acceleration limits exactly, reports the minimum duration and the "
        "clearance to the scene and between the links (proven between samples). "
        "Exit code 3 (after printing the result) when a limit is violated or two "
        "bodies touch.",
    )
    add_robot_argument(pick)
    add_limit_arguments(pick)
    for name in ("pick", "place"):
        given = pick.add_mutually_exclusive_group(required=True)
        given.add_argument(
            f"--{name}-deg",
            nargs="+",
            type=finite_float,
            metavar="Q",
            help=f"{name} configuration [deg]",
        )
        given.add_argument(
            f"--{name}-xyz-quat-wxyz",
            nargs=7,
            type=finite_float,
            metavar="X",
            help=f"{name} pose of the tool frame, base frame: position x y z [m], "
            "then unit quaternion w x y z; pick and place solved together "
            "(workbench.ik.pick_place_configurations): on the branch serving both "
            "with the largest joint-limit margin",
        )
    add_redundancy_argument(
        pick,
        "[rad]: both poses are solved at that value (with "
        "--pick-xyz-quat-wxyz and --place-xyz-quat-wxyz)",
    )
    pick.add_argument(
        "--criterion",
        choices=CRITERIA,
        help="seven-axis arms, poses without --redundancy: how each pose's value "
        "is chosen (ik.choose_redundancy; limit_margin, the default, or "
        "manipulability), both poses on the branch that scores best",
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
    pick.add_argument(
        "--avoid",
        action="store_true",
        help="when the spline collides, plan a collision-free motion between the "
        "same pick and place around the scene instead (workbench.motion.plan_around: "
        "RRT-Connect, time-scaled within the joint limits, which need "
        "--acceleration-limit; verified on the exact meshes); --csv and --plot "
        "then hold that motion; exit 3 when none is found",
    )
    add_search_arguments(pick, scope="with --avoid: ", defaults=False)
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
    _check_avoid_options(args)
    csv_files = [] if args.csv is None else get_output_paths(args.csv)
    check_outputs([*csv_files, args.plot], get_input_paths(args))
    if args.plot is not None:
        check_plot_format(args.plot)
    check_sample_count(
        int(args.duration * args.rate) + 1,
        f"--duration {args.duration:g} s at --rate {args.rate:g} Hz",
    )
    robot = load_robot_from_args(args)
    q_pick, q_place, ik_keys = get_configurations(args, robot)
    traj = pick_and_place(robot, q_pick, q_place, args.duration, n_points=args.n_points)
    t_min = minimum_duration(robot, q_pick, q_place, n_points=args.n_points)
    violations = traj.check_limits()
    scene, clearance = check_pick_and_place_path(robot, traj, args, args.rate)
    skipped = get_skip_reason(robot, args)
    around = _plan_around(robot, scene, traj, clearance, args)
    motion = traj if around is None else around.trajectory
    samples = (
        motion.sample_uniform(args.rate) if args.csv and motion is not None else None
    )
    outputs = (
        [*csv_files, *([] if args.plot is None else [args.plot])]
        if motion is not None
        else []
    )
    with atomic_files(*outputs) as temps:
        staged = dict(zip(outputs, temps, strict=True))
        if samples is not None:
            csv_file, record = csv_files
            write_trajectory_csv(
                staged[csv_file],
                samples,
                joint_names=robot.joint_names,
                record=staged[record],
            )
        if args.plot and motion is not None:
            from workbench.plots.trajectory import plot_joint_trajectory

            plot_joint_trajectory(
                motion,
                staged[args.plot],
                title=f"{robot.name}: pick-and-place, T = {traj.duration:g} s "
                f"(minimum {t_min:.4g} s)"
                if motion is traj
                else f"{robot.name}: pick-and-place planned around the scene, "
                f"{motion.duration:.4g} s",
            )
    result = {
        "robot": robot.name,
        "joint_names": robot.joint_names,
        "duration": traj.duration,
        "min_duration": t_min,
        "unknown_limits": get_unknown_limits(robot),
        "n_points": traj.spline.n_points,
        "amplitude": traj.spline.amplitude,
        "q_pick": traj.q_pick,
        "q_place": traj.q_place,
        "peak_velocity": traj.get_extrema(1).peak,
        "peak_acceleration": traj.get_extrema(2).peak,
        "violations": [v.as_dict() for v in violations],
        "csv": None if samples is None else str(args.csv),
        "samples": 0 if samples is None else int(samples.t.size),
        "plot": None if args.plot is None or motion is None else str(args.plot),
        **ik_keys,
        **get_collision_keys(scene, clearance, skipped),
        "avoided": None
        if around is None
        else {**around.as_dict(), "seed": _seed(args), "time_limit": _limit(args)},
    }
    if args.json:
        print_json(result)
    else:
        _print_human(robot, traj, result)
        print_collision_summary(clearance, skipped)
        _print_avoided(result["avoided"])
    if violations:
        more = f" (and {len(violations) - 1} more)" if len(violations) > 1 else ""
        print(f"workbench: error: {violations[0].message}{more}", file=sys.stderr)
        return EXIT_INFEASIBLE
    if around is not None:
        if around.solved:
            return 0
        avoided = result["avoided"]
        print(
            f"workbench: error: no motion around the scene: {avoided['reason']}: "
            f"{avoided['detail']} (the spline: {get_collision_error(clearance)})",
            file=sys.stderr,
        )
        return EXIT_INFEASIBLE
    if report_collision_error(clearance):
        return EXIT_INFEASIBLE
    return 0


def _check_avoid_options(args: argparse.Namespace) -> None:
    """Refuse the options of ``--avoid`` without it, and it with ``--no-collision``.

    Raises:
        InputError: Naming the option.
    """
    if not args.avoid:
        for option, value in (("--seed", args.seed), ("--time-limit", args.time_limit)):
            if value is not None:
                raise InputError(f"{option} is an option of --avoid")
    elif args.no_collision:
        raise InputError("--avoid and --no-collision contradict each other")


def _seed(args: argparse.Namespace) -> int:
    return 0 if args.seed is None else int(args.seed)


def _limit(args: argparse.Namespace) -> float:
    return 1.0 if args.time_limit is None else float(args.time_limit)


def _plan_around(
    robot: Robot,
    scene: Scene | None,
    traj: JointTrajectory,
    clearance: PathClearance | None,
    args: argparse.Namespace,
) -> PlannedAround | None:
    """With ``--avoid`` and a spline not proven free: the plan around, else None.

    Raises:
        InputError: ``--avoid`` on a robot without collision geometry (there
            is nothing to check a motion with), or without acceleration limits.
    """
    if not args.avoid:
        return None
    if clearance is None:
        raise InputError(
            f"--avoid: {robot.name!r} has no collision geometry in its URDF, so "
            "there is nothing to plan around"
        )
    if clearance.collision_free:
        return None
    from workbench.motion import plan_around

    return plan_around(
        robot,
        scene,
        traj,
        clearance=clearance,
        rate_hz=args.rate,
        seed=_seed(args),
        time_limit=_limit(args),
        progress=args.progress.stages("plan --avoid"),
    )


def _print_avoided(avoided: dict[str, Any] | None) -> None:
    if avoided is None:
        return
    if not avoided["solved"]:
        print(f"no motion around the scene ({avoided['reason']})")
        return
    print(
        f"planned around the scene: {len(avoided['waypoints'])} waypoints, "
        f"path {avoided['path_length']:.4g} rad, duration {avoided['duration']:.4g} s, "
        f"min clearance {avoided['min_clearance'] * 1e3:.1f} mm (the spline went "
        f"{avoided['direct_penetration'] * 1e3:.1f} mm deep)"
    )


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
    note = describe_unknown_limits(robot)
    if note is not None:
        print(note)
    redundancy = result["redundancy"]
    if result["branch"] is not None:
        print(f"pick and place poses on branch {result['branch']}")
    if redundancy is not None:
        how = {
            "given": "given",
            "chosen": f"chosen: {redundancy['criterion']}",
            "configuration": "of the configurations",
        }[redundancy["source"]]
        print(
            f"{redundancy['parameter']} at pick {redundancy['pick']:.6f} rad, at "
            f"place {redundancy['place']:.6f} rad ({how})"
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
