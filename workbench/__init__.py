"""workbench: a kinematics workbench for the PUMA 560 and any URDF arm, on Pinocchio."""

import logging

from workbench.errors import (
    DHTableError,
    DimensionError,
    FrameNotFoundError,
    InfeasibleError,
    InputError,
    JointLimitError,
    JointNotFoundError,
    NonFiniteError,
    RobotNotFoundError,
    URDFLoadError,
    WorkbenchError,
)
from workbench.model.dh import DHJoint, DHTable
from workbench.model.loading import get_robot_names, load_robot
from workbench.model.robot import Robot
from workbench.model.urdf_generator import generate_urdf

logging.getLogger(__name__).addHandler(logging.NullHandler())

__all__ = [
    "DHJoint",
    "DHTable",
    "DHTableError",
    "DimensionError",
    "FrameNotFoundError",
    "InfeasibleError",
    "InputError",
    "JointLimitError",
    "JointNotFoundError",
    "NonFiniteError",
    "Robot",
    "RobotNotFoundError",
    "URDFLoadError",
    "WorkbenchError",
    "generate_urdf",
    "get_robot_names",
    "load_robot",
]
