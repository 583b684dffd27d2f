r"""What the compiled closed forms of seven-axis arms share: status codes and flag bits.

The kernels of both seven-axis families (:mod:`workbench.ik._srs_kernel`, SRS arms
such as the KUKA LBR iiwa; :mod:`workbench.ik._franka_kernel`, the Franka Panda and
FR3 geometry) solve one pose for one value of the redundancy parameter (SRS: the
arm angle ψ; Franka: q7) and describe each branch by one byte of flag bits.

A branch's row of ``q`` is NaN when the branch does not reach the pose for that
value; a byte's bits are only meaningful on reached branches.
"""

from __future__ import annotations

#: Status codes of the kernels' ``solve_pose`` and ``diagnose``: solved (at
#: least one branch reaches); the pose is not a finite rigid transform; no
#: branch reaches the pose for this value of the parameter (the wrist point is
#: out of the arm's reach, or, Franka, out of the reach the fixed q7 leaves).
OK, NOT_RIGID, OUT_OF_REACH = 0, 1, 2

#: Flag bits of one branch (a uint8 per branch).
#: Every joint within its limits (± the 6R kernels' LIMIT_TOL).
WITHIN_LIMITS = 1
#: The branch meets its shoulder twin (SRS: sin θ2 = 0, axes 1 and 3 aligned).
SHOULDER_SINGULAR = 2
#: The branch meets its elbow twin (SRS: sin θ4 = 0, the arm stretched).
ELBOW_SINGULAR = 4
#: The branch meets its wrist twin (SRS: sin θ6 = 0, axes 5 and 7 aligned).
WRIST_SINGULAR = 8
#: The redundancy parameter itself is undefined or degenerate here (SRS: the
#: wrist centre on axis 1, where the arm angle's reference plane is not
#: defined: the algorithmic singularity).
PARAMETER_SINGULAR = 16

__all__ = [
    "ELBOW_SINGULAR",
    "NOT_RIGID",
    "OK",
    "OUT_OF_REACH",
    "PARAMETER_SINGULAR",
    "SHOULDER_SINGULAR",
    "WITHIN_LIMITS",
    "WRIST_SINGULAR",
]
