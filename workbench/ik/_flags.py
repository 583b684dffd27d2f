"""The flag bits of a closed-form branch: one byte per branch, for every family.

Every closed-form kernel (6R: :mod:`workbench.ik._puma_kernel`,
:mod:`workbench.ik._ur_kernel`; 7R: :mod:`workbench.ik._srs_kernel`,
:mod:`workbench.ik._franka_kernel`) writes, with the (B, n) joint values of a
pose, a (B,) uint8 array of these bits, and :class:`workbench.ik.IKSolution`
reads its flags from them. A branch that does not reach the pose has the byte
0 (no :data:`REACHED` bit) and a NaN row of joint values.

The same bits as an :class:`enum.IntFlag`: :class:`Flag` (``IKSolution.flags``).
The kernels use the plain ints (compiled code reads module constants).

A solve as a whole has one more byte, :class:`SolveFlag`: what carrying the
branches of a calibrated arm from its idealised structure to the model
(``_refine_kernel``, ``_refine_redundant_kernel``) could not place. It is 0 on
an exact model, and on every pose whose branches all carried over one to one.
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


#: Solve-level bits (:class:`SolveFlag`). A branch of the idealised arm that
#: reaches the pose found no solution of the model continuing it (it vanished
#: at a fold of the model, e.g. where the two elbows meet): its row is NaN.
BRANCH_VANISHED = 1
#: Two branches of the idealised arm led to one solution of the model and no
#: other solution was found for the second: its row is NaN.
BRANCHES_MERGED = 2
#: The model may have solutions near a singularity that no branch holds (more
#: solutions than free branches, or a valley of near-singular solutions that
#: is not searched).
SOLUTIONS_UNLISTED = 4


class Flag(enum.IntFlag):
    """The flag bits of a branch (module docs), as an :class:`enum.IntFlag`."""

    REACHED = REACHED
    WITHIN_LIMITS = WITHIN_LIMITS
    SHOULDER_SINGULAR = SHOULDER_SINGULAR
    ELBOW_SINGULAR = ELBOW_SINGULAR
    WRIST_SINGULAR = WRIST_SINGULAR
    PARAMETER_SINGULAR = PARAMETER_SINGULAR


class SolveFlag(enum.IntFlag):
    """The solve-level bits of one pose (module docs), as an :class:`enum.IntFlag`."""

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
