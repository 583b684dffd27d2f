"""Damped least squares and the bounded QP step of differential IK."""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import lsq_linear

from workbench import DimensionError, InputError, NonFiniteError, Robot, load_robot
from workbench.ik import (
    DLS_EPSILON,
    DLS_LAMBDA_MAX,
    dls_inverse,
    dls_step,
    qp_step,
)

ATOL_EXACT = 1e-12
"""Same formula, other rounding."""

ATOL_QP = 1e-8
"""OSQP (polished) against a bounded least-squares reference [rad/s]."""

ATOL_SMALL_DAMPING = 1e-6
"""QP with damping 1e-9 against the undamped pseudo-inverse step [rad/s]."""

ATOL_FIRST_ORDER = 1e-5
"""One DLS step towards a pose 1e-3 rad away: second-order remainder [rad]."""

ROBOT_NAMES = ("puma560", "ur5", "panda")


@pytest.fixture(scope="module", params=ROBOT_NAMES)
def robot(request: pytest.FixtureRequest) -> Robot:
    return load_robot(request.param)


def regular_configuration(robot: Robot, rng: np.random.Generator) -> np.ndarray:
    """A random q whose tool Jacobian is well outside the singular region."""
    while True:
        q = rng.uniform(robot.lower, robot.upper)
        if np.linalg.svd(robot.jacobian(q), compute_uv=False)[-1] > 4 * DLS_EPSILON:
            return q


def reference_qp(jacobian, twist, damping, lower, upper):
    """min |J v - twist|^2 + damping |v|^2 on a box, by scipy's lsq_linear."""
    nv = jacobian.shape[1]
    a = np.vstack([jacobian, np.sqrt(damping) * np.eye(nv)])
    b = np.concatenate([twist, np.zeros(nv)])
    return lsq_linear(a, b, bounds=(lower, upper), tol=1e-14, method="bvls").x


def test_dls_is_the_pseudo_inverse_far_from_singularities(
    robot: Robot, rng: np.random.Generator
) -> None:
    for _ in range(10):
        jacobian = robot.jacobian(regular_configuration(robot, rng))
        np.testing.assert_allclose(
            dls_inverse(jacobian), np.linalg.pinv(jacobian), rtol=0, atol=ATOL_EXACT
        )


def test_dls_damping_law_on_a_diagonal_jacobian() -> None:
    epsilon, lambda_max = 0.1, 0.05
    for sigma_min in (0.2, 0.1, 0.05, 1e-3, 0.0):
        jacobian = np.diag([2.0, 1.0, 1.0, 0.5, 0.5, sigma_min])
        lambda2 = max(0.0, 1.0 - (sigma_min / epsilon) ** 2) * lambda_max**2
        expected = np.diag(np.diag(jacobian) / (np.diag(jacobian) ** 2 + lambda2))
        np.testing.assert_allclose(
            dls_inverse(jacobian, epsilon=epsilon, lambda_max=lambda_max),
            expected,
            rtol=0,
            atol=ATOL_EXACT,
        )


def test_dls_stays_bounded_at_the_puma_wrist_singularity(
    puma: Robot, rng: np.random.Generator
) -> None:
    """theta5 -> 0 aligns axes 4 and 6: J^-1 twist blows up, J# twist does not."""
    q = np.array([0.3, -0.8, 0.5, 0.4, 0.0, -0.2])
    twist = rng.normal(size=6)
    bound = max(1.0 / DLS_EPSILON, DLS_EPSILON / DLS_LAMBDA_MAX**2) * np.linalg.norm(
        twist
    )
    plain, damped = [], []
    for theta5 in (1e-1, 1e-3, 1e-5, 1e-7):
        q[4] = theta5
        jacobian = puma.jacobian(q)
        plain.append(np.linalg.norm(np.linalg.pinv(jacobian) @ twist))
        damped.append(np.linalg.norm(dls_inverse(jacobian) @ twist))
    assert plain[-1] > 1e6  # grows like 1 / theta5
    assert plain[-1] / plain[0] > 1e5
    assert max(damped) <= bound
    q[4] = 0.0  # exactly singular: still finite
    assert np.linalg.norm(dls_inverse(puma.jacobian(q)) @ twist) <= bound


def test_dls_step_with_a_twist(robot: Robot, rng: np.random.Generator) -> None:
    q = regular_configuration(robot, rng)
    twist = rng.normal(size=6)
    expected = np.linalg.pinv(robot.jacobian(q)) @ twist
    np.testing.assert_allclose(
        dls_step(robot, q, twist, 0.01), expected, rtol=0, atol=ATOL_EXACT
    )


def test_dls_step_towards_a_pose(robot: Robot, rng: np.random.Generator) -> None:
    q = regular_configuration(robot, rng)
    dq = rng.uniform(-1e-3, 1e-3, robot.nv)
    target = robot.fk(q + dq)
    dt = 0.1
    v = dls_step(robot, q, target.homogeneous, dt)
    after = robot.fk(pin.integrate(robot.model, q, v * dt))
    assert np.linalg.norm(pin.log6(after.actInv(target)).vector) < ATOL_FIRST_ORDER
    if robot.nv == 6:
        np.testing.assert_allclose(v * dt, dq, rtol=0, atol=ATOL_FIRST_ORDER)


