"""Compiled step 2 of the online planner's cycle (Kang 2007, §5).

Step 2 turns the tool-tip command into the wrist-centre command in the base
frame; step 3, the closed-form IK that continues the motion, is
:meth:`workbench.ik.Solver.track`. Step 2 runs once per planning
cycle, so it is compiled with Numba (the same arithmetic in Python costs
several times more than the IK itself).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point

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
