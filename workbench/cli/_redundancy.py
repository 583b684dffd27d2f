"""The redundancy parameter of seven-axis arms on the command line (``ik``, ``view``).

A seven-axis arm of the SRS family (KUKA LBR iiwa) or of the Franka family
(Panda, FR3) has a closed form per value of one redundancy parameter: the arm
angle ψ (SRS) or the joint value q7 (Franka), both in rad
(:func:`workbench.ik.get_solver`). Here: the ``--redundancy VALUE``
option, the solver of a robot or None, and the feasible intervals as text and
JSON.
"""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING, Any

from workbench.cli._common import finite_float
from workbench.errors import InfeasibleError, InputError
from workbench.model.robot import Robot

if TYPE_CHECKING:
    import pinocchio as pin

    from workbench.ik import FeasibleRedundancy, Solver

#: Decimals of a parameter value printed in rad (in degrees: this minus 3).
DIGITS = 6
#: Largest |--redundancy| [rad]: the arm angle is taken modulo 2π, which
#: loses 3.9e-14 rad at this size (the float nearest 2π is 2.4e-16 short).
MAX_REDUNDANCY = 1000.0


def add_redundancy_argument(parser: argparse.ArgumentParser, unit_help: str) -> None:
    """``--redundancy VALUE``: ψ (SRS) or q7 (Franka) of a seven-axis arm.

    Args:
        parser: The command's parser.
        unit_help: How the command says the value's unit (rad, or degrees
            with ``--deg``).
    """
    parser.add_argument(
        "--redundancy",
        type=finite_float,
        metavar="VALUE",
        help="seven-axis arms (SRS: KUKA iiwa; Franka: Panda, FR3): the value of "
        "the redundancy parameter, the arm angle ψ (SRS) or q7 (Franka), "
        f"{unit_help}",
    )


def get_redundant(robot: Robot) -> Solver | None:
    """The closed form of a seven-axis arm of a known family, else None."""
    from workbench.ik import UnsupportedRobotError, get_solver

    try:
        solver = get_solver(robot)
    except UnsupportedRobotError:
        return None
    return solver if solver.parameter is not None else None


def refuse_redundancy(robot: Robot, option: str = "--redundancy") -> InputError:
    """The error for a redundancy option given for an arm without the parameter."""
    if robot.nv == 6:
        what = "a six-axis arm has no redundancy"
    else:
        what = (
            f"{robot.nv} joints, but no closed form with a redundancy parameter "
            "(SRS or Franka family)"
        )
    return InputError(f"{option}: {robot.name}: {what}")


def to_radians(value: float, degrees: bool) -> float:
    """A typed parameter value in rad (typed in degrees when ``degrees``).

    Raises:
        InputError: If it exceeds :data:`MAX_REDUNDANCY` in magnitude.
    """
    radians = math.radians(value) if degrees else value
    if abs(radians) > MAX_REDUNDANCY:
        raise InputError(
            f"--redundancy {value:g}{' deg' if degrees else ' rad'}: at most "
            f"{MAX_REDUNDANCY:g} rad in magnitude (the arm angle is taken modulo "
            "2π, q7 must be within the joint's limits)"
        )
    return radians


def format_value(value: float, degrees: bool) -> str:
    """``0.523599 rad`` or ``30.000°``."""
    if degrees:
        return f"{math.degrees(value):.{DIGITS - 3}f}°"
    return f"{value:.{DIGITS}f} rad"


def format_intervals(
    intervals: tuple[tuple[float, float], ...] | list[tuple[float, float]],
    degrees: bool,
) -> str:
    """``[-1.2 rad, 0.4 rad], [...]``, or ``none``."""
    if not intervals:
        return "none"
    return ", ".join(
        f"[{format_value(lo, degrees)}, {format_value(hi, degrees)}]"
        for lo, hi in intervals
    )


def describe_feasible(feasible: FeasibleRedundancy, degrees: bool) -> str:
    """One line: ``feasible arm angle: [...], [...]`` (and whether the ends join)."""
    union = feasible.union
    text = f"feasible {feasible.parameter}: {format_intervals(union, degrees)}"
    low, high = feasible.range
    if (
        feasible.circular
        and len(union) > 1
        and union[0][0] == low
        and union[-1][1] == high
    ):
        text += " (the first and the last are one arc through ±π)"
    return text


def with_feasible(
    err: InfeasibleError,
    robot: Robot,
    target: pin.SE3,
    degrees: bool,
    feasible: FeasibleRedundancy | None = None,
) -> InfeasibleError:
    """``err`` on one line, with the feasible intervals when it does not give them.

    Args:
        err: The solver's reason (an out-of-reach value, none within limits).
        robot: A seven-axis arm.
        target: The tool pose.
        degrees: Print the intervals in degrees.
        feasible: The intervals if already known (else computed).
    """
    from workbench.ik import get_solver

    message = " ".join(str(err).split())
    if "feasible" not in message:  # the solver's reason, without the intervals
        feasible = feasible or get_solver(robot).feasible(target)
        message += f"; {describe_feasible(feasible, degrees)}"
    return InfeasibleError(message)


def feasible_json(feasible: FeasibleRedundancy) -> dict[str, Any]:
    """The ``feasible_redundancy`` object of the commands' JSON (rad)."""
    return {
        "parameter": feasible.parameter,
        "range": list(feasible.range),
        "union": [list(i) for i in feasible.union],
        "circular": feasible.circular,
        "branches": {
            label: [list(i) for i in intervals]
            for label, intervals in zip(
                feasible.branches, feasible.intervals, strict=True
            )
        },
    }
