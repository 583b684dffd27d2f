r"""Compiled tool poses and manipulability of a batch of configurations (any arm).

One pass per configuration of the chain kinematics of the numerical IK
(``workbench.ik._chain_kernel``: ``_forward`` then ``_jacobian``, the tool's
LOCAL Jacobian): the tool pose in the base frame and Yoshikawa's
manipulability :math:`\sqrt{\det(J J^T)}` of the 6 × n Jacobian, as the
product of the pivots of the Cholesky factor of :math:`J J^T` (0 when
:math:`J J^T` is not positive definite: fewer than six independent columns).
Rotating the Jacobian's rows into the base axes does not change it.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point
from workbench.ik._chain_kernel import _forward, _jacobian

FloatArray = npt.NDArray[np.float64]


@entry_point(
    outputs=("rotations", "positions", "manipulability"), contiguous=("chain", "q")
)
def tool_poses(
    chain: FloatArray,
    q: FloatArray,
    rotations: FloatArray,
    positions: FloatArray,
    manipulability: FloatArray,
) -> None:
    """Tool poses and manipulability of N configurations.

    Args:
        chain: (n + 1, CHAIN_WIDTH) packed chain (``_chain_kernel``).
        q: (N, n) chain coordinates [rad or m].
        rotations: (N, 3, 3) output, tool rotation in the base frame.
        positions: (N, 3) output, tool position [m] in the base frame.
        manipulability: (N,) output, √det(J Jᵀ) [m³ for six
            revolute joints].
    """
    n = chain.shape[0] - 1
    frames = np.empty((n + 1, 12))
    jac = np.empty((6, n))
    low = np.empty((6, 6))
    for b in range(q.shape[0]):
        _forward(chain, q[b], frames)
        _jacobian(chain, frames, jac)
        f = frames[n]
        for i in range(3):
            for j in range(3):
                rotations[b, i, j] = f[3 * i + j]
            positions[b, i] = f[9 + i]
        product = 1.0
        for i in range(6):  # Cholesky of J Jᵀ, row by row
            for j in range(i + 1):
                total = 0.0
                for k in range(n):
                    total += jac[i, k] * jac[j, k]
                for k in range(j):
                    total -= low[i, k] * low[j, k]
                if i == j:
                    pivot = math.sqrt(total) if total > 0.0 else 0.0
                    low[i, i] = pivot
                    product *= pivot
                else:
                    low[i, j] = total / low[j, j] if low[j, j] > 0.0 else 0.0
        manipulability[b] = product
