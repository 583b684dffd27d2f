"""``workbench fk``: forward kinematics of the tool frame."""

from __future__ import annotations

import argparse

import numpy as np

from workbench.cli._common import (
    add_angle_arguments,
    add_json_flag,
    add_robot_argument,
    configuration_from_args,
    format_vector,
    load_robot_from_args,
    name_text,
    print_json,
)
from workbench.poses import angeles7_from_se3, quat_wxyz_from_rotation


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``fk`` command."""
    parser = commands.add_parser(
        "fk",
        help="forward kinematics of the tool frame",
        description="Pose of the tool frame in the base frame at one configuration.",
    )
    add_robot_argument(parser)
    parser.add_argument(
        "--frame", type=name_text, help="frame name (default: the robot's tool frame)"
    )
    add_angle_arguments(parser)
    add_json_flag(parser)
    parser.set_defaults(
        run=run, progress_message="fk: computing the forward kinematics…"
    )


def run(args: argparse.Namespace) -> int:
    """Print the pose; returns the exit code."""
    robot = load_robot_from_args(args)
    q = configuration_from_args(robot, args, args.q)
    frame = robot.tool_frame if args.frame is None else args.frame
    pose = robot.fk(q, frame)
    result = {
        "robot": robot.name,
        "frame": frame,
        "q": q,
        "joint_values": robot.joint_values_from_q(q),
        "position": pose.translation,
        "rotation": pose.rotation,
        "quat_wxyz": quat_wxyz_from_rotation(pose.rotation),
        "angeles7": angeles7_from_se3(pose),
    }
    if args.json:
        print_json(result)
        return 0
    a7 = result["angeles7"]
    print(f"robot     {robot.name}   frame {frame}")
    print(f"q [deg]   {format_vector(np.rad2deg(result['joint_values']), 4)}")
    print(f"position  {format_vector(pose.translation * 1e3, 3)}  [mm]")
    print(
        "rotation  " + "\n          ".join(format_vector(row) for row in pose.rotation)
    )
    print(f"quat_wxyz {format_vector(result['quat_wxyz'])}")
    print(f"angeles7  e·sinφ {format_vector(a7[:3])}   cosφ {a7[3]: .6f}")
    return 0
