r"""Joint-space pick-and-place trajectory: the normal spline scaled per joint.

Eq. (9) of Angeles et al. (1988): with :math:`t' = t/T`,

.. math::

    q(t) = q_\mathrm{pick} + (q_\mathrm{place} - q_\mathrm{pick})\,s(t'),\quad
    \dot q = \frac{\Delta q}{T}\,\dot s,\quad
    \ddot q = \frac{\Delta q}{T^2}\,\ddot s,

so every joint starts and stops with zero speed and acceleration, and by
eqs. (3)–(4) so does the tool, even at a singular configuration. The robot
must have one coordinate per joint (nq == nv: revolute and prismatic joints);
there the affine form equals ``pin.integrate(q_pick, Δq·s)`` and is used
directly because it vectorises.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import numpy.typing as npt

from workbench.collision import (
    CollisionChecker,
    PathClearance,
    check_path,
    get_pick_and_place_scene,
)
from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.trajectory.csv_io import JointTrajectorySamples
from workbench.trajectory.limits import (
    JointExtrema,
    LimitViolation,
    _require_vector_space,
    check_limits,
)
from workbench.trajectory.normal_spline import (
    DEFAULT_N_POINTS,
    NormalSpline,
    SplineExtremum,
    get_normal_spline,
)
from workbench.validation import as_vector

FloatArray = npt.NDArray[np.float64]

#: Default rate [Hz] of :meth:`JointTrajectory.check_collisions`'s distance
#: samples (``workbench plan pick-place --rate``'s default).
COLLISION_RATE_HZ = 100.0


class _Sampleable(Protocol):
    """A trajectory sampled by time over [0, duration] (JointTrajectory, ...)."""

    @property
    def duration(self) -> float: ...  # pragma: no cover

    def sample(
        self, t: npt.ArrayLike
    ) -> tuple[FloatArray, FloatArray, FloatArray]: ...  # pragma: no cover


def check_duration(duration: float, name: str = "duration") -> float:
    """Return ``duration`` as a float if it is finite and > 0 [s].

    Raises:
        InputError: Otherwise (zero, negative, NaN, infinite, not a number).
    """
    try:
        value = float(duration)
    except (TypeError, ValueError):
        raise InputError(
            f"{name} must be a number of seconds, got {duration!r}"
        ) from None
    if not (math.isfinite(value) and value > 0.0):
        raise InputError(f"{name} must be a finite number > 0 [s], got {duration!r}")
    return value


def _read_only(values: FloatArray) -> FloatArray:
    arr = np.array(values, dtype=np.float64)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, slots=True, eq=False)
class JointTrajectory:
    """A pick-and-place motion from rest to rest: scaled normal spline per joint.

    Build one with :func:`pick_and_place`. Before t = 0 and after
    ``duration`` the robot is at rest at the pick / place configuration.

    Attributes:
        robot: The robot whose limits apply.
        q_pick: Start configuration, shape (nq,) [rad], read-only.
        q_place: End configuration, shape (nq,) [rad], read-only.
        duration: T [s], > 0.
        spline: The normal spline s(t') shared by all joints.
    """

    robot: Robot
    q_pick: FloatArray
    q_place: FloatArray
    duration: float
    spline: NormalSpline

    @property
    def displacement(self) -> FloatArray:
        """``q_place - q_pick``, shape (nq,) [rad]."""
        return self.q_place - self.q_pick

    def sample(self, t: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Positions, velocities and accelerations at time(s) ``t``.

        Exact evaluation of the piecewise cubic (no interpolation of samples).

        Args:
            t: Time [s], scalar or shape (K,); clamped into [0, duration].

        Returns:
            ``(q, qd, qdd)`` [rad, rad/s, rad/s²], each (nq,) for a scalar
            ``t``, else (K, nq) (Fortran-ordered: transposed views of
            joint-major arrays).

        Raises:
            NonFiniteError: If ``t`` holds NaN or infinity.
        """
        T = self.duration
        s, sd, sdd = self.spline.evaluate(np.asarray(t, dtype=np.float64) / T)
        return _scale(s, sd, sdd, self.q_pick, self.q_place - self.q_pick, T)

    def jerk(self, t: npt.ArrayLike) -> FloatArray:
        """Joint jerk [rad/s³] at ``t``: (nq,) or (K, nq), piecewise constant."""
        T = self.duration
        j = self.spline.jerk(np.asarray(t, dtype=np.float64) / T)
        return np.multiply.outer(j, self.displacement / T**3)

    def sample_uniform(self, rate_hz: float) -> JointTrajectorySamples:
        """Samples at ``rate_hz`` from 0 to ``duration``, both ends included.

        The last step is shorter when ``duration · rate_hz`` is not an integer.

        Raises:
            InputError: If ``rate_hz`` is not finite and > 0.
        """
        return sample_uniform(self, rate_hz)

    def get_extrema(self, order: int) -> JointExtrema:
        """Exact per-joint extremes of q (0), q̇ (1) or q̈ (2) over [0, T].

        Raises:
            InputError: If ``order`` is not 0, 1 or 2.
        """
        if order not in (0, 1, 2):
            raise InputError(f"order must be 0, 1 or 2, got {order!r}")
        ext: SplineExtremum = (
            self.spline.position,
            self.spline.velocity,
            self.spline.acceleration,
        )[order]
        T = self.duration
        gain = self.displacement / T**order
        up = gain >= 0.0
        at_max = gain * ext.maximum
        at_min = gain * ext.minimum
        offset = self.q_pick if order == 0 else 0.0
        return JointExtrema(
            minimum=np.where(up, at_min, at_max) + offset,
            t_minimum=np.where(up, ext.t_minimum, ext.t_maximum) * T,
            maximum=np.where(up, at_max, at_min) + offset,
            t_maximum=np.where(up, ext.t_maximum, ext.t_minimum) * T,
        )

    def check_limits(self) -> list[LimitViolation]:
        """Every position, speed and acceleration limit left (exact extremes)."""
        return check_limits(self)

    def check_collisions(
        self,
        checker: CollisionChecker | None = None,
        rate_hz: float = COLLISION_RATE_HZ,
    ) -> PathClearance:
        """Clearance along the whole motion, not only at the samples.

        Distances are computed at ``rate_hz`` samples; between them the
        spline's exact peak speeds and accelerations bound how far any point
        can move (:func:`workbench.collision.check_path`).

        Args:
            checker: Robot (this trajectory's), scene and body pairs; None
                checks the default scene of a pick-and-place,
                :func:`workbench.collision.get_pick_and_place_scene` (as
                ``workbench plan pick-place`` without ``--scene``).
            rate_hz: Sampling rate of the distance computations [Hz], > 0
                (default :data:`COLLISION_RATE_HZ`, the command's ``--rate``).

        Raises:
            InputError: If ``checker`` is None and the robot has no collision
                geometry.
        """
        if checker is None:
            checker = CollisionChecker(self.robot, get_pick_and_place_scene(self.robot))
        grid = self.sample_uniform(rate_hz)
        return check_path(
            checker,
            grid.t,
            grid.q,
            sample=lambda t: self.sample(t)[0],
            max_joint_speed=self.get_extrema(1).peak,
            max_joint_acceleration=self.get_extrema(2).peak,
        )


def _scale(
    s: FloatArray,
    sd: FloatArray,
    sdd: FloatArray,
    q0: FloatArray,
    dq: FloatArray,
    T: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """q0 + dq·s, dq·ṡ/T, dq·s̈/T², shape s.shape + (nq,).

    Computed joint-major, (nq, K), and returned transposed: broadcasting along
    the long axis is ~7x faster than along a 6-wide one.
    """
    if s.ndim == 0:
        return q0 + dq * s, dq * (sd / T), dq * (sdd / (T * T))
    shape = (-1,) + (1,) * s.ndim
    col = dq.reshape(shape)
    q = col * s
    q += q0.reshape(shape)
    qd = (col / T) * sd
    qdd = (col / (T * T)) * sdd
    return np.moveaxis(q, 0, -1), np.moveaxis(qd, 0, -1), np.moveaxis(qdd, 0, -1)


def sample_uniform(trajectory: _Sampleable, rate_hz: float) -> JointTrajectorySamples:
    """Samples of ``trajectory`` at ``rate_hz`` from 0 to its duration, ends included.

    The last step is shorter when ``duration · rate_hz`` is not an integer.
    What the trajectory CSV writer and the exports take, from any trajectory
    with ``duration`` [s] and ``sample(t) -> (q, qd, qdd)``.

    Raises:
        InputError: If ``rate_hz`` is not finite and > 0.
    """
    duration = trajectory.duration
    try:
        rate = float(rate_hz)
    except (TypeError, ValueError):
        raise InputError(f"rate_hz must be a number, got {rate_hz!r}") from None
    if not (math.isfinite(rate) and rate > 0.0):
        raise InputError(f"rate_hz must be a finite number > 0 [Hz], got {rate_hz!r}")
    steps = math.floor(duration * rate + 1e-9)
    t = np.arange(steps + 1) / rate
    if duration - t[-1] > 1e-9 / rate:
        t = np.append(t, duration)
    else:
        t[-1] = duration
    q, qd, qdd = trajectory.sample(t)
    return JointTrajectorySamples(t=t, q=q, qd=qd, qdd=qdd)


def pick_and_place(
    robot: Robot,
    q_pick: npt.ArrayLike,
    q_place: npt.ArrayLike,
    duration: float,
    *,
    n_points: int = DEFAULT_N_POINTS,
) -> JointTrajectory:
    """Angeles' smooth pick-and-place trajectory between two configurations.

    Every joint follows the normal spline (see
    :func:`~workbench.trajectory.compute_normal_spline`) scaled to its own
    displacement, so all joints start and stop together, at rest, with zero
    acceleration. Limits are not enforced here: call
    :meth:`JointTrajectory.check_limits` or
    :func:`~workbench.trajectory.minimum_duration`.

    Args:
        robot: Any robot with one coordinate per joint (nq == nv).
        q_pick: Start configuration, shape (nq,) [rad].
        q_place: End configuration, shape (nq,) [rad].
        duration: T [s], finite and > 0.
        n_points: Knots N of the normal spline (>= 4; default 40 as the paper).

    Returns:
        The trajectory; ``sample(t)`` gives (q, qd, qdd).

    Raises:
        DimensionError: If a configuration does not have nq values.
        NonFiniteError: If a configuration holds NaN or infinity.
        InputError: If ``duration`` is not finite and > 0, ``n_points`` is not
            an int >= 4, or the robot has nq != nv.
    """
    _require_vector_space(robot)
    q0 = as_vector(q_pick, robot.nq, "q_pick")
    q1 = as_vector(q_place, robot.nq, "q_place")
    T = check_duration(duration)
    return JointTrajectory(
        robot=robot,
        q_pick=_read_only(q0),
        q_place=_read_only(q1),
        duration=T,
        spline=get_normal_spline(n_points),
    )
