r"""Every in-limit representative of a branch: joints with more than a full turn.

A closed-form solve gives each angle once: the representative (mod 2π) within
the joint's limits when one is (:func:`workbench.ik.analytic`). A joint whose
range exceeds 2π (KUKA's a4 and a6 at ±350°, a UR arm's ±360°) has two or
more representatives within its limits, each a different configuration of the
robot that puts the tool at the same pose (a different cable wind-up).
:func:`expand_turns` lists them all: for each solution, every combination of
:math:`q_j + 2\pi k_j` within the limits, over the joints of such range,
labelled with the turns ``k`` (``"right/elbow-up/no-flip (q4-1, q6+1)"``: q4 a
turn less, q6 a turn more than the representative the solve gave).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import numpy.typing as npt

from workbench.ik._flags import WITHIN_LIMITS
from workbench.ik._puma import LIMIT_TOL
from workbench.ik.solution import Solutions
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]
TAU = 2.0 * math.pi
#: The values of ``representatives=`` of :func:`workbench.ik.analytic`.
REPRESENTATIVES = ("one", "all")


def get_turns(value: float, lower: float, upper: float) -> list[int]:
    """The k with ``lower <= value + 2πk <= upper`` (± ``LIMIT_TOL``), ascending."""
    if not (math.isfinite(lower) and math.isfinite(upper)):
        return [0]  # an unlimited joint: every turn is the same configuration
    first = math.ceil((lower - LIMIT_TOL - value) / TAU)
    last = math.floor((upper + LIMIT_TOL - value) / TAU)
    return list(range(first, last + 1)) or [0]


def expand_turns(robot: Robot, solutions: Solutions) -> Solutions:
    """``solutions`` with every in-limit representative of each (module docs).

    Args:
        robot: The robot the solutions are of (its limits).
        solutions: A solve's result (:func:`workbench.ik.analytic`).

    Returns:
        A :class:`~workbench.ik.Solutions` whose rows are, for each solution in
        order, the turns of its joints in ascending order (the solve's own
        representative among them, its label unchanged); each row's
        ``WITHIN_LIMITS`` bit is its own.
    """
    lower, upper = np.asarray(robot.lower), np.asarray(robot.upper)
    wide = [j for j in range(len(lower)) if upper[j] - lower[j] > TAU]
    if not wide:
        return solutions
    rows, flags, labels = [], [], []
    for solution in solutions:
        q = np.asarray(solution.q)
        options = [get_turns(float(q[j]), lower[j], upper[j]) for j in wide]
        for turns in itertools.product(*options):
            row = q.copy()
            for j, k in zip(wide, turns, strict=True):
                row[j] += TAU * k
            within = bool(
                np.all(row >= lower - LIMIT_TOL) and np.all(row <= upper + LIMIT_TOL)
            )
            bits = (int(solution.flags) & ~WITHIN_LIMITS) | (
                WITHIN_LIMITS if within else 0
            )
            marks = [f"q{j + 1}{k:+d}" for j, k in zip(wide, turns, strict=True) if k]
            rows.append(row)
            flags.append(bits)
            labels.append(solution.branch + (f" ({', '.join(marks)})" if marks else ""))
    return Solutions.from_arrays(
        np.array(rows),
        np.array(flags, dtype=np.uint8),
        tuple(labels),
        solutions.redundancy,
        int(solutions.solve_flags),
    )


__all__ = ["REPRESENTATIVES", "expand_turns", "get_turns"]
