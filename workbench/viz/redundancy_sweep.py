r"""One pose of a seven-axis arm drawn over its redundancy parameter (self-motion).

A seven-axis arm of the SRS or Franka family reaches one tool pose along a
one-parameter family of configurations per branch (the arm angle ψ, or q7;
:func:`workbench.ik.get_solver`). :func:`compute_redundancy_sweep`
samples one branch at ``count`` values spread over the intervals where it is
within the joint limits (:meth:`workbench.ik.Solver.feasible`): the total
length of the intervals is cut into ``count`` equal cells and each value is a
cell's centre, so every value lies inside an interval and the spacing is even
across them. The arm angle is periodic: a branch feasible through ψ = ±π (its
first interval starts at −π and its last ends at π) is swept through ±π, the
two joined into one interval, so that the sweep runs on without a jump there.
:func:`show_redundancy_sweep` draws those configurations as
translucent ghosts coloured by the value (viridis, the legend gives the
scale) and animates the arm through them (play, pause and scrub in the page).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InfeasibleError, InputError
from workbench.model.robot import Robot
from workbench.viz import _legend
from workbench.viz.viewer import Viewer

FloatArray = npt.NDArray[np.float64]

#: Colour map of the ghosts (perceptually uniform, as the workspace view's).
COLOR_MAP = "viridis"
#: Colour stops written into the legend's ramp.
RAMP_STOPS = 11
#: Duration of the animation through the sweep [s].
SWEEP_SECONDS = 4.0
#: Opacity of the ghosts.
SWEEP_OPACITY = 0.35
#: Largest number of values of a sweep (each a ghost arm in the page).
MAX_SWEEP = 64
#: A full turn [rad], the period of the arm angle.
TAU = 2.0 * np.pi
#: How close [rad] a range is to 2π (periodic), and an interval end to its end.
PERIOD_TOL = 1e-12


@dataclass(frozen=True, slots=True)
class RedundancySweep:
    """One branch of one pose at several values of the redundancy parameter.

    Attributes:
        parameter: ``"arm angle"`` (SRS) or ``"q7"`` (Franka).
        branch: The branch label.
        values: (N,) parameter values [rad] in sweep order, within the
            parameter's range.
        q: (N, 7) configurations [rad], all within the joint limits.
        intervals: The branch's feasible intervals [rad] the values spread over.
        unwrapped: (N,) the values, increasing: through ±π a periodic
            parameter goes on below −π (``values`` = ``unwrapped`` + 2π there).
    """

    parameter: str
    branch: str
    values: FloatArray
    q: FloatArray
    intervals: tuple[tuple[float, float], ...]
    unwrapped: FloatArray


def spread_over_intervals(
    intervals: tuple[tuple[float, float], ...], count: int
) -> FloatArray:
    """``count`` values evenly spread over disjoint intervals (cell centres).

    Args:
        intervals: Sorted disjoint closed intervals ``(lo, hi)``.
        count: Number of values, >= 1.

    Returns:
        (count,) increasing values, each inside an interval.

    Raises:
        InputError: If ``count`` < 1 or the intervals have no length.
    """
    if count < 1:
        raise InputError(f"a sweep needs at least 1 value, got {count}")
    lengths = np.array([hi - lo for lo, hi in intervals], dtype=np.float64)
    total = float(lengths.sum()) if len(lengths) else 0.0
    if not total > 0.0:
        raise InputError("the intervals have no length to spread values over")
    position = (np.arange(count) + 0.5) / count * total  # along the joined intervals
    ends = np.cumsum(lengths)
    index = np.minimum(np.searchsorted(ends, position, side="right"), len(ends) - 1)
    starts = np.array([lo for lo, _ in intervals])
    return starts[index] + position - (ends[index] - lengths[index])


def find_branch(robot: Robot, q: npt.ArrayLike) -> tuple[float, str]:
    """The parameter value and the branch label of configuration ``q`` (7,) [rad].

    Raises:
        UnsupportedRobotError: If the robot has no seven-axis closed form.
        InfeasibleError: If no branch at that value reproduces ``q``.
    """
    from workbench import ik

    q = robot.check_configuration(q)
    value = float(ik.get_solver(robot).parameter_of(q))
    solutions = ik.analytic(robot, robot.fk(q), redundancy=value)
    if not solutions:
        raise InfeasibleError(f"no branch reproduces the configuration {q.tolist()}")
    wrapped = [np.abs(np.angle(np.exp(1j * (s.q - q)))).max() for s in solutions]
    return value, solutions[int(np.argmin(wrapped))].branch


def compute_redundancy_sweep(
    robot: Robot, target: pin.SE3 | npt.ArrayLike, count: int, branch: str
) -> RedundancySweep:
    """Branch ``branch`` of pose ``target`` at ``count`` values within the limits.

    Args:
        robot: A seven-axis arm of the SRS or Franka family.
        target: Tool pose, ``pin.SE3`` or (4, 4), base frame [m].
        count: Number of values (1..:data:`MAX_SWEEP`).
        branch: Label of the branch (``ik.get_solver(robot).branches``).

    Raises:
        InputError: If ``count`` is out of range or the label unknown.
        InfeasibleError: If the branch is within the limits for no value.
    """
    from workbench import ik

    if not 1 <= count <= MAX_SWEEP:
        raise InputError(f"a sweep takes 1..{MAX_SWEEP} values, got {count}")
    feasible = ik.get_solver(robot).feasible(target)
    if branch not in feasible.branches:
        raise InputError(
            f"unknown branch {branch!r}; {robot.name} has "
            + ", ".join(feasible.branches)
        )
    intervals = feasible.intervals[feasible.branches.index(branch)]
    if not intervals:
        raise InfeasibleError(
            f"branch {branch} reaches the pose within the joint limits for no "
            f"{feasible.parameter}"
        )
    joined = _join_through_pi(tuple(intervals), feasible.range)
    if sum(hi - lo for lo, hi in joined) <= 0.0:
        unwrapped = np.array([joined[0][0]] * count)
    else:
        unwrapped = spread_over_intervals(joined, count)
    values = np.where(unwrapped < feasible.range[0], unwrapped + TAU, unwrapped)
    rows = []
    for value in values:
        found = [
            s
            for s in ik.analytic(robot, target, redundancy=float(value))
            if s.branch == branch
        ]
        if not found:  # cannot happen inside a feasible interval
            raise InfeasibleError(
                f"branch {branch} does not reach the pose at {feasible.parameter} "
                f"= {value:.6f} rad, inside its feasible interval"
            )
        rows.append(found[0].q)
    return RedundancySweep(
        feasible.parameter, branch, values, np.array(rows), tuple(intervals), unwrapped
    )


def _join_through_pi(
    intervals: tuple[tuple[float, float], ...], parameter_range: tuple[float, float]
) -> tuple[tuple[float, float], ...]:
    """The intervals, the last one moved below the first when they meet at ±π.

    Only for a periodic parameter (a range of 2π, the arm angle) whose first
    interval starts at the range's start and last ends at its end.
    """
    lo, hi = parameter_range
    periodic = abs((hi - lo) - TAU) <= PERIOD_TOL
    if not (periodic and len(intervals) > 1):
        return intervals
    (first_lo, first_hi), (last_lo, last_hi) = intervals[0], intervals[-1]
    if first_lo > lo + PERIOD_TOL or last_hi < hi - PERIOD_TOL:
        return intervals
    return ((last_lo - TAU, first_hi), *intervals[1:-1])


def sweep_colors(values: FloatArray) -> FloatArray:
    """RGB (N, 3) in [0, 1] of each value on the sweep's scale (its min to max).

    Args:
        values: (N,) the sweep's ``unwrapped`` values [rad].
    """
    from matplotlib import colormaps

    lo, hi = float(values.min()), float(values.max())
    scaled = (values - lo) / (hi - lo) if hi > lo else np.full(values.shape, 0.5)
    return np.asarray(colormaps[COLOR_MAP](scaled))[:, :3]


def _scale_legend(sweep: RedundancySweep, degrees: bool) -> str:
    from matplotlib import colormaps

    cmap = colormaps[COLOR_MAP]
    stops = [
        (x, tuple(float(c) for c in cmap(x)[:3]))
        for x in np.linspace(0.0, 1.0, RAMP_STOPS)
    ]
    unwrapped = sweep.unwrapped
    lo, hi = float(unwrapped.min()), float(unwrapped.max())
    ends = np.array([sweep.values[0], sweep.values[-1]])
    shown = np.degrees(ends) if degrees else ends
    unit = "deg" if degrees else "rad"
    ticks = [(0.0, f"{shown[0]:.3g}"), (1.0, f"{shown[1]:.3g}")]
    if lo < -np.pi and hi > lo:  # through ±π: mark where
        ticks.insert(1, ((-np.pi - lo) / (hi - lo), "±180" if degrees else "±π"))
    return _legend.color_scale(
        "Ghost colour",
        f"{sweep.parameter} [{unit}] of branch {sweep.branch}, "
        f"{len(sweep.values)} values within the joint limits",
        stops,
        ticks,
    )


def show_redundancy_sweep(
    viewer: Viewer, sweep: RedundancySweep, *, degrees: bool = False
) -> None:
    """Draw the sweep as ghosts coloured by the value and animate the arm through it.

    Replaces the viewer's ghosts; the arm plays the sweep over
    :data:`SWEEP_SECONDS` (scrub it in the page).

    Args:
        viewer: A viewer of the sweep's robot.
        sweep: From :func:`compute_redundancy_sweep`.
        degrees: Label the values in degrees (else rad).
    """
    unit = "deg" if degrees else "rad"
    shown = np.degrees(sweep.values) if degrees else sweep.values
    labels = [f"{sweep.branch} {sweep.parameter}={v:+.4f} {unit}" for v in shown]
    viewer.show_ghosts(
        sweep.q,
        labels=labels,
        opacity=SWEEP_OPACITY,
        colors=sweep_colors(sweep.unwrapped),
        legend=_scale_legend(sweep, degrees),
    )
    if len(sweep.values) > 1:
        t = np.linspace(0.0, SWEEP_SECONDS, len(sweep.values))
        viewer.play_trajectory(t, sweep.q, trace_tool=False)
