"""MoveIt planning scenes (YAML) as scenes of the workbench.

A MoveIt ``moveit_msgs/PlanningScene`` written as YAML (what MoveIt's
``PlanningScene::getPlanningSceneMsg`` and MotionBenchMaker write) becomes a
:class:`~workbench.collision.Scene`:

* each ``world.collision_objects[*]`` primitive is one obstacle: ``type``
  ``box`` (1; ``dimensions`` x y z), ``sphere`` (2; radius) or ``cylinder``
  (3; height, radius: MoveIt's ``CYLINDER_HEIGHT`` first), at its
  ``primitive_poses`` entry; each ``meshes`` entry (``vertices`` {x, y, z},
  ``triangles`` {vertex_indices}) one inline mesh at its ``mesh_poses``
  entry. Poses are ``position`` [m] and ``orientation`` x y z w, lists or
  mappings; an object ``pose`` (MoveIt ≥ 2) is composed with them. An object
  of one shape keeps its ``id`` as its name, the shapes of one with several
  are named ``id/0``, ``id/1``, …;
* the ``allowed_collision_matrix`` entries between a robot link and an
  object become that obstacle's ``allow`` list (entries between two links
  are the robot's own: its SRDF's or the workbench's self-collision filter);
* the frame of every object must be the scene's (``header.frame_id`` empty
  or one frame for all), taken as the robot's base frame; ``robot_state``
  and ``fixed_frame_transforms`` are not read; ``operation`` must be ADD (0).

Cones and planes, octomaps and attached objects are refused with a message
naming them (:class:`~workbench.errors.SceneFileError`).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import yaml

from workbench.collision._scene_values import (
    FloatArray,
    floats,
    mesh_arrays,
    numbers,
    rotation_from_quat_xyzw,
)
from workbench.collision.scene import Obstacle, Scene
from workbench.errors import SceneFileError

#: MoveIt's ``shape_msgs/SolidPrimitive`` types this reader takes, by code.
PRIMITIVES = {1: "box", 2: "sphere", 3: "cylinder"}
#: How many ``dimensions`` each primitive has.
DIMENSIONS = {"box": 3, "sphere": 1, "cylinder": 2}
#: Largest planning-scene file read [bytes].
MAX_SCENE_BYTES = 64 * 2**20


def read_yaml_file(path: str | Path, what: str) -> Any:
    """The parsed YAML of a file (safe loader), every failure one line.

    Raises:
        SceneFileError: If the file cannot be read, is larger than
            :data:`MAX_SCENE_BYTES`, not UTF-8, or not YAML.
    """
    path = Path(path)
    try:
        if path.stat().st_size > MAX_SCENE_BYTES:
            raise SceneFileError(
                f"{path}: larger than {MAX_SCENE_BYTES // 2**20} MiB, not read"
            )
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise SceneFileError(
            f"cannot read {what} {path}: {err.strerror or err}"
        ) from err
    except UnicodeDecodeError as err:
        raise SceneFileError(f"{path}: not UTF-8 text (byte {err.start})") from err
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = "" if mark is None else f" (line {mark.line + 1})"
        problem = getattr(err, "problem", None) or type(err).__name__
        raise SceneFileError(f"{path}: not valid YAML{where}: {problem}") from None
    except RecursionError:
        raise SceneFileError(f"{path}: YAML nested too deeply to read") from None


def parse_moveit_scene(raw: Any, *, source: str = "scene") -> Scene:
    """A :class:`Scene` from the parsed YAML of a MoveIt planning scene.

    Args:
        raw: The parsed document (module docstring).
        source: Name used in messages and as the scene's source.

    Raises:
        SceneFileError: If it is no planning scene, or an object is of a kind
            not read (cone, plane, octomap), malformed or not finite.
    """
    if not isinstance(raw, Mapping):
        raise SceneFileError(f"{source}: not a MoveIt planning scene (no mapping)")
    world = raw.get("world") or {}
    if not isinstance(world, Mapping):
        raise SceneFileError(f"{source}: 'world' must be a mapping")
    if world.get("octomap"):
        raise SceneFileError(f"{source}: octomaps are not read; give the obstacles")
    objects = world.get("collision_objects") or []
    if not isinstance(objects, list):
        raise SceneFileError(f"{source}: 'world.collision_objects' must be a list")
    state = raw.get("robot_state")
    if isinstance(state, Mapping) and state.get("attached_collision_objects"):
        raise SceneFileError(f"{source}: attached collision objects are not read")
    allowed = _allowed_links(raw.get("allowed_collision_matrix"), source)
    obstacles: list[Obstacle] = []
    frames: set[str] = set()
    for i, item in enumerate(objects):
        where = f"{source}: collision object {i}"
        if not isinstance(item, Mapping):
            raise SceneFileError(f"{where} must be a mapping")
        name = item.get("id")
        if not isinstance(name, str) or not name:
            raise SceneFileError(f"{where}: 'id' must be a non-empty string")
        obstacles.extend(_object(item, f"{where} ({name})", allowed.get(name, ())))
        header = item.get("header") or {}
        frame = header.get("frame_id", "") if isinstance(header, Mapping) else ""
        if frame:
            frames.add(str(frame))
    if len(frames) > 1:
        raise SceneFileError(
            f"{source}: objects in several frames ({', '.join(sorted(frames))}); "
            "give them in the robot's base frame"
        )
    seen: set[str] = set()
    for obstacle in obstacles:
        if obstacle.name in seen:
            raise SceneFileError(f"{source}: duplicate object name {obstacle.name!r}")
        seen.add(obstacle.name)
    name = raw.get("name")
    title = name if isinstance(name, str) and name else Path(source).stem
    return Scene(title, tuple(obstacles), source)


def _allowed_links(matrix: Any, source: str) -> dict[str, tuple[str, ...]]:
    """Object id → the names it may touch, from MoveIt's allowed collision matrix."""
    if not matrix:
        return {}
    names = matrix.get("entry_names") if isinstance(matrix, Mapping) else None
    rows = matrix.get("entry_values") if isinstance(matrix, Mapping) else None
    if (
        not isinstance(names, list)
        or not isinstance(rows, list)
        or len(rows) != len(names)
        or not all(isinstance(r, list) and len(r) == len(names) for r in rows)
    ):
        raise SceneFileError(
            f"{source}: allowed_collision_matrix must have N entry_names and N "
            "rows of N entry_values"
        )
    allowed: dict[str, list[str]] = {}
    for a, row in zip(names, rows, strict=True):
        for b, value in zip(names, row, strict=True):
            if value is True and a != b:
                allowed.setdefault(str(a), []).append(str(b))
    return {key: tuple(value) for key, value in allowed.items()}


