r"""Differential inverse kinematics: damped least squares and a bounded QP.

Damped least squares (DLS), after Nakamura & Hanafusa (1986) and Chiaverini
(1997): with the singular value decomposition
:math:`J = \sum_i \sigma_i u_i v_i^T`,

.. math::

    J^\# = \sum_i \frac{\sigma_i}{\sigma_i^2 + \lambda^2}\, v_i u_i^T,
    \qquad
    \lambda^2 = \begin{cases}
        \left(1 - (\sigma_\min / \varepsilon)^2\right) \lambda_\max^2
            & \sigma_\min < \varepsilon \\
        0 & \text{otherwise.}
    \end{cases}

Outside the singular region (:math:`\sigma_\min \ge \varepsilon`) it is the
Moore–Penrose pseudo-inverse. Inside, the damping grows smoothly to
:math:`\lambda_\max` as :math:`\sigma_\min \to 0`, so the gain stays bounded:
with :math:`\lambda_\max \le \varepsilon`, :math:`\|J^\#\| \le
\max(1/\varepsilon, \varepsilon/\lambda_\max^2)`, whereas :math:`\|J^+\| =
1/\sigma_\min` blows up.

:func:`qp_step` solves instead, with OSQP through ``qpsolvers``,

.. math::

    \min_v \tfrac12 \|J v - \xi\|^2 + \tfrac12 \rho \|v\|^2
    \quad\text{s.t.}\quad
    |v| \le \dot q_\max, \quad q_\min \le q + v\,\delta t \le q_\max,

so that the step respects the joint speed and position limits; with no
limit active it is the DLS step with constant damping :math:`\lambda^2 =
\rho`.

Twists are LOCAL_WORLD_ALIGNED like :meth:`Robot.jacobian`: [linear velocity
of the tool origin (m/s); angular velocity (rad/s)], both in base axes.
"""

from __future__ import annotations

import importlib.metadata
import math

import numba
import numpy as np
import numpy.typing as npt
import pinocchio as pin
import scipy.sparse
from qpsolvers import solve_qp

from workbench.errors import DimensionError, InfeasibleError, InputError
from workbench.model.robot import Robot
from workbench.poses import as_se3
from workbench.validation import as_finite_array, as_vector

FloatArray = npt.NDArray[np.float64]

DLS_EPSILON = 0.05
"""Default size of the singular region, in units of sigma_min of J."""

DLS_LAMBDA_MAX = 0.05
"""Default damping at a singularity (sigma_min = 0), units of sigma of J."""

QP_DAMPING = 1e-6
"""Default damping weight rho of :func:`qp_step`."""

_OSQP_SETTINGS: dict[str, float | bool] = {
    "eps_abs": 1e-10,
    "eps_rel": 1e-10,
    "verbose": False,
}
"""OSQP tolerances; the solution is then polished to its exact active set."""
if int(importlib.metadata.version("osqp").split(".")[0]) >= 1:
    _OSQP_SETTINGS |= {"polishing": True, "raise_error": False}
else:  # OSQP 0.6 names
    _OSQP_SETTINGS |= {"polish": True}


class DifferentialIKError(InfeasibleError):
    """The QP of :func:`qp_step` has no solution the solver could find."""


def dls_inverse(
    jacobian: npt.ArrayLike,
    *,
    epsilon: float = DLS_EPSILON,
    lambda_max: float = DLS_LAMBDA_MAX,
) -> FloatArray:
    r"""Damped-least-squares inverse of a Jacobian (see the module docstring).

    Args:
        jacobian: Shape (m, n), typically (6, nv).
        epsilon: Size of the singular region, > 0, same unit as the singular
            values of ``jacobian``.
        lambda_max: Damping reached when :math:`\sigma_\min = 0`, >= 0.

    Returns:
        :math:`J^\#`, shape (n, m): the pseudo-inverse when the smallest
        singular value is >= ``epsilon``, damped below.

    Raises:
        InputError: If ``jacobian`` is not 2-D, or ``epsilon`` <= 0 or
            ``lambda_max`` < 0 (or not finite).
        NonFiniteError: If it holds NaN or infinity.
    """
    jac = np.asarray(jacobian, dtype=np.float64)
    if jac.ndim != 2:
        raise InputError(f"jacobian must be a 2-D array (m, n), got shape {jac.shape}")
    jac = as_finite_array(jac, jac.shape, "jacobian")
    _check_positive(epsilon, "epsilon", strict=True)
    _check_positive(lambda_max, "lambda_max", strict=False)
    u, sigma, vt = np.linalg.svd(jac, full_matrices=False)
    return (vt.T * dls_gains(sigma, float(epsilon), float(lambda_max))) @ u.T


