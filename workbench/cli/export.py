"""``workbench export``: a joint trajectory to a ROS 2 bag, URScript or a CSV."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from workbench.atomic_files import check_output
from workbench.cli._collision import (
    add_collision_arguments,
    check_fish_cutting_path,
    check_pick_and_place_path,
    get_collision_error,
    load_scene,
)
from workbench.cli._common import (
    add_json_flag,
    add_limit_arguments,
    add_robot_argument,
    bounded_float,
    get_input_paths,
    load_robot_from_args,
    name_text,
    print_json,
)
from workbench.collision import PathClearance
from workbench.errors import InfeasibleError, InputError
from workbench.export import write_ros2_bag, write_urscript
from workbench.export.ros2_bag import DEFAULT_TOPIC
from workbench.export.urscript import (
    DEFAULT_SERVO_RATE,
    MAX_SERVO_RATE,
    check_ur_joints,
)
from workbench.model.robot import Robot
from workbench.trajectory.csv_io import (
    JointTrajectorySamples,
    get_output_paths,
    read_trajectory_csv,
    write_trajectory_csv,
)

FORMATS = ("ros2-bag", "urscript", "csv")
PICK_PLACE_RATE_HZ = 100.0


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``export`` command."""
    parser = commands.add_parser(
        "export",
        help="export a joint trajectory (ROS 2 bag, URScript, CSV)",
        description=(
            "Export a joint trajectory: a ROS 2 bag (MCAP) with one "
            "trajectory_msgs/msg/JointTrajectory message, a URScript program "
            "(servoj at the servo rate; UR arms only) or the trajectory CSV of "
            "plan and fishcut (t,q1..qn,qd1..qdn,qdd1..qddn in SI units, with its "
            "record FILE.csv.json naming the joints). Nothing is written unless "
            "the export succeeds."
        ),
    )
    parser.add_argument("--format", required=True, choices=FORMATS)
    parser.add_argument(
        "--out", type=Path, required=True, help="output file (a new folder for a bag)"
    )
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument(
        "--trajectory",
        type=Path,
        metavar="FILE",
        help="trajectory CSV (t,q..,qd..,qdd..)",
    )
    source.add_argument(
        "--pick-place",
        action="store_true",
        help="Angeles' Table III pick-and-place (T = 10 s, 100 Hz)",
    )
    source.add_argument(
        "--fishcut", action="store_true", help="Kang's fish-cutting run (servo rate)"
    )
    add_robot_argument(
        parser,
        help_text="robot name or URDF (default: puma560, puma560-kang for --fishcut)",
    )
    add_limit_arguments(parser, acceleration=False)
    parser.add_argument(
        "--servo-rate",
        type=bounded_float(MAX_SERVO_RATE, "Hz"),
        default=DEFAULT_SERVO_RATE,
        metavar="HZ",
        help=f"URScript servoj rate (default {DEFAULT_SERVO_RATE:g}; CB3: 125; at "
        f"most {MAX_SERVO_RATE:g})",
    )
    add_collision_arguments(
        parser,
        "for --pick-place Angeles' cell (as plan), for --fishcut Kang's cell "
        "(as fishcut); a contact exits 3 and writes nothing",
    )
    parser.add_argument(
        "--topic", type=name_text, default=DEFAULT_TOPIC, help="bag topic"
    )
    parser.add_argument(
        "--frame-id", type=name_text, default="base", help="bag header.frame_id"
    )
    add_json_flag(parser)
    parser.set_defaults(
        run=run, progress_message="export: planning and writing the trajectory…"
    )


def _samples(args: argparse.Namespace, robot: Robot) -> JointTrajectorySamples:
    """The trajectory to export, checked as ``plan`` and ``fishcut`` check theirs.

    Raises:
        InfeasibleError: If the pick-and-place leaves a limit, or the planned
            trajectory touches the scene or itself (unless ``--no-collision``).
    """
    if args.trajectory is not None:
        return read_trajectory_csv(args.trajectory, robot.nq)
    if args.pick_place:
        from workbench.paper_data import (
            ANGELES_DURATION,
            ANGELES_PICK_Q_DEG,
            ANGELES_PLACE_Q_DEG,
        )
        from workbench.trajectory import pick_and_place

        traj = pick_and_place(
            robot,
            np.deg2rad(ANGELES_PICK_Q_DEG),
            np.deg2rad(ANGELES_PLACE_Q_DEG),
            ANGELES_DURATION,
        )
        violations = traj.check_limits()
        if violations:
            raise InfeasibleError(violations[0].message)
        _refuse_contact(
            check_pick_and_place_path(robot, traj, args, PICK_PLACE_RATE_HZ)[1]
        )
        return traj.sample_uniform(PICK_PLACE_RATE_HZ)
    from workbench.tasks import run_fish_cutting

    given = load_scene(args, lambda: None)
    result = run_fish_cutting(robot)
    _refuse_contact(check_fish_cutting_path(robot, result, given, args)[2])
    return result.servo


def _refuse_contact(clearance: PathClearance | None) -> None:
    message = get_collision_error(clearance)
    if message is not None:
        raise InfeasibleError(f"{message}; nothing written (see --no-collision)")


def run(args: argparse.Namespace) -> int:
    """Export; returns the exit code."""
    inputs = get_input_paths(args)
    check_output(args.out, folder=args.format == "ros2-bag", inputs=inputs)
    if args.format == "csv":
        check_output(get_output_paths(args.out)[1], inputs=inputs)
    if args.velocity_limit is not None and not args.fishcut:
        raise InputError("--velocity-limit applies to --fishcut (its planner) only")
    if args.trajectory is not None and (args.scene or args.no_collision):
        raise InputError(
            "--scene and --no-collision apply to --pick-place and --fishcut only"
        )
    if args.no_collision and args.scene is not None:
        raise InputError("--scene and --no-collision contradict each other")
    name = args.robot or ("puma560-kang" if args.fishcut else "puma560")
    robot = load_robot_from_args(args, name)
    names = robot.joint_names
    if args.format == "urscript":  # refuse before any work
        check_ur_joints(names, robot.name)
    samples = _samples(args, robot)
    if args.format == "ros2-bag":
        write_ros2_bag(
            args.out, samples, names, topic=args.topic, frame_id=args.frame_id
        )
    elif args.format == "urscript":
        write_urscript(
            args.out, samples, names, servo_rate=args.servo_rate, robot_name=robot.name
        )
    else:
        write_trajectory_csv(args.out, samples, joint_names=names)
    result = {
        "format": args.format,
        "out": str(args.out),
        "robot": robot.name,
        "joint_names": names,
        "samples": int(samples.t.size),
        "duration": float(samples.t[-1] - samples.t[0]),
    }
    if args.json:
        print_json(result)
    else:
        print(
            f"{args.format}: {result['samples']} samples of {robot.name} "
            f"({result['duration']:.6g} s) written to {args.out}"
        )
    return 0
