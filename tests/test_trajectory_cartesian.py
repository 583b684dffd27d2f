"""Pick and place from Cartesian poses: IK choice, FK histories, tool rates."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from conftest import random_configurations

from workbench import (
    InfeasibleError,
    InputError,
    ik,
    load_robot,
    paper_data,
    trajectory,
)
from workbench.poses import ANGELES7_PRINTED_TOL, angeles7_from_se3, se3_from_angeles7

ATOL_ENDS = 1e-9
ATOL_FD = 1e-5
Q3_PICK = np.deg2rad(paper_data.ANGELES_PICK_Q_DEG)
Q3_PLACE = np.deg2rad(paper_data.ANGELES_PLACE_Q_DEG)
T = paper_data.ANGELES_DURATION


@pytest.fixture(scope="module")
def table2(puma):
    return trajectory.pick_and_place_from_poses(
        puma,
        paper_data.ANGELES_PICK_ANGELES7,
        paper_data.ANGELES_PLACE_ANGELES7,
        T,
        angeles7_tol=ANGELES7_PRINTED_TOL,
    )


def _nearest(robot, printed, q3):
    target = se3_from_angeles7(printed, tol=ANGELES7_PRINTED_TOL)
    return ik.nearest(ik.analytic(robot, target, q_previous=q3), q3)


def test_table2_inverts_to_table3_branches(puma) -> None:
    pick = _nearest(puma, paper_data.ANGELES_PICK_ANGELES7, Q3_PICK)
    place = _nearest(puma, paper_data.ANGELES_PLACE_ANGELES7, Q3_PLACE)
    assert pick.branch == "right/elbow-down/no-flip"
    assert place.branch == "right/elbow-up/flip"
    # Table II is printed to two decimals: IK lands within 1 deg of Table III
    assert np.abs(np.rad2deg(pick.q) - paper_data.ANGELES_PICK_Q_DEG).max() < 1
    assert np.abs(np.rad2deg(place.q) - paper_data.ANGELES_PLACE_Q_DEG).max() < 1
    # ...and joint 2 of the pick lands a hair above its 45 deg limit
    assert not pick.within_limits
    (violation,) = trajectory.pick_and_place(puma, pick.q, place.q, T).check_limits()
    assert (violation.joint, violation.kind, violation.t) == ("joint2", "position", 0)
    assert 0 < np.rad2deg(violation.value - violation.limit) < 1e-3


def test_from_poses_is_the_selection_rule(puma, table2) -> None:
    """Both ends on one branch within the limits: ik.pick_place_configurations."""
    pick, place = ik.pick_place_configurations(
        puma,
        se3_from_angeles7(paper_data.ANGELES_PICK_ANGELES7, tol=ANGELES7_PRINTED_TOL),
        se3_from_angeles7(paper_data.ANGELES_PLACE_ANGELES7, tol=ANGELES7_PRINTED_TOL),
    )
    assert table2.pick.branch == table2.place.branch == pick.branch == place.branch
    assert table2.pick.rule == "limit_margin"
    assert table2.pick.within_limits and table2.place.within_limits
    assert np.array_equal(table2.pick.q, pick.q)
    assert np.array_equal(table2.place.q, place.q)
    assert table2.trajectory.check_limits() == []


def test_cartesian_rates_vanish_at_both_ends(table2) -> None:
    cart = trajectory.compute_cartesian_trajectory(table2.trajectory, [0.0, T])
    ends = np.concatenate([cart.velocity, cart.acceleration])
    np.testing.assert_allclose(ends, 0.0, rtol=0, atol=ATOL_ENDS)
    # and the end poses are the (normalised) Table II poses
    poses = (table2.pick_pose, table2.place_pose)
    for pose7, target in zip(cart.angeles7, poses, strict=True):
        np.testing.assert_allclose(pose7, angeles7_from_se3(target), atol=1e-9)


def test_cartesian_rates_are_derivatives_of_the_pose(table2) -> None:
    t = np.linspace(0.5, T - 0.5, 19)
    h = 1e-5
    cart = trajectory.compute_cartesian_trajectory(table2.trajectory, t)
    plus = trajectory.compute_cartesian_trajectory(table2.trajectory, t + h)
    minus = trajectory.compute_cartesian_trajectory(table2.trajectory, t - h)
    np.testing.assert_allclose(
        (plus.angeles7[:, 4:] - minus.angeles7[:, 4:]) / (2 * h),
        cart.velocity[:, :3],
        rtol=0,
        atol=ATOL_FD,
    )
    np.testing.assert_allclose(
        (plus.velocity - minus.velocity) / (2 * h),
        cart.acceleration,
        rtol=0,
        atol=ATOL_FD,
    )
    # angular velocity from the rotation: R(t+h) R(t-h)^T ≈ exp(2h ω)
    robot = table2.trajectory.robot
    for i in range(0, t.size, 6):
        r_plus = se3_from_angeles7(plus.angeles7[i]).rotation
        r_minus = se3_from_angeles7(minus.angeles7[i]).rotation
        omega = pin.log3(r_plus @ r_minus.T) / (2 * h)
        np.testing.assert_allclose(omega, cart.velocity[i, 3:], atol=ATOL_FD)
    assert robot.name == "puma560"


def test_pose_forms_agree(puma) -> None:
    pose = puma.fk(Q3_PLACE)
    a = trajectory.pick_and_place_from_poses(puma, pose, pose, T, q_near=Q3_PLACE)
    b = trajectory.pick_and_place_from_poses(
        puma, pose.homogeneous, pose.homogeneous, T, q_near=Q3_PLACE
    )
    c = trajectory.pick_and_place_from_poses(
        puma, angeles7_from_se3(pose), angeles7_from_se3(pose), T, q_near=Q3_PLACE
    )
    np.testing.assert_allclose(a.pick.q, Q3_PLACE, atol=1e-9)
    assert a.pick.rule == "nearest"
    np.testing.assert_allclose(b.pick.q, a.pick.q, atol=1e-12)
    np.testing.assert_allclose(c.pick.q, a.pick.q, atol=1e-9)
    with pytest.raises(
        InputError, match="angeles7 \\(7 numbers\\), got shape \\(3,\\)"
    ):
        trajectory.as_target_pose([1.0, 2.0, 3.0])


def test_unreachable_pose_is_infeasible(puma) -> None:
    far = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.0]))
    with pytest.raises(InfeasibleError):
        trajectory.pick_and_place_from_poses(puma, far, puma.fk(Q3_PLACE), T)


def test_panda_from_poses_uses_its_closed_form(rng) -> None:
    """A seven-axis arm: values and branch chosen together, in closed form."""
    panda = load_robot("panda")
    q0, q1 = random_configurations(panda, rng, 2)
    planned = trajectory.pick_and_place_from_poses(
        panda, panda.fk(q0), panda.fk(q1), 5.0
    )
    assert planned.pick.branch in ik.FRANKA_BRANCHES
    assert planned.pick.branch == planned.place.branch
    assert planned.pick.criterion == "limit_margin"
    for choice, q in ((planned.pick, q0), (planned.place, q1)):
        np.testing.assert_allclose(
            panda.fk(choice.q).homogeneous, panda.fk(q).homogeneous, atol=1e-12
        )
    cart = trajectory.compute_cartesian_trajectory(planned.trajectory, [0.0, 5.0])
    np.testing.assert_allclose(
        np.concatenate([cart.velocity, cart.acceleration]), 0.0, atol=ATOL_ENDS
    )
    label = planned.pick.branch
    one = trajectory.pick_and_place_from_poses(
        panda, panda.fk(q0), panda.fk(q1), 5.0, branch=label
    )
    assert one.pick.branch == one.place.branch == label and one.pick.rule == "branch"
    with pytest.raises(InputError, match="unknown branch"):
        trajectory.pick_and_place_from_poses(
            panda, panda.fk(q0), panda.fk(q1), 5.0, branch="right/elbow-up/flip"
        )


def test_an_arm_without_closed_form_uses_numerical_ik(rng) -> None:
    arm = load_robot("generic6r")
    q0, q1 = random_configurations(arm, rng, 2)
    planned = trajectory.pick_and_place_from_poses(
        arm, arm.fk(q0), arm.fk(q1), 5.0, q_near=q0
    )
    assert planned.pick.branch == planned.place.branch == "numeric"
    for choice, q in ((planned.pick, q0), (planned.place, q1)):
        np.testing.assert_allclose(
            arm.fk(choice.q).homogeneous, arm.fk(q).homogeneous, atol=1e-9
        )
    with pytest.raises(InputError, match="no closed-form IK"):
        trajectory.pick_and_place_from_poses(
            arm, arm.fk(q0), arm.fk(q1), 5.0, branch="right/elbow-up/flip"
        )


def test_ur5_from_poses_uses_the_closed_form() -> None:
    """A UR-type arm gets labelled closed-form branches, not numerical IK."""
    ur5 = load_robot("ur5")
    q = np.array([0.4, -1.2, 1.5, -0.9, 0.8, 0.5])
    label = "shoulder-left/elbow-up/wrist-up"
    planned = trajectory.pick_and_place_from_poses(
        ur5, ur5.fk(q), ur5.fk(q), 5.0, branch=label
    )
    assert planned.pick.branch == label
    np.testing.assert_allclose(
        ur5.fk(planned.pick.q).homogeneous, ur5.fk(q).homogeneous, atol=1e-9
    )
