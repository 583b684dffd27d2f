"""Workspace atlas: reachability and dexterity maps over a grid of tool poses.

A :class:`PoseGrid` (voxel positions × tool orientations, :mod:`.grid`), the
per-pose measures of a block of it in closed form (:mod:`.measures`; seven-axis
arms at K values of their redundancy parameter, :mod:`.redundant`) and the
sampled maps of arms without a closed form (:mod:`.sampled`); the joint-space
singularity map (:mod:`.joint_space`); base placement for a task
(:mod:`.placement`, its default region :mod:`.placement_region`, task poses
from :mod:`.task_poses`); maps built on Dask
(:mod:`.build`) into a Zarr store, opened and queried (:mod:`.store`).
"""

from workbench.workspace.build import MapSummary, build_map
from workbench.workspace.grid import (
    PoseGrid,
    cone_orientations,
    default_bounds,
    make_pose_grid,
    uniform_orientations,
)
from workbench.workspace.joint_space import JointSpaceMap, compute_joint_space_map
from workbench.workspace.map_query import MapQuery
from workbench.workspace.measures import (
    POSE_KEYS,
    VOXEL_KEYS,
    evaluate_block,
    singularity_margin,
)
from workbench.workspace.placement import (
    Placement,
    PlacementInfeasibleError,
    place_base,
)
from workbench.workspace.placement_region import default_region
from workbench.workspace.redundant import evaluate_redundant_block, redundancy_values
from workbench.workspace.sampled import accumulate, sample_block
from workbench.workspace.store import WorkspaceMap, open_map
from workbench.workspace.task_poses import (
    TaskPoses,
    read_task_poses,
    task_poses_from_trajectory,
)

__all__ = [
    "POSE_KEYS",
    "VOXEL_KEYS",
    "JointSpaceMap",
    "MapQuery",
    "MapSummary",
    "Placement",
    "PlacementInfeasibleError",
    "PoseGrid",
    "TaskPoses",
    "WorkspaceMap",
    "accumulate",
    "build_map",
    "compute_joint_space_map",
    "cone_orientations",
    "default_bounds",
    "default_region",
    "evaluate_block",
    "evaluate_redundant_block",
    "make_pose_grid",
    "open_map",
    "place_base",
    "read_task_poses",
    "redundancy_values",
    "sample_block",
    "singularity_margin",
    "task_poses_from_trajectory",
    "uniform_orientations",
]
