"""``plan pick-place`` from tool poses: the pick and place configurations by IK.

``--pick-xyz-quat-wxyz`` and ``--place-xyz-quat-wxyz`` give the two tool poses
(base frame, metres, unit quaternion w x y z, as ``ik --xyz-quat-wxyz``); the
closed form turns them into joint values on one branch: the pick's is the
solution of the largest joint-limit margin, the place's the same branch.
Seven-axis arms (SRS: the arm angle ψ; Franka: q7) take the redundancy
parameter as ``ik`` does: ``--redundancy VALUE`` [rad] solves both poses at
that value, else ``--criterion`` (default ``limit_margin``) chooses each
pose's value by ``workbench.ik.choose_redundancy`` (the place's on the pick's
branch). Joint values (``--pick-deg``, ``--place-deg``) fix the parameter:
``--redundancy`` and ``--criterion`` are refused with them.
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench import ik
from workbench.cli._common import q_from_degrees
from workbench.cli._redundancy import get_redundant, refuse_redundancy
from workbench.cli.ik import MAX_TARGET_COORDINATE, QUAT_TYPED_TOL
from workbench.errors import InfeasibleError, InputError
from workbench.model.robot import Robot
from workbench.planning.redundancy_policy import compute_limit_margin
from workbench.poses import rotation_from_quat_wxyz

FloatArray = npt.NDArray[np.float64]


def get_configurations(
    args: argparse.Namespace, robot: Robot
) -> tuple[FloatArray, FloatArray, dict[str, Any]]:
    """``(q_pick, q_place, keys)``: the configurations and the JSON keys about them.

    ``keys``: ``branch`` (the IK branch of poses, None for joint values) and
    ``redundancy`` (None for a six-axis arm; else ``parameter``, ``source``
    ``"given"``, ``"chosen"`` or ``"configuration"``, ``criterion``, and the
    ``pick`` and ``place`` values [rad]).

    Raises:
        InputError: Contradictory options, a pose that is not rigid, or
            redundancy options for an arm without the parameter.
        InfeasibleError: A pose without an IK solution within the limits on
            the branch (exit 3).
    """
    solver = get_redundant(robot)
    for option, value in (
        ("--redundancy", args.redundancy),
        ("--criterion", args.criterion),
    ):
        if value is None:
            continue
        if solver is None:
            raise refuse_redundancy(robot, option)
        if args.pick_deg is not None or args.place_deg is not None:
            raise InputError(
                f"{option} chooses the IK of --pick-xyz-quat-wxyz and "
                "--place-xyz-quat-wxyz: joint values (--pick-deg, --place-deg) "
                "fix the redundancy"
            )
    if args.redundancy is not None and args.criterion is not None:
        raise InputError("--criterion chooses a value: not with --redundancy")
    joints = (args.pick_deg is not None, args.place_deg is not None)
    if joints[0] != joints[1]:
        raise InputError(
            "give pick and place both as joint values (--pick-deg, --place-deg) "
            "or both as poses (--pick-xyz-quat-wxyz, --place-xyz-quat-wxyz)"
        )
    if joints[0]:
        q_pick = q_from_degrees(robot, args.pick_deg)
        q_place = q_from_degrees(robot, args.place_deg)
        redundancy = None
        if solver is not None:
            redundancy = {
                "parameter": solver.parameter,
                "source": "configuration",
                "criterion": None,
                "pick": float(solver.parameter_of(robot.check_configuration(q_pick))),
                "place": float(solver.parameter_of(robot.check_configuration(q_place))),
            }
        return q_pick, q_place, {"branch": None, "redundancy": redundancy}
    pick = _target(args.pick_xyz_quat_wxyz, "--pick-xyz-quat-wxyz")
    place = _target(args.place_xyz_quat_wxyz, "--place-xyz-quat-wxyz")
    if solver is None:
        first = _best(robot, ik.analytic(robot, pick), "pick")
        second = _on_branch(ik.analytic(robot, place, q_previous=first.q), first)
        return first.q, second.q, {"branch": first.branch, "redundancy": None}
    if args.redundancy is not None:
        value = float(args.redundancy)
        first = _best(robot, ik.analytic(robot, pick, redundancy=value), "pick")
        solutions = ik.analytic(robot, place, q_previous=first.q, redundancy=value)
        second = _on_branch(solutions, first)
        source, criterion = "given", None
    else:
        criterion = args.criterion or "limit_margin"
        first = ik.choose_redundancy(robot, pick, criterion=criterion).solution
        second = ik.choose_redundancy(
            robot, place, criterion=criterion, branch=first.branch
        ).solution
        source = "chosen"
    redundancy = {
        "parameter": solver.parameter,
        "source": source,
        "criterion": criterion,
        "pick": first.redundancy,
        "place": second.redundancy,
    }
    return first.q, second.q, {"branch": first.branch, "redundancy": redundancy}


def _target(values: list[float], option: str) -> pin.SE3:
    """The pose of ``x y z qw qx qy qz`` (metres, unit quaternion scalar first)."""
    x = np.array(values)
    if np.abs(x[:3]).max() > MAX_TARGET_COORDINATE:
        raise InputError(
            f"{option}: position {x[:3].tolist()} too far: each coordinate at most "
            f"{MAX_TARGET_COORDINATE:g} m"
        )
    try:
        rotation = rotation_from_quat_wxyz(x[3:], tol=QUAT_TYPED_TOL)
    except InputError as err:
        raise InputError(f"{option}: {err}") from err
    return pin.SE3(rotation, x[:3])


def _best(robot: Robot, solutions: list, which: str) -> Any:
    """The solution within the limits of the largest joint-limit margin.

    Raises:
        InfeasibleError: If none is within the limits.
    """
    within = [s for s in solutions if s.within_limits]
    if not within:
        raise InfeasibleError(
            f"the {which} pose has no IK solution within the joint limits"
        )
    return max(
        within, key=lambda s: compute_limit_margin(s.q, robot.lower, robot.upper)
    )


def _on_branch(solutions: list, first: Any) -> Any:
    """The place's solution on the pick's branch, within the limits.

    Raises:
        InfeasibleError: If the branch does not reach it within the limits.
    """
    for solution in solutions:
        if solution.branch == first.branch and solution.within_limits:
            return solution
    raise InfeasibleError(
        f"the place pose has no IK solution within the joint limits on the pick's "
        f"branch {first.branch}"
    )
