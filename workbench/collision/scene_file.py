"""Scene files: JSON, strictly validated (see the format below), or MoveIt YAML.

A scene file is one JSON object (SI units, base frame of the robot)::

    {
      "name": "pick-and-place cell",
      "frame": "base",
      "objects": [
        {"name": "table", "shape": "box", "size": [0.3, 0.3, 0.04],
         "position": [0.2, -0.1, -0.59], "rpy": [0, 0, 0.3]},
        {"name": "post", "shape": "cylinder", "radius": 0.05, "length": 0.6,
         "position": [0.4, 0.4, -0.3], "quat_xyzw": [0, 0, 0, 1]},
        {"name": "ball", "shape": "sphere", "radius": 0.1, "position": [0.5, 0, 0]},
        {"name": "part", "shape": "mesh", "file": "part.stl", "scale": [1, 1, 1],
         "position": [0, 0.5, 0], "allow": ["link6"]}
      ]
    }

Boxes are centred on their pose (``size`` = full edge lengths), cylinders lie
along their local z axis (centred), meshes are given in their own frame and
read with coal's loader (STL, OBJ, DAE, ...; a relative ``file`` is read from
the scene file's folder). ``allow`` lists robot links allowed to touch the
object (a knife in the fish, the first link on its pedestal), like the allowed
collision matrix of MoveIt. Every key is checked: unknown keys or shapes,
non-positive sizes, non-finite numbers, non-unit quaternions, duplicate names
and missing mesh files are :class:`~workbench.errors.SceneFileError`.

A MoveIt planning scene written as YAML (``*.yaml``, ``*.yml``; e.g. the
scenes of MotionBenchMaker) is read by :mod:`workbench.collision.moveit_scene`
into the same :class:`~workbench.collision.Scene`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pinocchio as pin

from workbench.atomic_files import write_text_atomic
from workbench.collision._scene_values import (
    QUATERNION_NORM_TOL,
    floats,
    mesh_arrays,
    numbers,
    rotation_from_quat_xyzw,
)
from workbench.collision.moveit_scene import parse_moveit_scene, read_yaml_file
from workbench.collision.scene import SHAPES, Obstacle, Scene
from workbench.errors import InputError, SceneFileError
from workbench.validation import read_json_file

_COMMON_KEYS = ("name", "shape", "position", "quat_xyzw", "rpy", "allow", "color")
#: Suffixes of MoveIt planning-scene files (YAML).
YAML_SUFFIXES = (".yaml", ".yml")


def write_scene(scene: Scene, path: str | Path) -> Path:
    """Write ``scene`` as JSON; returns the path.

    Raises:
        SceneFileError: If the file cannot be written.
    """
    try:
        return write_text_atomic(path, json.dumps(scene.to_dict(), indent=1) + "\n")
    except InputError as err:
        raise SceneFileError(f"scene: {err}") from err


def read_scene(path: str | Path) -> Scene:
    """Read and validate a scene file: JSON (above), or a MoveIt planning scene.

    A file named ``*.yaml`` or ``*.yml`` is a MoveIt planning scene
    (:mod:`workbench.collision.moveit_scene`), any other one JSON.

    Raises:
        SceneFileError: If the file is missing, not JSON (not YAML), or
            invalid; the message names the object and the key.
    """
    path = Path(path)
    if path.suffix.lower() in YAML_SUFFIXES:
        raw = read_yaml_file(path, "scene")
        return parse_moveit_scene(raw, source=str(path))
    raw = read_json_file(path, SceneFileError, "scene")
    return parse_scene(raw, source=str(path), folder=path.parent)


def parse_scene(
    raw: Any, *, source: str = "scene", folder: Path | None = None
) -> Scene:
    """Build a scene from its parsed JSON form.

    Args:
        raw: The parsed JSON object.
        source: Name used in error messages.
        folder: Folder relative mesh files are read from (default: cwd).

    Raises:
        SceneFileError: If anything is invalid.
    """
    if not isinstance(raw, dict):
        raise SceneFileError(f"{source}: top level must be a JSON object")
    _check_keys(raw, ("name", "frame", "objects"), source)
    if raw.get("frame", "base") != "base":
        raise SceneFileError(f"{source}: 'frame' must be 'base', got {raw['frame']!r}")
    name = raw.get("name", Path(source).stem)
    if not isinstance(name, str):
        raise SceneFileError(f"{source}: 'name' must be a string")
    objects = raw.get("objects")
    if not isinstance(objects, list):
        raise SceneFileError(f"{source}: 'objects' must be a list")
    obstacles = [
        _parse_object(item, f"{source}: object {i}", folder or Path())
        for i, item in enumerate(objects)
    ]
    seen: set[str] = set()
    for obstacle in obstacles:
        if obstacle.name in seen:
            raise SceneFileError(f"{source}: duplicate object name {obstacle.name!r}")
        seen.add(obstacle.name)
    return Scene(name, tuple(obstacles), source)


def _check_keys(raw: dict, valid: tuple[str, ...], where: str) -> None:
    unknown = sorted(set(raw) - set(valid))
    if unknown:
        raise SceneFileError(
            f"{where}: unknown key(s) {', '.join(map(str, unknown))}; "
            f"valid keys: {', '.join(valid)}"
        )


def _parse_object(raw: Any, where: str, folder: Path) -> Obstacle:
    if not isinstance(raw, dict):
        raise SceneFileError(f"{where} must be a JSON object")
    shape = raw.get("shape")
    if shape not in SHAPES:
        raise SceneFileError(
            f"{where}: unknown shape {shape!r}; valid shapes: {', '.join(SHAPES)}"
        )
    _check_keys(raw, _COMMON_KEYS + SHAPES[shape], where)
    name = raw.get("name")
    if not isinstance(name, str) or not name:
        raise SceneFileError(f"{where}: 'name' must be a non-empty string")
    where = f"{where} ({name})"
    for key in SHAPES[shape]:
        if key not in raw and shape != "mesh":
            raise SceneFileError(f"{where}: missing key {key!r}")
    size, mesh = _parse_size(raw, shape, where, folder)
    allow = raw.get("allow", [])
    if not isinstance(allow, list) or not all(isinstance(a, str) for a in allow):
        raise SceneFileError(f"{where}: 'allow' must be a list of link names")
    color = floats(numbers(raw.get("color", [0.55, 0.45, 0.35, 0.9]), 4, where))
    if not all(0.0 <= c <= 1.0 for c in color):
        raise SceneFileError(f"{where}: 'color' entries must be in [0, 1]")
    return Obstacle(
        name,
        shape,
        size,
        _parse_pose(raw, where),
        tuple(allow),
        color=color,  # type: ignore[arg-type]
        **mesh,
    )


def _parse_size(
    raw: dict, shape: str, where: str, folder: Path
) -> tuple[tuple[float, ...], dict[str, Any]]:
    if shape == "box":
        return floats(numbers(raw["size"], 3, f"{where}: size", positive=True)), {}
    if shape == "sphere":
        return floats(
            numbers([raw["radius"]], 1, f"{where}: radius", positive=True)
        ), {}
    if shape == "cylinder":
        values = [raw["radius"], raw["length"]]
        return floats(numbers(values, 2, f"{where}: radius, length", positive=True)), {}
    scale = floats(
        numbers(raw.get("scale", [1, 1, 1]), 3, f"{where}: scale", positive=True)
    )
    if ("file" in raw) == ("vertices" in raw or "triangles" in raw):
        raise SceneFileError(
            f"{where}: a mesh needs 'file' or 'vertices' + 'triangles'"
        )
    if "file" in raw:
        if not isinstance(raw["file"], str) or not raw["file"]:
            raise SceneFileError(f"{where}: 'file' must be a path")
        path = Path(raw["file"]).expanduser()
        path = path if path.is_absolute() else folder / path
        if not path.is_file():
            raise SceneFileError(f"{where}: mesh file not found: {path}")
        return scale, {"mesh_file": path}
    return scale, _parse_inline_mesh(raw, where)


def _parse_inline_mesh(raw: dict, where: str) -> dict[str, Any]:
    vertices, triangles = raw.get("vertices"), raw.get("triangles")
    if (
        not isinstance(vertices, list)
        or not isinstance(triangles, list)
        or not triangles
    ):
        raise SceneFileError(f"{where}: 'vertices' and 'triangles' must be lists")
    points = [numbers(p, 3, f"{where}: vertex") for p in vertices]
    v, t = mesh_arrays(points, triangles, where)
    return {"vertices": v, "triangles": t}


def _parse_pose(raw: dict, where: str) -> pin.SE3:
    position = numbers(raw.get("position", [0, 0, 0]), 3, f"{where}: position")
    if "quat_xyzw" in raw and "rpy" in raw:
        raise SceneFileError(f"{where}: give 'quat_xyzw' or 'rpy', not both")
    if "rpy" in raw:
        rotation = pin.rpy.rpyToMatrix(numbers(raw["rpy"], 3, f"{where}: rpy"))
    else:
        quat = numbers(raw.get("quat_xyzw", [0, 0, 0, 1]), 4, f"{where}: quat_xyzw")
        rotation = rotation_from_quat_xyzw(quat, f"{where}: quat_xyzw")
    return pin.SE3(rotation, position)


__all__ = ["QUATERNION_NORM_TOL", "parse_scene", "read_scene", "write_scene"]
