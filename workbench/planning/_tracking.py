"""Compiled steps 2 and 3 of the online planner's cycle (Kang 2007, §5).

Step 2 turns the tool-tip command into the wrist-centre command in the base
frame; step 3 solves the closed-form IK and keeps the branch that continues
the motion. Both run once per planning cycle, so they are compiled with Numba
(the same arithmetic in Python costs several times more than the IK itself)
and called together (:func:`command_joints`, one call per cycle).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point
from workbench.ik import _puma_kernel as kernel

FloatArray = npt.NDArray[np.float64]


@entry_point(outputs=("pose", "twist"))
def wrist_command(
    rotation: FloatArray,
    position: FloatArray,
    velocity: FloatArray,
    angular_velocity: FloatArray,
    frames: FloatArray,
    pose: FloatArray,
    twist: FloatArray,
) -> None:
    """Tool-tip command (world frame) -> wrist-centre command (base frame).

    The wrist frame is ``R6 = R tip_rotation_t`` at ``p + R6 tip_back``, moving
    at ``v + ω × (R6 tip_back)``; all of it is then expressed in the base
    frame (``base_rotation``, ``base_position`` in the world frame).

    Args:
        rotation: (3, 3) tool-tip orientation, world frame.
        position: (3,) tool-tip position [m], world frame.
        velocity: (3,) [m/s], world axes.
        angular_velocity: (3,) [rad/s], world axes.
        frames: (8, 3): rows 0-2 ``tip_rotation_t``, the transpose of the
            tip's rotation in the tool frame; row 3 ``tip_back``, from the tip
            to the wrist centre [m], tool axes; rows 4-6 ``base_rotation``, the
            base orientation in the world frame; row 7 ``base_position``, the
            base origin in the world frame [m].
        pose: (4, 4) output, wrist-centre pose in the base frame.
        twist: (6,) output [m/s, rad/s], linear first, base axes.
    """
    tip_rotation_t, tip_back = frames[0:3], frames[3]
    base_rotation, base_position = frames[4:7], frames[7]
    r6 = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            r6[i, j] = (
                rotation[i, 0] * tip_rotation_t[0, j]
                + rotation[i, 1] * tip_rotation_t[1, j]
                + rotation[i, 2] * tip_rotation_t[2, j]
            )
    lever, p6, v6 = np.empty(3), np.empty(3), np.empty(3)
    for i in range(3):
        lever[i] = (
            r6[i, 0] * tip_back[0] + r6[i, 1] * tip_back[1] + r6[i, 2] * tip_back[2]
        )
        p6[i] = position[i] + lever[i] - base_position[i]
    w0, w1, w2 = angular_velocity[0], angular_velocity[1], angular_velocity[2]
    v6[0] = velocity[0] + w1 * lever[2] - w2 * lever[1]
    v6[1] = velocity[1] + w2 * lever[0] - w0 * lever[2]
    v6[2] = velocity[2] + w0 * lever[1] - w1 * lever[0]
    # in base axes: multiply by base_rotation^T
    for i in range(3):
        for j in range(3):
            pose[i, j] = (
                base_rotation[0, i] * r6[0, j]
                + base_rotation[1, i] * r6[1, j]
                + base_rotation[2, i] * r6[2, j]
            )
        pose[i, 3] = (
            base_rotation[0, i] * p6[0]
            + base_rotation[1, i] * p6[1]
            + base_rotation[2, i] * p6[2]
        )
        twist[i] = (
            base_rotation[0, i] * v6[0]
            + base_rotation[1, i] * v6[1]
            + base_rotation[2, i] * v6[2]
        )
        twist[3 + i] = (
            base_rotation[0, i] * w0
            + base_rotation[1, i] * w1
            + base_rotation[2, i] * w2
        )
        pose[3, i] = 0.0
    pose[3, 3] = 1.0


@entry_point()
def track(
    geometry: np.ndarray,
    pose: FloatArray,
    q: FloatArray,
    q_before: FloatArray,
    pair: int,
    max_step2: float,
    check: bool,
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
        check: Run the kernel's quick rigidity test on ``pose``.

    Returns:
        ``(status, q_new, index, within)``: ``_puma_kernel`` status (the rest
        is meaningful if OK), the joint command (6,) [rad], its branch index
        and whether it is within the joint limits.
    """
    q_pred = 2.0 * q - q_before
    q_all = np.empty((8, 6))
    flags = np.empty(14, dtype=np.bool_)
    status = kernel.solve_pose(geometry, pose, q_pred, q_all, flags, check)
    if status != kernel.OK:
        return status, q_pred, -1, False
    index = kernel.continuing_branch(q_all, q_pred, pair, max_step2)
    return status, q_all[index].copy(), index, flags[index]


@entry_point(outputs=("pose", "twist"))
def command_joints(
    rotation: FloatArray,
    position: FloatArray,
    velocity: FloatArray,
    angular_velocity: FloatArray,
    frames: FloatArray,
    geometry: np.ndarray,
    q: FloatArray,
    q_before: FloatArray,
    pair: int,
    max_step2: float,
    pose: FloatArray,
    twist: FloatArray,
) -> tuple[int, FloatArray, int, bool]:
    """:func:`wrist_command` then :func:`track`, in one call.

    Args:
        rotation: (3, 3) tool-tip orientation, world frame.
        position: (3,) tool-tip position [m], world frame.
        velocity: (3,) [m/s], world axes.
        angular_velocity: (3,) [rad/s], world axes.
        frames: (8, 3), the tip and base frames of :func:`wrist_command`.
        geometry: ``_puma_kernel.packed_geometry(robot)``.
        q: (6,) last joint command [rad].
        q_before: (6,) the one before it [rad].
        pair: (Arm, elbow) pair of the last command's branch.
        max_step2: Largest squared joint step [rad²] that keeps the pair.
        pose: (4, 4) output, wrist-centre pose in the base frame.
        twist: (6,) output [m/s, rad/s], linear first, base axes.

    Returns:
        As :func:`track` (with its quick rigidity test).
    """
    wrist_command(rotation, position, velocity, angular_velocity, frames, pose, twist)
    return track(geometry, pose, q, q_before, pair, max_step2, True)
