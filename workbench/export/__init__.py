"""Trajectories out to controllers and ROS: MCAP bags, URScript, named CSV.

Example::

    from workbench.export import write_ros2_bag, write_urscript, write_named_csv

    write_ros2_bag("traj_bag", samples, robot.joint_names)     # a new folder
    write_urscript("traj.script", samples, ur5.joint_names)    # UR arms only
    write_named_csv("traj.csv", samples, robot.joint_names)
"""

from workbench.export.named_csv import get_named_header, write_named_csv
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
    "get_named_header",
    "read_ros2_bag",
    "resample_hermite",
    "write_named_csv",
    "write_ros2_bag",
    "write_urscript",
]
