r"""Joint velocity from a tool twist: exact inverse, DLS in the singular region.

For an arm with a spherical wrist whose tool frame is the wrist centre (the
PUMA models), the wrist joints do not move the tool origin, so the Jacobian is
block lower-triangular,

.. math:: J = \begin{bmatrix} A & 0 \\ B & C \end{bmatrix}, \qquad
          J^{-1} = \begin{bmatrix} A^{-1} & 0 \\ -C^{-1} B A^{-1} & C^{-1}
          \end{bmatrix},

and two 3 × 3 inverses give :math:`\dot q`. The smallest singular value obeys
:math:`\sigma_\min = 1/\|J^{-1}\|_2 \ge 1/\|J^{-1}\|_F`; whenever that bound
is at least ε the damped-least-squares inverse of :func:`workbench.ik.dls_inverse`
has zero damping and *equals* :math:`J^{-1}`, so the exact block solve is used.
Otherwise (near a singularity, or a Jacobian without the block structure) the
DLS solution is computed from a one-sided Jacobi SVD, with the damping law of
``dls_inverse``.
The result is that of ``dls_inverse`` in every case (to rounding); only the
cost differs. Both solves are compiled with Numba: they run once per planning
cycle of the online planner.

Inside the singular region the planner damps about a reference velocity (the
rate of its closed-form IK positions) rather than about zero, so that the
joint velocity command stays consistent with the joint position command in
the directions the damping suppresses (see :func:`solve_velocity`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point, helper

FloatArray = npt.NDArray[np.float64]

#: |J[0:3, 3:6]| entries at or below this count as zero (rounding of FK).
BLOCK_TOL = 1e-12

#: Columns count as orthogonal when |w_p . w_q| <= JACOBI_TOL |w_p| |w_q|.
JACOBI_TOL = 1e-15
#: Sweeps of the Jacobi SVD at most (6 × 6 Jacobians converge in 5 to 8).
JACOBI_MAX_SWEEPS = 60


@entry_point()
def dls_damping(sigma_min2: float, epsilon: float, lambda_max: float) -> float:
    r"""The damping :math:`\lambda^2` (module docstring) given :math:`\sigma_\min^2`.

    The damping law in one place: :func:`dls_gains` (hence
    :func:`workbench.ik.dls_inverse`) and :func:`damped_solve` use it.
    """
    if sigma_min2 < epsilon * epsilon:
        return (1.0 - sigma_min2 / (epsilon * epsilon)) * lambda_max * lambda_max
    return 0.0


@entry_point()
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
    gains = np.zeros(sigma.size)
    for k in range(sigma.size):
        denominator = sigma[k] * sigma[k] + lambda2
        if denominator > 0.0:
            gains[k] = sigma[k] / denominator
    return gains


@helper()
def _inverse3(m: FloatArray, row: int, col: int) -> tuple[float, ...]:
    """Inverse of the 3 × 3 block of ``m`` at (``row``, ``col``), by cofactors.

    Returns:
        Its nine entries, row-major; NaN if the block is singular.
    """
    a, b, c = m[row, col], m[row, col + 1], m[row, col + 2]
    d, e, f = m[row + 1, col], m[row + 1, col + 1], m[row + 1, col + 2]
    g, h, k = m[row + 2, col], m[row + 2, col + 1], m[row + 2, col + 2]
    c0, c1, c2 = e * k - f * h, f * g - d * k, d * h - e * g
    det = a * c0 + b * c1 + c * c2
    r = 1.0 / det if det != 0.0 else math.nan
    return (
        c0 * r, (c * h - b * k) * r, (b * f - c * e) * r,
        c1 * r, (a * k - c * g) * r, (c * d - a * f) * r,
        c2 * r, (b * g - a * h) * r, (a * e - b * d) * r,
    )  # fmt: skip


@entry_point(outputs=("qd",))
def block_solve(
    jacobian: FloatArray, twist: FloatArray, epsilon: float, qd: FloatArray
) -> bool:
    r"""Exact :math:`\dot q = J^{-1}\dot x` where that is the DLS solution.

    That is if J is block lower-triangular and the bound
    :math:`1/\|J^{-1}\|_F` on σmin is at least ``epsilon``.

    Args:
        jacobian: (6, 6), LOCAL_WORLD_ALIGNED, tool frame at the wrist centre.
        twist: (6,) [m/s, rad/s], linear first.
        epsilon: DLS singular-region size.
        qd: (6,) output [rad/s], meaningful when True is returned.

    Returns:
        False if the structure or the bound does not hold.
    """
    for i in range(3):
        for j in range(3, 6):
            if abs(jacobian[i, j]) > BLOCK_TOL:
                return False
    a_inv = _inverse3(jacobian, 0, 0)
    c_inv = _inverse3(jacobian, 3, 3)
    frob2 = 0.0  # ||J^-1||_F^2, which the bound needs below 1 / epsilon^2
    for x in a_inv + c_inv:
        frob2 += x * x
    # D = C^-1 B A^-1, the lower-left block of J^-1 negated (E = C^-1 B first)
    e = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            e[i, j] = (
                c_inv[3 * i] * jacobian[3, j]
                + c_inv[3 * i + 1] * jacobian[4, j]
                + c_inv[3 * i + 2] * jacobian[5, j]
            )
    v0, v1, v2 = twist[0], twist[1], twist[2]
    for i in range(3):
        d0 = e[i, 0] * a_inv[0] + e[i, 1] * a_inv[3] + e[i, 2] * a_inv[6]
        d1 = e[i, 0] * a_inv[1] + e[i, 1] * a_inv[4] + e[i, 2] * a_inv[7]
        d2 = e[i, 0] * a_inv[2] + e[i, 1] * a_inv[5] + e[i, 2] * a_inv[8]
        frob2 += d0 * d0 + d1 * d1 + d2 * d2
        qd[3 + i] = (
            c_inv[3 * i] * twist[3]
            + c_inv[3 * i + 1] * twist[4]
            + c_inv[3 * i + 2] * twist[5]
            - (d0 * v0 + d1 * v1 + d2 * v2)
        )
    for i in range(3):
        qd[i] = a_inv[3 * i] * v0 + a_inv[3 * i + 1] * v1 + a_inv[3 * i + 2] * v2
    # a NaN (singular block) fails the comparison too
    return frob2 * epsilon * epsilon <= 1.0


@helper(forceinline=True)
def _dot(a: FloatArray, b: FloatArray) -> float:
    """Dot product of two short vectors (no BLAS call)."""
    acc = 0.0
    for i in range(a.size):
        acc += a[i] * b[i]
    return acc


@helper()
def _orthogonalise_rows(x: FloatArray, y: FloatArray) -> FloatArray:
    r"""One-sided Jacobi (Hestenes) SVD in place: ``x ← Qᵀx``, ``y ← Qᵀy``.

    Plane rotations (a product Q) make the rows of ``x`` mutually orthogonal.
    With ``y`` the identity on entry, :math:`x = \sum_k y_k^T x_k` over the
    rows after the call, and the norms of the rows ``x_k`` are the singular
    values. Accurate to rounding (Demmel & Veselić 1992); 6 to 8 sweeps for
    a 6 × 6 Jacobian, cheaper than a LAPACK call at that size.

    Returns:
        The squared norms of the rows of ``x``, the squared singular values.
    """
    n, m = x.shape
    norms2 = np.empty(n)
    for _ in range(JACOBI_MAX_SWEEPS):
        for k in range(n):  # recomputed each sweep: no drift from the updates
            norms2[k] = _dot(x[k], x[k])
        rotated = False
        for p in range(n - 1):
            for q in range(p + 1, n):
                gamma = _dot(x[p], x[q])
                alpha, beta = norms2[p], norms2[q]
                if abs(gamma) <= JACOBI_TOL * math.sqrt(alpha * beta):
                    continue  # orthogonal already (also when a row is zero)
                rotated = True
                zeta = (beta - alpha) / (2.0 * gamma)  # rotation zeroing gamma
                if abs(zeta) < 1e150:
                    t = math.copysign(1.0, zeta) / (
                        abs(zeta) + math.sqrt(1.0 + zeta**2)
                    )
                else:
                    t = 0.5 / zeta
                c = 1.0 / math.sqrt(1.0 + t * t)
                s = c * t
                norms2[p], norms2[q] = alpha - t * gamma, beta + t * gamma
                for i in range(m):
                    a, b = x[p, i], x[q, i]
                    x[p, i], x[q, i] = c * a - s * b, s * a + c * b
                for i in range(n):
                    a, b = y[p, i], y[q, i]
                    y[p, i], y[q, i] = c * a - s * b, s * a + c * b
        if not rotated:  # norms2 untouched since computed from x
            return norms2
    for k in range(n):
        norms2[k] = _dot(x[k], x[k])
    return norms2


@entry_point(outputs=("qd",))
def damped_solve(
    jacobian: FloatArray,
    twist: FloatArray,
    epsilon: float,
    lambda_max: float,
    qd_reference: FloatArray,
    qd: FloatArray,
) -> float:
    r"""DLS solution about a reference: :math:`\dot q_r + J^\#(\dot x - J\dot q_r)`.

    :math:`J^\#` as :func:`workbench.ik.dls_inverse`, with the damping law of
    :func:`workbench.ik.damped.dls_damping`, from a one-sided Jacobi SVD of a
    tall or square J, :math:`J = \sum_k w_k v_k^T` with orthogonal
    :math:`w_k = \sigma_k u_k` (of :math:`J^T` for a wide J):

    .. math:: J^\# r = \sum_k \frac{\sigma_k\, u_k^T r}{\sigma_k^2 + \lambda^2} v_k
              = \sum_k \frac{w_k^T r}{\|w_k\|^2 + \lambda^2} v_k .

    Args:
        jacobian: (6, nv).
        twist: (6,) [m/s, rad/s].
        epsilon: DLS singular-region size, > 0.
        lambda_max: Damping at a singularity, >= 0.
        qd_reference: (nv,) [rad/s], the velocity damped towards.
        qd: (nv,) output [rad/s].

    Returns:
        The damping :math:`\lambda^2` used (0 outside the singular region).
    """
    # Loops rather than array expressions (``@``, ``.copy()``, ``np.eye``,
    # ``qd[:] = ...``): each of those compiles as a function of its own, seconds
    # on the first run; and the residual's sum no longer depends on the layout
    # of J (BLAS summed a C and an F-ordered J in different orders).
    rows, cols = jacobian.shape
    residual = np.empty(rows)
    for i in range(rows):
        acc = 0.0
        for j in range(cols):
            acc += jacobian[i, j] * qd_reference[j]
        residual[i] = twist[i] - acc
    wide = cols > rows
    # rows of x: w_k (the columns of J V), or of J^T V for a wide J
    count, length = (rows, cols) if wide else (cols, rows)
    x = np.empty((count, length))
    for k in range(count):
        for i in range(length):
            x[k, i] = jacobian[k, i] if wide else jacobian[i, k]
    y = np.zeros((count, count))
    for k in range(count):
        y[k, k] = 1.0
    norms2 = _orthogonalise_rows(x, y)
    smallest = math.inf  # norms2.min(), NaN if one is
    for k in range(count):
        if norms2[k] < smallest or norms2[k] != norms2[k]:
            smallest = norms2[k]
    lambda2 = dls_damping(smallest, epsilon, lambda_max)
    for i in range(cols):
        qd[i] = qd_reference[i]
    for k in range(count):
        denominator = norms2[k] + lambda2
        if denominator <= 0.0:
            continue
        if wide:  # J = sum_k y_k x_k^T
            gain = _dot(y[k], residual) / denominator
            for i in range(cols):
                qd[i] += x[k, i] * gain
        else:  # J = sum_k x_k y_k^T
            gain = _dot(x[k], residual) / denominator
            for i in range(cols):
                qd[i] += y[k, i] * gain
    return lambda2


def solve_velocity(
    jacobian: FloatArray,
    twist: FloatArray,
    epsilon: float,
    lambda_max: float,
    reference: Callable[[], FloatArray] | None = None,
) -> tuple[FloatArray, bool]:
    r"""Joint velocity: :math:`J^{-1}` outside the singular region, DLS inside.

    Inside the singular region the damped-least-squares solution about a
    reference velocity :math:`\dot q_r`,

    .. math:: \dot q = \dot q_r + J^\# (\dot x - J \dot q_r)
              = \arg\min \|J\dot q - \dot x\|^2 + \lambda^2 \|\dot q - \dot q_r\|^2,

    with :math:`J^\#` of :func:`workbench.ik.dls_inverse`. With
    :math:`\dot q_r = 0` it is the plain :math:`J^\# \dot x`. Outside the
    region (no damping) the result is :math:`J^{-1}\dot x` whatever the
    reference. ``epsilon`` and ``lambda_max`` are taken as valid (checked by
    the caller once).

    Args:
        jacobian: Shape (6, nv), LOCAL_WORLD_ALIGNED, tool frame, finite.
        twist: Shape (6,) [m/s, rad/s], linear first, base axes.
        epsilon: DLS singular-region size.
        lambda_max: DLS damping at a singularity.
        reference: Returns the reference joint velocity (nv,) [rad/s] (called
            only in the singular region), or None for zero.

    Returns:
        ``(qd, used_dls)``: shape (nv,) [rad/s], and True if the DLS solution
        was computed (the singular region, or no block structure).
    """
    qd = np.empty(jacobian.shape[1])
    if jacobian.shape == (6, 6) and block_solve(jacobian, twist, epsilon, qd):
        return qd, False
    qd_reference = np.zeros(len(qd)) if reference is None else reference()
    damped_solve(jacobian, twist, epsilon, lambda_max, qd_reference, qd)
    return qd, True


def solve_null_space_velocity(
    jacobian: FloatArray,
    twist: FloatArray,
    epsilon: float,
    lambda_max: float,
    qd_null: FloatArray,
) -> tuple[FloatArray, bool]:
    r"""Joint velocity of a redundant arm: a particular solution plus a null motion.

    For a wide Jacobian (6 × nv, nv > 6),

    .. math:: \dot q = J^\# \dot x + (I - J^\# J)\, \dot q_n
              = \dot q_n + J^\# (\dot x - J \dot q_n),

    with :math:`J^\#` of :func:`workbench.ik.dls_inverse`. Outside the singular
    region :math:`J^\# = J^+` and this is the minimum-norm solution plus
    :math:`\dot q_n` projected on the null space of J (the self-motion; J
    :math:`\dot q = \dot x` exactly); inside it the damped solution about
    :math:`\dot q_n` (:func:`solve_velocity`). ``epsilon`` and ``lambda_max``
    are taken as valid (checked by the caller once).

    Args:
        jacobian: Shape (6, nv), LOCAL_WORLD_ALIGNED, tool frame, finite.
        twist: Shape (6,) [m/s, rad/s], linear first, base axes.
        epsilon: DLS singular-region size.
        lambda_max: DLS damping at a singularity.
        qd_null: Shape (nv,) [rad/s], the joint velocity whose null-space part
            is kept (e.g. the gradient of a criterion, or the rate of the
            joint position commands).

    Returns:
        ``(qd, damped)``: shape (nv,) [rad/s], and True if the damping was
        non-zero (:math:`\sigma_\min < \varepsilon`).
    """
    qd = np.empty(jacobian.shape[1])
    lambda2 = damped_solve(jacobian, twist, epsilon, lambda_max, qd_null, qd)
    return qd, lambda2 > 0.0


__all__ = [
    "BLOCK_TOL",
    "dls_damping",
    "dls_gains",
    "solve_null_space_velocity",
    "solve_velocity",
]
