"""``workbench fishcut``: Kang's fish-cutting program on a simulated fish, online."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from workbench.atomic_files import atomic_files, check_outputs
from workbench.cli._collision import (
    add_collision_arguments,
    check_fish_cutting_path,
    get_collision_keys,
    get_skip_reason,
    load_scene,
    print_collision_summary,
    report_collision_error,
)
from workbench.cli._common import (
    add_json_flag,
    add_limit_arguments,
    add_robot_argument,
    bounded_float,
    bounded_int,
    get_input_paths,
    load_robot_from_args,
    print_json,
)
from workbench.cli._redundancy import refuse_redundancy
from workbench.collision import CollisionChecker
from workbench.model.robot import Robot
from workbench.planning.redundancy_policy import REDUNDANCY_POLICIES
from workbench.tasks import FishCuttingSetup, SimulatedFish, run_fish_cutting
from workbench.tasks.fish_cutting import FishCuttingResult, summarize_fish_cutting
from workbench.tasks.fish_program import get_cell_scale, is_redundant
from workbench.trajectory.csv_io import get_output_paths, write_trajectory_csv

DEFAULT_ROBOT = "puma560-kang"
_DEFAULTS = FishCuttingSetup()
#: Largest ``--planning-rate`` and ``--servo-rate`` [Hz].
MAX_RATE_HZ = 100_000.0
#: Largest ``--max-velocity`` [m/s].
MAX_TOOL_SPEED = 100.0
#: Largest ``--seed`` (NumPy seeds are >= 0).
MAX_SEED = 2**63 - 1


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``fishcut`` command."""
    parser = commands.add_parser(
        "fishcut",
        help="Kang's fish-cutting program on a simulated fish, planned online",
        description=(
            "Run the fish-cutting program of Kang (2007, Fig. 7) on a simulated fish "
            "with the online planner, on any arm with a closed form (OPW or UR "
            "type, or a seven-axis SRS or Franka arm): Kang's cell is scaled to "
            "the arm's reach (every length and the tool's speed and acceleration "
            "limits; scale 1 for the PUMA models) and the arm's shoulder is put "
            "where the PUMA's is. Cartesian command, closed-form IK with branch "
            "continuity (seven-axis arms: its redundancy parameter moved by "
            "--redundancy-policy) and DLS joint rates each planning cycle, cubic "
            "Hermite "
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
        "--seed",
        type=bounded_int(0, MAX_SEED),
        default=0,
        help="seed of the fish's flesh and bone, >= 0 (default 0)",
    )
    parser.add_argument(
        "--max-velocity",
        type=bounded_float(MAX_TOOL_SPEED, "m/s"),
        metavar="M_S",
        help=f"tool speed limit [m/s] (default {_DEFAULTS.max_velocity:g} times "
        f"the cell scale; at most {MAX_TOOL_SPEED:g})",
    )
    parser.add_argument(
        "--planning-rate",
        type=bounded_float(MAX_RATE_HZ, "Hz"),
        default=_DEFAULTS.planning_rate,
        metavar="HZ",
        help=f"planning cycles per second (default {_DEFAULTS.planning_rate:g}, "
        f"at most {MAX_RATE_HZ:g})",
    )
    parser.add_argument(
        "--servo-rate",
        type=bounded_float(MAX_RATE_HZ, "Hz"),
        default=_DEFAULTS.servo_rate,
        metavar="HZ",
        help=f"servo samples per second, a multiple of the planning rate "
        f"(default {_DEFAULTS.servo_rate:g}, at most {MAX_RATE_HZ:g})",
    )
    parser.add_argument(
        "--redundancy-policy",
        choices=REDUNDANCY_POLICIES,
        metavar="POLICY",
        help="seven-axis arms: how the planner moves the redundancy parameter (the "
        "arm angle ψ of an SRS arm, q7 of a Franka arm): keep (the default: "
        "constant unless a joint nears a limit), limit_margin or manipulability",
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
    csv_files = [] if args.csv is None else get_output_paths(args.csv)
    check_outputs([*csv_files, args.html], get_input_paths(args))
    robot = load_robot_from_args(args)
    given = load_scene(args, lambda: None)  # a --scene file is checked first
    result = _run_fish_cutting(robot, args)
    scene, checker, clearance = check_fish_cutting_path(robot, result, given, args)
    skipped = get_skip_reason(robot, args)
    _write_outputs(args, robot, result, checker)
    summary = {
        **summarize_fish_cutting(result, robot.name),
        **get_collision_keys(scene, clearance, skipped),
    }
    if args.json:
        print_json(summary)
        return 3 if report_collision_error(clearance) else 0
    setup = result.setup
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
    trace = summary["redundancy"]
    if trace is not None:
        print(
            f"redundancy {trace['parameter']} ({trace['policy']}): "
            f"{trace['start']:.4f} -> {trace['end']:.4f} rad, range "
            f"[{trace['min']:.4f}, {trace['max']:.4f}], travel {trace['travel']:.4f} "
            f"rad, max rate {trace['max_rate']:.3f} rad/s, moved in "
            f"{trace['moving_cycles']} cycles; min limit margin "
            f"{trace['min_limit_margin']:.4f} rad; branch flips "
            f"{summary['branch_flips']}"
        )
    for option, path in (("csv", args.csv), ("html", args.html)):
        if path is not None:
            print(f"{option} written to {path}")
    print_collision_summary(clearance, skipped)
    return 3 if report_collision_error(clearance) else 0


def _run_fish_cutting(robot: Robot, args: argparse.Namespace) -> FishCuttingResult:
    """Kang's program on ``robot`` with the options of ``args`` (rates, seed, speed).

    Raises:
        InfeasibleError: If the run does not finish or leaves a limit.
    """
    scale = get_cell_scale(robot)  # (an arm without a closed form fails here)
    if args.redundancy_policy is not None and not is_redundant(robot):
        raise refuse_redundancy(robot, "--redundancy-policy")
    setup = FishCuttingSetup(
        planning_rate=args.planning_rate, servo_rate=args.servo_rate
    ).scaled(scale)
    if args.max_velocity is not None:
        setup = dataclasses.replace(setup, max_velocity=args.max_velocity)
    fish = SimulatedFish(args.seed).scaled(scale)
    return run_fish_cutting(robot, fish, setup, redundancy=args.redundancy_policy)


def _write_outputs(
    args: argparse.Namespace,
    robot: Robot,
    result: FishCuttingResult,
    checker: CollisionChecker | None,
) -> None:
    """``--html`` and ``--csv``, together (all or none)."""
    csv_files = [] if args.csv is None else get_output_paths(args.csv)
    outputs = [*([] if args.html is None else [args.html]), *csv_files]
    with atomic_files(*outputs) as temps:
        staged = dict(zip(outputs, temps, strict=True))
        if args.html is not None:  # viewer imported lazily (optional extra)
            from workbench.viz import write_trajectory_html

            write_trajectory_html(
                robot,
                result.servo,
                staged[args.html],
                title=f"workbench fishcut: {robot.name}, fish seed {args.seed}",
                checker=checker,
            )
        if args.csv is not None:
            csv_file, record = csv_files
            write_trajectory_csv(
                staged[csv_file],
                result.servo,
                joint_names=robot.joint_names,
                record=staged[record],
            )
