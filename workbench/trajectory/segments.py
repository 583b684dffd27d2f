"""Pick → via points → place: rest-to-rest normal-spline segments with dwells.

Each segment is a :func:`~workbench.trajectory.pick_and_place` motion, scaled
to its own duration; it starts and ends at rest with zero acceleration, so the
chain is C² without any matching, and the robot may wait (dwell) at each via
point. Beyond Angeles et al. (1988), who plan a single segment.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.trajectory.csv_io import JointTrajectorySamples
from workbench.trajectory.limits import (
    JointExtrema,
    LimitViolation,
    _require_vector_space,
    check_limits,
)
from workbench.trajectory.normal_spline import DEFAULT_N_POINTS
from workbench.trajectory.pick_and_place import (
    JointTrajectory,
    check_duration,
    pick_and_place,
    sample_uniform,
)
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True, eq=False)
class SegmentedTrajectory:
    """Rest-to-rest segments one after the other, with dwells between them.

    Attributes:
        segments: The motions, each starting at its own t = 0.
        start_times: When each segment starts, shape (M,) [s], read-only.
        duration: Total time, motions plus dwells [s].
    """

    segments: tuple[JointTrajectory, ...]
    start_times: FloatArray
    duration: float

    @property
    def robot(self) -> Robot:
        """The robot whose limits apply."""
        return self.segments[0].robot

    def sample(self, t: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(q, qd, qdd)`` at ``t`` [s]: (nq,) each for a scalar, else (K, nq).

        During a dwell the robot is at rest at the via point; ``t`` is clamped
        into [0, duration].

        Raises:
            NonFiniteError: If ``t`` holds NaN or infinity.
        """
        t = np.asarray(t, dtype=np.float64)
        flat = t.reshape(-1)
        index = np.searchsorted(self.start_times, flat, side="right") - 1
        np.clip(index, 0, len(self.segments) - 1, out=index)
        nq = self.robot.nq
        out = [np.empty((flat.size, nq)) for _ in range(3)]
        for i, segment in enumerate(self.segments):
            mask = index == i
            if mask.any():
                values = segment.sample(flat[mask] - self.start_times[i])
                for dst, src in zip(out, values, strict=True):
                    dst[mask] = src
        return tuple(x.reshape((*t.shape, nq)) for x in out)  # type: ignore[return-value]

    def sample_uniform(self, rate_hz: float) -> JointTrajectorySamples:
        """Samples at ``rate_hz`` from 0 to ``duration``, both ends included."""
        return sample_uniform(self, rate_hz)

    def get_extrema(self, order: int) -> JointExtrema:
        """Exact per-joint extremes of q (0), q̇ (1), q̈ (2) over the whole chain."""
        parts = []
        for start, segment in zip(self.start_times, self.segments, strict=True):
            ext = segment.get_extrema(order)
            parts.append(
                JointExtrema(
                    ext.minimum,
                    ext.t_minimum + start,
                    ext.maximum,
                    ext.t_maximum + start,
                )
            )
        return JointExtrema.combine(parts)

    def check_limits(self) -> list[LimitViolation]:
        """Every limit the chain leaves (exact extremes, times on its clock)."""
        return check_limits(self)


def pick_via_place(
    robot: Robot,
    waypoints: npt.ArrayLike,
    durations: npt.ArrayLike,
    *,
    dwell_times: npt.ArrayLike | float = 0.0,
    n_points: int = DEFAULT_N_POINTS,
) -> SegmentedTrajectory:
    """Chain normal-spline motions through via configurations, resting at each.

    Args:
        robot: Any robot with nq == nv.
        waypoints: Pick, via points, place: shape (M + 1, nq) [rad], M >= 1.
        durations: Motion time of each segment, shape (M,) [s], each > 0 (use
            :func:`~workbench.trajectory.minimum_duration` per segment for the
            fastest feasible chain).
        dwell_times: Rest at each via point, scalar or shape (M - 1,) [s], >= 0.
        n_points: Knots of the normal spline.

    Returns:
        The chained trajectory, C² everywhere (every joint at rest with zero
        acceleration at each waypoint).

    Raises:
        DimensionError: If a shape is wrong.
        NonFiniteError: If a value is NaN or infinite.
        InputError: If a duration is not > 0, a dwell is negative, fewer than
            two waypoints are given or the robot has nq != nv.
    """
    _require_vector_space(robot)
    points = np.asarray(waypoints, dtype=np.float64)
    if points.ndim != 2 or points.shape[0] < 2:
        raise InputError(
            f"waypoints must have shape (M + 1, {robot.nq}) with M >= 1, "
            f"got shape {points.shape}"
        )
    points = as_finite_array(points, (points.shape[0], robot.nq), "waypoints")
    m = points.shape[0] - 1
    times = as_finite_array(durations, (m,), "durations")
    for i, value in enumerate(times):
        check_duration(value, f"durations[{i}]")
    if np.ndim(dwell_times) == 0:
        dwell = np.full(m - 1, float(as_finite_array(dwell_times, (), "dwell_times")))
    else:
        dwell = as_finite_array(dwell_times, (m - 1,), "dwell_times")
    if (dwell < 0.0).any():
        raise InputError(f"dwell_times must be >= 0 [s], got {dwell.tolist()}")
    segments = tuple(
        pick_and_place(robot, points[i], points[i + 1], times[i], n_points=n_points)
        for i in range(m)
    )
    starts = np.concatenate([[0.0], np.cumsum(times[:-1] + dwell)])
    starts.setflags(write=False)
    return SegmentedTrajectory(segments, starts, float(starts[-1] + times[-1]))
