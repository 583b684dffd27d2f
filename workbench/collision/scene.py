"""Scenes: static obstacles around the robot, in its base frame.

An :class:`Obstacle` is a box, cylinder, sphere or mesh with a pose in the
robot base frame; a :class:`Scene` is a named tuple of them. Files are read
and written by :mod:`workbench.collision.scene_file`, which documents the
format.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import coal
import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import SceneFileError

FloatArray = npt.NDArray[np.float64]

#: Shapes and the keys that size them.
SHAPES: dict[str, tuple[str, ...]] = {
    "box": ("size",),
    "cylinder": ("radius", "length"),
    "sphere": ("radius",),
    "mesh": ("file", "scale", "vertices", "triangles"),
}


@dataclass(frozen=True, slots=True)
class Obstacle:
    """One static obstacle of a scene.

    Attributes:
        name: Unique name in the scene.
        shape: ``"box"``, ``"cylinder"``, ``"sphere"`` or ``"mesh"``.
        size: Box edge lengths (3,) [m]; cylinder ``(radius, length)``;
            sphere ``(radius,)``; mesh scale (3,).
        placement: Pose of the obstacle in the robot base frame.
        allow: Robot links allowed to touch it.
        mesh_file: Mesh file (``shape == "mesh"`` read from a file), else None.
        vertices: Inline mesh vertices (V, 3) [m], else None.
        triangles: Inline mesh triangles (T, 3) vertex indices, else None.
        color: RGBA in [0, 1] for viewers.
    """

    name: str
    shape: str
    size: tuple[float, ...]
    placement: pin.SE3
    allow: tuple[str, ...] = ()
    mesh_file: Path | None = None
    vertices: FloatArray | None = field(default=None, repr=False)
    triangles: npt.NDArray[np.int64] | None = field(default=None, repr=False)
    color: tuple[float, float, float, float] = (0.55, 0.45, 0.35, 0.9)

    def build_geometry(self) -> coal.CollisionGeometry:
        """The coal geometry of the obstacle in its own frame.

        Raises:
            SceneFileError: If a mesh file cannot be read.
        """
        if self.shape == "box":
            return coal.Box(*self.size)
        if self.shape == "cylinder":
            return coal.Cylinder(*self.size)
        if self.shape == "sphere":
            return coal.Sphere(self.size[0])
        if self.mesh_file is not None:
            try:
                return coal.MeshLoader().load(str(self.mesh_file), np.array(self.size))
            except (RuntimeError, ValueError) as err:
                message = " ".join(str(err).split())
                raise SceneFileError(
                    f"obstacle {self.name!r}: cannot read mesh {self.mesh_file}: "
                    f"{message}"
                ) from err
        vertices, triangles = self.vertices, self.triangles
        if vertices is None or triangles is None:
            raise SceneFileError(f"obstacle {self.name!r}: a mesh needs a file or data")
        mesh = coal.BVHModelOBBRSS()
        mesh.beginModel(len(triangles), len(vertices))
        scaled = vertices * np.array(self.size)
        for a, b, c in triangles:
            mesh.addTriangle(scaled[a], scaled[b], scaled[c])
        mesh.endModel()
        return mesh

    def to_dict(self) -> dict[str, Any]:
        """The JSON form of the obstacle (``read_scene`` reads it back)."""
        out: dict[str, Any] = {"name": self.name, "shape": self.shape}
        if self.shape == "box":
            out["size"] = list(self.size)
        elif self.shape == "cylinder":
            out["radius"], out["length"] = self.size
        elif self.shape == "sphere":
            out["radius"] = self.size[0]
        else:
            out["scale"] = list(self.size)
            if self.mesh_file is not None:
                out["file"] = str(self.mesh_file)
            elif self.vertices is not None and self.triangles is not None:
                out["vertices"] = self.vertices.tolist()
                out["triangles"] = self.triangles.tolist()
        out["position"] = self.placement.translation.tolist()
        out["quat_xyzw"] = pin.Quaternion(self.placement.rotation).coeffs().tolist()
        if self.allow:
            out["allow"] = list(self.allow)
        out["color"] = list(self.color)
        return out


@dataclass(frozen=True, slots=True)
class Scene:
    """Static obstacles in the robot's base frame.

    Attributes:
        name: Scene name.
        obstacles: The obstacles, names unique.
        source: Where the scene comes from (file or paper), for reports.
    """

    name: str
    obstacles: tuple[Obstacle, ...] = ()
    source: str = ""
    frame: ClassVar[str] = "base"

    def to_dict(self) -> dict[str, Any]:
        """The JSON form (``read_scene`` reads it back)."""
        return {
            "name": self.name,
            "frame": self.frame,
            "objects": [o.to_dict() for o in self.obstacles],
        }


__all__ = ["SHAPES", "Obstacle", "Scene"]
