r"""Pick and place given as Cartesian poses: IK at both ends, FK in between.

Angeles et al. (1988), Sections III and V: the two end poses are inverted
together (:func:`workbench.ik.pick_place_configurations`: closed form for the
arms of a known family, else numerically), the joint
trajectory is the scaled normal spline, and the Cartesian trajectory is its
forward kinematics, reported as the paper's seven numbers
``angeles7 = [e sinφ, cosφ, p]`` (Figs. 4–6). The tool twist is
:math:`J\dot q` and its derivative :math:`J\ddot q + \dot J\dot q` (eqs. (3),
(4)), from Pinocchio in the LOCAL_WORLD_ALIGNED frame; both vanish at t = 0
and t = T because :math:`\dot q` and :math:`\ddot q` do.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.ik import IKChoice, pick_place_configurations
from workbench.model.robot import Robot
from workbench.poses import ANGELES7_TOL, angeles7_from_se3, as_se3, se3_from_angeles7
from workbench.trajectory.normal_spline import DEFAULT_N_POINTS
from workbench.trajectory.pick_and_place import JointTrajectory, pick_and_place

FloatArray = npt.NDArray[np.float64]


class _Sampled(Protocol):
    @property
    def robot(self) -> Robot: ...

    def sample(self, t: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]: ...


@dataclass(frozen=True, slots=True, eq=False)
class PosePickAndPlace:
    """A pick-and-place motion planned from two Cartesian poses.

    Attributes:
        trajectory: The joint trajectory between the two IK solutions.
        pick: IK choice at the pick pose (:class:`workbench.ik.IKChoice`).
        place: IK choice at the place pose.
        pick_pose: Pick pose of the tool frame in the base frame.
        place_pose: Place pose.
    """

    trajectory: JointTrajectory
    pick: IKChoice
    place: IKChoice
    pick_pose: pin.SE3
    place_pose: pin.SE3


@dataclass(frozen=True, slots=True)
class CartesianSamples:
    r"""Tool-frame time histories, the paper's Figs. 4–6 plus velocity/acceleration.

    Attributes:
        t: Times, shape (K,) [s].
        angeles7: ``[e sinφ (3), cosφ, p (3) m]`` per time, shape (K, 7).
        velocity: Tool twist :math:`J\dot q`, shape (K, 6): linear velocity of
            the tool origin [m/s], then angular velocity [rad/s], base axes.
        acceleration: :math:`J\ddot q + \dot J\dot q`, shape (K, 6): linear
            acceleration of the tool origin [m/s²], angular acceleration
            [rad/s²], base axes.
    """

    t: FloatArray
    angeles7: FloatArray
    velocity: FloatArray
    acceleration: FloatArray


def as_target_pose(
    pose: pin.SE3 | npt.ArrayLike, *, angeles7_tol: float = ANGELES7_TOL
) -> pin.SE3:
    """A pose given as ``pin.SE3``, a (4, 4) matrix or angeles7 (7,), as SE3.

    Args:
        pose: Tool pose in the base frame; positions in metres.
        angeles7_tol: Norm tolerance for angeles7 input (pass
            ``poses.ANGELES7_PRINTED_TOL`` for numbers printed to 2 decimals).

    Raises:
        InputError: If the shape is neither (7,) nor (4, 4), or the pose is not
            rigid / not unit norm (``NonFiniteError`` on NaN).
    """
    if isinstance(pose, pin.SE3):
        return as_se3(pose)
    try:
        shape = np.shape(pose)
    except (TypeError, ValueError):
        shape = None
    if shape == (7,):
        return se3_from_angeles7(pose, tol=angeles7_tol)
    if shape == (4, 4):
        return as_se3(pose)
    raise InputError(
        "pose must be a pinocchio.SE3, a (4, 4) homogeneous matrix or angeles7 "
        f"(7 numbers), got shape {shape}"
    )


def pick_and_place_from_poses(
    robot: Robot,
    pick: pin.SE3 | npt.ArrayLike,
    place: pin.SE3 | npt.ArrayLike,
    duration: float,
    *,
    rule: str | None = None,
    q_near: npt.ArrayLike | None = None,
    branch: str | None = None,
    redundancy: float | None = None,
    criterion: str | None = None,
    angeles7_tol: float = ANGELES7_TOL,
    n_points: int = DEFAULT_N_POINTS,
) -> PosePickAndPlace:
    """Angeles' pick-and-place from two tool poses: IK, then the joint spline.

    The configurations are :func:`workbench.ik.pick_place_configurations`'s
    (the same as ``workbench plan pick-place`` from the same poses): both on
    the branch that serves both with the largest joint-limit margin, unless
    ``rule``, ``q_near`` or ``branch`` say otherwise.

    Args:
        robot: The robot.
        pick: Pick pose: ``pin.SE3``, (4, 4) matrix or angeles7 (7,) [m].
        place: Place pose, same forms.
        duration: T [s], > 0.
        rule: The selection rule (``workbench.ik.RULES``), None for the default.
        q_near: Configuration (nq,) [rad] the motion starts from.
        branch: The branch of both poses (rule ``"branch"``).
        redundancy: Seven-axis arms: both poses at this value [rad].
        criterion: Seven-axis arms without ``redundancy``: how the values are
            chosen (``ik.choose_redundancy``).
        angeles7_tol: Norm tolerance for angeles7 input.
        n_points: Knots of the normal spline.

    Raises:
        InputError: As :func:`workbench.ik.pick_place_configurations` and
            :func:`~workbench.trajectory.pick_and_place`.
        InfeasibleError: If a pose cannot be inverted within the limits.
    """
    pick_pose = as_target_pose(pick, angeles7_tol=angeles7_tol)
    place_pose = as_target_pose(place, angeles7_tol=angeles7_tol)
    first, second = pick_place_configurations(
        robot,
        pick_pose,
        place_pose,
        rule=rule,
        q_near=q_near,
        branch=branch,
        redundancy=redundancy,
        criterion=criterion,
    )
    traj = pick_and_place(robot, first.q, second.q, duration, n_points=n_points)
    return PosePickAndPlace(traj, first, second, pick_pose, place_pose)


def compute_cartesian_trajectory(
    trajectory: _Sampled, t: npt.ArrayLike
) -> CartesianSamples:
    """Forward kinematics along a joint trajectory: pose, twist and acceleration.

    Args:
        trajectory: Anything with ``robot`` and ``sample(t) -> (q, qd, qdd)``,
            e.g. a :class:`~workbench.trajectory.JointTrajectory`.
        t: Times, shape (K,) [s].

    Returns:
        Tool-frame samples (see :class:`CartesianSamples`).

    Raises:
        NonFiniteError: If ``t`` holds NaN or infinity.
    """
    times = np.atleast_1d(np.asarray(t, dtype=np.float64))
    q, qd, qdd = trajectory.sample(times)
    robot = trajectory.robot
    model, data, frame = robot.model, robot.data, robot.tool_frame_id
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    k = times.size
    pose7, vel, acc = np.empty((k, 7)), np.empty((k, 6)), np.empty((k, 6))
    for i in range(k):
        pin.computeJointJacobiansTimeVariation(model, data, q[i], qd[i])
        pin.updateFramePlacements(model, data)
        jac = pin.getFrameJacobian(model, data, frame, lwa)
        jac_dot = pin.getFrameJacobianTimeVariation(model, data, frame, lwa)
        pose7[i] = angeles7_from_se3(data.oMf[frame])
        vel[i] = jac @ qd[i]
        acc[i] = jac @ qdd[i] + jac_dot @ qd[i]
    return CartesianSamples(times, pose7, vel, acc)
