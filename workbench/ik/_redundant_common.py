r"""What the compiled closed forms of seven-axis arms share: status codes.

The kernels of both seven-axis families (:mod:`workbench.ik._srs_kernel`, SRS arms
such as the KUKA LBR iiwa; :mod:`workbench.ik._franka_kernel`, the Franka Panda and
FR3 geometry) solve one pose for one value of the redundancy parameter (SRS: the
arm angle ψ; Franka: q7) and describe each branch by one byte of the flag bits
of :mod:`workbench.ik._flags` (re-exported here for the kernels), as the 6R
kernels do.

A branch's row of ``q`` is NaN when the branch does not reach the pose for that
value; its byte is then 0.
"""

from __future__ import annotations

from workbench.ik._flags import ELBOW_SINGULAR as ELBOW_SINGULAR
from workbench.ik._flags import PARAMETER_SINGULAR as PARAMETER_SINGULAR
from workbench.ik._flags import REACHED as REACHED
from workbench.ik._flags import SHOULDER_SINGULAR as SHOULDER_SINGULAR
from workbench.ik._flags import WITHIN_LIMITS as WITHIN_LIMITS
from workbench.ik._flags import WRIST_SINGULAR as WRIST_SINGULAR

#: Status codes of the kernels' ``solve_pose`` and ``diagnose``: solved (at
#: least one branch reaches); the pose is not a finite rigid transform; no
#: branch reaches the pose for this value of the parameter (the wrist point is
#: out of the arm's reach, or, Franka, out of the reach the fixed q7 leaves).
OK, NOT_RIGID, OUT_OF_REACH = 0, 1, 2

__all__ = [
    "ELBOW_SINGULAR",
    "NOT_RIGID",
    "OK",
    "OUT_OF_REACH",
    "PARAMETER_SINGULAR",
    "REACHED",
    "SHOULDER_SINGULAR",
    "WITHIN_LIMITS",
    "WRIST_SINGULAR",
]
