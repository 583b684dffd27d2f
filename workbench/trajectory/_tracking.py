"""Compiled steps 2 and 3 of the online planner's cycle (Kang 2007, §5).

Step 2 turns the tool-tip command into the wrist-centre command in the base
frame; step 3 solves the closed-form IK and keeps the branch that continues
the motion. Both run once per planning cycle, so they are compiled with Numba
(the same arithmetic in Python costs several times more than the IK itself).
"""

from __future__ import annotations

import numba
import numpy as np
import numpy.typing as npt

from workbench.ik import _puma_kernel as kernel

FloatArray = npt.NDArray[np.float64]

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")


@_jit
def wrist_command(
    rotation: FloatArray,
    position: FloatArray,
    velocity: FloatArray,
    angular_velocity: FloatArray,
    tip_back: FloatArray,
    base_position: FloatArray,
    pose: FloatArray,
    twist: FloatArray,
) -> None:
    """Tool-tip command (world frame) -> wrist-centre command (base frame).

    For a tip frame and a base frame that are translated, not rotated: the
    wrist centre is ``p + R tip_back``, moving at ``v + ω × (R tip_back)``.

    Args:
        rotation: (3, 3) tool orientation, world frame.
        position: (3,) tool-tip position [m], world frame.
        velocity: (3,) [m/s], world axes.
        angular_velocity: (3,) [rad/s], world axes.
        tip_back: (3,) from the tip to the wrist centre [m], tool axes.
        base_position: (3,) robot base origin in the world frame [m].
        pose: (4, 4) output, wrist-centre pose in the base frame.
        twist: (6,) output [m/s, rad/s], linear first, base axes.
    """
    w0, w1, w2 = angular_velocity[0], angular_velocity[1], angular_velocity[2]
    lever = np.empty(3)
    for i in range(3):
        lever[i] = (
            rotation[i, 0] * tip_back[0]
            + rotation[i, 1] * tip_back[1]
            + rotation[i, 2] * tip_back[2]
        )
        for j in range(3):
            pose[i, j] = rotation[i, j]
        pose[i, 3] = position[i] + lever[i] - base_position[i]
        pose[3, i] = 0.0
    pose[3, 3] = 1.0
    twist[0] = velocity[0] + w1 * lever[2] - w2 * lever[1]
    twist[1] = velocity[1] + w2 * lever[0] - w0 * lever[2]
    twist[2] = velocity[2] + w0 * lever[1] - w1 * lever[0]
    twist[3], twist[4], twist[5] = w0, w1, w2


@_jit
def track(
    geometry: np.ndarray,
    pose: FloatArray,
    q: FloatArray,
    q_before: FloatArray,
    pair: int,
    max_step2: float,
) -> tuple[int, FloatArray, int, bool]:
    """The IK solution that continues a motion (Kang's θ4 flip rule, generalised).

    The configuration is predicted from the last two commands,
    ``2 q - q_before``, so that at a wrist singularity (θ4, θ6 free) the wrist
    keeps moving as it was; every angle is taken as the representative nearest
    the prediction, and the branch by ``_puma_kernel.continuing_branch``.

    Args:
        geometry: ``_puma_kernel.packed_geometry(robot)``.
        pose: (4, 4) wrist-centre target in the base frame.
        q: (6,) last joint command [rad].
        q_before: (6,) the one before it [rad] (``q`` on the first cycle).
        pair: (Arm, elbow) pair of the last command's branch, ``index >> 1``.
        max_step2: Largest squared joint step [rad²] that keeps the pair.

    Returns:
        ``(status, q_new, index, within)``: ``_puma_kernel`` status (the rest
        is meaningful if OK), the joint command (6,) [rad], its branch index
        and whether it is within the joint limits.
    """
    q_pred = 2.0 * q - q_before
    q_all = np.empty((8, 6))
    flags = np.empty(12, dtype=np.bool_)
    status = kernel.solve_pose(geometry, pose, q_pred, q_all, flags)
    if status != kernel.OK:
        return status, q_pred, -1, False
    index = kernel.continuing_branch(q_all, q_pred, pair, max_step2)
    return status, q_all[index].copy(), index, flags[index]
