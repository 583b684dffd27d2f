r"""Pick and place given as Cartesian poses: IK at both ends, FK in between.

Angeles et al. (1988), Sections III and V: the two end poses are inverted
once each (closed form for the PUMA models, else numerically), the joint
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

from workbench.errors import InfeasibleError, InputError
from workbench.model.robot import Robot
from workbench.poses import ANGELES7_TOL, angeles7_from_se3, as_se3, se3_from_angeles7
from workbench.trajectory.normal_spline import DEFAULT_N_POINTS
from workbench.trajectory.pick_and_place import JointTrajectory, pick_and_place

FloatArray = npt.NDArray[np.float64]

NUMERIC_BRANCH = "numeric"
"""Branch label of a solution found by the numerical IK."""

_LIMIT_TOL = 1e-9  # [rad]: slack of ``within_limits`` for numerical solutions


class _Sampled(Protocol):
    @property
    def robot(self) -> Robot: ...

    def sample(self, t: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]: ...


@dataclass(frozen=True, slots=True)
class IKChoice:
    """The IK solution chosen for one end pose.

    Attributes:
        q: Configuration, shape (nq,) [rad], read-only.
        branch: Closed-form branch label (e.g. ``"right/elbow-up/no-flip"``) or
            ``"numeric"``.
        within_limits: True if every joint is within its position limits.
        rule: How it was chosen: ``"branch"``, ``"nearest"``,
            ``"first-within-limits"``, ``"largest-limit-margin"`` (seven-axis
            arms without ``q_near``: the branch and the value of the redundancy
            parameter that ``ik.choose_redundancy`` picks) or ``"numeric"``
            (the numerical IK).
    """

    q: FloatArray
    branch: str
    within_limits: bool
    rule: str


@dataclass(frozen=True, slots=True, eq=False)
class PosePickAndPlace:
    """A pick-and-place motion planned from two Cartesian poses.

    Attributes:
        trajectory: The joint trajectory between the two IK solutions.
        pick: IK choice at the pick pose.
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


def _within(robot: Robot, q: FloatArray) -> bool:
    return bool(
        np.all(q >= robot.lower - _LIMIT_TOL) and np.all(q <= robot.upper + _LIMIT_TOL)
    )


def select_ik_solution(
    robot: Robot,
    pose: pin.SE3 | npt.ArrayLike,
    *,
    branch: str | None = None,
    q_near: npt.ArrayLike | None = None,
    angeles7_tol: float = ANGELES7_TOL,
) -> IKChoice:
    """Invert one end pose and choose one solution.

    Closed form (``ik.analytic``) for the arms that have one (OPW and UR-type
    six-axis arms; SRS and Franka seven-axis arms at the redundancy parameter
    of ``q_near``, else at the value and branch of the largest joint-limit
    margin, ``ik.choose_redundancy``), else ``ik.numeric``.
    Rule, first that applies: ``branch`` given → that closed-form branch;
    ``q_near`` given → the solution nearest to it (angles compared modulo 2π,
    each angle the representative nearest ``q_near``), within limits or not;
    else the first branch within the joint limits. The numerical IK starts
    from ``q_near`` (default mid-range).

    Args:
        robot: The robot.
        pose: Tool pose: ``pin.SE3``, (4, 4) matrix or angeles7 (7,) [m].
        branch: Closed-form label, e.g. ``"right/elbow-down/no-flip"``.
        q_near: Configuration (nq,) [rad] to stay close to.
        angeles7_tol: See :func:`as_target_pose`.

    Raises:
        InputError: Bad pose or ``q_near``, unknown ``branch`` (the message
            lists the valid ones) or ``branch`` for a robot without closed form.
        InfeasibleError: Pose out of reach, no branch within limits, or the
            numerical IK did not converge.
    """
    target = as_target_pose(pose, angeles7_tol=angeles7_tol)
    near = None if q_near is None else robot.check_configuration(q_near)
    from workbench.ik import closed_form, get_family

    family = get_family(robot)  # any arm of a closed-form family, else None
    if family is not None:
        if near is None and family.redundant:  # a seven-axis arm: choose its value
            return _most_inside(robot, target, branch)
        solutions = closed_form.analytic(robot, target, q_previous=near)
        return _choose(robot, solutions, branch, near, closed_form)
    if branch is not None:
        raise InputError(
            f"branch {branch!r} given, but robot {robot.name} has no closed-form IK"
        )
    from workbench.ik.numerical import numeric

    result = numeric(robot, target, q0=near)
    if not result.success:
        raise InfeasibleError(
            f"numerical IK did not reach the pose (error {result.error:.3g} after "
            f"{result.iterations} iterations)"
        )
    q = np.array(result.q)
    q.setflags(write=False)
    return IKChoice(q, NUMERIC_BRANCH, _within(robot, q), "numeric")


