"""The flag bits of a closed-form branch: one byte per branch, for every family.

Every closed-form kernel (6R: :mod:`workbench.ik._puma_kernel`,
:mod:`workbench.ik._ur_kernel`; 7R: :mod:`workbench.ik._srs_kernel`,
:mod:`workbench.ik._franka_kernel`) writes, with the (B, n) joint values of a
pose, a (B,) uint8 array of these bits, and :class:`workbench.ik.IKSolution`
reads its flags from them. A branch that does not reach the pose has the byte
0 (no :data:`REACHED` bit) and a NaN row of joint values.

The same bits as an :class:`enum.IntFlag`: :class:`Flag` (``IKSolution.flags``).
The kernels use the plain ints (compiled code reads module constants).

What holds for a whole solve rather than for one branch is a second byte,
:class:`SolveFlag` (``Solutions.solve_flags``): on an arm solved through the
ideal structure of its family and refined on its own model (a calibrated
arm), a branch of the ideal arm that has no counterpart on the model, two
that meet, or solutions of the model no branch holds. It is 0 on an exact
model.
"""

from __future__ import annotations

import enum

#: The branch reaches the pose (its row of joint values is finite).
REACHED = 1
#: Every joint within its limits (± ``LIMIT_TOL`` of ``workbench.ik._puma``).
WITHIN_LIMITS = 2
#: The branch meets its shoulder twin (6R: the right and left arms meet, the
#: wrist centre on the cylinder |D| around the base axis; SRS: sin θ2 = 0).
SHOULDER_SINGULAR = 4
#: The branch meets its elbow twin (the arm stretched or folded: 6R |sin γ| or
#: |sin θ3| below ``ELBOW_SINGULAR_TOL``; SRS: sin θ4 = 0).
ELBOW_SINGULAR = 8
#: The branch meets its wrist twin (6R: sin θ5 = 0; SRS: sin θ6 = 0).
WRIST_SINGULAR = 16
#: The redundancy parameter is degenerate here (SRS: the wrist centre on
#: axis 1, where the arm angle's reference plane is not defined); never set
#: on a 6R arm.
PARAMETER_SINGULAR = 32


class Flag(enum.IntFlag):
    """The flag bits of a branch (module docs), as an :class:`enum.IntFlag`."""

    REACHED = REACHED
    WITHIN_LIMITS = WITHIN_LIMITS
    SHOULDER_SINGULAR = SHOULDER_SINGULAR
    ELBOW_SINGULAR = ELBOW_SINGULAR
    WRIST_SINGULAR = WRIST_SINGULAR
    PARAMETER_SINGULAR = PARAMETER_SINGULAR


#: A calibrated arm: a branch of the ideal arm that reaches the pose has no
#: solution of the model continuing it (it vanished at a fold of the model);
#: it is not among the solutions.
BRANCH_VANISHED = 1
#: A calibrated arm: two branches of the ideal arm led to one solution of the
#: model and no other was found for the second; it is not among the solutions.
BRANCHES_MERGED = 2
#: A calibrated arm: near a singularity the model may have solutions that no
#: branch holds.
SOLUTIONS_UNLISTED = 4


class SolveFlag(enum.IntFlag):
    """The flag bits of a whole solve (module docs), an :class:`enum.IntFlag`."""

    BRANCH_VANISHED = BRANCH_VANISHED
    BRANCHES_MERGED = BRANCHES_MERGED
    SOLUTIONS_UNLISTED = SOLUTIONS_UNLISTED


__all__ = [
    "BRANCHES_MERGED",
    "BRANCH_VANISHED",
    "ELBOW_SINGULAR",
    "PARAMETER_SINGULAR",
    "REACHED",
    "SHOULDER_SINGULAR",
    "SOLUTIONS_UNLISTED",
    "WITHIN_LIMITS",
    "WRIST_SINGULAR",
    "Flag",
    "SolveFlag",
]
