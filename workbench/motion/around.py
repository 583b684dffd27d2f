"""Around the obstacles: a pick-and-place whose direct spline collides, planned anew.

Angeles' pick-and-place (:func:`workbench.trajectory.pick_and_place`) moves
every joint along the straight segment from the pick to the place
configuration, timed by the normal spline; the paper left the obstacles to a
person watching a display. :func:`plan_around` checks that direct trajectory
in the scene (exact meshes, proven between the samples) and, when it is not
free, plans a collision-free motion between the same two configurations with
:func:`workbench.motion.plan`: RRT-Connect on the sphere model, shortened,
time-scaled within the joint limits (C², at rest at both ends, as the spline)
and verified on the exact meshes. The :class:`PlannedAround` record keeps
both, so the motion before (how deep it went into what) and after (its
clearance and duration) can be compared.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.collision.checker import CollisionChecker
from workbench.collision.clearance_report import PathClearance
from workbench.collision.scene import Scene
from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.motion.planner import MotionPlan, plan, require_acceleration_limits
from workbench.motion.spheres import SphereModel
from workbench.motion.timing import WaypointTrajectory
from workbench.progress import StageProgress
from workbench.trajectory.pick_and_place import JointTrajectory

FloatArray = npt.NDArray[np.float64]

#: Default rate [Hz] of the direct trajectory's check (``plan pick-place --rate``).
DEFAULT_RATE_HZ = 100.0


@dataclass(frozen=True, slots=True, eq=False)
class PlannedAround:
    """Outcome of :func:`plan_around`: the direct trajectory and what replaces it.

    Attributes:
        direct: The pick-and-place trajectory given (Angeles' spline).
        direct_clearance: Its clearance in the scene (exact meshes, proven
            between samples at ``rate_hz``).
        plan: The motion planned between its two ends; None when the direct
            trajectory is proven free (nothing to plan around).
        rate_hz: Sample rate [Hz] of the direct trajectory's check.
    """

    direct: JointTrajectory
    direct_clearance: PathClearance
    plan: MotionPlan | None
    rate_hz: float

    @property
    def needed(self) -> bool:
        """True when the direct trajectory is not proven free (a plan was made)."""
        return self.plan is not None

    @property
    def solved(self) -> bool:
        """True when there is a collision-free motion to run (:attr:`trajectory`)."""
        return self.plan is None or self.plan.solved

    @property
    def trajectory(self) -> WaypointTrajectory | JointTrajectory | None:
        """The motion to run: the planned one, the direct one when it is free.

        None when a plan was needed and none was found.
        """
        if self.plan is None:
            return self.direct
        return self.plan.trajectory if self.plan.solved else None

    @property
    def waypoints(self) -> FloatArray:
        """Corners of the motion to run, (K, nq) [rad].

        The planned path's waypoints; pick and place (2, nq) for a free direct
        trajectory; (0, nq) when no motion was found.
        """
        if self.plan is None:
            return np.array([self.direct.q_pick, self.direct.q_place])
        return np.array(self.plan.waypoints)

    @property
    def penetration(self) -> float:
        """Deepest penetration of the direct trajectory [m], >= 0 (0: no contact)."""
        return self.get_penetration()

    def get_penetration(self, body: str | None = None) -> float:
        """Deepest penetration [m] of the direct trajectory, >= 0.

        Args:
            body: Only contacts of this body (an obstacle or a link, e.g.
                ``"obstacle"``); None: every contact.

        Returns:
            The largest depth of the contacts found (0 without contact).
        """
        depths = [
            -c.distance
            for c in self.direct_clearance.contacts
            if body is None or body in (c.body_a, c.body_b)
        ]
        return max([0.0, *depths])

    @property
    def clearance(self) -> float:
        """Smallest exact distance along the motion to run [m] (NaN: no motion)."""
        if self.plan is None:
            return self.direct_clearance.min_clearance
        return self.plan.min_clearance if self.plan.solved else math.nan

    @property
    def duration(self) -> float:
        """Duration of the motion to run [s] (NaN: no motion)."""
        motion = self.trajectory
        return math.nan if motion is None else float(motion.duration)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready keys (``avoided`` of ``workbench plan pick-place --avoid``).

        ``needed, solved, reason, detail, direct_penetration`` [m]``,
        direct_duration`` [s]``, waypoints`` (K, nq) [rad]``, path_length``
        [rad]``, duration`` [s]``, min_clearance, clearance_lower_bound`` [m]``,
        setup_time, planning_time, smoothing_time, verification_time`` [s]``,
        iterations, allowances`` (``[link, obstacle or link, m]``); numbers that
        do not exist (no motion found, no plan needed) are None.
        """
        result = self.plan
        solved = self.solved
        waypoints = self.waypoints
        report = (
            self.direct_clearance
            if result is None
            else (result.clearance if solved else None)
        )
        return {
            "needed": self.needed,
            "solved": solved,
            "reason": None if result is None else result.reason,
            "detail": "" if result is None else result.detail,
            "direct_penetration": self.penetration,
            "direct_duration": self.direct.duration,
            "waypoints": waypoints,
            "path_length": float(
                np.sum(np.linalg.norm(np.diff(waypoints, axis=0), axis=1))
            )
            if solved
            else None,
            "duration": self.duration if solved else None,
            "min_clearance": self.clearance if solved else None,
            "clearance_lower_bound": None
            if report is None
            else float(report.lower_bound),
            **{
                key: None if result is None else getattr(result, key)
                for key in (
                    "setup_time",
                    "planning_time",
                    "smoothing_time",
                    "verification_time",
                    "iterations",
                )
            },
            "allowances": []
            if result is None
            else [list(entry) for entry in result.allowances],
        }


def plan_around(
    robot: Robot,
    scene: Scene | None,
    direct: JointTrajectory,
    *,
    clearance: PathClearance | None = None,
    rate_hz: float = DEFAULT_RATE_HZ,
    seed: int = 0,
    time_limit: float = 1.0,
    spheres: SphereModel | None = None,
    progress: StageProgress | None = None,
) -> PlannedAround:
    """A collision-free motion from the pick to the place of a colliding spline.

    Args:
        robot: The robot of ``direct`` (same joints), with speed and
            acceleration limits for the time scaling
            (:meth:`~workbench.model.Robot.with_limits`).
        scene: Obstacles in the base frame, or None (self-collisions only).
        direct: The pick-and-place trajectory
            (:func:`workbench.trajectory.pick_and_place`); its ``q_pick`` and
            ``q_place`` (nq,) [rad] are the start and goal of the plan.
        clearance: ``direct``'s clearance in ``scene`` when already computed
            (``direct.check_collisions(CollisionChecker(robot, scene),
            rate_hz)``); None computes it.
        rate_hz: Sample rate [Hz] of the direct trajectory's check, > 0.
        seed: Seed of the planner (:func:`workbench.motion.plan`).
        time_limit: Planning budget [s], > 0.
        spheres: The sphere model; default the robot's
            (:func:`workbench.motion.planner.get_spheres`).
        progress: Called as ``progress(stage, done, total)`` while the
            robot's sphere model and pair tables are built
            (:func:`workbench.motion.plan`).

    Returns:
        The record. When ``direct`` is proven free, ``plan`` is None and the
        motion to run is ``direct`` itself; when no motion is found,
        ``solved`` is False and ``plan.reason`` says why ("start in
        collision", "goal in collision", "time limit", ...).

    Raises:
        InputError: ``direct`` is not a pick-and-place trajectory of the
            robot's joints, ``rate_hz`` is not finite and > 0, the robot has
            no acceleration limits, or a bad planner argument
            (:func:`workbench.motion.plan`).
    """
    if not isinstance(direct, JointTrajectory):
        raise InputError(
            "direct must be a pick-and-place JointTrajectory "
            f"(workbench.trajectory.pick_and_place), got {type(direct).__name__}"
        )
    if list(direct.robot.joint_names) != list(robot.joint_names):
        raise InputError(
            f"the direct trajectory moves the joints {list(direct.robot.joint_names)}, "
            f"the robot has {list(robot.joint_names)}"
        )
    if (
        isinstance(rate_hz, bool)
        or not isinstance(rate_hz, int | float)
        or not (math.isfinite(rate_hz) and rate_hz > 0.0)
    ):
        raise InputError(f"rate_hz must be a finite number > 0 [Hz], got {rate_hz!r}")
    if clearance is not None and not isinstance(clearance, PathClearance):
        raise InputError(
            f"clearance must be a PathClearance or None, got {type(clearance).__name__}"
        )
    require_acceleration_limits(robot, "planning around")
    if clearance is None:
        clearance = direct.check_collisions(
            CollisionChecker(robot, scene), float(rate_hz)
        )
    planned = (
        None
        if clearance.collision_free
        else plan(
            robot,
            scene,
            direct.q_pick,
            direct.q_place,
            seed=seed,
            time_limit=time_limit,
            spheres=spheres,
            progress=progress,
        )
    )
    return PlannedAround(direct, clearance, planned, float(rate_hz))


__all__ = ["DEFAULT_RATE_HZ", "PlannedAround", "plan_around"]
