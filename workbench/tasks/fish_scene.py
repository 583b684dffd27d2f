"""Kang's fish-cutting cell (2007, Fig. 5 and 7) as a collision scene, base frame.

Kang shows the cell but gives no dimensions, so these are assumptions around
the simulated fish (:class:`~workbench.tasks.fish.SimulatedFish`) and the world
frame of Fig. 7 (the base placed by
:func:`~workbench.tasks.fish_program.get_base_placement`: for the PUMA,
:data:`~workbench.tasks.fish_program.KANG_BASE_HEIGHT` above the world origin).
Sizes are those of Kang's cell times the setup's ``scale`` (1 for the PUMA):

* the **pedestal** drawn under the base of an arm generated from a DH table
  (the PUMA models, the KUKA and ABB models), as in Angeles' scene; arms from
  other URDFs (UR) draw their own base and get none;
* a **cutting table** :data:`TABLE_THICKNESS` thick whose top is the fish's
  ``table_z``, :data:`TABLE_MARGIN` larger than the fish on every side;
* the **fish**: a closed triangle mesh of its flesh surface over the table
  (``flesh_top`` on a grid, floored at the table). The knife cuts it by
  design, so the wrist links that carry the knife (:func:`get_knife_links`,
  :data:`KNIFE_LINKS` for the PUMA) are allowed to touch it; every other link
  is checked.

:func:`compute_fish_cutting_clearance` checks a run's servo path in that cell
(or any scene), as ``workbench fishcut`` does.
"""

from __future__ import annotations

import itertools

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.collision import CollisionChecker, PathClearance, check_path
from workbench.collision.paper_scenes import TABLE_COLOR, get_pedestal
from workbench.collision.scene import Obstacle, Scene
from workbench.model.robot import Robot
from workbench.tasks.fish import SimulatedFish
from workbench.tasks.fish_cutting import FishCuttingResult
from workbench.tasks.fish_program import (
    FishCuttingSetup,
    get_cell_scale,
    get_world_transforms,
)

#: Margin [m] of the table around the fish, in Kang's cell (times ``scale``).
TABLE_MARGIN = 0.08
#: Thickness [m] of the table, in Kang's cell (times ``scale``).
TABLE_THICKNESS = 0.03
#: Links of the PUMA models that hold the knife: allowed to touch the fish.
KNIFE_LINKS = ("link5", "link6", "wrist_center")
FISH_COLOR = (0.85, 0.55, 0.45, 0.95)
_GRID = (40, 12)  # samples along and across the fish


