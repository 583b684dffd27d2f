"""Collision checking with coal: robot geometry, scenes, clearance along paths.

Example::

    from workbench import load_robot
    from workbench.collision import CollisionChecker, check_path, get_angeles_scene

    robot = load_robot("puma560")
    checker = CollisionChecker(robot, get_angeles_scene(robot))
    report = check_path(checker, t, q)        # t (K,) [s], q (K, nq) [rad]
    report.min_clearance, report.contacts     # [m], contact intervals
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from workbench._lazy import attach

if TYPE_CHECKING:
    from workbench.collision.along_path import check_path
    from workbench.collision.checker import CollisionChecker, PairInfo
    from workbench.collision.clearance_report import Contact, PathClearance
    from workbench.collision.paper_scenes import (
        get_angeles_obstacle_scene,
        get_angeles_scene,
        get_pedestal,
        get_pick_and_place_scene,
    )
    from workbench.collision.scene import Obstacle, Scene
    from workbench.collision.scene_file import parse_scene, read_scene, write_scene
    from workbench.collision.self_filter import (
        DisabledPair,
        SelfCollisionFilter,
        compute_self_collision_filter,
    )

__all__ = [
    "CollisionChecker",
    "Contact",
    "DisabledPair",
    "Obstacle",
    "PairInfo",
    "PathClearance",
    "Scene",
    "SelfCollisionFilter",
    "check_path",
    "compute_self_collision_filter",
    "get_angeles_obstacle_scene",
    "get_angeles_scene",
    "get_pedestal",
    "get_pick_and_place_scene",
    "parse_scene",
    "read_scene",
    "write_scene",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
