"""``workbench ik``: inverse kinematics, closed form for OPW and UR-type arms.

The target is parsed by :func:`workbench.poses.parse_target`, the
configuration chosen by :func:`workbench.ik.select` (the same answer as the
same call in Python). Seven-axis arms of the SRS and Franka families are
solved in closed form at one value of their redundancy parameter
(:mod:`workbench.cli._ik_redundant`). Any other robot falls back to
numerical IK (one solution, branch "numeric"), and the output says so:
``solver`` is ``"closed-form"`` or ``"numeric"``.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

import numpy as np
import pinocchio as pin

from workbench import ik
from workbench.cli import _redundancy
from workbench.cli._common import (
    add_json_flag,
    add_robot_argument,
    finite_float,
    load_robot_from_args,
    print_json,
)
from workbench.cli._ik_output import (
    deviation_head,
    print_deviation,
    print_infeasible,
    print_rows,
    residual,
)
from workbench.cli._redundancy import add_redundancy_argument
from workbench.errors import (
    InfeasibleError,
    InputError,
    UnreachableError,
    UnsupportedRobotError,
)
from workbench.model.robot import Robot
from workbench.poses import ANGELES7_PRINTED_TOL, TARGET_FORMS, parse_target

_MM = 1e-3  # [m] per mm (--mm)
#: ``--criterion`` choices (``ik.choose_redundancy`` criteria needing no q_previous).
CRITERIA = ("limit_margin", "manipulability")
#: What a partial target asks (``--position-only``, ``--free-axis``), for the output.
PART_NOTES = {
    "position": "position only",
    "free-x": "position and tool x axis",
    "free-y": "position and tool y axis",
    "free-z": "position and tool z axis",
}
#: The flags printed after a six-axis branch: (JSON key, text).
SIX_AXIS_FLAGS = (
    ("wrist_singular", "wrist singular"),
    ("shoulder_singular", "shoulder singular"),
)


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``ik`` command."""
    parser = commands.add_parser(
        "ik",
        help="inverse kinematics (closed form for OPW and UR-type arms, else "
        "numerical)",
        description="Joint values that put the tool frame at a pose. Prints the "
        "configuration workbench.ik.select chooses (the branch within the joint "
        "limits of the largest limit margin; seven-axis arms: the value of the "
        "redundancy parameter and the branch of the largest limit margin, or the "
        "value given by --redundancy, or chosen by --criterion), or with --all "
        "every closed-form branch (seven-axis arms: at that value). Arms of the OPW "
        "(PUMA, KUKA, ABB, ...) and UR families are recognised from their joint "
        "axes, and so are the seven-axis SRS (KUKA iiwa) and Franka (Panda) "
        "families; any other robot gets one numerical solution (solver 'numeric', "
        "branch 'numeric'). residual = max(position "
        "error [m], rotation error [rad]) of FK(q) against the target.",
    )
    add_robot_argument(parser)
    parser.add_argument(
        "--tool-frame",
        help="tool frame whose pose is the target (default: the robot's)",
    )
    pose = parser.add_mutually_exclusive_group(required=True)
    pose.add_argument(
        "--angeles7",
        nargs=7,
        type=finite_float,
        metavar="X",
        help="e_x sinφ, e_y sinφ, e_z sinφ, cosφ, p_x, p_y, p_z (Angeles et al.; "
        f"numbers printed to 2 decimals are accepted, norm² within "
        f"{ANGELES7_PRINTED_TOL:g} of 1)",
    )
    pose.add_argument(
        "--matrix",
        nargs=16,
        type=finite_float,
        metavar="M",
        help="homogeneous 4x4 matrix, row by row (rotation orthonormal to 1e-6)",
    )
    pose.add_argument(
        "--xyz-quat-wxyz",
        nargs=7,
        type=finite_float,
        metavar="X",
        help="position x y z, then unit quaternion w x y z (scalar first)",
    )
    parser.add_argument("--mm", action="store_true", help="positions are in mm")
    part = parser.add_mutually_exclusive_group()
    part.add_argument(
        "--position-only",
        action="store_true",
        help="reach the target's position in any orientation (numerical IK; e.g. "
        "an arm of fewer than six axes)",
    )
    part.add_argument(
        "--free-axis",
        choices=("x", "y", "z"),
        help="reach the target's position and the direction of this tool axis, "
        "any rotation about it (numerical IK; e.g. a drill or a nozzle)",
    )
    parser.add_argument(
        "--all",
        action="store_true",
        help="print every closed-form branch (seven-axis arms: at the given or "
        "chosen value; also when none is within the limits, exit 0)",
    )
    parser.add_argument(
        "--all-turns",
        action="store_true",
        help="with --all: every representative within the limits of a joint whose "
        "range exceeds a full turn (q ± 2πk, each labelled with its turns)",
    )
    add_redundancy_argument(
        parser,
        "[rad, or degrees with --deg]; the branch of largest limit margin at that "
        "value is printed, with --all every branch (default: the value and "
        "branch of largest joint-limit margin, or --criterion)",
    )
    parser.add_argument(
        "--deg",
        action="store_true",
        help="--redundancy, and the values and intervals printed, in degrees",
    )
    parser.add_argument(
        "--criterion",
        choices=CRITERIA,
        help="seven-axis arms without --redundancy: how the value is chosen "
        "(limit_margin: largest distance of a joint to its limits, the default; "
        "manipulability: largest √det(J Jᵀ))",
    )
    parser.add_argument(
        "--feasible",
        action="store_true",
        help="seven-axis arms: also print the intervals of the redundancy "
        "parameter where a branch reaches the pose within the joint limits "
        "(per branch in --json)",
    )
    add_json_flag(parser)
    parser.set_defaults(run=run, progress_message="ik: solving the inverse kinematics…")


