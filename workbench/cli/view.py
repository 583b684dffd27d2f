"""``workbench view``: Meshcat 3D preview, as an offline HTML file or a live server."""

from __future__ import annotations

import argparse
import html
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from workbench.atomic_files import check_outputs
from workbench.cli import _redundancy
from workbench.cli._common import (
    add_robot_argument,
    bounded_int,
    configuration_from_args,
    finite_float,
    get_input_paths,
    load_robot_from_args,
    name_text,
)
from workbench.cli._redundancy import add_redundancy_argument
from workbench.errors import InfeasibleError, InputError
from workbench.model.robot import Robot
from workbench.trajectory.csv_io import (
    JointTrajectorySamples,
    TrajectoryFileError,
    read_trajectory_csv,
)
from workbench.validation import parse_int

if TYPE_CHECKING:
    from workbench.viz import Viewer


def _port(text: str) -> int:
    try:
        value = parse_int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a port number: {text!r}") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"port must be in 0..65535, got {value}")
    return value


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``view`` command."""
    parser = commands.add_parser(
        "view",
        help="Meshcat 3D preview (offline HTML file or live server)",
        description="Show the robot at one configuration or play a joint "
        "trajectory, coloured by distance to the nearest singularity, as a "
        "self-contained HTML file (works offline) or served live on 127.0.0.1.",
    )
    add_robot_argument(parser)
    unit = parser.add_mutually_exclusive_group()
    unit.add_argument("--deg", action="store_true", help="joint values in degrees")
    unit.add_argument("--rad", action="store_true", help="joint values in radians")
    parser.add_argument(
        "q",
        nargs="*",
        type=finite_float,
        metavar="Q",
        help="configuration to show (with --deg or --rad; default zeros)",
    )
    parser.add_argument(
        "--trajectory",
        type=Path,
        metavar="FILE.csv",
        help="play a trajectory CSV (t,q1..qn,qd1..qdn,qdd1..qddn, SI) as an animation",
    )
    parser.add_argument(
        "--ik-branches",
        action="store_true",
        help="also draw every closed-form IK branch of the pose FK(Q) as ghost "
        "arms (OPW and UR-type arms; seven-axis arms: the branches at one value "
        "of the redundancy parameter, --redundancy; needs Q)",
    )
    add_redundancy_argument(
        parser,
        "in the unit of Q (--deg or --rad): the value whose branches "
        "--ik-branches draws (default: the value of Q itself)",
    )
    parser.add_argument(
        "--redundancy-sweep",
        type=bounded_int(1, MAX_SWEEP),
        metavar="N",
        help="seven-axis arms: draw one branch of the pose FK(Q) at N values of "
        "the redundancy parameter spread over the intervals where it is within "
        "the joint limits, as ghosts coloured by the value, and animate the arm "
        f"through them (1..{MAX_SWEEP}; needs Q)",
    )
    parser.add_argument(
        "--branch",
        type=name_text,
        metavar="LABEL",
        help="the branch --redundancy-sweep draws (default: the branch of Q)",
    )
    parser.add_argument(
        "--scene",
        type=Path,
        metavar="FILE",
        help="draw this scene (JSON, base frame) and colour contacts red and the "
        "closest pair orange instead of the singularity colours",
    )
    parser.add_argument(
        "--no-singularity-color",
        dest="singularity_color",
        action="store_false",
        help="keep the URDF colours instead of colouring by singularity distance",
    )
    out = parser.add_mutually_exclusive_group(required=True)
    out.add_argument("--html", type=Path, metavar="FILE.html", help="write the page")
    out.add_argument(
        "--serve",
        action="store_true",
        help="serve on http://127.0.0.1:PORT/ until interrupted (Ctrl-C)",
    )
    parser.add_argument(
        "--port", type=_port, default=0, help="port for --serve (default: a free one)"
    )
    parser.set_defaults(run=run, progress_message="view: building the 3D page…")


def read_samples(path: Path, robot: Robot) -> JointTrajectorySamples:
    """Read a trajectory CSV for ``robot``; errors name the file and line.

    Raises:
        TrajectoryFileError: If the file is unreadable or malformed, or its
            joint count (line 1, the header) differs from the robot's.
    """
    samples = read_trajectory_csv(path)
    if samples.nq != robot.nq:
        raise TrajectoryFileError(
            f"{path}, line 1: the header has {samples.nq} joints, "
            f"robot {robot.name} has {robot.nq}"
        )
    return samples


#: Largest ``--redundancy-sweep`` (each value a ghost arm in the page): the
#: viewer's ``redundancy_sweep.MAX_SWEEP``, not imported (the viewer loads
#: lazily; a test checks that they agree).
MAX_SWEEP = 64


def _ik_branches(
    args: argparse.Namespace, robot: Robot, q: npt.NDArray[np.float64]
) -> tuple[list, list[str], str | None]:
    """The branches of FK(q), their labels and, on a seven-axis arm, what value."""
    from workbench.ik import analytic

    if _redundancy.get_redundant(robot) is None:
        solutions = analytic(robot, robot.fk(q))
        return [s.q for s in solutions], [s.branch for s in solutions], None
    return _redundant_branches(args, robot, q)


def _redundant_branches(
    args: argparse.Namespace, robot: Robot, q: npt.NDArray[np.float64]
) -> tuple[list, list[str], str]:
    from workbench.ik import analytic, get_solver

    solver = get_solver(robot)
    if args.redundancy is None:
        value, source = float(solver.parameter_of(q)), "the value of Q"
    else:
        value, source = _redundancy.to_radians(args.redundancy, args.deg), "given"
    target = robot.fk(q)
    try:
        solutions = analytic(robot, target, redundancy=value)
    except InfeasibleError as err:
        raise _redundancy.with_feasible(err, robot, target, bool(args.deg)) from err
    labels = [
        s.branch + ("" if s.within_limits else " (outside the joint limits)")
        for s in solutions
    ]
    shown = _redundancy.format_value(value, bool(args.deg))
    return [s.q for s in solutions], labels, f"{solver.parameter} = {shown} ({source})"


def _check_redundancy_options(args: argparse.Namespace, robot: Robot) -> None:
    """Exit 2 for the seven-axis options on another arm or without Q."""
    given = [
        option
        for option, value in (
            ("--redundancy", args.redundancy is not None),
            ("--redundancy-sweep", args.redundancy_sweep is not None),
            ("--branch", args.branch is not None),
        )
        if value
    ]
    if not given:
        return
    if _redundancy.get_redundant(robot) is None:
        raise _redundancy.refuse_redundancy(robot, given[0])
    if args.redundancy_sweep is not None and args.ik_branches:
        raise InputError("--ik-branches or --redundancy-sweep, not both")
    if args.redundancy is not None and not args.ik_branches:
        raise InputError("--redundancy sets the value --ik-branches draws: add it")
    if args.branch is not None and args.redundancy_sweep is None:
        raise InputError("--branch chooses the branch of --redundancy-sweep: add it")


def _show_sweep(
    args: argparse.Namespace, viewer: Viewer, robot: Robot, q: npt.NDArray[np.float64]
) -> None:
    from workbench.viz.redundancy_sweep import (
        compute_redundancy_sweep,
        find_branch,
        show_redundancy_sweep,
    )

    branch = find_branch(robot, q)[1] if args.branch is None else args.branch
    sweep = compute_redundancy_sweep(robot, robot.fk(q), args.redundancy_sweep, branch)
    show_redundancy_sweep(viewer, sweep, degrees=bool(args.deg))


def run(args: argparse.Namespace) -> int:
    """Write the page or serve it; returns the exit code."""
    from workbench.viz import Viewer

    unit = args.deg or args.rad
    if args.q and not unit:
        raise InputError("joint values need --deg or --rad")
    if unit and not args.q:
        raise InputError("--deg/--rad need joint values")
    if args.q and args.trajectory:
        raise InputError("give joint values or --trajectory, not both")
    for option, wanted in (
        ("--ik-branches", args.ik_branches),
        ("--redundancy-sweep", args.redundancy_sweep is not None),
    ):
        if wanted and not args.q:
            raise InputError(f"{option} needs joint values (the pose is their FK)")
    if args.html is not None:
        check_outputs([args.html], get_input_paths(args))
    robot = load_robot_from_args(args)
    _check_redundancy_options(args, robot)
    samples = read_samples(args.trajectory, robot) if args.trajectory else None
    q = configuration_from_args(robot, args, args.q) if args.q else None
    viewer = Viewer(robot, q, color_by_singularity=args.singularity_color)
    if args.scene is not None:
        from workbench.collision import CollisionChecker, read_scene

        viewer.show_collisions(CollisionChecker(robot, read_scene(args.scene)))
    viewer.show_frames()
    if samples is not None:
        viewer.play_trajectory(samples.t, samples.q)
    if args.ik_branches and q is not None:
        branches, labels, value = _ik_branches(args, robot, q)
        viewer.show_ghosts(branches, labels=labels)
        if value is not None:
            viewer.add_legend("redundancy", f"<div>{html.escape(value)}</div>")
    if args.redundancy_sweep is not None and q is not None:
        _show_sweep(args, viewer, robot, q)
    if args.html is not None:
        path = viewer.save_html(args.html)
        print(f"wrote {path}")
        return 0
    url = viewer.start_server(port=args.port)
    args.progress.finish()  # serving until Ctrl-C is not slowness
    print(f"workbench viewer at {url} (Ctrl-C to stop)", flush=True)
    try:
        viewer.serve_forever()
    except KeyboardInterrupt:
        pass
    return 0
