"""Tool poses and manipulability of any serial arm for a batch of configurations.

Compiled (``_pose_kernel``, on the chain kinematics of the numerical IK): one
pass per configuration, no call into Pinocchio. For maps that sample millions
of configurations (the sampled workspace maps of arms without a closed form).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from workbench.ik import _pose_kernel as kernel
from workbench.ik._chain import get_chain
from workbench.model.robot import Robot
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]

#: Configurations per pass of the compiled kernel (bounds the work arrays).
POSE_CHUNK = 1 << 16


def compute_tool_poses(
    robot: Robot, q: npt.ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Tool frame poses and Yoshikawa manipulability at N configurations.

    Args:
        robot: Any serial arm (revolute, continuous and prismatic joints).
        q: Configurations, shape (N, nq) [rad or m].

    Returns:
        ``(rotations, positions, manipulability)``: (N, 3, 3) rotations and
        (N, 3) positions [m] of the tool frame in the base frame
        (:meth:`Robot.fk`), and (N,) √det(J Jᵀ) of the
        tool Jacobian (6 × joints on the path to the tool; m³ for six
        revolute joints), 0 below rank six.

    Raises:
        DimensionError: If ``q`` is not (N, nq).
        NonFiniteError: If ``q`` holds NaN or inf.
        InputError: If a joint on the path to the tool is neither revolute nor
            prismatic.
    """
    q = np.asarray(q, dtype=np.float64)
    q = as_finite_array(q, (q.shape[0] if q.ndim == 2 else -1, robot.nq), "q")
    chain = get_chain(robot)
    values = np.ascontiguousarray(chain.to_chain(q))
    count = len(values)
    rotations, positions = np.empty((count, 3, 3)), np.empty((count, 3))
    manipulability = np.empty(count)
    for start in range(0, count, POSE_CHUNK):
        part = slice(start, start + POSE_CHUNK)
        kernel.tool_poses(
            chain.packed, values[part], rotations[part], positions[part],
            manipulability[part],
        )  # fmt: skip
    return rotations, positions, manipulability


__all__ = ["POSE_CHUNK", "compute_tool_poses"]
