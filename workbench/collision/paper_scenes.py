"""The scene of Angeles' pick-and-place (1988, Sec. V), in the robot base frame.

The paper gives no work cell (collisions were checked on a graphic display),
so the scene is an assumption built from the model and Table III:

* the **pedestal** drawn under the PUMA's base (the cylinder of
  :func:`workbench.model.urdf_generator.get_pedestal_cylinder`); joint 1's housing
  sits on it, so ``link1`` is allowed to touch it;
* a **pick table**: a 0.30 m × 0.30 m × 0.04 m plate whose top is
  :data:`PICK_TABLE_DROP` below the wrist centre at the pick of Table III
  (room for a gripper), centred :data:`PICK_TABLE_REACH` further out from the
  base axis than the wrist centre, square to that direction.

:func:`get_pick_and_place_scene` is the default scene of a pick-and-place
(``workbench plan pick-place``, ``workbench export --pick-place`` and
:meth:`workbench.trajectory.JointTrajectory.check_collisions`): Angeles' cell
for his PUMA, the pedestal for other arms generated from a DH table, an empty
scene (self-collisions only) for any other arm.

:func:`get_angeles_obstacle_scene` adds an obstacle to that cell: a
:data:`OBSTACLE_SIZE` cube centred where the straight joint motion of
Table III (the path of Angeles' spline) puts the tool frame halfway, so the
paper's motion runs through it and a planner has to go around
(:func:`workbench.motion.plan_around`, ``workbench demo``). In that scene
``link2`` may touch the pedestal too: the model's upper-arm cylinder cuts the
pedestal's top edge whenever joint 2 is more than about 24° below the
horizontal, and Table III's pick puts joint 2 at 45°, its upper limit — a
contact of the assumed geometry (the drawn pedestal and link cylinders), not
of the arm, which would otherwise make the paper's pick itself a collision.

Kang's fish-cutting scene (pedestal, table, fish) is built by
:func:`workbench.tasks.fish_scene.get_fish_cutting_scene`.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from workbench.collision.scene import Obstacle, Scene
from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.model.urdf_generator import get_pedestal_cylinder
from workbench.paper_data import ANGELES_PICK_Q_DEG, ANGELES_PLACE_Q_DEG

#: Height [m] of the wrist centre above the pick table's top.
PICK_TABLE_DROP = 0.10
#: Horizontal distance [m] from the pick's wrist centre to the table centre.
PICK_TABLE_REACH = 0.10
PICK_TABLE_SIZE = (0.30, 0.30, 0.04)
PEDESTAL_COLOR = (0.25, 0.27, 0.3, 1.0)
TABLE_COLOR = (0.6, 0.45, 0.3, 0.9)
#: Edges [m] of the obstacle of :func:`get_angeles_obstacle_scene`.
OBSTACLE_SIZE = (0.10, 0.10, 0.10)
OBSTACLE_COLOR = (0.8, 0.25, 0.2, 0.9)
#: Links allowed on the pedestal in :func:`get_angeles_obstacle_scene`.
OBSTACLE_SCENE_PEDESTAL_LINKS = ("link1", "link2")


def get_pedestal(robot: Robot, *, allow: tuple[str, ...] = ("link1",)) -> Obstacle:
    """The PUMA's pedestal as an obstacle (base frame).

    Raises:
        InputError: If the robot was not generated from a DH table.
    """
    if robot.dh_table is None:
        raise InputError(
            f"robot {robot.name!r} has no DH table: the pedestal scenes are for "
            "the PUMA models (give --scene FILE for other robots)"
        )
    radius, length, z = get_pedestal_cylinder(robot.dh_table)
    return Obstacle(
        "pedestal",
        "cylinder",
        (radius, length),
        pin.SE3(np.eye(3), np.array([0.0, 0.0, z])),
        allow,
        color=PEDESTAL_COLOR,
    )


def get_angeles_scene(robot: Robot) -> Scene:
    """Pedestal and pick table of Angeles' pick-and-place (see module docstring).

    Args:
        robot: A PUMA model (``puma560``; ``puma560-kang`` also works).

    Raises:
        InputError: If the robot is not a PUMA model from a DH table.
    """
    pedestal = get_pedestal(robot)
    q_pick = np.deg2rad(ANGELES_PICK_Q_DEG)
    if robot.nq != q_pick.size:
        raise InputError(f"robot {robot.name!r} is not a six-joint PUMA")
    wrist = robot.fk(q_pick).translation
    out = np.array([wrist[0], wrist[1], 0.0])
    out = out / np.linalg.norm(out) if np.linalg.norm(out) > 0 else np.array([1, 0, 0])
    size = PICK_TABLE_SIZE
    center = wrist + PICK_TABLE_REACH * out
    center[2] = wrist[2] - PICK_TABLE_DROP - size[2] / 2
    rotation = pin.rpy.rpyToMatrix(0.0, 0.0, float(np.arctan2(out[1], out[0])))
    table = Obstacle(
        "pick_table", "box", size, pin.SE3(rotation, center), color=TABLE_COLOR
    )
    return Scene("angeles-pick-and-place", (pedestal, table), "Angeles 1988, Sec. V")


def get_angeles_obstacle_scene(robot: Robot) -> Scene:
    """Angeles' cell with a cube on the paper's path (see module docstring).

    The pedestal (``link1`` and ``link2`` allowed on it), the pick table of
    :func:`get_angeles_scene`, and an ``obstacle``: an axis-aligned
    :data:`OBSTACLE_SIZE` cube centred at the tool frame's origin halfway
    along the straight joint motion from Table III's pick to its place.

    Args:
        robot: A six-joint PUMA model (``puma560``).

    Returns:
        The scene ``"angeles-obstacle"``, base frame.

    Raises:
        InputError: If the robot is not a six-joint PUMA model from a DH table.
    """
    cell = get_angeles_scene(robot)
    pedestal = get_pedestal(robot, allow=OBSTACLE_SCENE_PEDESTAL_LINKS)
    halfway = 0.5 * np.deg2rad(ANGELES_PICK_Q_DEG + ANGELES_PLACE_Q_DEG)
    cube = Obstacle(
        "obstacle",
        "box",
        OBSTACLE_SIZE,
        pin.SE3(np.eye(3), robot.fk(halfway).translation),
        color=OBSTACLE_COLOR,
    )
    table = next(o for o in cell.obstacles if o.name == "pick_table")
    return Scene(
        "angeles-obstacle",
        (pedestal, table, cube),
        "Angeles 1988, Sec. V, with a 10 cm cube on the path of Table III",
    )


def get_pick_and_place_scene(robot: Robot) -> Scene:
    """The default scene of a pick-and-place of ``robot`` (base frame).

    Args:
        robot: Any arm.

    Returns:
        :func:`get_angeles_scene` for Angeles' PUMA (the ``puma560`` DH
        table), the pedestal of :func:`get_pedestal` (scene ``"pedestal"``)
        for another arm generated from a DH table, else the empty scene
        ``"empty"`` (only self-collisions are checked).
    """
    if robot.dh_table is None:
        return Scene("empty")
    if robot.dh_table.name == "puma560":
        return get_angeles_scene(robot)
    return Scene("pedestal", (get_pedestal(robot),), "the pedestal under the base")


__all__ = [
    "OBSTACLE_SCENE_PEDESTAL_LINKS",
    "OBSTACLE_SIZE",
    "PICK_TABLE_DROP",
    "PICK_TABLE_REACH",
    "get_angeles_obstacle_scene",
    "get_angeles_scene",
    "get_pedestal",
    "get_pick_and_place_scene",
]
