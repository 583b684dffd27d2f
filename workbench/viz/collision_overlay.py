"""Obstacles of a scene in the viewer, and the collision state along an animation.

:class:`CollisionOverlay` draws every obstacle of a
:class:`~workbench.collision.CollisionChecker`'s scene under the node
``scene/`` and, for a configuration, gives the colour of every link and
obstacle: red for bodies in contact, orange for the closest pair, else their
own colour (links: neutral grey), and the placement of two small spheres on
the closest points of the closest pair (node ``closest/``).
"""

from __future__ import annotations

import io
from pathlib import Path

import meshcat
import meshcat.geometry as mg
import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.collision import CollisionChecker, Obstacle
from workbench.collision.self_filter import get_link_name
from workbench.model.mesh_files import get_obj_with_uniform_faces
from workbench.viz._arm import Arm, to_node_name
from workbench.viz._shapes import _rgb_int

FloatArray = npt.NDArray[np.float64]

CONTACT_RGB = (0.9, 0.1, 0.1)
CLOSEST_RGB = (1.0, 0.6, 0.0)
LINK_RGB = (0.85, 0.86, 0.88)
_Y_TO_Z = pin.SE3(pin.rpy.rpyToMatrix(np.pi / 2, 0.0, 0.0), np.zeros(3))


def _geometry(obstacle: Obstacle) -> tuple[mg.Geometry, pin.SE3]:
    """Meshcat geometry and its placement in the obstacle frame."""
    if obstacle.shape == "box":
        return mg.Box(list(obstacle.size)), pin.SE3.Identity()
    if obstacle.shape == "cylinder":  # meshcat cylinders lie along y
        radius, length = obstacle.size
        return mg.Cylinder(length, radius), _Y_TO_Z
    if obstacle.shape == "sphere":
        return mg.Sphere(obstacle.size[0]), pin.SE3.Identity()
    scale = pin.SE3.Identity()
    if obstacle.mesh_file is None:
        vertices = obstacle.vertices * np.array(obstacle.size)
        return mg.TriangularMeshGeometry(vertices, obstacle.triangles), scale
    suffix = Path(obstacle.mesh_file).suffix.lower()
    text = get_obj_with_uniform_faces(obstacle.mesh_file) if suffix == ".obj" else None
    if text is not None:  # the page cannot merge faces with and without UVs
        return mg.ObjMeshGeometry.from_stream(io.StringIO(text)), scale
    loader = {".obj": mg.ObjMeshGeometry, ".dae": mg.DaeMeshGeometry}
    return loader.get(suffix, mg.StlMeshGeometry).from_file(
        str(obstacle.mesh_file)
    ), scale


class CollisionOverlay:
    """Scene obstacles and collision highlights of one viewer.

    Args:
        scene: The viewer's Meshcat visualizer.
        arm: The drawn arm (its visual nodes are coloured by link).
        checker: Robot, scene and checked pairs.
    """

    def __init__(self, scene: meshcat.Visualizer, arm: Arm, checker: CollisionChecker):
        self.checker = checker
        self.obstacle_nodes: dict[str, str] = {}
        self.obstacle_colors: dict[str, list[float]] = {}
        for obstacle in checker.scene.obstacles:
            node = f"scene/{to_node_name(obstacle.name)}"
            geometry, local = _geometry(obstacle)
            rgba = obstacle.color
            material = mg.MeshLambertMaterial(
                color=_rgb_int(rgba[:3]),
                opacity=float(rgba[3]),
                transparent=bool(rgba[3] < 1.0),
            )
            scene[node].set_object(geometry, material)
            transform = (obstacle.placement * local).homogeneous
            if obstacle.shape == "mesh":
                transform = transform @ np.diag([*obstacle.size, 1.0])
            scene[node].set_transform(transform)
            self.obstacle_nodes[obstacle.name] = node
            self.obstacle_colors[obstacle.name] = list(rgba[:3])
        model = checker.robot.model
        visual = checker.robot.visual_model.geometryObjects
        self.link_nodes: dict[str, list[str]] = {}
        for node, g in zip(arm.nodes, visual, strict=True):
            if node in arm.keyed_color_nodes:
                self.link_nodes.setdefault(get_link_name(model, g), []).append(node)
        self.link_colors = {node: list(LINK_RGB) for node in arm.nodes}
        for name in ("a", "b"):
            scene[f"closest/{name}"].set_object(
                mg.Sphere(0.012), mg.MeshLambertMaterial(color=_rgb_int(CLOSEST_RGB))
            )

    def compute_state(
        self, q: FloatArray
    ) -> tuple[dict[str, list[float]], dict[str, FloatArray]]:
        """Colours (node -> RGB) and marker placements (node -> 4×4) at ``q``."""
        distances = self.checker.compute_distances(q)
        k = int(np.argmin(distances))
        closest = {self.checker.pairs[k].body_a, self.checker.pairs[k].body_b}
        touching = {
            body
            for pair, d in zip(self.checker.pairs, distances, strict=True)
            if d <= 0.0
            for body in (pair.body_a, pair.body_b)
        }
        colors: dict[str, list[float]] = {}
        for link, nodes in self.link_nodes.items():
            for node in nodes:
                colors[node] = self._color(
                    link, touching, closest, self.link_colors[node]
                )
        for name, node in self.obstacle_nodes.items():
            colors[node] = self._color(
                name, touching, closest, self.obstacle_colors[name]
            )
        a, b = self.checker.compute_closest_points(k)
        markers = {
            "closest/a": pin.SE3(np.eye(3), a).homogeneous,
            "closest/b": pin.SE3(np.eye(3), b).homogeneous,
        }
        return colors, markers

    @staticmethod
    def _color(
        body: str, touching: set[str], closest: set[str], own: list[float]
    ) -> list[float]:
        if body in touching:
            return list(CONTACT_RGB)
        if body in closest:
            return list(CLOSEST_RGB)
        return own


__all__ = ["CollisionOverlay"]
