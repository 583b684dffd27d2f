r"""Differential inverse kinematics by damped least squares (DLS).

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

Twists are LOCAL_WORLD_ALIGNED like :meth:`Robot.jacobian`: [linear velocity
of the tool origin (m/s); angular velocity (rad/s)], both in base axes.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import DimensionError, InputError
from workbench.ik._velocity_kernel import (
    dls_damping,
    dls_gains,
    solve_null_space_velocity,
    solve_velocity,
)
from workbench.model.robot import Robot
from workbench.poses import as_se3
from workbench.validation import as_finite_array, as_vector, check_positive

FloatArray = npt.NDArray[np.float64]

DLS_EPSILON = 0.05
"""Default size of the singular region, in units of sigma_min of J."""

DLS_LAMBDA_MAX = 0.05
"""Default damping at a singularity (sigma_min = 0), units of sigma of J."""


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
    check_positive(epsilon, "epsilon", strict=True)
    check_positive(lambda_max, "lambda_max", strict=False)
    u, sigma, vt = np.linalg.svd(jac, full_matrices=False)
    return (vt.T * dls_gains(sigma, float(epsilon), float(lambda_max))) @ u.T


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
    check_positive(dt, "dt", strict=True)
    twist = _twist_command(robot, q, command, dt)
    jac = robot.jacobian(q)
    return dls_inverse(jac, epsilon=epsilon, lambda_max=lambda_max) @ twist


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


__all__ = [
    "DLS_EPSILON",
    "DLS_LAMBDA_MAX",
    "dls_damping",
    "dls_gains",
    "dls_inverse",
    "dls_step",
    "solve_null_space_velocity",
    "solve_velocity",
]
