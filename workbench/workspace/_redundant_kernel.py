r"""Compiled fold of a seven-axis map's candidates, one value of ψ or q7 at a time.

After the batch closed form at one value of the redundancy parameter
(:func:`workbench.ik.analytic_batch`), :func:`fold_value` updates, per pose,
the branches reached and within the joint limits at some value so far (bit
masks, bit b = branch b) and the best candidate so far: the in-limit branch
of largest limit margin, the first one kept on ties. Values are folded in
increasing order and branches in label order, so a tie keeps the first value,
then the first branch (:mod:`workbench.workspace.redundant`).

Each angle's representative :math:`q + 2\pi k` nearest the middle of its
limits is taken (:func:`workbench.workspace._measure_kernel.branch_limits`, the
six-axis maps' test): within the limits if any representative is, and of
largest margin.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point
from workbench.workspace._measure_kernel import (
    JOINT_ROWS,
    branch_limits,
    write_representatives,
)

FloatArray = npt.NDArray[np.float64]

__all__ = ["JOINT_ROWS", "fold_value"]


@entry_point(
    outputs=("reached", "usable", "margin", "best_q", "best_value"),
    contiguous=("joints", "q", "valid"),
)
def fold_value(
    joints: FloatArray,
    q: FloatArray,
    valid: npt.NDArray[np.bool_],
    value_index: int,
    first: int,
    reached: npt.NDArray[np.uint8],
    usable: npt.NDArray[np.uint8],
    margin: FloatArray,
    best_q: FloatArray,
    best_value: npt.NDArray[np.int64],
) -> None:
    """Fold the branches of N poses at one parameter value into the block's state.

    Args:
        joints: (JOINT_ROWS, n) per-joint constants, the rows of
            :mod:`workbench.workspace._measure_kernel` (sign and offset unused).
        q: (N, B, n) joint values [rad] of every branch (B <= 8; NaN rows:
            not reached).
        valid: (N, B) branch reaches the pose.
        value_index: Index of this value among the map's values.
        first: Row of pose 0 in the state arrays.
        reached: (P,) bit masks of the branches reaching at some value.
        usable: (P,) bit masks of the branches within the limits at some value.
        margin: (P,) best limit margin so far [rad] (−inf: none).
        best_q: (P, n) representatives of the best candidate [rad].
        best_value: (P,) value index of the best candidate (−1: none).
    """
    for i in range(q.shape[0]):
        row = first + i
        for b in range(q.shape[1]):
            if not valid[i, b]:
                continue
            bit = np.uint8(1 << b)
            reached[row] |= bit
            within, candidate = branch_limits(joints, q, i, b)
            if not within:
                continue
            usable[row] |= bit
            if candidate > margin[row]:
                margin[row] = candidate
                best_value[row] = value_index
                write_representatives(joints, q, i, b, best_q, row)
