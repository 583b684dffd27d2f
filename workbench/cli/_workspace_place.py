"""``workbench workspace place``: where to put the arm's base for a task.

Reads the task (``--targets`` pose CSV, or ``--trajectory`` joint CSV with its
robot), ranks candidate base poses with
:func:`workbench.workspace.placement.place_base` (screened against ``--map``
or a map built in memory, the best verified exactly) and prints them. Exit 3
when no placement reaches every pose; with ``--json`` the JSON is printed all
the same (``feasible`` false, ``placements`` the best candidate verified, if
any). Seven-axis arms (SRS, Franka) are verified at the K values of their
map's redundancy parameter (``--redundancy-samples`` for a map built in
memory). The ``workspace`` group
(``workbench/cli/workspace.py``) calls :func:`register`.
"""

from __future__ import annotations

import argparse
import functools
import math
import sys
import time
from pathlib import Path
from typing import Any

from workbench.cli._common import (
    EXIT_INFEASIBLE,
    add_json_flag,
    add_robot_argument,
    bounded_float,
    bounded_int,
    finite_float,
    load_robot_from_args,
    print_json,
)
from workbench.collision import read_scene
from workbench.workspace.placement import (
    DEFAULT_RESOLUTION,
    DEFAULT_YAW_STEP,
    Placement,
    PlacementInfeasibleError,
    place_base,
)
from workbench.workspace.placement_region import default_region
from workbench.workspace.redundant import MAX_REDUNDANCY_SAMPLES
from workbench.workspace.task_map import TASK_MAP_REDUNDANCY_SAMPLES
from workbench.workspace.task_poses import (
    read_task_poses,
    read_trajectory_task_poses,
)

#: Largest ``--top``.
MAX_TOP = 10_000
#: Exit code of a task no candidate reaches whole (as every command's).


def register(commands: argparse._SubParsersAction) -> None:
    """Add ``place`` to the ``workspace`` group's subcommands."""
    parser = commands.add_parser(
        "place",
        help="rank base poses of the arm so that it reaches every task pose",
        description="Rank candidate base poses (x, y on a lattice over --region "
        "at --height, yaw in steps of --yaw-step) by: every task pose reached "
        "within the joint limits (collision-free with --scene; for a "
        "--trajectory, one IK branch along the whole path, no flip), then the "
        "worst singularity margin and dexterity along the task. Candidates are "
        "screened against a workspace map (--map, else one built in memory), "
        "the best verified exactly in closed form (seven-axis arms: at the K "
        "values of the map's redundancy parameter). Exit 3 when none reaches "
        "every pose.",
    )
    add_robot_argument(parser)
    task = parser.add_mutually_exclusive_group(required=True)
    task.add_argument(
        "--targets",
        type=Path,
        metavar="FILE",
        help="task poses, CSV with header x,y,z,qx,qy,qz,qw (world frame, m, "
        "unit quaternion)",
    )
    task.add_argument(
        "--trajectory",
        type=Path,
        metavar="FILE",
        help="a joint trajectory CSV of --robot (t,q1..qn,...): the task is its "
        "tool path, world frame = the base frame it was recorded in",
    )
    parser.add_argument(
        "--map", type=Path, metavar="MAP.zarr", help="workspace map of --robot"
    )
    parser.add_argument(
        "--region",
        nargs=4,
        type=finite_float,
        metavar=("XMIN", "XMAX", "YMIN", "YMAX"),
        help="where the base may go [m], world frame (default: the task's "
        "extent widened by the arm's reach)",
    )
    parser.add_argument(
        "--height",
        type=finite_float,
        default=0.0,
        metavar="Z",
        help="base height [m] in the world frame (default: 0)",
    )
    parser.add_argument(
        "--resolution",
        type=bounded_float(10.0, "m"),
        default=DEFAULT_RESOLUTION,
        metavar="M",
        help=f"spacing of the candidate positions [m] (default: {DEFAULT_RESOLUTION})",
    )
    parser.add_argument(
        "--yaw-step",
        type=bounded_float(360.0, "degrees"),
        default=math.degrees(DEFAULT_YAW_STEP),
        metavar="DEG",
        help=f"step of the candidate yaws [deg] (default: "
        f"{math.degrees(DEFAULT_YAW_STEP):g})",
    )
    parser.add_argument(
        "--scene",
        type=Path,
        metavar="FILE",
        help="obstacles (scene JSON) in the world frame: branches must be "
        "collision-free",
    )
    parser.add_argument(
        "--redundancy-samples",
        type=bounded_int(1, MAX_REDUNDANCY_SAMPLES),
        metavar="K",
        help="seven-axis arms without --map: K values of the redundancy "
        "parameter (arm angle ψ or q7) the map built in memory and the exact "
        "check solve at (default: "
        f"{TASK_MAP_REDUNDANCY_SAMPLES}); with --map, the map's values",
    )
    parser.add_argument(
        "--top",
        type=bounded_int(1, MAX_TOP),
        default=10,
        metavar="K",
        help="placements to print (default: 10)",
    )
    add_json_flag(parser)
    parser.set_defaults(run=run_place, progress_message="workspace place: ranking…")