def target_from_args(args: argparse.Namespace) -> pin.SE3:
    """The target pose of the command line, positions in metres.

    Raises:
        InputError: If the numbers do not make a rigid pose.
    """
    for form in TARGET_FORMS:
        values = getattr(args, form)
        if values is not None:
            return parse_target(values, form, scale=_MM if args.mm else 1.0)
    raise InputError("no target pose given")  # argparse requires one


def _row(robot: Robot, choice: ik.IKChoice, target: pin.SE3) -> dict[str, object]:
    """The JSON row of the numerical solution."""
    values = robot.joint_values_from_q(choice.q)
    return {
        "branch": choice.branch,
        "q": choice.q,
        "joint_values": values,
        "q_deg": np.rad2deg(values),
        "within_limits": choice.within_limits,
        "wrist_singular": False,
        "shoulder_singular": False,
        "residual": residual(robot, choice.q, target),
    }


def run(args: argparse.Namespace) -> int:
    """Print the solution(s); returns the exit code.

    One pose of a six-axis arm: the kernels run interpreted
    (``_compiled.interpreted``), which takes milliseconds where compiling them
    on a first run takes seconds. A seven-axis arm's kernels run compiled: the
    choice of the value and the feasible intervals call them hundreds of
    times (0.3 s compiled, cache warm; 3 s interpreted).
    """
    from workbench._compiled import interpreted  # (the kernels: imported to run)

    if args.all_turns and not args.all:
        raise InputError("--all-turns lists the turns of every branch: give --all too")
    robot = load_robot_from_args(args, tool_frame=args.tool_frame)
    target = target_from_args(args)
    if args.position_only or args.free_axis:
        return _solve_part_and_print(args, robot, target)
    redundant = _redundancy.get_redundant(robot)
    if redundant is not None:
        from workbench.cli._ik_redundant import solve_and_print_redundant

        return solve_and_print_redundant(args, robot, target, redundant)
    with interpreted():
        return _solve_and_print(args, robot, target)


