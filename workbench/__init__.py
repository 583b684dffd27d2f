"""workbench: a kinematics workbench for the PUMA 560 and any URDF arm, on Pinocchio."""

# isort: off
from workbench import _sigint  # noqa: F401 (first: Ctrl-C while the command starts)

# isort: on
import importlib.metadata
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
from workbench.model.urdf_joints import MimicJoint

logging.getLogger(__name__).addHandler(logging.NullHandler())

DISTRIBUTION = "kinematics-workbench"  # on PyPI; the import name is ``workbench``
try:
    __version__ = importlib.metadata.version(DISTRIBUTION)
except importlib.metadata.PackageNotFoundError:  # run from a source tree
    __version__ = "0+unknown"

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
    "MimicJoint",
    "NonFiniteError",
    "Robot",
    "RobotNotFoundError",
    "URDFLoadError",
    "WorkbenchError",
    "generate_urdf",
    "get_robot_names",
    "load_robot",
]