def run_place(args: argparse.Namespace) -> int:
    """Rank the placements and print them; returns the exit code."""
    robot = load_robot_from_args(args)
    if args.targets is not None:
        task = read_task_poses(args.targets)
    else:
        task = read_trajectory_task_poses(robot, args.trajectory)
    scene = read_scene(args.scene) if args.scene is not None else None
    region = args.region
    if region is None:  # the one place_base takes by default, for the summary
        region = default_region(robot, task, resolution=args.resolution)
    started = time.perf_counter()
    try:
        placements = place_base(
            robot,
            task,
            region=region,
            height=args.height,
            yaw_step=math.radians(args.yaw_step),
            resolution=args.resolution,
            map=args.map,
            scene=scene,
            top=args.top,
            redundancy_samples=args.redundancy_samples,
            progress=functools.partial(
                args.progress.count, unit="steps", label="workspace place"
            ),
        )
        infeasible = None
    except PlacementInfeasibleError as err:
        if not args.json:
            raise  # one line on stderr, exit 3
        infeasible = err
        placements = [] if err.best is None else [err.best]
    seconds = time.perf_counter() - started
    args.progress.finish()
    summary: dict[str, Any] = {
        "robot": robot.name,
        "poses": len(task),
        "path": task.ordered,
        "region": [float(v) for v in region],
        "height": args.height,
        "seconds": seconds,
        "feasible": infeasible is None,
        "placements": [p.as_dict() for p in placements],
    }
    if infeasible is not None:
        summary["error"] = " ".join(str(infeasible).split())
    if args.json:
        print_json(summary)
        if infeasible is not None:
            print(f"workbench: error: {summary['error']}", file=sys.stderr)
            return EXIT_INFEASIBLE
        return 0
    _print_placements(summary, placements)
    return 0


def _print_placements(summary: dict[str, Any], placements: list[Placement]) -> None:
    xmin, xmax, ymin, ymax = summary["region"]
    kind = "path samples" if summary["path"] else "poses"
    print(
        f"{summary['robot']}: {summary['poses']} task {kind}, base region "
        f"x {xmin:g}..{xmax:g} m, y {ymin:g}..{ymax:g} m at z {summary['height']:g} m "
        f"({summary['seconds']:.2f} s)"
    )
    seven_axis = any(p.redundancy is not None for p in placements)
    measure = "min √det(JJᵀ) [m³]" if seven_axis else "min |det J| [m³]"
    print(f"   x [m]    y [m]    z [m]  yaw [deg] {measure:>17}  margin  branch")
    for p in placements:
        print(
            f"{p.x:8.3f} {p.y:8.3f} {p.z:8.3f} {math.degrees(p.yaw):10.1f} "
            f"{p.min_dexterity:17.6g} {p.min_singularity_margin:7.3g}  "
            f"{p.branch or '(per pose)'}"
        )