def test_qp_step_is_the_dls_step_when_no_limit_is_active(
    robot: Robot, rng: np.random.Generator
) -> None:
    q = regular_configuration(robot, rng)
    q = np.clip(q, robot.lower + 0.2, robot.upper - 0.2)
    jacobian = robot.jacobian(q)
    twist = 0.05 * rng.normal(size=6)
    damping = 1e-4
    v = qp_step(robot, q, twist, 0.01, damping=damping)
    assert np.all(np.abs(v) < robot.velocity_limit)  # really unconstrained
    free = np.linalg.solve(
        jacobian.T @ jacobian + damping * np.eye(robot.nv), jacobian.T @ twist
    )
    np.testing.assert_allclose(v, free, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(  # = DLS with constant lambda^2 = damping
        v,
        jacobian.T
        @ np.linalg.solve(jacobian @ jacobian.T + damping * np.eye(6), twist),
        rtol=0,
        atol=1e-10,
    )
    # ... and tends to the undamped DLS step (the pseudo-inverse here).
    np.testing.assert_allclose(
        qp_step(robot, q, twist, 0.01, damping=1e-9),
        dls_step(robot, q, twist, 0.01),
        rtol=0,
        atol=ATOL_SMALL_DAMPING,
    )


def test_qp_step_respects_speed_limits(robot: Robot, rng: np.random.Generator) -> None:
    q = regular_configuration(robot, rng)
    q = np.clip(q, robot.lower + 0.5, robot.upper - 0.5)
    twist = 20.0 * rng.normal(size=6)  # far beyond what the joints can do
    dt, damping = 1e-3, 1e-6
    v = qp_step(robot, q, twist, dt, damping=damping)
    speed = robot.velocity_limit
    assert np.all(np.abs(v) <= speed)
    assert np.any(np.isclose(np.abs(v), speed, rtol=0, atol=1e-9))  # active
    expected = reference_qp(robot.jacobian(q), twist, damping, -speed, speed)
    np.testing.assert_allclose(v, expected, rtol=0, atol=ATOL_QP)


def test_qp_step_respects_position_limits(
    robot: Robot, rng: np.random.Generator
) -> None:
    q = regular_configuration(robot, rng)
    q[0] = robot.upper[0] - 1e-3  # 1 mrad below the limit
    jacobian = robot.jacobian(q)
    v_away = np.zeros(robot.nv)
    v_away[0] = 1.0  # a twist that wants joint 1 to go up at 1 rad/s
    twist = jacobian @ v_away
    dt, damping = 0.01, 1e-6
    v = qp_step(robot, q, twist, dt, damping=damping)
    q_next = q + v * dt
    assert np.all(q_next <= robot.upper)
    assert np.all(q_next >= robot.lower)
    np.testing.assert_allclose(q_next[0], robot.upper[0], rtol=0, atol=1e-12)
    speed = robot.velocity_limit
    lower = np.maximum(-speed, (robot.lower - q) / dt)
    upper = np.minimum(speed, (robot.upper - q) / dt)
    expected = reference_qp(jacobian, twist, damping, lower, upper)
    np.testing.assert_allclose(v, expected, rtol=0, atol=ATOL_QP)


def test_qp_step_brings_a_joint_back_into_range(
    puma: Robot, rng: np.random.Generator
) -> None:
    q = regular_configuration(puma, rng)
    q[0] = puma.upper[0] + 0.05  # outside: 50 mrad above
    v = qp_step(puma, q, np.zeros(6), 0.01)
    np.testing.assert_allclose(v[0], -puma.velocity_limit[0], rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("call", "error", "fragment"),
    [
        (lambda r: dls_inverse(np.ones(6)), InputError, "2-D"),
        (lambda r: dls_inverse(np.full((6, 6), np.nan)), NonFiniteError, "finite"),
        (lambda r: dls_inverse(np.eye(6), epsilon=0.0), InputError, "epsilon"),
        (lambda r: dls_inverse(np.eye(6), lambda_max=-1.0), InputError, "lambda_max"),
        (lambda r: dls_step(r, np.zeros(6), np.zeros(6), 0.0), InputError, "dt"),
        (lambda r: dls_step(r, np.zeros(6), np.zeros(5), 0.1), DimensionError, "(6,)"),
        (lambda r: dls_step(r, np.zeros(5), np.zeros(6), 0.1), DimensionError, "q "),
        (
            lambda r: dls_step(r, np.zeros(6), np.full(6, np.nan), 0.1),
            NonFiniteError,
            "twist must be finite",
        ),
        (
            lambda r: dls_step(r, np.zeros(6), 2.0 * np.eye(4), 0.1),
            InputError,
            "bottom row",
        ),
        (lambda r: qp_step(r, np.zeros(6), np.zeros(6), -1.0), InputError, "dt"),
        (
            lambda r: qp_step(r, np.zeros(6), np.zeros(6), 0.1, damping=-1e-3),
            InputError,
            "damping must be",
        ),
        (
            lambda r: qp_step(r, np.full(6, np.nan), np.zeros(6), 0.1),
            NonFiniteError,
            "q must be finite",
        ),
    ],
)
def test_bad_input_raises(puma: Robot, call, error, fragment: str) -> None:
    with pytest.raises(error, match=re.escape(fragment)):
        call(puma)
