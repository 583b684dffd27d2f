"""MotionBenchMaker problem sets: found in an archive or a folder, checked for validity.

MotionBenchMaker (Chamzas et al., *MotionBenchMaker: A Tool to Generate and
Benchmark Motion Planning Datasets*, RA-L 2022) writes each problem as a
MoveIt planning scene (``sceneNNNN.yaml``: boxes and cylinders in the robot's
base frame) and a MoveIt motion request (``requestNNNN.yaml``: start joint
state, joint goal), one folder per scenario and robot
(``problems/<scenario>_<robot>/``). :func:`find_problems` reads them from

* ``problems.tar.bz2`` (as the ``vamp-planner`` 0.6.4 sdist ships them in
  ``resources/{panda,ur5}/``: 7 scenarios x 100 problems per robot), or the
  folder it unpacks to;
* the ``vamp-planner`` sdist itself (``vamp_planner-0.6.4.tar.gz``: the
  ``problems.tar.bz2`` of every robot in it);
* a flat folder ``<robot>/<scenario>_sceneNNNN.yaml`` with
  ``<scenario>_requestNNNN.yaml`` beside it.

A :class:`Problem` holds its scene (read) and its request (its YAML, matched
to a robot's joints by :meth:`Problem.read_request`), so it can be sent to
another process as it is. :func:`check_validity` says whether a problem is
valid: its start and goal free of collision on the robot's exact meshes
(coal, the SRDF's allowed pairs).
"""

from __future__ import annotations

import io
import math
import re
import tarfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Any

import yaml

from workbench.collision import CollisionChecker, Scene
from workbench.collision.moveit_scene import parse_moveit_scene, read_yaml_file
from workbench.errors import InputError, SceneFileError
from workbench.model.robot import Robot
from workbench.motion.requests import MotionRequest, parse_request

#: MotionBenchMaker's scenarios, in the order of its paper's tables.
SCENARIOS = (
    "table_pick",
    "table_under_pick",
    "box",
    "bookshelf_small",
    "bookshelf_tall",
    "bookshelf_thin",
    "cage",
)
#: ``<scenario>_<robot>/sceneNNNN.yaml`` or ``<robot>/<scenario>_sceneNNNN.yaml``.
_SCENE = re.compile(r"^(?:(?P<flat>.+)_)?scene(?P<index>\d+)\.ya?ml$")
#: Largest problem file read from an archive [bytes].
MAX_FILE_BYTES = 16 * 2**20


@dataclass(frozen=True, slots=True)
class Problem:
    """One MotionBenchMaker problem: a scene and a motion request.

    Attributes:
        robot_name: The robot the problem is for (``"panda"``, ``"ur5"``).
        scenario: Its scenario (``"cage"``, ...).
        index: Its number in the scenario.
        scene: The obstacles, in the robot's base frame.
        request: The MoveIt ``MotionPlanRequest`` as its YAML reads.
        scene_path, request_path: Where they were read (``ARCHIVE:MEMBER``
            inside an archive).
    """

    robot_name: str
    scenario: str
    index: int
    scene: Scene = field(repr=False)
    request: Mapping[str, Any] = field(repr=False)
    scene_path: str
    request_path: str

    def read_request(self, robot: Robot) -> MotionRequest:
        """Start and goal (nq,) [rad] of ``robot``, as ``read_request`` reads them.

        Raises:
            InputError: If a joint of the robot is missing from the request.
        """
        return parse_request(self.request, robot, source=self.request_path)


