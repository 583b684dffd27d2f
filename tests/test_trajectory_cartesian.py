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
        pick_near=Q3_PICK,
        place_near=Q3_PLACE,
        angeles7_tol=ANGELES7_PRINTED_TOL,
    )


def test_table2_inverts_to_table3_branches(table2) -> None:
    assert table2.pick.branch == "right/elbow-down/no-flip"
    assert table2.place.branch == "right/elbow-up/flip"
    assert table2.pick.rule == table2.place.rule == "nearest"
    # Table II is printed to two decimals: IK lands within 1 deg of Table III
    assert np.abs(np.rad2deg(table2.pick.q) - paper_data.ANGELES_PICK_Q_DEG).max() < 1
    assert np.abs(np.rad2deg(table2.place.q) - paper_data.ANGELES_PLACE_Q_DEG).max() < 1
    # ...and joint 2 of the pick lands a hair above its 45 deg limit
    assert not table2.pick.within_limits
    (violation,) = table2.trajectory.check_limits()
    assert (violation.joint, violation.kind, violation.t) == ("joint2", "position", 0)
    assert 0 < np.rad2deg(violation.value - violation.limit) < 1e-3


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


def test_default_rule_is_first_branch_within_limits(puma) -> None:
    choice = trajectory.select_ik_solution(
        puma, paper_data.ANGELES_PICK_ANGELES7, angeles7_tol=ANGELES7_PRINTED_TOL
    )
    assert choice.rule == "first-within-limits" and choice.within_limits
    assert choice.branch == "right/elbow-up/no-flip"


def test_explicit_branch_and_unknown_branch(puma) -> None:
    pose = puma.fk(Q3_PLACE)
    choice = trajectory.select_ik_solution(puma, pose, branch="right/elbow-up/flip")
    np.testing.assert_allclose(choice.q, Q3_PLACE, atol=1e-9)
    with pytest.raises(InputError, match="valid: right/elbow-up/no-flip"):
        trajectory.select_ik_solution(puma, pose, branch="elbow-sideways")


def test_se3_matrix_and_angeles7_inputs_agree(puma) -> None:
    pose = puma.fk(Q3_PICK)
    a = trajectory.select_ik_solution(puma, pose, q_near=Q3_PICK)
    b = trajectory.select_ik_solution(puma, pose.homogeneous, q_near=Q3_PICK)
    c = trajectory.select_ik_solution(puma, angeles7_from_se3(pose), q_near=Q3_PICK)
    np.testing.assert_allclose(a.q, Q3_PICK, atol=1e-9)
    np.testing.assert_allclose(b.q, a.q, atol=1e-12)
    np.testing.assert_allclose(c.q, a.q, atol=1e-9)
    with pytest.raises(
        InputError, match="angeles7 \\(7 numbers\\), got shape \\(3,\\)"
    ):
        trajectory.as_target_pose([1.0, 2.0, 3.0])


def test_unreachable_pose_is_infeasible(puma) -> None:
    far = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.0]))
    with pytest.raises(InfeasibleError):
        trajectory.select_ik_solution(puma, far)


def test_panda_from_poses_uses_its_closed_form(rng) -> None:
    """A seven-axis arm: the closed form at q7 of ``q_near``, else a chosen q7."""
    panda = load_robot("panda")
    q0, q1 = random_configurations(panda, rng, 2)
    planned = trajectory.pick_and_place_from_poses(
        panda, panda.fk(q0), panda.fk(q1), 5.0, pick_near=q0, place_near=q1
    )
    assert planned.pick.branch in ik.FRANKA_BRANCHES
    np.testing.assert_allclose(planned.pick.q, q0, atol=1e-9)  # its own branch
    np.testing.assert_allclose(planned.place.q, q1, atol=1e-9)
    cart = trajectory.compute_cartesian_trajectory(planned.trajectory, [0.0, 5.0])
    np.testing.assert_allclose(
        np.concatenate([cart.velocity, cart.acceleration]), 0.0, atol=ATOL_ENDS
    )
    np.testing.assert_allclose(
        cart.angeles7[0], angeles7_from_se3(panda.fk(q0)), atol=1e-8
    )
    chosen = trajectory.select_ik_solution(panda, panda.fk(q0))  # no q_near
    best = ik.choose_redundancy(panda, panda.fk(q0))
    assert chosen.within_limits and chosen.rule == "largest-limit-margin"
    assert chosen.branch == best.solution.branch
    np.testing.assert_allclose(chosen.q, best.solution.q, atol=0.0)
    np.testing.assert_allclose(
        panda.fk(chosen.q).homogeneous, panda.fk(q0).homogeneous, atol=1e-12
    )
    label = planned.pick.branch
    one = trajectory.select_ik_solution(panda, panda.fk(q0), branch=label)
    assert one.branch == label and one.rule == "branch"
    with pytest.raises(InputError, match="is not one of"):
        trajectory.select_ik_solution(panda, panda.fk(q0), branch="right/elbow-up/flip")


def test_an_arm_without_closed_form_uses_numerical_ik(rng) -> None:
    arm = load_robot("generic6r")
    q0 = random_configurations(arm, rng, 1)[0]
    choice = trajectory.select_ik_solution(arm, arm.fk(q0), q_near=q0)
    assert choice.branch == "numeric"
    np.testing.assert_allclose(
        arm.fk(choice.q).homogeneous, arm.fk(q0).homogeneous, atol=1e-9
    )
    with pytest.raises(InputError, match="no closed-form IK"):
        trajectory.select_ik_solution(arm, arm.fk(q0), branch="right/elbow-up/flip")


def test_ur5_from_poses_uses_the_closed_form(rng) -> None:
    """A UR-type arm gets labelled closed-form branches, not numerical IK."""
    from workbench.trajectory.cartesian import select_ik_solution

    ur5 = load_robot("ur5")
    q = np.array([0.4, -1.2, 1.5, -0.9, 0.8, 0.5])
    choice = select_ik_solution(
        ur5, ur5.fk(q), branch="shoulder-left/elbow-up/wrist-up"
    )
    assert choice.branch == "shoulder-left/elbow-up/wrist-up"
    np.testing.assert_allclose(
        ur5.fk(choice.q).homogeneous, ur5.fk(q).homogeneous, atol=1e-9
    )
