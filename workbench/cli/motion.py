"""``workbench motion plan``: a collision-free, time-scaled motion in a scene.

(``workbench motion bench``, a MotionBenchMaker set planned, is in
:mod:`workbench.cli._motion_bench`.)

Runs :func:`workbench.motion.plan` (RRT-Connect on the robot's spheres,
shortcuts, time scaling, the exact-mesh check) from a MoveIt motion request
or from start and goal given as joint angles or a tool pose, and writes the
trajectory as the project's CSV and as a page that plays it in its scene.
Exit 3, with the reason, when no motion is found.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from workbench.atomic_files import atomic_files, check_outputs
from workbench.cli._common import (
    EXIT_INFEASIBLE,
    add_json_flag,
    add_limit_arguments,
    add_robot_argument,
    add_search_arguments,
    bounded_float,
    finite_float,
    get_input_paths,
    load_robot_from_args,
    print_json,
    q_from_degrees,
)
from workbench.cli._motion_bench import register as register_bench
from workbench.cli._plan_poses import parse_pose_option
from workbench.errors import InputError
from workbench.model.robot import Robot

#: Sample rate [Hz] of ``--csv``.
DEFAULT_RATE = 100.0


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``motion`` command group, ``motion plan`` and ``motion bench``."""
    parser = commands.add_parser(
        "motion",
        help="collision-free motions around the obstacles of a scene",
        description="Plan collision-free motions: RRT-Connect on spheres that "
        "cover the robot's collision meshes, shortened, time-scaled to the joint "
        "limits (C², at rest at every waypoint) and checked on the exact meshes.",
    )
    subcommands = parser.add_subparsers(
        dest="motion", metavar="SUBCOMMAND", required=True
    )
    plan = subcommands.add_parser(
        "plan",
        help="plan a collision-free motion from a start to a goal",
        description="Find a collision-free motion from the start to the goal in "
        "the scene and time-scale it within the joint limits. Start and goal come "
        "from a MoveIt MotionPlanRequest (--request) or are given as joint angles "
        "or tool poses; a pose goal becomes every closed-form branch within the "
        "limits. Exit 3 when no motion is found (the reason says whether the start "
        "or goal is in collision, the goal is unreachable or the time ran out).",
    )
    add_robot_argument(plan)
    add_limit_arguments(plan)
    plan.add_argument(
        "--scene",
        type=Path,
        metavar="FILE",
        help="obstacles: a scene JSON or a MoveIt planning scene (.yaml)",
    )
    plan.add_argument(
        "--request",
        type=Path,
        metavar="FILE",
        help="a MoveIt MotionPlanRequest (.yaml): start state and joint goal",
    )
    start = plan.add_mutually_exclusive_group()
    start.add_argument(
        "--start-deg",
        nargs="+",
        type=finite_float,
        metavar="Q",
        help="start joint angles [deg]",
    )
    start.add_argument(
        "--start-pose",
        nargs=7,
        type=finite_float,
        metavar=("X", "Y", "Z", "QW", "QX", "QY", "QZ"),
        help="start tool pose [m] (base frame): the first collision-free branch",
    )
    goal = plan.add_mutually_exclusive_group()
    goal.add_argument(
        "--goal-deg",
        nargs="+",
        type=finite_float,
        metavar="Q",
        help="goal joint angles [deg]",
    )
    goal.add_argument(
        "--goal-pose",
        nargs=7,
        type=finite_float,
        metavar=("X", "Y", "Z", "QW", "QX", "QY", "QZ"),
        help="goal tool pose [m] (base frame): any closed-form branch within "
        "the limits",
    )
    add_search_arguments(plan, planner=True)
    plan.add_argument(
        "--csv",
        type=Path,
        metavar="FILE",
        help="write the trajectory: t,q..,qd..,qdd.. (SI units)",
    )
    plan.add_argument(
        "--rate",
        type=bounded_float(1e6, "Hz"),
        default=DEFAULT_RATE,
        metavar="HZ",
        help=f"sample rate of --csv [Hz] (default: {DEFAULT_RATE:g})",
    )
    plan.add_argument(
        "--html",
        type=Path,
        metavar="FILE",
        help="write a page that plays the motion in its scene",
    )
    add_json_flag(plan)
    plan.set_defaults(run=run_plan, progress_message="motion plan: planning…")
    register_bench(subcommands)


