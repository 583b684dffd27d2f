"""``plan pick-place`` from tool poses: the pick and place configurations by IK.

``--pick-xyz-quat-wxyz`` and ``--place-xyz-quat-wxyz`` give the two tool poses
(base frame, metres, unit quaternion w x y z, as ``ik --xyz-quat-wxyz``,
parsed by :func:`workbench.poses.parse_target`);
:func:`workbench.ik.pick_place_configurations` turns them into joint values,
both on the branch that serves both with the largest joint-limit margin (the
same answer as the same call in Python). Seven-axis arms (SRS: the arm angle
ψ; Franka: q7) take the redundancy parameter as ``ik`` does:
``--redundancy VALUE`` [rad] solves both poses at that value, else
``--criterion`` (default ``limit_margin``) chooses each pose's value.
Joint values (``--pick-deg``, ``--place-deg``) fix the parameter:
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
from workbench.cli._redundancy import get_redundant, refuse_redundancy, to_radians
from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.poses import parse_target

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
        InputError: Contradictory options, a pose that is not rigid,
            redundancy options for an arm without the parameter, or a
            ``--redundancy`` beyond its bound.
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
    given = None if args.redundancy is None else to_radians(args.redundancy, False)
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
    pick = parse_pose_option(args.pick_xyz_quat_wxyz, "--pick-xyz-quat-wxyz")
    place = parse_pose_option(args.place_xyz_quat_wxyz, "--place-xyz-quat-wxyz")
    criterion = None
    if solver is not None and args.redundancy is None:
        criterion = args.criterion or "limit_margin"
    first, second = ik.pick_place_configurations(
        robot, pick, place, redundancy=given, criterion=criterion
    )
    branch = first.branch
    if second.branch != branch:
        branch = f"{first.branch} -> {second.branch}"
    redundancy = None
    if solver is not None:
        redundancy = {
            "parameter": solver.parameter,
            "source": "given" if args.redundancy is not None else "chosen",
            "criterion": criterion,
            "pick": first.redundancy,
            "place": second.redundancy,
        }
    return first.q, second.q, {"branch": branch, "redundancy": redundancy}


def parse_pose_option(values: list[float], option: str) -> pin.SE3:
    """The pose of ``x y z qw qx qy qz`` (metres, unit quaternion scalar first).

    Raises:
        InputError: Naming ``option``, if the numbers make no rigid pose.
    """
    try:
        return parse_target(values, "xyz_quat_wxyz")
    except InputError as err:
        raise InputError(f"{option}: {err}") from err
