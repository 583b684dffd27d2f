"""MotionBenchMaker's problems as the ``vamp-planner`` 0.6.4 sdist ships them.

The sdist (from ``--sdist``, a cache, or PyPI's simple index, checked against
its SHA-256), its ``resources/`` unpacked (the robots' URDFs, SRDFs, meshes
and ``problems.tar.bz2``) and the robots loaded with acceleration limits. The
problems are found and judged valid by the package
(:func:`workbench.motion.find_problems`, :func:`workbench.motion.check_validity`).
Used by :mod:`benchmarks.bench_motion`.
"""

from __future__ import annotations

import hashlib
import json
import sys
import tarfile
import urllib.request
from pathlib import Path

from workbench import Robot, load_robot
from workbench.motion.problems import SCENARIOS

SDIST_NAME = "vamp_planner-0.6.4.tar.gz"
SDIST_SHA256 = "d3150c6b67ff941af9ad56480b31d3fb73b12211ea21dc684f7737b059f6daba"
INDEX_URL = "https://pypi.org/simple/vamp-planner/"
ROBOTS = ("panda", "ur5")
__all__ = ["ROBOTS", "SCENARIOS", "extract_resources", "get_sdist", "load_mbm_robot"]
#: Acceleration limits [rad/s²] of the robots (their URDFs have none; the
#: trajectories need them): the Franka datasheet's for the Panda, a round value
#: for the UR5.
ACCELERATION_LIMITS = {
    "panda": (15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0),
    "ur5": (8.0,) * 6,
}

# --- the sdist -------------------------------------------------------------


def get_sdist(cache: Path, sdist: Path | None = None) -> Path:
    """The ``vamp-planner`` sdist: given, cached, or from PyPI's simple index.

    Raises:
        SystemExit: If the file's SHA-256 is not the release's.
    """
    if sdist is not None:
        _check_sha256(sdist)
        return sdist
    path = cache / SDIST_NAME
    if path.is_file():
        _check_sha256(path)
        return path
    request = urllib.request.Request(
        INDEX_URL, headers={"Accept": "application/vnd.pypi.simple.v1+json"}
    )
    with urllib.request.urlopen(request, timeout=60) as response:
        index = json.load(response)
    (entry,) = [f for f in index["files"] if f["filename"] == SDIST_NAME]
    if entry["hashes"].get("sha256") != SDIST_SHA256:
        raise SystemExit(f"{INDEX_URL}: {SDIST_NAME} has an unexpected SHA-256")
    print(f"downloading {entry['url']}", file=sys.stderr)
    cache.mkdir(parents=True, exist_ok=True)
    partial = path.with_suffix(".part")
    with urllib.request.urlopen(entry["url"], timeout=300) as response:
        partial.write_bytes(response.read())
    _check_sha256(partial)
    partial.replace(path)
    return path


def _check_sha256(path: Path) -> None:
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    if digest != SDIST_SHA256:
        raise SystemExit(f"{path}: SHA-256 {digest}, expected {SDIST_SHA256}")


def extract_resources(sdist: Path, cache: Path) -> Path:
    """``resources/`` of the sdist under ``cache``, with the problems unpacked.

    Returns:
        The folder holding ``panda/`` and ``ur5/`` (URDF, SRDF, meshes and a
        ``problems/`` folder of ``<scenario>_<robot>/{scene,request}NNNN.yaml``).
    """
    root = cache / sdist.name.removesuffix(".tar.gz")
    resources = root / "resources"
    done = root / ".extracted"
    if not done.is_file():
        prefix = f"{root.name}/resources/"
        with tarfile.open(sdist) as archive:
            members = [
                m
                for m in archive.getmembers()
                if m.name.startswith(prefix) and m.name.split("/")[2] in ROBOTS
            ]
            archive.extractall(cache, members=members, filter="data")
        for robot in ROBOTS:
            with tarfile.open(resources / robot / "problems.tar.bz2") as problems:
                problems.extractall(resources / robot, filter="data")
        done.write_text(SDIST_SHA256)
    return resources


def load_mbm_robot(resources: Path, name: str) -> Robot:
    """MotionBenchMaker's ``name`` robot (its URDF, meshes and SRDF).

    Its speed limits are the URDF's, its acceleration limits
    :data:`ACCELERATION_LIMITS`.
    """
    robot = load_robot(resources / name / f"{name}.urdf")
    return robot.with_limits(acceleration_limit=ACCELERATION_LIMITS[name])