def _object(
    item: Mapping[str, Any], where: str, allow: tuple[str, ...]
) -> list[Obstacle]:
    operation = item.get("operation", 0)
    if operation not in (0, "0", "add", "ADD", b"\x00"):
        raise SceneFileError(f"{where}: operation {operation!r} is not ADD (0)")
    if item.get("planes"):
        raise SceneFileError(f"{where}: planes are not read")
    base = (
        _pose(item["pose"], f"{where}: pose") if "pose" in item else pin.SE3.Identity()
    )
    primitives = item.get("primitives") or []
    meshes = item.get("meshes") or []
    poses = item.get("primitive_poses") or []
    mesh_poses = item.get("mesh_poses") or []
    if len(poses) != len(primitives) or len(mesh_poses) != len(meshes):
        raise SceneFileError(
            f"{where}: {len(primitives)} primitives with {len(poses)} poses, "
            f"{len(meshes)} meshes with {len(mesh_poses)} poses"
        )
    if not primitives and not meshes:
        raise SceneFileError(f"{where}: no primitive and no mesh")
    name = str(item["id"])
    count = len(primitives) + len(meshes)
    names = [name] if count == 1 else [f"{name}/{k}" for k in range(count)]
    out = []
    for k, (primitive, pose) in enumerate(zip(primitives, poses, strict=True)):
        at = f"{where}: primitive {k}"
        shape, size = _primitive(primitive, at)
        placement = base * _pose(pose, f"{at}: pose")
        out.append(Obstacle(names[k], shape, size, placement, allow))
    for k, (mesh, pose) in enumerate(zip(meshes, mesh_poses, strict=True)):
        at = f"{where}: mesh {k}"
        vertices, triangles = _mesh(mesh, at)
        placement = base * _pose(pose, f"{at}: pose")
        out.append(
            Obstacle(
                names[len(primitives) + k],
                "mesh",
                (1.0, 1.0, 1.0),
                placement,
                allow,
                vertices=vertices,
                triangles=triangles,
            )
        )
    return out


def _primitive(primitive: Any, where: str) -> tuple[str, tuple[float, ...]]:
    if not isinstance(primitive, Mapping):
        raise SceneFileError(f"{where} must be a mapping")
    kind = primitive.get("type")
    shape = PRIMITIVES.get(kind, "") if isinstance(kind, int) else str(kind).lower()
    if shape not in PRIMITIVES.values():
        raise SceneFileError(
            f"{where}: type {kind!r} is not read (box, sphere or cylinder)"
        )
    dims = floats(
        numbers(
            primitive.get("dimensions"),
            DIMENSIONS[shape],
            f"{where}: dimensions",
            positive=True,
        )
    )
    if shape == "cylinder":  # MoveIt's (height, radius): the workbench's (r, length)
        return shape, (dims[1], dims[0])
    return shape, dims


def _vector(value: Any, keys: str, where: str) -> FloatArray:
    """A list, or a mapping of ``keys`` (``x`` ``y`` ``z`` ``w``; ``w`` required)."""
    if isinstance(value, Mapping):
        value = [value.get(k, 0.0 if k != "w" else None) for k in keys]
    return numbers(value, len(keys), where)


def _pose(raw: Any, where: str) -> pin.SE3:
    if not isinstance(raw, Mapping):
        raise SceneFileError(f"{where} must be a mapping of position and orientation")
    position = _vector(
        raw.get("position", [0.0, 0.0, 0.0]), "xyz", f"{where}: position"
    )
    quat = _vector(
        raw.get("orientation", [0.0, 0.0, 0.0, 1.0]), "xyzw", f"{where}: orientation"
    )
    return pin.SE3(rotation_from_quat_xyzw(quat, f"{where}: orientation"), position)


def _mesh(raw: Any, where: str) -> tuple[FloatArray, np.ndarray]:
    vertices = raw.get("vertices") if isinstance(raw, Mapping) else None
    triangles = raw.get("triangles") if isinstance(raw, Mapping) else None
    if (
        not isinstance(vertices, list)
        or not isinstance(triangles, list)
        or not triangles
    ):
        raise SceneFileError(f"{where}: needs lists of vertices and triangles")
    points = [_vector(p, "xyz", f"{where}: vertex") for p in vertices]
    indices = [
        item.get("vertex_indices") if isinstance(item, Mapping) else item
        for item in triangles
    ]
    return mesh_arrays(points, indices, where)
