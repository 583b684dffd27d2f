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
product per pair besides the rotations.

:data:`LANES` matrices go through the sweeps side by side, until all of them
have converged: the innermost loops run over them, and their count is read
from the scratch array's shape (a number unknown when compiling: a loop of a
constant 16 turns is unrolled into scalar code instead of being vectorised),
so the compiler uses vector instructions for the square roots and divisions
of the rotations. A matrix that has converged goes on with rotations by the
angle 0 (cos 1, sin 0: its columns unchanged, exactly), so each matrix gets
the bits it would get alone, whatever the batch around it.

Only :func:`singular_values` is an entry point.
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
#: Matrices swept side by side (16: four AVX2 registers of doubles per loop).
LANES = 16

_ORTHOGONALITY2 = ORTHOGONALITY**2  # the test squared: no square root per pair


@helper(forceinline=True)
def _rotate_pair(a, norms, gamma, cos, sin, p, q, m) -> int:
    """Rotate columns p and q of every lane of ``a`` (k, m, LANES) to orthogonal.

    ``norms`` (k, LANES): squared column norms, updated; ``gamma``, ``cos``,
    ``sin`` (LANES,): scratch. Returns how many lanes were rotated (by a
    nonzero angle).
    """
    lanes = a.shape[2]
    for lane in range(lanes):
        gamma[lane] = 0.0
    for i in range(m):
        for lane in range(lanes):
            gamma[lane] += a[p, i, lane] * a[q, i, lane]
    rotated = 0
    for lane in range(lanes):
        alpha, beta, g = norms[p, lane], norms[q, lane], gamma[lane]
        rotate = g * g > _ORTHOGONALITY2 * (alpha * beta)  # False for NaN
        zeta = (beta - alpha) / (2.0 * (g if rotate else 1.0))
        t = 1.0 / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
        t = (t if zeta >= 0.0 else -t) if rotate else 0.0
        c = 1.0 / math.sqrt(1.0 + t * t)
        cos[lane], sin[lane] = c, c * t
        norms[p, lane] = alpha - t * g
        norms[q, lane] = beta + t * g
        rotated += 1 if rotate else 0
    for i in range(m):
        for lane in range(lanes):
            x, y = a[p, i, lane], a[q, i, lane]
            a[p, i, lane] = cos[lane] * x - sin[lane] * y
            a[q, i, lane] = sin[lane] * x + cos[lane] * y
    return rotated


@helper(forceinline=True)
def _sweep(a, norms, gamma, cos, sin, k, m) -> int:
    """One sweep over the pairs of the first ``k`` columns; lanes rotated, summed."""
    lanes = a.shape[2]
    for c in range(k):
        for lane in range(lanes):
            norms[c, lane] = 0.0
        for i in range(m):
            for lane in range(lanes):
                norms[c, lane] += a[c, i, lane] * a[c, i, lane]
    rotated = 0
    for p in range(k - 1):
        for q in range(p + 1, k):
            rotated += _rotate_pair(a, norms, gamma, cos, sin, p, q, m)
    return rotated


@entry_point(outputs=("out",), contiguous=("jacobians",))
def singular_values(jacobians: FloatArray, out: FloatArray) -> None:
    """Singular values of each Jacobian, in descending order.

    Args:
        jacobians: (N, 6, n) matrices [mixed units].
        out: (N, min(6, n)) output, written.
    """
    count, n = jacobians.shape[0], jacobians.shape[2]
    k, m = min(6, n), max(6, n)
    a, norms = np.empty((k, m, LANES)), np.empty((k, LANES))
    gamma, cos, sin = np.empty(LANES), np.empty(LANES), np.empty(LANES)
    lanes = a.shape[2]
    for first in range(0, count, lanes):
        for lane in range(lanes):  # columns of J (n <= 6) or of J^T; zeros past N
            b = first + lane
            for c in range(k):
                for i in range(m):
                    value = 0.0
                    if b < count:
                        value = jacobians[b, i, c] if n <= 6 else jacobians[b, c, i]
                    a[c, i, lane] = value
        for _ in range(MAX_SWEEPS):
            if _sweep(a, norms, gamma, cos, sin, k, m) == 0:
                break
        for lane in range(min(lanes, count - first)):
            row = out[first + lane]
            for c in range(k):  # norms of the columns, by insertion into the row
                s = 0.0
                for i in range(m):
                    s += a[c, i, lane] * a[c, i, lane]
                value = math.sqrt(s)
                j = c
                while j > 0 and row[j - 1] < value:
                    row[j] = row[j - 1]
                    j -= 1
                row[j] = value