def _most_inside(robot: Robot, target: pin.SE3, branch: str | None) -> IKChoice:
    """A seven-axis arm's branch and parameter with the largest limit margin.

    Raises:
        UnsupportedRobotError: If the arm has no closed form.
        InputError: If ``branch`` is not one of its labels.
        InfeasibleError: If no value of the parameter puts a branch (or
            ``branch``) within the limits.
    """
    from workbench.ik import choose_redundancy

    chosen = choose_redundancy(robot, target, branch=branch).solution
    rule = "largest-limit-margin" if branch is None else "branch"
    return IKChoice(chosen.q, chosen.branch, bool(chosen.within_limits), rule)


def _choose(robot, solutions, branch, near, closed_form) -> IKChoice:
    if branch is not None:
        labels = [s.branch for s in solutions]
        if branch not in labels:
            raise InputError(f"unknown branch {branch!r}; valid: {', '.join(labels)}")
        chosen, rule = solutions[labels.index(branch)], "branch"
    elif near is not None:
        chosen, rule = closed_form.nearest(solutions, near), "nearest"
    else:
        inside = [s for s in solutions if s.within_limits]
        if not inside:
            raise InfeasibleError(
                "no closed-form IK branch is within the joint limits; pick one "
                "with branch=... or q_near=..."
            )
        chosen, rule = inside[0], "first-within-limits"
    return IKChoice(chosen.q, chosen.branch, bool(chosen.within_limits), rule)


def pick_and_place_from_poses(
    robot: Robot,
    pick: pin.SE3 | npt.ArrayLike,
    place: pin.SE3 | npt.ArrayLike,
    duration: float,
    *,
    pick_branch: str | None = None,
    place_branch: str | None = None,
    pick_near: npt.ArrayLike | None = None,
    place_near: npt.ArrayLike | None = None,
    angeles7_tol: float = ANGELES7_TOL,
    n_points: int = DEFAULT_N_POINTS,
) -> PosePickAndPlace:
    """Angeles' pick-and-place from two tool poses: IK, then the joint spline.

    Args:
        robot: The robot.
        pick: Pick pose: ``pin.SE3``, (4, 4) matrix or angeles7 (7,) [m].
        place: Place pose, same forms.
        duration: T [s], > 0.
        pick_branch: Branch rule for the pick, see :func:`select_ik_solution`.
        place_branch: Branch rule for the place.
        pick_near: Configuration (nq,) [rad] the pick solution should be near.
        place_near: Same for the place.
        angeles7_tol: Norm tolerance for angeles7 input.
        n_points: Knots of the normal spline.

    Raises:
        InputError: As :func:`select_ik_solution` and
            :func:`~workbench.trajectory.pick_and_place`.
        InfeasibleError: If a pose cannot be inverted.
    """
    pick_pose = as_target_pose(pick, angeles7_tol=angeles7_tol)
    place_pose = as_target_pose(place, angeles7_tol=angeles7_tol)
    first = select_ik_solution(robot, pick_pose, branch=pick_branch, q_near=pick_near)
    second = select_ik_solution(
        robot, place_pose, branch=place_branch, q_near=place_near
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
