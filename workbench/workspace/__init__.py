"""Workspace atlas: reachability and dexterity maps over a grid of tool poses.

A :class:`PoseGrid` (voxel positions × tool orientations, :mod:`.grid`), the
per-pose measures of a block of it in closed form (:mod:`.measures`; seven-axis
arms at K values of their redundancy parameter, :mod:`.redundant`) and the
sampled maps of arms without a closed form (:mod:`.sampled`); the joint-space
singularity map (:mod:`.joint_space`); base placement for a task
(:mod:`.placement`, its default region :mod:`.placement_region`, task poses
from :mod:`.task_poses`); maps built on Dask
(:mod:`.build`) into a Zarr store, opened and queried (:mod:`.store`), whose
manifest (:mod:`.manifest`) and attribute schema (:mod:`.map_schema`) every
open checks, and :mod:`.verify` checks whole.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from workbench._lazy import attach

if TYPE_CHECKING:
    from workbench.workspace._block_tasks import SAMPLES_PER_BLOCK
    from workbench.workspace.build import (
        DEFAULT_SAMPLES,
        MapSummary,
        build_map,
    )
    from workbench.workspace.grid import (
        DEFAULT_BLOCK_VOXELS,
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
        check_voxel_range,
        evaluate_block,
        get_core_count,
        singularity_margin,
    )
    from workbench.workspace.placement import (
        Placement,
        PlacementInfeasibleError,
        place_base,
    )
    from workbench.workspace.placement_check import (
        PATH_STEP_MAX,
        PlacementEvaluator,
        base_transform,
        follow_path,
    )
    from workbench.workspace.placement_region import default_region
    from workbench.workspace.redundant import (
        DEFAULT_REDUNDANCY_SAMPLES,
        MAX_REDUNDANCY_SAMPLES,
        REDUNDANT_POSE_KEYS,
        REDUNDANT_VOXEL_KEYS,
        evaluate_redundant_block,
        redundancy_values,
    )
    from workbench.workspace.robot_spec import (
        RobotSpec,
        get_robot_spec,
        load_spec_robot,
    )
    from workbench.workspace.sampled import accumulate, sample_block
    from workbench.workspace.store import (
        ARRAYS,
        FORMAT,
        FORMAT_VERSION,
        WorkspaceMap,
        get_partial_path,
        open_map,
    )
    from workbench.workspace.task_map import (
        TaskMap,
        build_task_map,
    )
    from workbench.workspace.task_poses import (
        TaskPoses,
        read_task_poses,
        read_trajectory_task_poses,
        task_poses_from_trajectory,
    )
    from workbench.workspace.verify import MapCheck, verify_map

__all__ = [
    "ARRAYS",
    "DEFAULT_BLOCK_VOXELS",
    "DEFAULT_REDUNDANCY_SAMPLES",
    "DEFAULT_SAMPLES",
    "FORMAT",
    "FORMAT_VERSION",
    "MAX_REDUNDANCY_SAMPLES",
    "PATH_STEP_MAX",
    "POSE_KEYS",
    "REDUNDANT_POSE_KEYS",
    "REDUNDANT_VOXEL_KEYS",
    "SAMPLES_PER_BLOCK",
    "VOXEL_KEYS",
    "JointSpaceMap",
    "MapCheck",
    "MapQuery",
    "MapSummary",
    "Placement",
    "PlacementEvaluator",
    "PlacementInfeasibleError",
    "PoseGrid",
    "RobotSpec",
    "TaskMap",
    "TaskPoses",
    "WorkspaceMap",
    "accumulate",
    "base_transform",
    "build_map",
    "build_task_map",
    "check_voxel_range",
    "compute_joint_space_map",
    "cone_orientations",
    "default_bounds",
    "default_region",
    "evaluate_block",
    "evaluate_redundant_block",
    "follow_path",
    "get_core_count",
    "get_partial_path",
    "get_robot_spec",
    "load_spec_robot",
    "make_pose_grid",
    "open_map",
    "place_base",
    "read_task_poses",
    "read_trajectory_task_poses",
    "redundancy_values",
    "sample_block",
    "singularity_margin",
    "task_poses_from_trajectory",
    "uniform_orientations",
    "verify_map",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
