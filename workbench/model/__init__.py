"""Robot models: DH tables, URDF generation, the robot catalog, loading, Robot."""

from workbench.model.catalog import (
    CATALOG,
    CatalogEntry,
    get_catalog_urdf,
    get_example_robot_data_dir,
    get_own_urdf_dir,
)
from workbench.model.dh import DEFAULT_VELOCITY_LIMIT, DHJoint, DHTable
from workbench.model.loading import get_robot_names, load_robot
from workbench.model.per_robot import per_robot
from workbench.model.robot import Robot
from workbench.model.urdf_generator import generate_urdf
from workbench.model.urdf_joints import MimicJoint

__all__ = [
    "CATALOG",
    "DEFAULT_VELOCITY_LIMIT",
    "CatalogEntry",
    "DHJoint",
    "DHTable",
    "MimicJoint",
    "Robot",
    "generate_urdf",
    "get_catalog_urdf",
    "get_example_robot_data_dir",
    "get_own_urdf_dir",
    "get_robot_names",
    "load_robot",
    "per_robot",
]
