"""``workbench ik`` on a seven-axis arm: every branch at one value of ψ or q7.

The configuration is :func:`workbench.ik.select`'s: at ``--redundancy``
(rad, or degrees with ``--deg``) the branch of largest limit margin, else the
value and branch :func:`workbench.ik.choose_redundancy` picks (largest
joint-limit margin, or ``--criterion``), and the output says which value.
``--all`` prints every branch reaching the pose at that value, with its
flags. None within the limits is an infeasible request (exit 3, the
feasible intervals in the message) unless ``--all`` asks for the branches
anyway.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from workbench import ik
from workbench.cli import _redundancy
from workbench.cli._common import print_json
from workbench.cli._ik_output import (
    deviation_head,
    print_deviation,
    print_infeasible,
    print_rows,
    residual,
)
from workbench.errors import InfeasibleError, InputError
from workbench.model.robot import Robot

if TYPE_CHECKING:
    from workbench.ik import FeasibleRedundancy, Solver

#: The singular flags of a branch, as JSON keys and as printed.
SINGULAR_FLAGS = (
    ("shoulder_singular", "shoulder singular"),
    ("elbow_singular", "elbow singular"),
    ("wrist_singular", "wrist singular"),
    ("parameter_singular", "parameter singular"),
)


def solve_and_print_redundant(
    args: argparse.Namespace, robot: Robot, target: pin.SE3, solver: Solver
) -> int:
    """Print ``ik.select``'s solution (``--all``: every branch at its value); exit code.

    Raises:
        InfeasibleError: If no value reaches the pose within the limits, the
            given value reaches it with no branch, or (without ``--all``)
            with no branch within the limits; the message gives the feasible
            intervals.
        InputError: If the value exceeds ``_redundancy.MAX_REDUNDANCY`` or
            comes with ``--criterion``.
    """
    head: dict[str, Any] = {
        "robot": robot.name,
        "frame": robot.tool_frame,
        "solver": "closed-form",
        "solver_note": f"{solver.family.name.upper()} family (seven axes, redundancy "
        f"parameter {solver.parameter})",
        **deviation_head(solver),
    }
    feasible: FeasibleRedundancy | None = None
    if args.feasible:
        feasible = solver.feasible(target)
        head["feasible_redundancy"] = _redundancy.feasible_json(feasible)
    try:
        value, redundancy = _get_value(args, solver)
        solutions: list[Any]
        if args.all and value is not None:  # every branch at the given value
            solutions = list(
                ik.analytic(
                    robot, target, redundancy=value, representatives=_turns(args)
                )
            )
        else:
            choice = ik.select(
                robot, target, redundancy=value, criterion=redundancy["criterion"]
            )
            redundancy["value"] = choice.redundancy
            if value is None:
                redundancy["score"] = choice.score
            solutions = [choice.solution]
            if args.all:  # every branch at the chosen value
                solutions = list(
                    ik.analytic(
                        robot,
                        target,
                        redundancy=choice.redundancy,
                        representatives=_turns(args),
                    )
                )
        head["redundancy"] = redundancy
        rows = _rows(robot, target, solutions)
    except InfeasibleError as err:
        said = _redundancy.with_feasible(err, robot, target, args.deg, feasible)
        if not args.json:
            raise said from err
        return print_infeasible(head, said)
    if args.json:
        print_json({**head, "solutions": rows, "feasible": True})
        return 0
    _print_text(args, head, rows, feasible, solver)
    return 0


def _get_value(
    args: argparse.Namespace, solver: Solver
) -> tuple[float | None, dict[str, Any]]:
    """The given value [rad] or None, and the ``redundancy`` JSON object to fill.

    Raises:
        InputError: ``--criterion`` with ``--redundancy``, or a value beyond
            ``_redundancy.MAX_REDUNDANCY``.
    """
    if args.redundancy is not None:
        if args.criterion is not None:
            raise InputError("--criterion chooses a value: not with --redundancy")
        value = _redundancy.to_radians(args.redundancy, args.deg)
        return value, {
            "parameter": solver.parameter,
            "value": value,
            "source": "given",
            "criterion": None,
            "score": None,
        }
    return None, {
        "parameter": solver.parameter,
        "value": None,
        "source": "chosen",
        "criterion": args.criterion or "limit_margin",
        "score": None,
    }


def _rows(robot: Robot, target: pin.SE3, solutions: list[Any]) -> list[dict[str, Any]]:
    """One JSON-ready row per branch reaching the pose."""
    return [
        {
            "branch": s.branch,
            "index": s.index,
            "q": s.q,
            "joint_values": s.q,  # the seven-axis families' joints are revolute
            "q_deg": np.rad2deg(s.q),
            "within_limits": s.within_limits,
            **{key: bool(getattr(s, key)) for key, _ in SINGULAR_FLAGS},
            "residual": residual(robot, s.q, target),
        }
        for s in solutions
    ]


def _print_text(
    args: argparse.Namespace,
    head: dict[str, Any],
    rows: list[dict[str, Any]],
    feasible: FeasibleRedundancy | None,
    solver: Solver,
) -> None:

    redundancy = head["redundancy"]
    value = _redundancy.format_value(redundancy["value"], args.deg)
    print(
        f"robot {head['robot']}   frame {head['frame']}   solver closed-form "
        f"({solver.family.name.upper()} family, seven axes)"
    )
    print_deviation(head)
    if redundancy["source"] == "given":
        print(f"{solver.parameter} = {value} (given)")
    else:
        print(
            f"{solver.parameter} = {value} (chosen: {redundancy['criterion']}, "
            f"score {redundancy['score']:.6g})"
        )
    if feasible is not None:
        print(_redundancy.describe_feasible(feasible, args.deg))
    print_rows(rows, SINGULAR_FLAGS)


def _turns(args: argparse.Namespace) -> str:
    """``representatives=`` of ``--all-turns``."""
    return "all" if args.all_turns else "one"