def _solve_part_and_print(
    args: argparse.Namespace, robot: Robot, target: pin.SE3
) -> int:
    """``--position-only`` / ``--free-axis``: numerical IK of part of the pose."""
    part = "position" if args.position_only else f"free-{args.free_axis}"
    for option in ("redundancy", "criterion", "all", "all_turns", "feasible"):
        if getattr(args, option) not in (None, False):
            raise InputError(
                f"--{option.replace('_', '-')} does not apply to a target of part "
                "of a pose (--position-only, --free-axis): it is solved numerically"
            )
    head = {
        "robot": robot.name,
        "frame": robot.tool_frame,
        "solver": "numeric",
        "solver_note": f"target: {PART_NOTES[part]}",
        "target": part,
    }
    try:
        choice = ik.select(robot, target, part=part)
    except InfeasibleError as err:
        if not args.json:
            raise
        return print_infeasible(head, err)
    row = {
        **_row(robot, choice, target),
        "residual": part_residual(robot, choice.q, target, part),
    }
    if args.json:
        print_json({**head, "solutions": [row], "feasible": True})
        return 0
    print(f"robot {robot.name}   frame {robot.tool_frame}   solver numeric   "
          f"target {PART_NOTES[part]}")  # fmt: skip
    print_rows([row], SIX_AXIS_FLAGS)
    return 0


def part_residual(robot: Robot, q: np.ndarray, target: pin.SE3, part: str) -> float:
    """The residual of what a partial target asks (``part``: a ``PART_NOTES`` key).

    The position error [m]; with ``free-x/y/z`` the larger of it and the angle
    [rad] between that tool axis and the target's.
    """
    pose = robot.fk(q)
    position = float(np.linalg.norm(pose.translation - target.translation))
    if part == "position":
        return position
    axis = "xyz".index(part[-1])
    cos = float(np.clip(pose.rotation[:, axis] @ target.rotation[:, axis], -1.0, 1.0))
    return max(position, float(np.arccos(cos)))


def _solve_and_print(args: argparse.Namespace, robot: Robot, target: pin.SE3) -> int:
    for option in ("redundancy", "criterion"):
        if getattr(args, option) is not None:
            raise _redundancy.refuse_redundancy(robot, f"--{option}")
    for option in ("deg", "feasible"):
        if getattr(args, option):
            raise _redundancy.refuse_redundancy(robot, f"--{option}")
    deviation: dict[str, Any] = {}
    try:
        closed_form = ik.get_solver(robot)
    except UnsupportedRobotError as err:
        solver, reason = "numeric", str(err)
        if args.all and not args.json:
            print(f"no closed form: {reason}", file=sys.stderr)
    else:
        solver = "closed-form"
        reason = f"{closed_form.family.name.upper()} family"
        deviation = deviation_head(closed_form)
    head = {
        "robot": robot.name,
        "frame": robot.tool_frame,
        "solver": solver,
        "solver_note": reason,
        **deviation,
    }
    try:
        rows = _solve(args, robot, target, solver)
    except InfeasibleError as err:
        if not args.json:
            raise
        return print_infeasible(head, err)
    if args.json:
        print_json({**head, "solutions": rows, "feasible": True})
        return 0
    print(f"robot {robot.name}   frame {robot.tool_frame}   solver {solver}")
    print_deviation(head)
    print_rows(rows, SIX_AXIS_FLAGS)
    return 0


def _solve(
    args: argparse.Namespace, robot: Robot, target: pin.SE3, solver: str
) -> list[dict[str, Any]]:
    """The rows to print: :func:`workbench.ik.select`'s, or every branch (``--all``).

    Raises:
        InfeasibleError: If the pose is out of reach, or no branch is within
            the joint limits.
    """
    if solver == "numeric":
        return [_row(robot, ik.select(robot, target), target)]
    if args.all:
        turns = "all" if args.all_turns else "one"
        solutions: list[Any] = list(ik.analytic(robot, target, representatives=turns))
    else:
        try:
            solutions = [ik.select(robot, target).solution]
        except UnreachableError:
            raise
        except InfeasibleError as err:  # reached outside the limits
            raise InfeasibleError(f"{err} (--all prints them)") from err
    return [
        {
            "branch": s.branch,
            "q": s.q,
            "joint_values": s.q,  # the closed-form arms' joints are all revolute
            "q_deg": np.rad2deg(s.q),
            "within_limits": s.within_limits,
            "wrist_singular": s.wrist_singular,
            "shoulder_singular": s.shoulder_singular,
            "residual": residual(robot, s.q, target),
        }
        for s in solutions
    ]
