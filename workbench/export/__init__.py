"""Trajectories out to controllers and ROS: MCAP bags and URScript.

Example::

    from workbench.export import write_ros2_bag, write_urscript

    write_ros2_bag("traj_bag", samples, robot.joint_names)     # a new folder
    write_urscript("traj.script", samples, ur5.joint_names)    # UR arms only

A trajectory CSV (``workbench export --format csv``) is the one dialect of
:func:`workbench.trajectory.write_trajectory_csv`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from workbench._lazy import attach

if TYPE_CHECKING:
    from workbench.export.ros2_bag import BagTrajectory, read_ros2_bag, write_ros2_bag
    from workbench.export.urscript import (
        UR_JOINTS,
        generate_urscript,
        resample_hermite,
        write_urscript,
    )

__all__ = [
    "UR_JOINTS",
    "BagTrajectory",
    "generate_urscript",
    "read_ros2_bag",
    "resample_hermite",
    "write_ros2_bag",
    "write_urscript",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