def run_plan(args: argparse.Namespace) -> int:
    """Plan, write the outputs together, print; exit 3 when no motion is found."""
    from workbench.collision import read_scene
    from workbench.motion import plan, read_request
    from workbench.trajectory.csv_io import get_output_paths, write_trajectory_csv

    csv_files = [] if args.csv is None else get_output_paths(args.csv)
    outputs = [*csv_files, *([] if args.html is None else [args.html])]
    check_outputs(outputs, get_input_paths(args, args.request))
    robot = load_robot_from_args(args)
    scene = read_scene(args.scene) if args.scene is not None else None
    start, goal = _start_and_goal(args, robot, scene, read_request)
    if start is None:
        raise InputError("give the start: --request, --start-deg or --start-pose")
    if goal is None:
        raise InputError("give the goal: --request, --goal-deg or --goal-pose")
    result = plan(
        robot,
        scene,
        start,
        goal,
        seed=args.seed,
        time_limit=args.time_limit,
        planner=args.planner,
        progress=args.progress.stages("motion plan"),
    )
    samples = (
        result.trajectory.sample_uniform(args.rate)
        if result.trajectory is not None and outputs
        else None
    )
    if samples is not None:
        with atomic_files(*outputs) as temps:
            staged = dict(zip(outputs, temps, strict=True))
            if args.csv is not None:
                csv_file, record = csv_files
                write_trajectory_csv(
                    staged[csv_file],
                    samples,
                    joint_names=robot.joint_names,
                    record=staged[record],
                )
            if args.html is not None:
                _write_page(robot, scene, result, samples, staged[args.html])
    keys = _result_keys(robot, result, args, samples is not None)
    if args.json:
        print_json(keys)
    else:
        _print_human(keys)
    if not result.solved:
        print(
            f"workbench: error: no motion: {result.reason}: {result.detail}",
            file=sys.stderr,
        )
        return EXIT_INFEASIBLE
    return 0


def _start_and_goal(
    args: argparse.Namespace, robot: Robot, scene: Any, read_request: Any
) -> tuple[np.ndarray | None, np.ndarray | pin.SE3 | None]:
    start: np.ndarray | None = None
    goal: np.ndarray | pin.SE3 | None = None
    if args.request is not None:
        start, goal = read_request(args.request, robot)
    if args.start_deg is not None:
        start = _joint_angles(robot, args.start_deg, "--start-deg")
    elif args.start_pose is not None:
        start = _start_from_pose(
            robot, args, scene, parse_pose_option(args.start_pose, "--start-pose")
        )
    if args.goal_deg is not None:
        goal = _joint_angles(robot, args.goal_deg, "--goal-deg")
    elif args.goal_pose is not None:
        goal = parse_pose_option(args.goal_pose, "--goal-pose")
    return start, goal


def _joint_angles(robot: Robot, values: list[float], option: str) -> np.ndarray:
    if len(values) != robot.n_joints:
        raise InputError(
            f"{option} takes {robot.n_joints} values "
            f"({', '.join(robot.joint_names)}), got {len(values)}"
        )
    return q_from_degrees(robot, values)


def _start_from_pose(
    robot: Robot, args: argparse.Namespace, scene: Any, pose: pin.SE3
) -> np.ndarray:
    from workbench.collision import CollisionChecker
    from workbench.errors import UnreachableError
    from workbench.motion import goal_configurations

    try:
        candidates = goal_configurations(robot, pose, seed=args.seed)
    except UnreachableError as err:
        raise InputError(f"--start-pose is out of reach: {err}") from None
    checker = CollisionChecker(robot, scene)
    for q in candidates:
        if checker.compute_least_distance(q)[1] > 0.0:
            return np.array(q)
    return np.array(candidates[0])  # in collision: plan() says so


def _write_page(
    robot: Robot, scene: Any, result: Any, samples: Any, path: Path
) -> None:
    from workbench.viz import write_motion_html

    write_motion_html(robot, scene, samples, path, waypoints=result.waypoints)


def _result_keys(
    robot: Robot, result: Any, args: argparse.Namespace, written: bool
) -> dict[str, Any]:
    trajectory = result.trajectory
    return {
        "robot": robot.name,
        "joint_names": robot.joint_names,
        "solved": result.solved,
        "reason": result.reason,
        "detail": result.detail,
        "waypoints": result.waypoints,
        "goal": result.goal,
        "path_length": result.path_length if result.solved else None,
        "duration": None if trajectory is None else trajectory.duration,
        "setup_time": result.setup_time,
        "planning_time": result.planning_time,
        "smoothing_time": result.smoothing_time,
        "verification_time": result.verification_time,
        "min_clearance": None
        if math.isnan(result.min_clearance)
        else result.min_clearance,
        "iterations": result.iterations,
        "allowances": [list(entry) for entry in result.allowances],
        "seed": args.seed,
        "planner": args.planner,
        "csv": str(args.csv) if written and args.csv is not None else None,
        "html": str(args.html) if written and args.html is not None else None,
    }


def _print_human(keys: dict[str, Any]) -> None:
    if not keys["solved"]:
        print(
            f"{keys['robot']}: no motion ({keys['reason']}) after "
            f"{keys['iterations']} iterations"
        )
        return
    print(
        f"{keys['robot']}: {len(keys['waypoints'])} waypoints, "
        f"path {keys['path_length']:.4g} rad, duration {keys['duration']:.4g} s, "
        f"min clearance {keys['min_clearance'] * 1e3:.1f} mm"
    )
    ms = {key: keys[key] * 1e3 for key in keys if key.endswith("_time")}
    print(
        f"planning {ms['planning_time']:.1f} ms (setup {ms['setup_time']:.1f} ms), "
        f"time scaling {ms['smoothing_time']:.2f} ms, "
        f"exact check {ms['verification_time']:.0f} ms, "
        f"{keys['iterations']} iterations"
    )
    for key in ("csv", "html"):
        if keys[key]:
            print(f"wrote {keys[key]}")