def build_fish_mesh(
    fish: SimulatedFish,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
    """Closed triangle mesh of the fish, world frame.

    Returns:
        ``(vertices (V, 3) [m], triangles (T, 3) indices)``, outward facing:
        the flesh surface on a grid and the flat bottom at ``table_z``.
    """
    n_u, n_x = _GRID
    eps = 1e-6
    ys = np.linspace(fish.head_y + eps, fish.tail_y - eps, n_u)
    xs = fish.center_x + fish.half_width * np.linspace(-1 + eps, 1 - eps, n_x)
    top = np.array(
        [[x, y, max(fish.flesh_top(x, y), fish.table_z)] for y in ys for x in xs]
    )
    bottom = top.copy()
    bottom[:, 2] = fish.table_z
    vertices = np.vstack([top, bottom])
    offset = len(top)
    triangles = []
    for i in range(n_u - 1):
        for j in range(n_x - 1):
            a, b = i * n_x + j, i * n_x + j + 1
            c, d = a + n_x, b + n_x
            triangles += [[a, b, d], [a, d, c]]  # top, facing up
            triangles += [[a + offset, d + offset, b + offset]]
            triangles += [[a + offset, c + offset, d + offset]]  # bottom
    rim = (
        [(0, j) for j in range(n_x)]
        + [(i, n_x - 1) for i in range(1, n_u)]
        + [(n_u - 1, j) for j in range(n_x - 2, -1, -1)]
        + [(i, 0) for i in range(n_u - 2, -1, -1)]
    )
    ids = [i * n_x + j for i, j in rim]
    for a, b in itertools.pairwise(ids):  # the walls around the rim
        triangles += [[a, b, b + offset], [a, b + offset, a + offset]]
    return vertices, np.array(triangles, dtype=np.int64)


def get_knife_links(robot: Robot) -> tuple[str, ...]:
    """Links with collision geometry moved by joints 5 and 6 only: the knife's.

    ``("link5", "link6", "wrist_center")`` (:data:`KNIFE_LINKS`) for the PUMA
    models, ``("wrist_2_link", "wrist_3_link", "ee_link")`` for a UR arm. They
    hold the knife, so they may touch the fish it cuts.
    """
    model = robot.model
    links: list[str] = []
    for geometry in robot.collision_model.geometryObjects:
        frame = model.frames[geometry.parentFrame]
        if geometry.parentJoint >= model.njoints - 2 and frame.name not in links:
            links.append(frame.name)
    return tuple(links)


def get_fish_cutting_scene(
    robot: Robot,
    fish: SimulatedFish | None = None,
    setup: FishCuttingSetup | None = None,
) -> Scene:
    """Pedestal (DH models), cutting table and fish in the robot base frame.

    Args:
        robot: An arm with closed-form IK (default use: ``puma560-kang``).
        fish: The fish; default ``SimulatedFish(0).scaled(setup.scale)``.
        setup: Program parameters (scale, world frame); default Kang's cell
            scaled to the arm, as :func:`~workbench.tasks.run_fish_cutting`.

    Raises:
        UnsupportedRobotError: If the robot has no closed-form IK.
    """
    setup = setup or FishCuttingSetup().scaled(get_cell_scale(robot))
    fish = fish or SimulatedFish().scaled(setup.scale)
    _, base = get_world_transforms(robot, setup)
    world_to_base = base.inverse()
    vertices, triangles = build_fish_mesh(fish)
    vertices = vertices @ world_to_base.rotation.T + world_to_base.translation
    vertices.setflags(write=False)
    triangles.setflags(write=False)
    margin = setup.scale * TABLE_MARGIN
    size = (
        2 * (fish.half_width + margin),
        fish.tail_y - fish.head_y + 2 * margin,
        setup.scale * TABLE_THICKNESS,
    )
    center_world = np.array(
        [fish.center_x, 0.5 * (fish.head_y + fish.tail_y), fish.table_z - size[2] / 2]
    )
    table = Obstacle(
        "cutting_table",
        "box",
        size,
        world_to_base * pin.SE3(np.eye(3), center_world),
        color=TABLE_COLOR,
    )
    body = Obstacle(
        "fish",
        "mesh",
        (1.0, 1.0, 1.0),
        pin.SE3.Identity(),
        get_knife_links(robot),
        vertices=vertices,
        triangles=triangles,
        color=FISH_COLOR,
    )
    pedestal = (get_pedestal(robot),) if robot.dh_table is not None else ()
    scale = "" if setup.scale == 1.0 else f", scaled by {setup.scale:g}"
    return Scene(
        "kang-fish-cutting",
        (*pedestal, table, body),
        f"Kang 2007, Fig. 7{scale}; fish seed {fish.seed}",
    )


def compute_fish_cutting_clearance(
    robot: Robot,
    result: FishCuttingResult,
    *,
    checker: CollisionChecker | None = None,
) -> PathClearance:
    """Clearance of a fish-cutting run's servo path to the scene and between links.

    Distances are computed at the planning cycles (every
    ``round(servo_rate / planning_rate)``-th servo sample) and bound over the
    servo samples between them (:func:`workbench.collision.check_path`), as
    ``workbench fishcut`` checks its run.

    Args:
        robot: The arm that ran it.
        result: The run (:func:`~workbench.tasks.run_fish_cutting`).
        checker: Robot, scene and body pairs; None checks Kang's cell of the
            run, :func:`get_fish_cutting_scene` with its fish and setup (the
            command's default).

    Returns:
        The clearance along ``result.servo``.

    Raises:
        InputError: If ``checker`` is None and the robot has no collision
            geometry.
    """
    if checker is None:
        scene = get_fish_cutting_scene(robot, result.fish, result.setup)
        checker = CollisionChecker(robot, scene)
    setup = result.setup
    stride = max(1, round(setup.servo_rate / setup.planning_rate))
    return check_path(checker, result.servo.t, result.servo.q, stride=stride)


__all__ = [
    "KNIFE_LINKS",
    "build_fish_mesh",
    "compute_fish_cutting_clearance",
    "get_fish_cutting_scene",
    "get_knife_links",
]
