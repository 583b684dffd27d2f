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
DLS inverse is computed. The result is that of ``dls_inverse`` in every case;
only the cost differs (a few µs instead of an SVD).

Inside the singular region the planner damps about a reference velocity (the
rate of its closed-form IK positions) rather than about zero, so that the
joint velocity command stays consistent with the joint position command in
the directions the damping suppresses (see :func:`solve_velocity`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from workbench.ik.damped import dls_inverse

FloatArray = npt.NDArray[np.float64]

#: |J[0:3, 3:6]| entries at or below this count as zero (rounding of FK).
BLOCK_TOL = 1e-12
_BLOCK_TOL2 = BLOCK_TOL * BLOCK_TOL


def _block_solve(
    rows: list[list[float]], twist: list[float], epsilon: float
) -> list[float] | None:
    """Exact solve if J is block triangular and sigma_min >= epsilon, else None."""
    (
        (a0, a1, a2, z0, z1, z2),
        (a3, a4, a5, z3, z4, z5),
        (a6, a7, a8, z6, z7, z8),
        (b0, b1, b2, c0, c1, c2),
        (b3, b4, b5, c3, c4, c5),
        (b6, b7, b8, c6, c7, c8),
    ) = rows
    # max |z| <= BLOCK_TOL, decided by a sum of squares when that is clear
    zz = z0 * z0 + z1 * z1 + z2 * z2 + z3 * z3 + z4 * z4 + z5 * z5 + z6 * z6
    if not zz + z7 * z7 + z8 * z8 <= _BLOCK_TOL2 and (
        max(
            abs(z0),
            abs(z1),
            abs(z2),
            abs(z3),
            abs(z4),
            abs(z5),
            abs(z6),
            abs(z7),
            abs(z8),
        )
        > BLOCK_TOL
    ):
        return None
    # A^-1 (cofactors / det)
    k0, k3, k6 = a4 * a8 - a5 * a7, a5 * a6 - a3 * a8, a3 * a7 - a4 * a6
    det_a = a0 * k0 + a1 * k3 + a2 * k6
    # C^-1
    m0, m3, m6 = c4 * c8 - c5 * c7, c5 * c6 - c3 * c8, c3 * c7 - c4 * c6
    det_c = c0 * m0 + c1 * m3 + c2 * m6
    if det_a == 0.0 or det_c == 0.0:
        return None
    ra, rc = 1.0 / det_a, 1.0 / det_c
    i0, i1, i2 = k0 * ra, (a2 * a7 - a1 * a8) * ra, (a1 * a5 - a2 * a4) * ra
    i3, i4, i5 = k3 * ra, (a0 * a8 - a2 * a6) * ra, (a2 * a3 - a0 * a5) * ra
    i6, i7, i8 = k6 * ra, (a1 * a6 - a0 * a7) * ra, (a0 * a4 - a1 * a3) * ra
    j0, j1, j2 = m0 * rc, (c2 * c7 - c1 * c8) * rc, (c1 * c5 - c2 * c4) * rc
    j3, j4, j5 = m3 * rc, (c0 * c8 - c2 * c6) * rc, (c2 * c3 - c0 * c5) * rc
    j6, j7, j8 = m6 * rc, (c1 * c6 - c0 * c7) * rc, (c0 * c4 - c1 * c3) * rc
    # ||J^-1||_F^2 summed in order: when the A^-1 and C^-1 terms alone pass the
    # bound (rounding is monotone), D is not needed to know the answer
    frob2 = (
        i0 * i0
        + i1 * i1
        + i2 * i2
        + i3 * i3
        + i4 * i4
        + i5 * i5
        + i6 * i6
        + i7 * i7
        + i8 * i8
        + j0 * j0
        + j1 * j1
        + j2 * j2
        + j3 * j3
        + j4 * j4
        + j5 * j5
        + j6 * j6
        + j7 * j7
        + j8 * j8
    )
    if frob2 * epsilon * epsilon > 1.0:
        return None
    # E = C^-1 B, then D = E A^-1 (the lower-left block of J^-1, negated)
    e0 = j0 * b0 + j1 * b3 + j2 * b6
    e1 = j0 * b1 + j1 * b4 + j2 * b7
    e2 = j0 * b2 + j1 * b5 + j2 * b8
    e3 = j3 * b0 + j4 * b3 + j5 * b6
    e4 = j3 * b1 + j4 * b4 + j5 * b7
    e5 = j3 * b2 + j4 * b5 + j5 * b8
    e6 = j6 * b0 + j7 * b3 + j8 * b6
    e7 = j6 * b1 + j7 * b4 + j8 * b7
    e8 = j6 * b2 + j7 * b5 + j8 * b8
    d0, d1, d2 = (
        e0 * i0 + e1 * i3 + e2 * i6,
        e0 * i1 + e1 * i4 + e2 * i7,
        e0 * i2 + e1 * i5 + e2 * i8,
    )
    d3, d4, d5 = (
        e3 * i0 + e4 * i3 + e5 * i6,
        e3 * i1 + e4 * i4 + e5 * i7,
        e3 * i2 + e4 * i5 + e5 * i8,
    )
    d6, d7, d8 = (
        e6 * i0 + e7 * i3 + e8 * i6,
        e6 * i1 + e7 * i4 + e8 * i7,
        e6 * i2 + e7 * i5 + e8 * i8,
    )
    frob2 = (
        frob2
        + d0 * d0
        + d1 * d1
        + d2 * d2
        + d3 * d3
        + d4 * d4
        + d5 * d5
        + d6 * d6
        + d7 * d7
        + d8 * d8
    )
    if frob2 * epsilon * epsilon > 1.0:  # the bound 1/||J^-1||_F is below epsilon
        return None
    vx, vy, vz, wx, wy, wz = twist
    return [
        i0 * vx + i1 * vy + i2 * vz,
        i3 * vx + i4 * vy + i5 * vz,
        i6 * vx + i7 * vy + i8 * vz,
        j0 * wx + j1 * wy + j2 * wz - (d0 * vx + d1 * vy + d2 * vz),
        j3 * wx + j4 * wy + j5 * wz - (d3 * vx + d4 * vy + d5 * vz),
        j6 * wx + j7 * wy + j8 * wz - (d6 * vx + d7 * vy + d8 * vz),
    ]


def solve_velocity_list(
    jacobian: FloatArray,
    twist: list[float],
    epsilon: float,
    lambda_max: float,
    reference: Callable[[], FloatArray] | None = None,
) -> tuple[list[float], bool]:
    """:func:`solve_velocity` with ``qd`` as a list of floats.

    ``epsilon`` and ``lambda_max`` are taken as valid (the planner checks them
    once), so the singular region skips the argument checks of
    :func:`~workbench.ik.dls_inverse`; the arithmetic is the same.
    """
    if jacobian.shape == (6, 6):
        qd = _block_solve(jacobian.tolist(), twist, epsilon)
        if qd is not None:
            return qd, False
    inverse = _dls_inverse(jacobian, epsilon, lambda_max)
    xd = np.array(twist, dtype=np.float64)
    if reference is None:
        return (inverse @ xd).tolist(), True
    qd_ref = reference()
    return (qd_ref + inverse @ (xd - jacobian @ qd_ref)).tolist(), True


def _dls_inverse(jacobian: FloatArray, epsilon: float, lambda_max: float) -> FloatArray:
    """:func:`~workbench.ik.dls_inverse` of a finite (m, n) float array, unchecked.

    The same SVD (numpy's LAPACK gufunc, called directly when numpy exposes
    it) and arithmetic, without the argument checks and wrappers.
    """
    u = None
    if _SVD_GUFUNC is not None:
        u, sigma, vt = _SVD_GUFUNC(jacobian, signature="d->ddd")
        if not np.isfinite(sigma[-1]):  # no convergence: let numpy report it
            u = None
    if u is None:
        u, sigma, vt = np.linalg.svd(jacobian, full_matrices=False)
    sigma_min = sigma[-1] if sigma.size else 0.0
    lambda2 = 0.0
    if sigma_min < epsilon:
        lambda2 = (1.0 - (sigma_min / epsilon) ** 2) * lambda_max**2
    gain = []
    for s in sigma.tolist():
        denominator = s * s + lambda2
        gain.append(s / denominator if denominator > 0.0 else 0.0)
    return (vt.T * np.array(gain)) @ u.T


try:  # the gufunc np.linalg.svd(a, full_matrices=False) runs for float64 input
    from numpy.linalg import _umath_linalg

    _SVD_GUFUNC = _umath_linalg.svd_s
except (ImportError, AttributeError):  # pragma: no cover - other numpy builds
    _SVD_GUFUNC = None


def solve_velocity(
    jacobian: FloatArray,
    twist: list[float],
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
    reference.

    Args:
        jacobian: Shape (6, nv), LOCAL_WORLD_ALIGNED, tool frame.
        twist: Six numbers [m/s, rad/s], linear first, base axes.
        epsilon: DLS singular-region size.
        lambda_max: DLS damping at a singularity.
        reference: Returns the reference joint velocity (nv,) [rad/s] (called
            only in the singular region), or None for zero.

    Returns:
        ``(qd, used_dls)``: shape (nv,) [rad/s], and True if the DLS inverse was
        computed (the singular region, or no block structure).
    """
    if jacobian.shape == (6, 6):
        qd = _block_solve(jacobian.tolist(), twist, epsilon)
        if qd is not None:
            return np.array(qd), False
    inverse = dls_inverse(jacobian, epsilon=epsilon, lambda_max=lambda_max)
    xd = np.array(twist, dtype=np.float64)
    if reference is None:
        return inverse @ xd, True
    qd_ref = reference()
    return qd_ref + inverse @ (xd - jacobian @ qd_ref), True


__all__ = ["BLOCK_TOL", "solve_velocity", "solve_velocity_list"]