def find_problems(
    source: str | Path,
    *,
    robot_name: str | None = None,
    scenarios: Sequence[str] | None = None,
    limit: int | None = None,
) -> list[Problem]:
    """The problems of one robot in ``source``, by scenario then index.

    Args:
        source: ``problems.tar.bz2``, the folder it unpacks to, a flat
            folder or the ``vamp-planner`` sdist (module docstring).
        robot_name: The robot whose problems to take; None when the source
            holds one robot's only.
        scenarios: Scenario names to keep, in this order; None: every one
            found (MotionBenchMaker's first, in :data:`SCENARIOS` order).
        limit: At most this many problems per scenario (the lowest indices),
            >= 1; None: all.

    Returns:
        The problems, their scenes read.

    Raises:
        InputError: If ``source`` is missing or holds no problem, holds
            several robots' and ``robot_name`` is None, has none of
            ``robot_name`` or of a scenario asked for, ``limit`` is not a
            positive integer, or a scene or request cannot be read.
    """
    if limit is not None and (
        isinstance(limit, bool) or not isinstance(limit, int) or limit < 1
    ):
        raise InputError(f"limit must be a positive integer, got {limit!r}")
    path = Path(source).expanduser()
    files = _list_files(path, robot_name)
    found: dict[tuple[str, str], dict[int, tuple[str, str]]] = {}
    for name in files:
        key = _classify(name)
        if key is None:
            continue
        robot, scenario, index, request = key
        if request in files:
            found.setdefault((robot, scenario), {})[index] = (name, request)
    robots = sorted({robot for robot, _ in found})
    if not robots:
        raise InputError(
            f"{path}: no MotionBenchMaker problem (<scenario>_<robot>/sceneNNNN.yaml "
            "with requestNNNN.yaml)"
        )
    if robot_name is None:
        if len(robots) > 1:
            raise InputError(
                f"{path} holds problems of {', '.join(robots)}: name the robot"
            )
        robot_name = robots[0]
    elif robot_name not in robots:
        raise InputError(
            f"{path}: no problem for robot {robot_name!r}; it has {', '.join(robots)}"
        )
    present = [s for robot, s in found if robot == robot_name]
    order = [s for s in SCENARIOS if s in present] + sorted(
        s for s in present if s not in SCENARIOS
    )
    if scenarios is None:
        scenarios = order
    missing = [s for s in scenarios if s not in present]
    if missing:
        raise InputError(
            f"{path}: no {robot_name} problem of scenario {', '.join(missing)}; "
            f"it has {', '.join(order)}"
        )
    problems = []
    for scenario in dict.fromkeys(scenarios):
        numbered = found[(robot_name, scenario)]
        for index in sorted(numbered)[:limit]:
            scene_name, request_name = numbered[index]
            problems.append(
                Problem(
                    robot_name,
                    scenario,
                    index,
                    parse_moveit_scene(
                        _read(files[scene_name], scene_name, "scene"),
                        source=_label(path, scene_name),
                    ),
                    _read(files[request_name], request_name, "motion request"),
                    _label(path, scene_name),
                    _label(path, request_name),
                )
            )
    return problems


def _label(source: Path, name: str) -> str:
    return str(source.parent / name) if source.is_dir() else f"{source}:{name}"


def _classify(name: str) -> tuple[str, str, int, str] | None:
    """``(robot, scenario, index, request name)`` of a scene file, else None."""
    parts = PurePosixPath(name)
    match = _SCENE.match(parts.name)
    if match is None:
        return None
    folder = parts.parent.name
    request = str(parts.with_name(parts.name.replace("scene", "request", 1)))
    if match["flat"] is not None:  # <robot>/<scenario>_sceneNNNN.yaml
        return folder, match["flat"], int(match["index"]), request
    if "_" not in folder:
        return None
    inner = re.match(r"^(?P<robot>[^/]+)/problems\.tar\.bz2/", name)
    if inner is not None and folder.endswith("_" + inner["robot"]):
        robot = inner["robot"]
        return robot, folder.removesuffix("_" + robot), int(match["index"]), request
    scenario, robot = folder.rsplit("_", 1)
    return robot, scenario, int(match["index"]), request


