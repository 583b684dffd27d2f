"""``workbench ik``: inverse kinematics, closed form for OPW and UR-type arms.

Seven-axis arms of the SRS and Franka families are solved in closed form at
one value of their redundancy parameter (:mod:`workbench.cli._ik_redundant`).
Any other robot falls back to numerical IK (one solution, branch "numeric"),
and the output says so: ``solver`` is ``"closed-form"`` or ``"numeric"``.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

import numpy as np
import pinocchio as pin

from workbench._compiled import interpreted
from workbench.cli import _redundancy
from workbench.cli._common import (
    add_json_flag,
    add_robot_argument,
    finite_float,
    load_robot_from_args,
    print_json,
)
from workbench.cli._ik_output import (
    print_infeasible,
    print_rows,
    residual,
)
from workbench.cli._redundancy import add_redundancy_argument
from workbench.errors import InfeasibleError, InputError
from workbench.ik import IKSolution, UnsupportedRobotError, get_solver, nearest
from workbench.ik.numerical import numeric
from workbench.model.robot import Robot
from workbench.poses import (
    ANGELES7_PRINTED_TOL,
    as_se3,
    rotation_from_quat_wxyz,
    se3_from_angeles7,
)

#: Largest accepted | |q| - 1 | of a typed quaternion (then normalised): four
#: decimals, as in "0.7071 0 0 0.7071", are enough.
QUAT_TYPED_TOL = 1e-3

_MM = 1e-3
#: Largest |coordinate| of a target position [m] (1000 km: far beyond any arm).
MAX_TARGET_COORDINATE = 1e6
#: ``--criterion`` choices (``ik.choose_redundancy`` criteria needing no q_previous).
CRITERIA = ("limit_margin", "manipulability")
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
        "branch within the joint limits nearest to q = 0, or with --all every "
        "closed-form branch. Arms of the OPW (PUMA, KUKA, ABB, ...) and UR families "
        "are recognised from their joint axes; so are the seven-axis SRS (KUKA "
        "iiwa) and Franka (Panda) families, whose every branch at one value of the "
        "redundancy parameter is printed (--redundancy, else the value chosen by "
        "--criterion, said in the output); any other robot gets one numerical "
        "solution (solver 'numeric', branch 'numeric'). residual = max(position "
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
    parser.add_argument(
        "--all",
        action="store_true",
        help="print every closed-form branch (seven-axis arms: every branch is "
        "printed; --all also when none is within the limits, exit 0)",
    )
    add_redundancy_argument(
        parser,
        "[rad, or degrees with --deg]; every branch at that value is printed "
        "(default: the value of largest joint-limit margin, or --criterion)",
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
    scale = _MM if args.mm else 1.0
    if args.angeles7 is not None:
        position = args.angeles7[4:]
    elif args.matrix is not None:
        position = args.matrix[3:12:4]
    else:
        position = args.xyz_quat_wxyz[:3]
    if max(abs(x) * scale for x in position) > MAX_TARGET_COORDINATE:
        raise InputError(
            f"target position {position} too far: each coordinate at most "
            f"{MAX_TARGET_COORDINATE:g} m"
        )
    if args.angeles7 is not None:
        x = np.array(args.angeles7)
        x[4:] *= scale
        return se3_from_angeles7(x, tol=ANGELES7_PRINTED_TOL)
    if args.matrix is not None:
        m = np.array(args.matrix).reshape(4, 4)
        m[:3, 3] *= scale
        return as_se3(m)
    x = np.array(args.xyz_quat_wxyz)
    rotation = rotation_from_quat_wxyz(x[3:], tol=QUAT_TYPED_TOL)
    return pin.SE3(rotation, x[:3] * scale)


def _pick(solutions: list[IKSolution], nq: int) -> IKSolution:
    feasible = [s for s in solutions if s.within_limits]
    if not feasible:
        raise InfeasibleError(
            f"the pose is reachable, but none of the {len(solutions)} closed-form "
            "branches is within the joint limits (use --all to see them)"
        )
    return nearest(feasible, np.zeros(nq))


def _numeric_row(robot: Robot, target: pin.SE3) -> dict[str, object]:
    result = numeric(robot, target)
    if not result.success:
        raise InfeasibleError(
            f"numerical IK found no solution for {robot.name} "
            f"(best error {result.error:.3g} after {result.iterations} iterations, "
            f"{result.restarts} restarts): the pose is probably out of reach"
        )
    return {
        "branch": "numeric",
        "q": result.q,
        "joint_values": robot.joint_values_from_q(result.q),
        "q_deg": np.rad2deg(robot.joint_values_from_q(result.q)),
        "within_limits": True,
        "wrist_singular": False,
        "shoulder_singular": False,
        "residual": residual(robot, result.q, target),
    }


def run(args: argparse.Namespace) -> int:
    """Print the solution(s); returns the exit code.

    One pose of a six-axis arm: the kernels run interpreted
    (``_compiled.interpreted``), which takes milliseconds where compiling them
    on a first run takes seconds. A seven-axis arm's kernels run compiled: the
    choice of the value and the feasible intervals call them hundreds of
    times (0.3 s compiled, cache warm; 3 s interpreted).
    """
    robot = load_robot_from_args(args, tool_frame=args.tool_frame)
    target = target_from_args(args)
    redundant = _redundancy.get_redundant(robot)
    if redundant is not None:
        from workbench.cli._ik_redundant import solve_and_print_redundant

        return solve_and_print_redundant(args, robot, target, redundant)
    with interpreted():
        return _solve_and_print(args, robot, target)


def _solve_and_print(args: argparse.Namespace, robot: Robot, target: pin.SE3) -> int:
    for option in ("redundancy", "criterion"):
        if getattr(args, option) is not None:
            raise _redundancy.refuse_redundancy(robot, f"--{option}")
    for option in ("deg", "feasible"):
        if getattr(args, option):
            raise _redundancy.refuse_redundancy(robot, f"--{option}")
    try:
        family = get_solver(robot).family.name
    except UnsupportedRobotError as err:
        solver, reason = "numeric", str(err)
        if args.all and not args.json:
            print(f"no closed form: {reason}", file=sys.stderr)
    else:
        solver, reason = "closed-form", f"{family.upper()} family"
    head = {
        "robot": robot.name,
        "frame": robot.tool_frame,
        "solver": solver,
        "solver_note": reason,
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
    print_rows(rows, SIX_AXIS_FLAGS)
    return 0


def _solve(
    args: argparse.Namespace, robot: Robot, target: pin.SE3, solver: str
) -> list[dict[str, Any]]:
    """The rows to print: the chosen branch, every branch (``--all``) or numeric.

    Raises:
        InfeasibleError: If the pose is out of reach, or no branch is within
            the joint limits.
    """
    if solver == "numeric":
        return [_numeric_row(robot, target)]
    solutions = get_solver(robot).solve(target)
    if not args.all:
        solutions = [_pick(solutions, robot.nq)]
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
