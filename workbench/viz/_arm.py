"""One copy of a robot in a Meshcat scene, drawn and placed by Pinocchio."""

from __future__ import annotations

import io
import re
import warnings

import meshcat
import numpy as np
import numpy.typing as npt
import pinocchio as pin
from pinocchio.visualize import MeshcatVisualizer

from workbench.errors import DimensionError, NonFiniteError, URDFLoadError
from workbench.model.mesh_files import (
    get_obj_with_uniform_faces,
    get_stl_with_normals,
)
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]


def _corners(geometry: pin.GeometryObject) -> FloatArray:
    """Corners of a geometry's bounding box in its own frame, shape (8, 3) [m]."""
    try:
        geometry.geometry.computeLocalAABB()
        box = geometry.geometry.aabb_local
        lo, hi = np.array(box.min_), np.array(box.max_)
    except (AttributeError, RuntimeError):
        lo, hi = np.full(3, -0.05), np.full(3, 0.05)
    return np.array(
        [
            [x, y, z]
            for x in (lo[0], hi[0])
            for y in (lo[1], hi[1])
            for z in (lo[2], hi[2])
        ]
    )


class _Visualizer(MeshcatVisualizer):
    """Pinocchio's Meshcat visualiser, STL and OBJ meshes as the page reads them.

    An STL file whose normals are zero is sent as the same triangles with
    normals computed from the vertices (:func:`get_stl_with_normals`): the page
    shades with the file's normals, and zero ones draw the mesh black. An OBJ
    file whose faces give texture coordinates only in part is sent without
    them (:func:`get_obj_with_uniform_faces`): the page drops such a mesh.
    """

    def loadMeshFromFile(self, geometry_object: pin.GeometryObject) -> object:
        path = geometry_object.meshPath
        if path.lower().endswith(".stl"):
            fixed = get_stl_with_normals(path)
            if fixed is not None:
                return meshcat.geometry.StlMeshGeometry.from_stream(io.BytesIO(fixed))
        if path.lower().endswith(".obj"):
            text = get_obj_with_uniform_faces(path)
            if text is not None:
                return meshcat.geometry.ObjMeshGeometry.from_stream(io.StringIO(text))
        return super().loadMeshFromFile(geometry_object)  # type: ignore[misc]


class Arm:
    """The robot's visual geometry under scene node ``root`` (arm or ghost).

    ``with_base=False`` leaves out the geometry fixed to the base (joint 0);
    ``geometry_model`` replaces the visual geometry (e.g. by the collision
    geometry, whose meshes take a colour where Collada ones keep their own).

    Raises:
        URDFLoadError: If Pinocchio cannot draw a geometry object (it only
            warns; a missing mesh file already fails in ``robot.visual_model``).
    """

    def __init__(
        self,
        robot: Robot,
        scene: meshcat.Visualizer,
        root: str,
        rgba: list[float] | None = None,
        *,
        with_base: bool = True,
        geometry_model: pin.GeometryModel | None = None,
    ):
        if geometry_model is None:
            geometry_model = robot.visual_model
        self.viz = _Visualizer(robot.model, None, geometry_model)
        self.viz.initViewer(viewer=scene)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            self.viz.loadViewerModel(rootNodeName=root, visual_color=rgba)
        problems = [str(w.message) for w in caught if w.category is UserWarning]
        if problems:
            reason = " ".join(problems[0].split())
            raise URDFLoadError(f"{robot.urdf_path}: cannot draw the robot: {reason}")
        objects = geometry_model.geometryObjects
        visual = pin.GeometryType.VISUAL
        self.nodes = [self.viz.getViewerNodeName(g, visual) for g in objects]
        self.colors = [np.array(g.meshColor) for g in objects]
        self.scales = [np.diag([*g.meshScale, 1.0]) for g in objects]
        self.corners = [_corners(g) for g in objects]
        self.on_base = [g.parentJoint == 0 for g in objects]
        self.moving_nodes = [
            n for n, b in zip(self.nodes, self.on_base, strict=True) if not b
        ]
        # Collada meshes load as groups without one material: no colour keys.
        self.keyed_color_nodes = [
            n
            for n, g in zip(self.nodes, objects, strict=True)
            if n in self.moving_nodes and not g.meshPath.lower().endswith(".dae")
        ]
        self.drawn = self.nodes if with_base else self.moving_nodes
        for node in set(self.nodes) - set(self.drawn):  # ghosts share the arm's base
            scene[node].delete()

    def place(self, q: FloatArray) -> list[FloatArray]:
        """Forward kinematics; returns each geometry's 4×4 pose (mesh scale applied)."""
        viz = self.viz
        pin.forwardKinematics(viz.model, viz.data, q)
        pin.updateFramePlacements(viz.model, viz.data)
        pin.updateGeometryPlacements(
            viz.model, viz.data, viz.visual_model, viz.visual_data
        )
        return [
            m.homogeneous @ s
            for m, s in zip(viz.visual_data.oMg, self.scales, strict=True)
        ]

    def get_frame_pose(self, frame_id: int) -> FloatArray:
        """4×4 pose of a frame after the last :meth:`place`."""
        return self.viz.data.oMf[frame_id].homogeneous

    def draw(self, scene: meshcat.Visualizer, q: FloatArray) -> None:
        """Place every geometry node at configuration ``q``."""
        for node, pose in zip(self.nodes, self.place(q), strict=True):
            if node in self.drawn:
                scene[node].set_transform(pose)

    def compute_points(self, q: FloatArray, *, base_only: bool = False) -> FloatArray:
        """World corners of the geometry bounding boxes at ``q``, shape (N, 3) [m].

        The boxes are those of the loaded geometry, whose vertices already
        carry the mesh scale: they are placed by the geometry poses alone.
        """
        self.place(q)
        poses = [m.homogeneous for m in self.viz.visual_data.oMg]
        chosen = [
            (t, c)
            for t, c, b in zip(poses, self.corners, self.on_base, strict=True)
            if b or not base_only
        ]
        if not chosen:
            return np.zeros((1, 3))
        return np.vstack([c @ t[:3, :3].T + t[:3, 3] for t, c in chosen])


def get_colorable_geometry(robot: Robot) -> tuple[pin.GeometryModel, bool]:
    """The geometry a coloured copy of the arm is drawn with, and whether it is visual.

    Collada (``.dae``) meshes keep the colours of their own materials, so an arm
    whose visual geometry has one is drawn with its collision geometry (STL,
    primitives) when that has none; else with its visual geometry.
    """

    def has_collada(model: pin.GeometryModel) -> bool:
        return any(g.meshPath.lower().endswith(".dae") for g in model.geometryObjects)

    visual, collision = robot.visual_model, robot.collision_model
    if has_collada(visual) and collision.ngeoms and not has_collada(collision):
        return collision, False
    return visual, True


def as_configurations(robot: Robot, q: npt.ArrayLike, name: str) -> FloatArray:
    """Check configurations of shape (K, nq), finite; returns them as float64."""
    arr = np.array(q, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != robot.nq:
        rows = arr.shape[0] if arr.ndim else 1
        raise DimensionError(name, (rows, robot.nq), arr.shape)
    if not np.all(np.isfinite(arr)):
        raise NonFiniteError(f"{name} contains NaN or infinite values")
    return arr


def to_node_name(label: str) -> str:
    """A Meshcat node name from a free label (``/`` separates nodes)."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", label).strip("-") or "unnamed"
