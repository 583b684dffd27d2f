"""``workbench fishcut``: Kang's fish-cutting program on a simulated fish, online."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from workbench.cli._collision import (
    add_collision_arguments,
    build_checker,
    get_collision_keys,
    load_scene,
    print_collision_summary,
    report_collision_error,
)
from workbench.cli._common import (
    add_json_flag,
    add_limit_arguments,
    add_robot_argument,
    load_robot_from_args,
    print_json,
)
from workbench.collision import check_path
from workbench.export.atomic_files import atomic_file, check_output
from workbench.tasks import FishCuttingSetup, SimulatedFish, run_fish_cutting
from workbench.tasks.fish_cutting import summarize_fish_cutting
from workbench.tasks.fish_program import get_cell_scale
from workbench.tasks.fish_scene import get_fish_cutting_scene
from workbench.trajectory.csv_io import write_trajectory_csv

DEFAULT_ROBOT = "puma560-kang"
_DEFAULTS = FishCuttingSetup()


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``fishcut`` command."""
    parser = commands.add_parser(
        "fishcut",
        help="Kang's fish-cutting program on a simulated fish, planned online",
        description=(
            "Run the fish-cutting program of Kang (2007, Fig. 7) on a simulated fish "
            "with the online planner, on any arm with a closed form (OPW or UR "
            "type): Kang's cell is scaled to the arm's reach (every length and the "
            "tool's speed and acceleration limits; scale 1 for the PUMA models) and "
            "the arm's shoulder is put where the PUMA's is. Cartesian command, "
            "closed-form IK with branch "
            "continuity and DLS joint rates each planning cycle, cubic Hermite "
            "interpolation at the servo rate. Touching the flesh slows the vertical "
            "cut, touching the bone stops it (or lifts the horizontal cut). The "
            "servo path is checked for collisions with the scene and between the "
            "links (exit code 3 on a contact, after writing the outputs)."
        ),
    )
    add_robot_argument(parser, default=DEFAULT_ROBOT)
    add_limit_arguments(parser, acceleration=False)
    parser.add_argument(
        "--csv", type=Path, metavar="FILE", help="write the servo-rate joint commands"
    )
    parser.add_argument(
        "--html", type=Path, metavar="FILE", help="write a 3D preview page (Meshcat)"
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="seed of the fish's flesh and bone (0)"
    )
    parser.add_argument(
        "--max-velocity",
        type=float,
        metavar="M_S",
        help=f"tool speed limit [m/s] (default {_DEFAULTS.max_velocity:g} times "
        "the cell scale)",
    )
    parser.add_argument(
        "--planning-rate",
        type=float,
        default=_DEFAULTS.planning_rate,
        metavar="HZ",
        help=f"planning cycles per second (default {_DEFAULTS.planning_rate:g})",
    )
    parser.add_argument(
        "--servo-rate",
        type=float,
        default=_DEFAULTS.servo_rate,
        metavar="HZ",
        help=f"servo samples per second, a multiple of the planning rate "
        f"(default {_DEFAULTS.servo_rate:g})",
    )
    add_collision_arguments(
        parser, "Kang's cell scaled to the arm: table, fish, pedestal of a DH model"
    )
    add_json_flag(parser)
    parser.set_defaults(
        run=run, progress_message="fishcut: running Kang's fish-cutting program online…"
    )


def run(args: argparse.Namespace) -> int:
    """Run the program; write the CSV and the page only if it completes."""
    for path in (args.csv, args.html):
        if path is not None:
            check_output(path)
    robot = load_robot_from_args(args)
    scene = load_scene(args, lambda: None)  # a --scene file is checked first
    scale = get_cell_scale(robot)  # (an arm without a closed form fails here)
    setup = FishCuttingSetup(
        planning_rate=args.planning_rate, servo_rate=args.servo_rate
    ).scaled(scale)
    if args.max_velocity is not None:
        setup = dataclasses.replace(setup, max_velocity=args.max_velocity)
    fish = SimulatedFish(args.seed).scaled(scale)
    result = run_fish_cutting(robot, fish, setup)
    if scene is None and not args.no_collision:
        scene = get_fish_cutting_scene(robot, fish, setup)
    checker = build_checker(robot, scene, explicit=args.scene is not None)
    clearance = None
    if checker is not None:  # distances at the planning cycles, bound over the servo
        stride = max(1, round(setup.servo_rate / setup.planning_rate))
        clearance = check_path(checker, result.servo.t, result.servo.q, stride=stride)
    if args.html is not None:  # viewer imported lazily (optional extra)
        from workbench.viz import write_trajectory_html

        with atomic_file(args.html) as tmp:
            write_trajectory_html(
                robot,
                result.servo,
                tmp,
                title=f"workbench fishcut: {robot.name}, fish seed {args.seed}",
                checker=checker,
            )
    if args.csv is not None:
        with atomic_file(args.csv) as tmp:
            write_trajectory_csv(tmp, result.servo)
    summary = {
        **summarize_fish_cutting(result, robot.name),
        **get_collision_keys(scene, clearance),
    }
    if args.json:
        print_json(summary)
        return 3 if report_collision_error(clearance) else 0
    print(
        f"robot {robot.name}, Kang's cell scaled by {setup.scale:g}: "
        f"{summary['cycles']} planning cycles at "
        f"{setup.planning_rate:g} Hz, {summary['duration']:.2f} s, servo "
        f"{setup.servo_rate:g} Hz"
    )
    for event in summary["events"]:
        print(f"  t = {event['t']:6.2f} s  {event['kind']:5s}  ({event['primitive']})")
    lat = summary["latency_us"]
    print(f"planning cycle  median {lat['median']:.1f} µs  p99 {lat['p99']:.1f} µs")
    print(
        f"max joint speed {summary['max_joint_speed']:.3f} rad/s, wrist flips "
        f"{summary['wrist_flips']}, wrist singularity crossings "
        f"{summary['wrist_singularity_crossings']}, DLS cycles {summary['dls_cycles']}"
    )
    for option, path in (("csv", args.csv), ("html", args.html)):
        if path is not None:
            print(f"{option} written to {path}")
    print_collision_summary(clearance)
    return 3 if report_collision_error(clearance) else 0
