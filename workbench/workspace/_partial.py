"""The partial folder of a map build: its lock, its identity, its completion.

A build of ``MAP.zarr`` writes ``MAP.zarr.partial``. :func:`locked` keeps two
builds from writing one partial folder at a time (a ``flock`` on a hidden lock
file beside it, which the operating system releases when the process dies);
:func:`map_attributes` are the group attributes that say which map a partial
folder is a build of, and :func:`check_same_build` refuses to resume a
partial folder of another map; :func:`finish` renames a complete one onto the
target.
"""

from __future__ import annotations

import contextlib
import fcntl
import importlib.metadata
import json
import os
import re
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

import workbench
from workbench.atomic_files import move_folder_into_place
from workbench.collision import Scene
from workbench.errors import InputError, WorkbenchError
from workbench.model.robot import Robot
from workbench.singularities.conditions import ELBOW_TOL, SHOULDER_TOL, WRIST_TOL
from workbench.workspace._block_tasks import SAMPLE_SEED, SAMPLES_PER_BLOCK
from workbench.workspace.grid import PoseGrid
from workbench.workspace.manifest import write_manifest
from workbench.workspace.robot_spec import RobotSpec, compute_file_sha256
from workbench.workspace.store import (
    DONE,
    FORMAT,
    FORMAT_VERSION,
    get_array_names,
    get_attributes,
    open_group_checked,
    read_array,
)

#: A chunk file Zarr was writing (``_atomic_write``): ``NAME.<uuid4 hex>.partial``.
_STRAY_CHUNK = re.compile(r".+\.[0-9a-f]{32}\.partial")
#: Packages whose versions a map records (``attrs["versions"]``).
VERSIONED = ("workbench", "pinocchio", "numpy", "numba", "zarr", "dask")


def get_versions() -> dict[str, str]:
    """The versions of :data:`VERSIONED` installed here."""
    versions = {}
    for name in VERSIONED:
        if name == "workbench":
            versions[name] = workbench.__version__
            continue
        try:
            versions[name] = importlib.metadata.version(
                "pin" if name == "pinocchio" else name
            )
        except importlib.metadata.PackageNotFoundError:
            versions[name] = "unknown"
    return versions


def as_json_attributes(attrs: Mapping[str, Any]) -> dict[str, Any]:
    """``attrs`` as stored (JSON): NumPy values as builtins, exactly; tuples as lists.

    Raises:
        ValueError: If a value is not finite.
    """
    ready = _json_ready(attrs)
    loaded: dict[str, Any] = json.loads(json.dumps(ready, allow_nan=False))
    return loaded


