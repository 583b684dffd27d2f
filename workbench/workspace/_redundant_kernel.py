r"""Compiled fold of a seven-axis map's candidates, one value of ψ or q7 at a time.

After the batch closed form at one value of the redundancy parameter
(:func:`workbench.ik.analytic_batch`), :func:`fold_value` updates, per pose,
the branches reached and within the joint limits at some value so far (bit
masks, bit b = branch b) and the best candidate so far: the in-limit branch
of largest limit margin, the first one kept on ties. Values are folded in
increasing order and branches in label order, so a tie keeps the first value,
then the first branch (:mod:`workbench.workspace.redundant`).

Each angle's representative :math:`q + 2\pi k` nearest the middle of its
limits is taken, as :func:`workbench.workspace._reference.limit_representatives`
does with NumPy, in the same arithmetic (``rint((mid − q) / 2π)`` turns):
within the limits if any representative is, and of largest margin.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point

FloatArray = npt.NDArray[np.float64]

#: Rows of the per-joint constants: lower, upper, middle of the limits,
#: bounded (1.0 or 0.0).
JOINT_ROWS = 4
_LOWER, _UPPER, _MID, _BOUNDED = range(JOINT_ROWS)

TAU = 2.0 * math.pi
#: 1 / 2π, the turns of an angle (as ``_reference.INV_TAU``).
INV_TAU = 1.0 / TAU


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
        joints: (JOINT_ROWS, n) per-joint constants (module slots).
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
    joint_count = q.shape[2]
    for i in range(q.shape[0]):
        row = first + i
        for b in range(q.shape[1]):
            if not valid[i, b]:
                continue
            bit = np.uint8(1 << b)
            reached[row] |= bit
            within = True
            candidate = math.inf
            for j in range(joint_count):
                if joints[_BOUNDED, j] != 0.0:
                    value = q[i, b, j]
                    lo, hi = joints[_LOWER, j], joints[_UPPER, j]
                    turns = np.rint((joints[_MID, j] - value) * INV_TAU)
                    shifted = value + turns * TAU
                    within &= (shifted >= lo) & (shifted <= hi)
                    candidate = min(candidate, min(shifted - lo, hi - shifted))
            if not within:
                continue
            usable[row] |= bit
            if candidate > margin[row]:
                margin[row] = candidate
                best_value[row] = value_index
                for j in range(joint_count):
                    value = q[i, b, j]
                    if joints[_BOUNDED, j] != 0.0:
                        turns = np.rint((joints[_MID, j] - value) * INV_TAU)
                        value = value + turns * TAU
                    best_q[row, j] = value
