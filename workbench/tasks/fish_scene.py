"""Kang's fish-cutting cell (2007, Fig. 5 and 7) as a collision scene, base frame.

Kang shows the cell but gives no dimensions, so these are assumptions around
the simulated fish (:class:`~workbench.tasks.fish.SimulatedFish`) and the world
frame of Fig. 7 (the base :data:`~workbench.tasks.fish_program.KANG_BASE_HEIGHT`
above the world origin):

* the PUMA's **pedestal** (as in Angeles' scene);
* a **cutting table** 0.03 m thick whose top is the fish's ``table_z``,
  :data:`TABLE_MARGIN` larger than the fish on every side;
* the **fish**: a closed triangle mesh of its flesh surface over the table
  (``flesh_top`` on a grid, floored at the table). The knife cuts it by
  design, so the wrist links that carry the knife (:data:`KNIFE_LINKS`) are
  allowed to touch it; every other link is checked.
"""

from __future__ import annotations

import itertools

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.collision.paper_scenes import TABLE_COLOR, get_pedestal
from workbench.collision.scene import Obstacle, Scene
from workbench.model.robot import Robot
from workbench.tasks.fish import SimulatedFish
from workbench.tasks.fish_program import FishCuttingSetup, get_world_transforms

#: Margin [m] of the table around the fish.
TABLE_MARGIN = 0.08
TABLE_THICKNESS = 0.03
#: Links that hold the knife: allowed to touch the fish.
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


def get_fish_cutting_scene(
    robot: Robot,
    fish: SimulatedFish | None = None,
    setup: FishCuttingSetup | None = None,
) -> Scene:
    """Pedestal, cutting table and fish in the robot base frame.

    Args:
        robot: A PUMA model (default use: ``puma560-kang``).
        fish: The fish; default ``SimulatedFish(0)``.
        setup: Program parameters (for the world frame); default ones.

    Raises:
        InputError: If the robot is not a PUMA model from a DH table.
    """
    fish = fish or SimulatedFish()
    _, base = get_world_transforms(setup or FishCuttingSetup())
    world_to_base = base.inverse()
    vertices, triangles = build_fish_mesh(fish)
    vertices = vertices @ world_to_base.rotation.T + world_to_base.translation
    vertices.setflags(write=False)
    triangles.setflags(write=False)
    size = (
        2 * (fish.half_width + TABLE_MARGIN),
        fish.tail_y - fish.head_y + 2 * TABLE_MARGIN,
        TABLE_THICKNESS,
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
        KNIFE_LINKS,
        vertices=vertices,
        triangles=triangles,
        color=FISH_COLOR,
    )
    return Scene(
        "kang-fish-cutting",
        (get_pedestal(robot), table, body),
        f"Kang 2007, Fig. 7; fish seed {fish.seed}",
    )


__all__ = ["KNIFE_LINKS", "build_fish_mesh", "get_fish_cutting_scene"]