@numba.njit(cache=True, nogil=True, error_model="numpy")
def dls_damping(sigma_min2: float, epsilon: float, lambda_max: float) -> float:
    r"""The damping :math:`\lambda^2` (module docstring) given :math:`\sigma_\min^2`.

    The damping law in one place: :func:`dls_gains` (hence
    :func:`dls_inverse`) and the online planner's compiled velocity step use it.
    """
    if sigma_min2 < epsilon * epsilon:
        return (1.0 - sigma_min2 / (epsilon * epsilon)) * lambda_max * lambda_max
    return 0.0


@numba.njit(cache=True, nogil=True, error_model="numpy")
def dls_gains(sigma: FloatArray, epsilon: float, lambda_max: float) -> FloatArray:
    r"""The factors :math:`\sigma_i / (\sigma_i^2 + \lambda^2)` of :math:`J^\#`.

    Args:
        sigma: Singular values of J, descending, shape (k,).
        epsilon: Size of the singular region, > 0.
        lambda_max: Damping at a singularity, >= 0.

    Returns:
        Shape (k,); 0 where :math:`\sigma_i^2 + \lambda^2 = 0`.
    """
    sigma_min = sigma[-1] if sigma.size else 0.0
    lambda2 = dls_damping(sigma_min * sigma_min, epsilon, lambda_max)
    gains = np.zeros_like(sigma)
    for k in range(sigma.size):
        denominator = sigma[k] * sigma[k] + lambda2
        if denominator > 0.0:
            gains[k] = sigma[k] / denominator
    return gains


def dls_step(
    robot: Robot,
    q: npt.ArrayLike,
    command: npt.ArrayLike | pin.SE3,
    dt: float,
    *,
    epsilon: float = DLS_EPSILON,
    lambda_max: float = DLS_LAMBDA_MAX,
) -> FloatArray:
    r"""Joint velocity that realises a tool twist, or reaches a pose in ``dt``.

    Args:
        robot: The robot (tool frame).
        q: Configuration, shape (nq,) [rad].
        command: Either a desired tool twist, shape (6,) [m/s; rad/s],
            LOCAL_WORLD_ALIGNED, or a target tool pose (``pin.SE3`` or (4, 4)
            homogeneous matrix, base frame, metres): then the twist is the
            constant one that moves the tool onto it in ``dt``,
            :math:`\log_6(M^{-1}T)/\delta t` rotated to base axes.
        dt: Time step [s], > 0.
        epsilon: See :func:`dls_inverse`.
        lambda_max: See :func:`dls_inverse`.

    Returns:
        ``v = J# twist``, shape (nv,) [rad/s]; integrate it with
        ``pin.integrate(robot.model, q, v * dt)``. Joint limits are not
        enforced (see :func:`qp_step`).

    Raises:
        DimensionError: If ``q`` or ``command`` has the wrong shape.
        NonFiniteError: If an input holds NaN or infinity.
        InputError: If ``dt`` <= 0, the pose is not rigid, or ``epsilon`` /
            ``lambda_max`` are invalid.
    """
    q = robot.check_configuration(q)
    _check_positive(dt, "dt", strict=True)
    twist = _twist_command(robot, q, command, dt)
    jac = robot.jacobian(q)
    return dls_inverse(jac, epsilon=epsilon, lambda_max=lambda_max) @ twist


