"""What ``workbench ik`` prints, for six- and seven-axis arms alike.

The rows of the solutions as text, the residual of each, the structure
deviation of a calibrated arm, and the ``--json`` answer of an infeasible
request (exit 3).
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.cli._common import EXIT_INFEASIBLE, format_vector, print_json
from workbench.errors import InfeasibleError
from workbench.ik import Solver
from workbench.model.robot import Robot


def residual(robot: Robot, q: npt.ArrayLike, target: pin.SE3) -> float:
    """max(position error [m], rotation angle error [rad]) of FK(q) vs target."""
    pose = robot.fk(q)
    error = target.actInv(pose)
    angle = float(np.linalg.norm(pin.log3(error.rotation)))
    return max(float(np.linalg.norm(pose.translation - target.translation)), angle)


def print_rows(rows: list[dict[str, Any]], flags: tuple[tuple[str, str], ...]) -> None:
    """Two lines per solution: branch, q [deg] and its flags; the residual.

    Args:
        rows: The JSON rows of the solutions.
        flags: ``(key, text)``: ``(text)`` is printed where ``row[key]`` is true.
    """
    width = max((len(row["branch"]) for row in rows), default=0) + 2
    for row in rows:
        marks = "" if row["within_limits"] else "  (outside joint limits)"
        marks += "".join(f"  ({text})" for key, text in flags if row[key])
        q_deg = format_vector(row["q_deg"], 3)
        print(f"{row['branch']:<{width}}q [deg] {q_deg}{marks}")
        print(f"{'':<{width}}residual {row['residual']:.2e}")


def deviation_head(solver: Solver) -> dict[str, Any]:
    """The JSON key of a calibrated arm's structure deviation, or nothing.

    Returns:
        ``{"structure_deviation": {"angle": [rad], "angle_test": ...,
        "distance": [m], "distance_test": ...}}`` for an arm whose model is
        off its family by more than URDF rounding
        (``StructureDeviation.calibrated``: its branches are carried to the
        model); ``{}`` otherwise.
    """
    deviation = solver.deviation
    if deviation is None or not deviation.calibrated:
        return {}
    return {
        "structure_deviation": {
            "angle": deviation.angle,
            "angle_test": deviation.angle_test,
            "distance": deviation.distance,
            "distance_test": deviation.distance_test,
        }
    }


def print_deviation(head: dict[str, Any]) -> None:
    """The text line of :func:`deviation_head`'s key, if ``head`` has it."""
    found = head.get("structure_deviation")
    if found is None:
        return
    print(
        f"calibrated arm: structure deviation {found['angle']:.2g} rad "
        f"({found['angle_test']}), {found['distance']:.2g} m "
        f"({found['distance_test']}); branches carried to the model"
    )


def print_infeasible(head: dict[str, Any], err: InfeasibleError) -> int:
    """The ``--json`` answer of an infeasible request (and its line on stderr): 3."""
    message = " ".join(str(err).split())
    print_json({**head, "solutions": [], "feasible": False, "error": message})
    print(f"workbench: error: {message}", file=sys.stderr)
    return EXIT_INFEASIBLE


__all__ = [
    "deviation_head",
    "print_deviation",
    "print_infeasible",
    "print_rows",
    "residual",
]
