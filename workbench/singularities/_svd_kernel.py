r"""Compiled singular values of batches of small Jacobians: one-sided Jacobi (Hestenes).

For a Jacobian :math:`J` (6, n), the columns of :math:`A = J` (n ≤ 6) or
:math:`A = J^T` (n > 6) are rotated in pairs until they are mutually
orthogonal; the singular values are then their norms. A pair (p, q) is
rotated by the angle that makes columns p and q orthogonal, and is left alone
once :math:`|a_p \cdot a_q| \le` :data:`ORTHOGONALITY` :math:`|a_p|\,|a_q|`.
Unlike the eigenvalues of :math:`J^T J`, whose smallest is lost below
:math:`\varepsilon\,\sigma_{\max}^2`, this keeps every singular value to a few
units of :math:`\varepsilon\,\sigma_{\max}` absolute (the accuracy of LAPACK's
``gesdd`` that ``np.linalg.svd`` calls), so that :math:`\sigma_{\min}` of a
configuration on a singular locus comes out at rounding level, not at
:math:`\sqrt{\varepsilon}`.

The squared norms of the two columns of a pair are updated with the rotation
(:math:`\alpha' = \alpha - t\gamma`, :math:`\beta' = \beta + t\gamma`) and
computed afresh at the start of every sweep, so a sweep costs one dot
product per pair besides the rotations. Only :func:`singular_values` is an
entry point.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point, helper

FloatArray = npt.NDArray[np.float64]

#: Relative size of the dot product of two columns below which they count as
#: orthogonal (a pair is rotated while above): four units of roundoff, about
#: the rounding error of a computed dot product of length 6 (at one unit, a
#: few matrices in a hundred never settle).
ORTHOGONALITY = 2.0**-51
#: Sweeps over every pair after which the iteration stops in any case (a 6 × 6
#: Jacobian converges in 6–9; the cap only bounds a matrix holding NaN).
MAX_SWEEPS = 30

_ORTHOGONALITY2 = ORTHOGONALITY**2  # the test squared: no square root per pair


@helper()
def _sweep(a: FloatArray, norms: FloatArray, k: int, m: int) -> bool:
    """One sweep of rotations over the pairs of the first ``k`` columns of ``a``.

    ``a`` (k, m): column c is the row ``a[c]``; ``norms`` (k,) gets their
    squared norms. Returns whether any pair was rotated.
    """
    for c in range(k):
        s = 0.0
        for i in range(m):
            s += a[c, i] * a[c, i]
        norms[c] = s
    rotated = False
    for p in range(k - 1):
        for q in range(p + 1, k):
            gamma = 0.0
            for i in range(m):
                gamma += a[p, i] * a[q, i]
            alpha, beta = norms[p], norms[q]
            if not gamma * gamma > _ORTHOGONALITY2 * (alpha * beta):
                continue  # orthogonal to working precision (or NaN: stop)
            rotated = True
            zeta = (beta - alpha) / (2.0 * gamma)
            t = 1.0 / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
            t = t if zeta >= 0.0 else -t
            cos = 1.0 / math.sqrt(1.0 + t * t)
            sin = cos * t
            for i in range(m):
                x, y = a[p, i], a[q, i]
                a[p, i] = cos * x - sin * y
                a[q, i] = sin * x + cos * y
            norms[p] = alpha - t * gamma
            norms[q] = beta + t * gamma
    return rotated


@entry_point(outputs=("out",), contiguous=("jacobians",))
def singular_values(jacobians: FloatArray, out: FloatArray) -> None:
    """Singular values of each Jacobian, in descending order.

    Args:
        jacobians: (N, 6, n) matrices [mixed units].
        out: (N, min(6, n)) output, written.
    """
    n = jacobians.shape[2]
    k, m = min(6, n), max(6, n)
    a, norms = np.empty((k, m)), np.empty(k)
    for b in range(jacobians.shape[0]):
        jac = jacobians[b]
        for c in range(k):  # columns of J (n <= 6) or of J^T (rows of J)
            for i in range(m):
                a[c, i] = jac[i, c] if n <= 6 else jac[c, i]
        for _ in range(MAX_SWEEPS):
            if not _sweep(a, norms, k, m):
                break
        row = out[b]
        for c in range(k):  # norms of the columns, by insertion into the row
            s = 0.0
            for i in range(m):
                s += a[c, i] * a[c, i]
            value = math.sqrt(s)
            j = c
            while j > 0 and row[j - 1] < value:
                row[j] = row[j - 1]
                j -= 1
            row[j] = value