def qp_step(
    robot: Robot,
    q: npt.ArrayLike,
    desired_twist: npt.ArrayLike | pin.SE3,
    dt: float,
    *,
    damping: float = QP_DAMPING,
) -> FloatArray:
    r"""Joint velocity closest to a tool twist within speed and position limits.

    Solves the QP of the module docstring with OSQP (``qpsolvers``). A joint
    already outside its range may only move back towards it, as fast as its
    speed limit allows.

    Args:
        robot: The robot (tool frame, ``lower``/``upper``, ``velocity_limit``).
        q: Configuration, shape (nq,) [rad].
        desired_twist: Tool twist, shape (6,) [m/s; rad/s],
            LOCAL_WORLD_ALIGNED; or a target pose, as in :func:`dls_step`.
        dt: Time step [s], > 0: ``q + v dt`` stays within the limits.
        damping: Weight rho >= 0 of :math:`\tfrac12\rho\|v\|^2`.

    Returns:
        ``v``, shape (nv,) [rad/s], with :math:`|v| \le` ``velocity_limit``
        and ``q (+) v dt`` within the position limits.

    Raises:
        DimensionError: If ``q`` or ``desired_twist`` has the wrong shape.
        NonFiniteError: If an input holds NaN or infinity.
        InputError: If ``dt`` <= 0 or ``damping`` < 0 (or not finite).
        DifferentialIKError: If OSQP fails to solve the QP.
    """
    q = robot.check_configuration(q)
    _check_positive(dt, "dt", strict=True)
    _check_positive(damping, "damping", strict=False)
    twist = _twist_command(robot, q, desired_twist, dt)
    jac = robot.jacobian(q)
    lower, upper = _velocity_bounds(robot, q, dt)
    hessian = jac.T @ jac + damping * np.eye(robot.nv)
    gradient = -jac.T @ twist
    # With no limit active the unconstrained minimiser is the solution.
    with np.errstate(all="ignore"):
        try:
            v = np.linalg.solve(hessian, -gradient)
        except np.linalg.LinAlgError:  # singular J and damping = 0
            v = None
    if v is not None and np.all(v >= lower) and np.all(v <= upper):
        return v
    v = solve_qp(
        scipy.sparse.csc_matrix(hessian),
        gradient,
        lb=lower,
        ub=upper,
        solver="osqp",
        **_OSQP_SETTINGS,
    )
    if v is None or not np.all(np.isfinite(v)):
        raise DifferentialIKError(
            f"OSQP found no solution of the differential-IK QP at q = {q.tolist()}"
        )
    # OSQP meets the bounds to its tolerance; make them exact.
    return np.minimum(np.maximum(v, lower), upper)


def _check_positive(value: float, name: str, *, strict: bool) -> None:
    ok = isinstance(value, int | float) and not isinstance(value, bool)
    ok = ok and math.isfinite(value) and (value > 0.0 if strict else value >= 0.0)
    if not ok:
        bound = "> 0" if strict else ">= 0"
        raise InputError(f"{name} must be a finite number {bound}, got {value!r}")


def _twist_command(
    robot: Robot, q: FloatArray, command: npt.ArrayLike | pin.SE3, dt: float
) -> FloatArray:
    """The commanded twist (6,), LOCAL_WORLD_ALIGNED [m/s; rad/s]."""
    if not isinstance(command, pin.SE3):
        shape = np.shape(command)
        if shape != (4, 4):
            if shape != (6,):
                raise DimensionError("twist (or a (4, 4) pose)", (6,), shape)
            return as_vector(command, 6, "twist")
    target = as_se3(command)
    pose = robot.fk(q)
    body = pin.log6(pose.actInv(target)).vector / dt  # LOCAL twist
    rotation = pose.rotation
    return np.concatenate([rotation @ body[:3], rotation @ body[3:]])


def _velocity_bounds(
    robot: Robot, q: FloatArray, dt: float
) -> tuple[FloatArray, FloatArray]:
    """Bounds (nv,) on v [rad/s] from the speed and position limits.

    Position limits bound the 1-dof joints (revolute, prismatic); joints with
    several coordinates (continuous, spherical) get their speed limit only.
    """
    model = robot.model
    speed = robot.velocity_limit
    if model.njoints - 1 == model.nq == model.nv:  # every joint 1-dof: q ~ v
        iq = iv = np.arange(model.nv)
    else:
        joints = [j for j in model.joints[1:] if j.nq == 1 and j.nv == 1]
        iq = np.array([j.idx_q for j in joints], dtype=int)
        iv = np.array([j.idx_v for j in joints], dtype=int)
    upper, lower = speed.copy(), -speed
    to_upper = (robot.upper[iq] - q[iq]) / dt
    to_lower = (robot.lower[iq] - q[iq]) / dt
    # Outside its range a joint may only move back in, at most at full speed.
    upper[iv] = np.maximum(np.minimum(upper[iv], to_upper), -speed[iv])
    lower[iv] = np.minimum(np.maximum(lower[iv], to_lower), upper[iv])
    return lower, upper


__all__ = [
    "DLS_EPSILON",
    "DLS_LAMBDA_MAX",
    "QP_DAMPING",
    "DifferentialIKError",
    "dls_inverse",
    "dls_step",
    "qp_step",
]