def _list_files(path: Path, robot_name: str | None) -> dict[str, Path | bytes]:
    """Every YAML file of the source by a posix name: a path, or bytes read."""
    if path.is_dir():
        return {
            p.relative_to(path.parent).as_posix(): p
            for p in sorted(path.rglob("*.y*ml"))
            if p.is_file()
        }
    if not path.is_file():
        raise InputError(f"no such problem set: {path}")
    try:
        with tarfile.open(path) as archive:
            files = _tar_files(archive, "", robot_name)
    except (tarfile.TarError, OSError, EOFError) as err:
        raise InputError(
            f"{path}: not a problem archive (tar.bz2 or the sdist): {err}"
        ) from None
    return files


def _tar_files(
    archive: tarfile.TarFile, prefix: str, robot_name: str | None
) -> dict[str, Path | bytes]:
    """The YAML files of a tar, and those of the ``problems.tar.bz2`` in it.

    A nested ``.../<robot>/problems.tar.bz2`` (the sdist's) is read as
    ``<robot>/problems.tar.bz2/<member>``.
    """
    files: dict[str, Path | bytes] = {}
    for member in archive:
        if not member.isfile() or member.size > 64 * MAX_FILE_BYTES:
            continue
        name = PurePosixPath(member.name)
        if name.name == "problems.tar.bz2" and not prefix:
            if robot_name not in (None, name.parent.name):
                continue  # another robot's problems in the sdist
            data = _extract(archive, member)
            with tarfile.open(fileobj=io.BytesIO(data)) as inner:
                prefix_in = f"{name.parent.name}/{name.name}/"
                files.update(_tar_files(inner, prefix_in, robot_name))
        elif name.suffix in (".yaml", ".yml") and member.size <= MAX_FILE_BYTES:
            if "scene" in name.name or "request" in name.name:
                files[prefix + member.name] = _extract(archive, member)
    return files


def _extract(archive: tarfile.TarFile, member: tarfile.TarInfo) -> bytes:
    handle = archive.extractfile(member)
    if handle is None:
        raise tarfile.ReadError(f"cannot read {member.name}")
    with handle:
        return handle.read()


def _read(content: Path | bytes, name: str, what: str) -> Any:
    """The YAML of a problem file, every failure an :class:`InputError`."""
    try:
        if isinstance(content, Path):
            return read_yaml_file(content, what)
        return yaml.safe_load(content.decode("utf-8"))
    except SceneFileError as err:
        raise InputError(str(err)) from None
    except (UnicodeDecodeError, yaml.YAMLError, RecursionError) as err:
        raise InputError(f"{name}: {what} is not YAML: {type(err).__name__}") from None


@dataclass(frozen=True, slots=True)
class Validity:
    """A problem's start and goal checked on the exact meshes.

    Attributes:
        valid: Both free of collision (every pair's distance > 0).
        where: ``"start"``, ``"goal"`` or ``"start and goal"`` when invalid,
            else ``""``.
        body_a, body_b, distance: The closest pair at the worse end and its
            signed distance [m] (negative: penetration depth).
    """

    valid: bool
    where: str
    body_a: str
    body_b: str
    distance: float


def check_validity(
    robot: Robot, problem: Problem, *, checker: CollisionChecker | None = None
) -> Validity:
    """Whether ``problem``'s start and goal are free on ``robot``'s exact meshes.

    Args:
        robot: The robot (its collision meshes and SRDF's allowed pairs).
        problem: The problem.
        checker: The exact checker of ``robot`` in the problem's scene, if
            built already.

    Raises:
        InputError: If a joint of the robot is missing from the request.
    """
    start, goal = problem.read_request(robot)
    if checker is None:
        checker = CollisionChecker(robot, problem.scene)
    worst = ("", "", math.inf)
    hit = []
    for name, q in (("start", start), ("goal", goal)):
        k, least = checker.compute_least_distance(q)
        if k < 0:
            continue
        if least <= 0.0:
            hit.append(name)
        if least < worst[2]:
            a, b = checker.body_pairs[k]
            worst = (a, b, least)
    return Validity(not hit, " and ".join(hit), *worst)
