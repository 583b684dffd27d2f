r"""Differential inverse kinematics as a QP bounded by the joint limits.

:func:`qp_step` solves, with OSQP through ``qpsolvers``,

.. math::

    \min_v \tfrac12 \|J v - \xi\|^2 + \tfrac12 \rho \|v\|^2
    \quad\text{s.t.}\quad
    |v| \le \dot q_\max, \quad q_\min \le q + v\,\delta t \le q_\max,

so that the step respects the joint speed and position limits; with no
limit active it is the DLS step (:mod:`workbench.ik.damped`) with constant
damping :math:`\lambda^2 = \rho`.

Twists are LOCAL_WORLD_ALIGNED like :meth:`Robot.jacobian`: [linear velocity
of the tool origin (m/s); angular velocity (rad/s)], both in base axes.
"""

from __future__ import annotations

import functools
import importlib.metadata
from typing import Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import DifferentialIKError
from workbench.ik.damped import _twist_command
from workbench.model.robot import Robot
from workbench.validation import check_positive

FloatArray = npt.NDArray[np.float64]

QP_DAMPING = 1e-6
"""Default damping weight rho of :func:`qp_step`."""


@functools.cache
def _osqp_settings() -> dict[str, Any]:
    """OSQP tolerances; the solution is then polished to its exact active set.

    Read on the first QP (as ``qpsolvers`` and ``scipy.sparse`` are imported):
    a quarter of a second that commands without a QP step do not pay.
    """
    settings: dict[str, Any] = {"eps_abs": 1e-10, "eps_rel": 1e-10, "verbose": False}
    if int(importlib.metadata.version("osqp").split(".")[0]) >= 1:
        return settings | {"polishing": True, "raise_error": False}
    return settings | {"polish": True}  # OSQP 0.6 names


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
    check_positive(dt, "dt", strict=True)
    check_positive(damping, "damping", strict=False)
    twist = _twist_command(robot, q, desired_twist, dt)
    jac = robot.jacobian(q)
    lower, upper = _velocity_bounds(robot, q, dt)
    hessian = jac.T @ jac + damping * np.eye(robot.nv)
    gradient = -jac.T @ twist
    # With no limit active the unconstrained minimiser is the solution.
    with np.errstate(all="ignore"):
        v: FloatArray | None
        try:
            v = np.linalg.solve(hessian, -gradient).astype(np.float64, copy=False)
        except np.linalg.LinAlgError:  # singular J and damping = 0
            v = None
    if v is not None and np.all(v >= lower) and np.all(v <= upper):
        return v
    import scipy.sparse  # here, not at import: see _osqp_settings
    from qpsolvers import solve_qp

    v = solve_qp(
        scipy.sparse.csc_matrix(hessian),
        gradient,
        lb=lower,
        ub=upper,
        solver="osqp",
        **_osqp_settings(),
    )
    if v is None or not np.all(np.isfinite(v)):
        raise DifferentialIKError(
            f"OSQP found no solution of the differential-IK QP at q = {q.tolist()}"
        )
    # OSQP meets the bounds to its tolerance; make them exact.
    return np.minimum(np.maximum(v, lower), upper)


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


__all__ = ["QP_DAMPING", "DifferentialIKError", "qp_step"]
