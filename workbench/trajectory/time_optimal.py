r"""How far the normal spline is from time-optimal on the same joint path.

Along the straight joint path :math:`q(u) = q_\mathrm{pick} + \Delta q\,u`,
:math:`u \in [0, 1]`, joint limits become bounds on the path speed and
acceleration, :math:`\dot u \le V = \min_i v_i/|\Delta_i|`,
:math:`|\ddot u| \le A = \min_i a_i/|\Delta_i|`, so the time-optimal motion is
a trapezoid in u (bang-coast-bang):

.. math::

    T^* = \frac{1}{V} + \frac{V}{A}\ \text{ if } V^2 \le A, \qquad
    T^* = \frac{2}{\sqrt{A}}\ \text{ otherwise}, \qquad
    T^* = \frac{1}{V}\ \text{ if } A = \infty.

The normal spline needs :math:`T_\min = \max(\max|\dot s|/V,
\sqrt{\max|\ddot s|/A})`; with speed limits only the ratio is
:math:`\max|\dot s| \approx 2`, the price of zero end accelerations.
TOPP-RA (``toppra``, optional ``bench`` extra) solves the same problem
numerically on a grid; it is imported only when asked for.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from workbench.errors import InfeasibleError, InputError
from workbench.model.robot import Robot
from workbench.trajectory.limits import (
    _rate_limit,
    _require_vector_space,
    minimum_duration,
)
from workbench.trajectory.normal_spline import DEFAULT_N_POINTS
from workbench.validation import as_vector

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class TimeOptimalComparison:
    """Normal-spline minimum duration against the time-optimal one, same path.

    Attributes:
        spline_duration: :func:`~workbench.trajectory.minimum_duration` [s].
        optimal_duration: Closed-form time-optimal T* on the straight path [s].
        toppra_duration: TOPP-RA's T* [s], or None if not computed.
        ratio: ``spline_duration / optimal_duration`` (>= 1).
    """

    spline_duration: float
    optimal_duration: float
    toppra_duration: float | None
    ratio: float


def compute_time_optimal_duration(
    robot: Robot, q_pick: npt.ArrayLike, q_place: npt.ArrayLike
) -> float:
    """Time-optimal T* along the straight joint path, closed form (module doc).

    Args:
        robot: The robot; its speed and (where finite) acceleration limits.
        q_pick: Start, shape (nq,) [rad].
        q_place: End, shape (nq,) [rad].

    Returns:
        T* [s]; 0.0 for equal configurations.
    """
    _require_vector_space(robot)
    dq = np.abs(
        as_vector(q_place, robot.nq, "q_place") - as_vector(q_pick, robot.nq, "q_pick")
    )
    moving = dq > 0.0
    if not moving.any():
        return 0.0
    v = float(np.min(_rate_limit(robot, 1)[moving] / dq[moving]))
    a = float(np.min(_rate_limit(robot, 2)[moving] / dq[moving]))
    if math.isinf(v):
        raise InputError(f"robot {robot.name} has no speed limit on the moving joints")
    return float(compute_bang_coast_bang_duration(v, a))


def compute_bang_coast_bang_duration(
    speed_bound: npt.ArrayLike, acceleration_bound: npt.ArrayLike
) -> FloatArray:
    r"""Shortest rest-to-rest time over a unit path, :math:`u: 0 \to 1`.

    With :math:`|\dot u| \le V` and :math:`|\ddot u| \le A` the fastest motion
    is bang-coast-bang (module docstring): :math:`1/V + V/A` when it reaches
    V (:math:`V^2 \le A`), else :math:`2/\sqrt{A}`; :math:`1/V` for
    :math:`A = \infty`. Element-wise over arrays.

    Args:
        speed_bound: V [1/s], > 0 and finite, scalar or array.
        acceleration_bound: A [1/s²], > 0 (inf: no bound), broadcast with V.

    Returns:
        T* [s], of the broadcast shape.
    """
    v = np.asarray(speed_bound, dtype=np.float64)
    a = np.asarray(acceleration_bound, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        cruise = 1.0 / v + v / a
        triangle = 2.0 / np.sqrt(a)
    return np.asarray(np.where(v * v <= a, cruise, triangle), dtype=np.float64)


def compute_toppra_duration(
    robot: Robot,
    q_pick: npt.ArrayLike,
    q_place: npt.ArrayLike,
    *,
    grid_points: int = 1001,
) -> float:
    """TOPP-RA's time-optimal duration on the straight joint path.

    Args:
        robot: The robot; speed limits and the finite acceleration limits.
        q_pick: Start, shape (nq,) [rad].
        q_place: End, shape (nq,) [rad].
        grid_points: TOPP-RA discretisation of the path.

    Returns:
        T* [s] as TOPP-RA computes it.

    Raises:
        ModuleNotFoundError: If ``toppra`` is not installed (``bench`` extra).
        InfeasibleError: If TOPP-RA finds no parametrisation.
    """
    import toppra
    import toppra.algorithm
    import toppra.constraint

    _require_vector_space(robot)
    q0 = as_vector(q_pick, robot.nq, "q_pick")
    q1 = as_vector(q_place, robot.nq, "q_place")
    path = toppra.SplineInterpolator([0.0, 1.0], np.vstack([q0, q1]), bc_type="natural")
    vel = _rate_limit(robot, 1)
    vlim = np.column_stack([-vel, vel])
    constraints = [toppra.constraint.JointVelocityConstraint(vlim)]
    acc = _rate_limit(robot, 2)
    if np.isfinite(acc).all():
        alim = np.column_stack([-acc, acc])
        constraints.append(toppra.constraint.JointAccelerationConstraint(alim))
    gridpoints = np.linspace(0.0, 1.0, grid_points)
    algorithm = toppra.algorithm.TOPPRA(
        constraints, path, gridpoints=gridpoints, parametrizer="ParametrizeConstAccel"
    )
    result = algorithm.compute_trajectory(0.0, 0.0)
    if result is None:
        raise InfeasibleError("TOPP-RA found no time parametrisation")
    return float(result.duration)


def compare_time_optimal(
    robot: Robot,
    q_pick: npt.ArrayLike,
    q_place: npt.ArrayLike,
    *,
    use_toppra: bool = True,
    n_points: int = DEFAULT_N_POINTS,
) -> TimeOptimalComparison:
    """Normal-spline minimum duration vs. time-optimal, on the same path and limits.

    Args:
        robot: The robot.
        q_pick: Start, shape (nq,) [rad].
        q_place: End, shape (nq,) [rad].
        use_toppra: Also run TOPP-RA when it is installed (silently skipped
            when it is not: ``toppra_duration`` is then None).
        n_points: Knots of the normal spline.
    """
    spline = minimum_duration(robot, q_pick, q_place, n_points=n_points)
    optimal = compute_time_optimal_duration(robot, q_pick, q_place)
    toppra_t = None
    if use_toppra:
        try:
            toppra_t = compute_toppra_duration(robot, q_pick, q_place)
        except ModuleNotFoundError:
            toppra_t = None
    ratio = spline / optimal if optimal > 0.0 else 1.0
    return TimeOptimalComparison(spline, optimal, toppra_t, ratio)
