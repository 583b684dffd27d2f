r"""Compiled Newton refinement of seven-axis branches on the robot's true chain.

The seven-axis closed forms (:mod:`workbench.ik._srs_kernel`,
:mod:`workbench.ik._franka_kernel`) solve the *idealised* structure fitted to
the joint axes. A URDF that is of a family only up to its rounding (π/2 written
``1.5708``, 3.67e-6 rad off: example-robot-data's xArm7) gets branches that
miss its pose by about that deviation times the reach. As for six axes
(:mod:`workbench.ik._refine_kernel`, whose tolerances and step rules this module
shares), each such branch is the start of Newton steps on the model's own chain
(``_chain.get_chain``), the redundancy parameter held at its value:

* Franka (the parameter is q7, a joint of the model): the six joints 1–6, q7
  fixed, :math:`q_{1..6} \leftarrow q_{1..6} - J_6^T (J_6 J_6^T + \lambda
  I)^{-1} e` (J_6 the first six columns of the LOCAL Jacobian of the tool);
* SRS (the parameter is the arm angle ψ, which the model does not define: it
  is read on the idealised chain, ``_srs_kernel.parameter_of``): the seven
  joints, for the square system :math:`r(q) = [e;\ ψ(q) - ψ^*]` (7),
  :math:`q \leftarrow q - A^T (A A^T + \lambda I)^{-1} r`, A = [J; ∇ψ] (7, 7),
  ∇ψ by central differences (:data:`PARAMETER_STEP`).

:math:`e = \log_6(T^{-1} M(q))`, λ = |r|² (Levenberg–Marquardt's damping of
Yamashita and Fukushima). A branch is kept when its FK residual, position [m]
and rotation [rad], and for SRS |ψ(q) − ψ*| [rad], are within ``ACCEPT``
times ``POSITION_TOL`` and ``ROTATION_TOL``; else its row is NaN (not
reached), never returned with a larger residual. Unlike six axes there is no
valley search: a branch Newton does not bring there is dropped.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point, helper
from workbench.ik._chain_kernel import _damped_step, _forward, _jacobian, _solve
from workbench.ik._kernel_common import remainder
from workbench.ik._puma import LIMIT_TOL
from workbench.ik._redundant_common import WITHIN_LIMITS
from workbench.ik._refine_kernel import (
    ACCEPT,
    REFINE_STEPS,
    ROTATION_TOL,
    keep_best,
    pose_error,
)
from workbench.ik._srs_kernel import _arm_angle

FloatArray = npt.NDArray[np.float64]

#: Step [rad] of the central differences of ψ(q): their truncation error,
#: ~1e-12 relative, and rounding, ~1e-10, only slow Newton's last step.
PARAMETER_STEP = 1e-6
#: Two refined branches this close [rad, each joint mod 2π] are one solution.
TWIN_TOL = 1e-8
#: Rows of the scratch array of :func:`_refine_row` (12 columns).
WORK_ROWS = 28


@helper()
def _arm_angle_of(geo, q: FloatArray, theta: FloatArray) -> float:
    """ψ [rad] of robot joint values ``q`` (7,) on the idealised SRS chain."""
    for j in range(7):
        theta[j] = geo.joint_sign[j] * q[j] + geo.theta_offset[j]
    return _arm_angle(geo, theta)


@helper()
def _refine_row(chain, geo, srs: bool, target, value: float, q, work) -> bool:
    """Newton steps on one branch ``q`` (7,) in place; whether it is within tolerance.

    Steps are taken until the residual is ``POLISH`` times the tolerances, has
    not decreased for ``STALL_STEPS`` steps, or ``REFINE_STEPS`` are taken;
    ``q`` is then the best iterate. ``geo``: the SRS record whose ψ is held at
    ``value`` when ``srs`` (else q7 is held, and ``geo`` is not read).
    ``work``: (:data:`WORK_ROWS`, 12) scratch.
    """
    frames = work[0:8]
    jac, normal = work[8:15, 0:7], work[15:22, 0:7]  # jac row 6: ∇ψ (SRS)
    r, dq, y = work[22, 0:7], work[23, 0:7], work[24, 0:7]
    best_q, theta, shifted = work[25, 0:7], work[26, 0:7], work[27, 0:7]
    rows = 7 if srs else 6
    no_pull = work.shape[0] < 0  # False, as a computed bool (no literal copy)
    dq[6] = 0.0
    best, best_step = math.inf, 0
    for step in range(REFINE_STEPS + 1):
        _forward(chain, q, frames)
        error = pose_error(target, frames, r)
        if srs:
            r[6] = remainder(_arm_angle_of(geo, q, theta) - value)
            error = max(error, abs(r[6]) / ROTATION_TOL)
        best, best_step, stop = keep_best(error, best, best_step, step, q, best_q)
        if stop:
            break
        damping = 0.0
        for i in range(rows):
            damping += r[i] * r[i]
        _jacobian(chain, frames, jac)
        if not srs:  # the first six columns: q7 stays
            _damped_step(jac, 6, r, dq, no_pull, damping, normal, y, dq)
        else:
            for k in range(7):
                for j in range(7):
                    shifted[j] = q[j]
                shifted[k] = q[k] + PARAMETER_STEP
                up = _arm_angle_of(geo, shifted, theta)
                shifted[k] = q[k] - PARAMETER_STEP
                down = _arm_angle_of(geo, shifted, theta)
                jac[6, k] = remainder(up - down) / (2.0 * PARAMETER_STEP)
            for i in range(7):  # A Aᵀ + λ I, and y = r
                for j in range(7):
                    s = 0.0
                    for k in range(7):
                        s += jac[i, k] * jac[j, k]
                    normal[i, j] = s
                normal[i, i] += damping
                y[i] = r[i]
            _solve(normal, y, 7)  # positive definite: never singular
            for k in range(7):  # Aᵀ y
                s = 0.0
                for i in range(7):
                    s += jac[i, k] * y[i]
                dq[k] = s
        for k in range(rows):  # (a turn of 2π or more is none: the angle stays near)
            q[k] -= remainder(dq[k])
    for k in range(7):
        q[k] = best_q[k]
    return best <= ACCEPT


@helper()
def _twin_of(q, b: int, reached: int) -> int:
    """An earlier reached row of ``q`` (B, 7) as row b (:data:`TWIN_TOL`), else −1."""
    for a in range(b):
        if reached >> a & 1 == 0:
            continue
        gap = 0.0
        for k in range(7):
            gap = max(gap, abs(remainder(q[a, k] - q[b, k])))
        if gap <= TWIN_TOL:
            return a
    return -1


@helper()
def _refine_branches(chain, geo, srs: bool, target, value: float, q, work) -> int:
    """Refine the reached rows (not NaN) of ``q`` (B, 7); NaN the ones that fail.

    A row that lands on the solution of an earlier one (twins that start at,
    or near, the idealised arm's fold, e.g. its wrist edge: the model's two
    solutions lie on either side, about √deviation apart) is refined again
    from its start mirrored through the solution found, and keeps what it
    reaches from there if that is another solution.

    Returns a bit mask of the branches that reach.
    """
    start, other = np.empty(7), np.empty(7)
    reached = 0
    for b in range(q.shape[0]):
        row = q[b]
        if not row[0] == row[0]:
            continue
        for k in range(7):
            start[k] = row[k]
        if not _refine_row(chain, geo, srs, target, value, row, work):
            for k in range(7):
                row[k] = np.nan
            continue
        reached |= 1 << b
        a = _twin_of(q, b, reached)
        if a < 0:
            continue
        for k in range(7):
            other[k] = 2.0 * start[k] - row[k]
        if not _refine_row(chain, geo, srs, target, value, other, work):
            continue
        gap = 0.0
        for k in range(7):
            gap = max(gap, abs(remainder(other[k] - q[a, k])))
        if gap > TWIN_TOL:
            for k in range(7):
                row[k] = other[k]
    return reached


@entry_point(outputs=("q", "flags"), contiguous=("chain", "pose"))
def refine_pose(
    chain: FloatArray,
    arm_angle_geometry: np.ndarray,
    srs: bool,
    pose: FloatArray,
    value: float,
    q: FloatArray,
    flags: npt.NDArray[np.uint8],
) -> int:
    """Refine the branches of one pose on the true chain.

    Args:
        chain: (8, CHAIN_WIDTH) packed true chain (``_chain_kernel``).
        arm_angle_geometry: (1,) SRS record (``_srs_kernel.pack_geometry``)
            whose arm angle is held at ``value`` when ``srs``; else any
            record of that dtype (not read: q7 is held).
        srs: True for an SRS arm (ψ held), False for a Franka arm (q7 held).
        pose: (4, 4) target pose of the tool frame in the base frame [m].
        value: The redundancy parameter [rad]: ψ (SRS) or q7 (Franka).
        q: (B, 7) branches of the closed form [rad], NaN rows for those that
            do not reach; refined in place, NaN where refinement fails.
        flags: (B,) uint8 flag bits of the kernels' ``solve_pose``: the bit
            ``WITHIN_LIMITS`` is updated.

    Returns:
        The number of branches that reach.
    """
    work = np.empty((WORK_ROWS, 12))
    reached = _refine_branches(chain, arm_angle_geometry[0], srs, pose, value, q, work)
    count = 0
    for b in range(q.shape[0]):
        alive = reached >> b & 1 != 0
        count += alive
        within = alive
        for k in range(7):
            within &= chain[k, 16] - LIMIT_TOL <= q[b, k] <= chain[k, 17] + LIMIT_TOL
        flags[b] = (flags[b] & ~WITHIN_LIMITS) | (WITHIN_LIMITS if within else 0)
    return count


@entry_point(outputs=("q", "valid"), contiguous=("chain", "targets", "values"))
def refine_batch(
    chain: FloatArray,
    arm_angle_geometry: np.ndarray,
    srs: bool,
    targets: FloatArray,
    values: FloatArray,
    q: FloatArray,
    valid: npt.NDArray[np.bool_],
) -> int:
    """Refine the branches of N poses on the true chain.

    Args:
        chain: (8, CHAIN_WIDTH) packed true chain.
        arm_angle_geometry: As :func:`refine_pose`.
        srs: True for an SRS arm (ψ held), False for a Franka arm (q7 held).
        targets: (N, 4, 4) target poses [m].
        values: (N,) the redundancy parameter of each pose [rad].
        q: (N, B, 7) branches [rad] (NaN rows where not valid), refined in
            place; NaN where refinement fails.
        valid: (N, B) True where a branch reaches; cleared where it fails.

    Returns:
        The number of branches that were valid and failed.
    """
    work = np.empty((WORK_ROWS, 12))
    geo = arm_angle_geometry[0]
    failed = 0
    for i in range(targets.shape[0]):
        reached = _refine_branches(chain, geo, srs, targets[i], values[i], q[i], work)
        for b in range(q.shape[1]):
            alive = reached >> b & 1 != 0
            failed += valid[i, b] and not alive
            valid[i, b] = alive
    return failed
