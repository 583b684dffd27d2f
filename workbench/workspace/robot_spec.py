"""A robot as a few picklable values, loaded once per thread of a worker process.

A map is computed by worker processes (a local pool or a Dask cluster) that
cannot receive a Pinocchio model: each gets a :class:`RobotSpec` (catalog name
or absolute URDF path, package folders, tool frame, the URDF's SHA-256 and the
position limits) and loads the robot from it with :func:`load_spec_robot`,
once per thread (a robot's Pinocchio data and a collision checker are scratch
space of one thread). The loaded robot is checked against the spec, so a worker
that sees another URDF (another file system, an edited file) fails with a clear
message instead of computing another arm's map.
"""

from __future__ import annotations

import hashlib
import json
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from workbench.collision import CollisionChecker, Scene, parse_scene
from workbench.errors import InputError
from workbench.model.loading import get_robot_names, load_robot
from workbench.model.robot import Robot


@dataclass(frozen=True, slots=True)
class RobotSpec:
    """What a worker needs to load the robot of a build again.

    Attributes:
        name: Catalog name, or the absolute path of the URDF file.
        package_dirs: Folders for ``package://`` URIs (:attr:`Robot.package_dirs`).
        tool_frame: Name of the tool frame.
        urdf_sha256: SHA-256 (hex) of the URDF file's bytes.
        lower, upper: Position limits, nq values each [rad, m for prismatic].
        xacro_args: The arguments of a xacro description (:attr:`Robot.xacro_args`).
        srdf: The SRDF the robot was loaded with (:attr:`Robot.srdf_path`), or None.
    """

    name: str
    package_dirs: tuple[str, ...]
    tool_frame: str
    urdf_sha256: str
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    xacro_args: tuple[tuple[str, str], ...] = ()
    srdf: str | None = None


def compute_file_sha256(path: str | Path) -> str:
    """SHA-256 (hex) of a file's bytes.

    Raises:
        InputError: If the file cannot be read.
    """
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError as err:
        raise InputError(f"cannot read {path}: {err.strerror or err}") from err


def get_robot_spec(robot: Robot) -> RobotSpec:
    """The spec that loads ``robot`` again (its URDF, tool frame and limits).

    Raises:
        InputError: If the robot's URDF file cannot be read.
    """
    catalog = robot.name in get_robot_names()
    return RobotSpec(
        name=robot.name if catalog else str(Path(robot.urdf_path).resolve()),
        package_dirs=robot.package_dirs,
        tool_frame=robot.tool_frame,
        urdf_sha256=compute_file_sha256(robot.urdf_path),
        lower=tuple(float(x) for x in robot.lower),
        upper=tuple(float(x) for x in robot.upper),
        xacro_args=robot.xacro_args,
        srdf=None if robot.srdf_path is None else str(robot.srdf_path),
    )


#: Robots and collision checkers of this thread, by spec (and scene).
_LOADED = threading.local()


def load_spec_robot(spec: RobotSpec) -> Robot:
    """The robot of ``spec``, loaded once per thread and checked against it.

    Raises:
        InputError: If the URDF found here differs from the build's (its
            SHA-256 or the position limits), or cannot be loaded.
    """
    robots: dict[RobotSpec, Robot] = _LOADED.__dict__.setdefault("robots", {})
    robot = robots.get(spec)
    if robot is None:
        robot = load_robot(
            spec.name,
            tool_frame=spec.tool_frame,
            package_dirs=spec.package_dirs,
            xacro_args=dict(spec.xacro_args) or None,
            srdf=spec.srdf,
        )
        _check_same_robot(robot, spec)
        robots[spec] = robot
    return robot


def get_scene_json(scene: Scene) -> str:
    """The JSON text of ``scene`` that every worker parses (:func:`load_spec_checker`).

    Every worker, the local ones included, builds its checker from this text,
    so that all of them hold the very same obstacle placements.
    """
    return json.dumps(scene.to_dict(), sort_keys=True, allow_nan=False)


def load_spec_checker(spec: RobotSpec, scene_json: str) -> CollisionChecker:
    """A collision checker of the robot of ``spec`` in a scene, once per thread.

    Args:
        spec: The robot.
        scene_json: The scene, from :func:`get_scene_json`.

    Raises:
        InputError: As :func:`load_spec_robot`; ``SceneFileError`` if the
            scene cannot be built here (a mesh file missing).
    """
    checkers: dict[tuple[RobotSpec, str], CollisionChecker] = (
        _LOADED.__dict__.setdefault("checkers", {})
    )
    checker = checkers.get((spec, scene_json))
    if checker is None:
        scene = parse_scene(json.loads(scene_json), source="the map's scene")
        checker = CollisionChecker(load_spec_robot(spec), scene)
        checkers[(spec, scene_json)] = checker
    return checker


def _check_same_robot(robot: Robot, spec: RobotSpec) -> None:
    """Raise unless ``robot`` is the arm ``spec`` was made from."""
    sha = compute_file_sha256(robot.urdf_path)
    if sha != spec.urdf_sha256:
        raise InputError(
            f"the URDF of {spec.name} here ({robot.urdf_path}, sha256 {sha[:12]}…) "
            f"is not the build's (sha256 {spec.urdf_sha256[:12]}…): every worker "
            "must see the same file"
        )
    same_limits = np.array_equal(robot.lower, spec.lower) and np.array_equal(
        robot.upper, spec.upper
    )
    if not same_limits:
        raise InputError(
            f"the joint limits of {spec.name} here differ from the build's: "
            "every worker must load the same robot"
        )
