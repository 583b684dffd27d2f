"""Tool Jacobians of any serial arm for a batch of configurations, in compiled code.

The compiled chain of the numerical IK (``_chain``: joint placements, axes
and kinds from the base to the tool frame) gives the tool's LOCAL Jacobian,
the one Pinocchio's ``getFrameJacobian(..., LOCAL)`` gives, without a call
into Pinocchio per configuration: maps over 10⁶ configurations (the
joint-space singularity map) need that speed.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from workbench.ik import _chain_kernel as kernel
from workbench.ik._chain import get_chain
from workbench.model.robot import Robot
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]


def compute_jacobians_local(robot: Robot, q: npt.ArrayLike) -> FloatArray:
    """LOCAL Jacobians of the tool frame at a batch of configurations.

    Args:
        robot: Any serial arm (revolute, continuous and prismatic joints).
        q: Configurations, shape (N, nq) [rad or m].

    Returns:
        Shape (N, 6, nv), rows [linear; angular] in the tool frame's own
        axes: :meth:`Robot.jacobian_local` of each configuration (columns of
        joints off the path to the tool are zero).

    Raises:
        DimensionError: If ``q`` is not (N, nq).
        NonFiniteError: If ``q`` holds NaN or inf.
        InputError: If a joint on the path to the tool is neither revolute nor
            prismatic (a mimic joint, a spherical joint, …).
    """
    q = np.asarray(q, dtype=np.float64)
    q = as_finite_array(q, (q.shape[0] if q.ndim == 2 else -1, robot.nq), "q")
    chain = get_chain(robot)
    values = np.ascontiguousarray(chain.to_chain(q))
    if chain.identity and chain.n == robot.nv:
        jac = np.empty((q.shape[0], 6, robot.nv))
        kernel.chain_jacobians(chain.packed, values, jac)
        return jac
    on_path = np.empty((q.shape[0], 6, chain.n))
    kernel.chain_jacobians(chain.packed, values, on_path)
    jac = np.zeros((q.shape[0], 6, robot.nv))
    jac[:, :, chain.idx_v] = on_path
    return jac