def _json_ready(value: Any) -> Any:
    """NumPy values as builtins, exactly (no rounding), tuples as lists."""
    if isinstance(value, Mapping):
        return {str(k): _json_ready(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return _json_ready(value.tolist())
    if isinstance(value, list | tuple):
        return [_json_ready(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def check_same_build(partial: Path, attrs: Mapping[str, Any]) -> None:
    """Raise unless the partial folder is a build of the map ``attrs`` describe.

    Every attribute must be equal, the versions of the packages included (a
    map is bitwise reproducible with the versions it records).

    Raises:
        InputError: If ``partial`` is no map, or a build of another one.
    """
    try:
        stored = get_attributes(open_group_checked(partial, mode="r"))
    except InputError as err:
        raise InputError(
            f"{partial} is in the way of this build and is not a partial map "
            f"of it ({err}); remove it to start again"
        ) from err
    differ = [key for key in attrs if stored.get(key) != attrs[key]]
    if differ:
        raise InputError(
            f"{partial} holds an unfinished build of another map ({', '.join(differ)} "
            "differ); run the command that started it to finish it, or remove it "
            "to start this one"
        )


@contextlib.contextmanager
def locked(partial: Path) -> Iterator[None]:
    """Hold the exclusive right to write the partial folder ``partial``.

    The lock is a ``flock`` on a hidden lock file beside the partial folder
    (the operating system drops it when the process dies), so two builds of
    one map never write the same partial folder.

    Raises:
        InputError: If another process holds it, or the folder is read-only.
    """
    lock = partial.with_name(f".{partial.name}.lock")
    fd = _lock_file(lock, partial)
    try:
        yield
    finally:
        lock.unlink(missing_ok=True)  # still ours: the next build makes a new one
        os.close(fd)


def _lock_file(lock: Path, partial: Path) -> int:
    """Open and ``flock`` the lock file; its descriptor (retried if replaced)."""
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as err:
            raise InputError(f"cannot write {lock}: {err.strerror or err}") from err
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            os.close(fd)
            raise InputError(
                f"{partial} is being built by another process; wait for it or stop it"
            ) from err
        try:
            same = os.fstat(fd).st_ino == lock.stat().st_ino
        except FileNotFoundError:  # its holder removed it as we took it
            same = False
        if same:
            return fd
        os.close(fd)


def finish(partial: Path, path: Path) -> None:
    """Check that every block of ``partial`` is done, write its manifest, rename it.

    The manifest (:func:`~workbench.workspace.manifest.write_manifest`)
    digests every chunk as it is on disk; then ``partial`` is renamed
    ``path``.

    Raises:
        WorkbenchError: If a block is not done.
        InputError: If ``path`` exists or the rename fails.
    """
    done = read_array(open_group_checked(partial, mode="r"), DONE)
    if not np.all(done == 1):
        raise WorkbenchError(
            f"{partial}: {int(np.sum(done == 1))} of {done.size} blocks done after "
            "the run"
        )
    if path.exists():
        raise InputError(f"cannot write {path}: it appeared during the build")
    remove_stray_chunk_files(partial)
    group = open_group_checked(partial, mode="r+")
    write_manifest(group, get_array_names(group))
    try:
        move_folder_into_place(partial, path)
    except OSError as err:
        raise InputError(f"cannot write {path}: {err.strerror or err}") from err


def remove_stray_chunk_files(folder: Path) -> int:
    """Remove the half-written chunk files of stopped writers; returns how many.

    Zarr writes a chunk to ``CHUNK.<32 hex digits>.partial`` and renames it
    onto ``CHUNK``; a writer killed in between (``kill -9``, Ctrl-C) leaves
    that file behind. Its block was not marked done, so it was written again
    whole: the leftover is garbage.
    """
    removed = 0
    for file in folder.rglob("*.partial"):
        if _STRAY_CHUNK.fullmatch(file.name) and file.is_file():
            file.unlink(missing_ok=True)
            removed += 1
    return removed


def map_attributes(
    robot: Robot,
    spec: RobotSpec,
    grid: PoseGrid,
    family: str | None,
    scene: Scene | None,
    block_voxels: int,
    samples: int,
    redundancy: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """The group attributes of a map (``docs/workspace.md`` lists them).

    Args:
        robot: The arm.
        spec: Its spec (URDF digest, limits).
        grid: The pose grid.
        family: ``"opw"``, ``"ur"``, ``"srs"``, ``"franka"`` or None.
        scene: The obstacles, or None.
        block_voxels: Voxels per block and chunk.
        samples: Configurations of a sampled map, 0 for an exact one.
        redundancy: Of a seven-axis map in closed form: ``parameter``,
            ``range`` [rad], ``samples`` (K) and ``values`` [rad]; else None.
    """
    sampled = samples > 0
    return as_json_attributes(
        {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "robot": robot.name,
            "urdf_sha256": spec.urdf_sha256,
            "srdf_sha256": None
            if spec.srdf is None
            else compute_file_sha256(spec.srdf),
            "tool_frame": robot.tool_frame,
            "family": family,
            "joint_limits": {"lower": spec.lower, "upper": spec.upper},
            "sampled": sampled,
            "samples": samples if sampled else None,
            "sampling": (
                {"samples_per_block": SAMPLES_PER_BLOCK, "seed": SAMPLE_SEED}
                if sampled
                else None
            ),
            "grid": {
                "origin": grid.origin,
                "resolution": grid.resolution,
                "shape": grid.shape,
                "bounds": grid.bounds,
            },
            "orientation_set": grid.orientation_set,
            "block_voxels": block_voxels,
            "tolerances": None  # no 6R factors of det J on a seven-axis map
            if redundancy is not None
            else {"shoulder": SHOULDER_TOL, "elbow": ELBOW_TOL, "wrist": WRIST_TOL},
            "redundancy": None if redundancy is None else dict(redundancy),
            "scene": None if scene is None else scene.to_dict(),
            "versions": get_versions(),
        }
    )
