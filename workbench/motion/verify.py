r"""A trajectory checked on the exact meshes, with nothing missed between samples.

:func:`verify_trajectory` samples a trajectory at equal time steps so short
that no joint moves more than ``max_step`` between two samples (the step is
``max_step`` over the largest peak joint speed), computes the distances of
every body pair with coal at the samples, and proves the intervals between
them with :func:`workbench.collision.check_path`'s lower bound, from the
trajectory's exact peak joint speeds and accelerations: the report's
``lower_bound`` holds for the whole continuous motion, and its contacts are
those of the real meshes.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
import numpy.typing as npt

from workbench.collision import CollisionChecker, PathClearance, check_path
from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.trajectory import JointExtrema, check_sample_count

FloatArray = npt.NDArray[np.float64]

#: Default largest joint step between two samples [rad] (0.25°).
DEFAULT_MAX_STEP = math.radians(0.25)


class _Trajectory(Protocol):
    """A joint trajectory with exact extremes (WaypointTrajectory, JointTrajectory)."""

    @property
    def robot(self) -> Robot: ...  # pragma: no cover

    @property
    def duration(self) -> float: ...  # pragma: no cover

    def sample(
        self, t: npt.ArrayLike
    ) -> tuple[FloatArray, FloatArray, FloatArray]: ...  # pragma: no cover

    def get_extrema(self, order: int) -> JointExtrema: ...  # pragma: no cover


def verify_trajectory(
    checker: CollisionChecker,
    trajectory: _Trajectory,
    *,
    max_step: float = DEFAULT_MAX_STEP,
) -> PathClearance:
    """Clearance of the whole motion on the exact meshes (module docstring).

    Args:
        checker: The robot (the trajectory's), its scene and body pairs.
        trajectory: Any trajectory with ``robot``, ``duration`` [s],
            ``sample(t)`` and exact ``get_extrema(order)``, e.g. a
            :class:`~workbench.motion.WaypointTrajectory` of
            :func:`~workbench.motion.time_scale`.
        max_step: Largest joint motion between two samples [rad], finite
            and > 0 (default :data:`DEFAULT_MAX_STEP`, 0.25°).

    Returns:
        The report: ``collision_free`` when no contact is found and its
        ``lower_bound`` > 0 proves the motion free between the samples.

    Raises:
        InputError: If ``max_step`` is not finite and > 0, the checker's
            robot has another joint count, or more than
            :data:`~workbench.trajectory.MAX_SAMPLES` samples would be needed.
    """
    if (
        isinstance(max_step, bool)
        or not isinstance(max_step, int | float)
        or not (math.isfinite(max_step) and max_step > 0.0)
    ):
        raise InputError(
            f"max_step must be a finite number > 0 [rad], got {max_step!r}"
        )
    if checker.robot.nq != trajectory.robot.nq:
        raise InputError(
            f"the checker's robot has {checker.robot.nq} joints, the "
            f"trajectory's {trajectory.robot.nq}"
        )
    speed = trajectory.get_extrema(1).peak
    acceleration = trajectory.get_extrema(2).peak
    duration = float(trajectory.duration)
    steps = max(1, math.ceil(duration * float(speed.max()) / max_step))
    check_sample_count(steps + 1, "verify_trajectory")
    t = np.linspace(0.0, duration, steps + 1)
    q = trajectory.sample(t)[0]
    return check_path(
        checker,
        t,
        q,
        sample=lambda s: trajectory.sample(s)[0],
        max_joint_speed=speed,
        max_joint_acceleration=acceleration,
    )
