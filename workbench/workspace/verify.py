"""Check a whole workspace map: every chunk, every value, the grid re-derived.

:func:`verify_map` (``workbench workspace verify MAP``) reads everything a
map holds and refuses it, in one line naming what is wrong, unless:

* its attributes follow the schema (:mod:`~.map_schema`) and, with its
  arrays' metadata, are those its manifest records (:mod:`~.manifest`);
* every block is done, and every chunk file of every data array has the
  digest the manifest records (or is absent where it records none) and
  decodes;
* every value lies in its array's range (:data:`~.store.ARRAYS`: counts
  0..8, sines and fractions in [0, 1], lengths and margins ≥ 0; the
  redundancy values within the map's range), NaN aside;
* the voxel centres are those of the grid its attributes describe, bitwise,
  and the orientations and the orientation set (its covering radius
  included) are those re-derived from its ``orientation_set``.

A map of format version 1 (written before maps carried a manifest) is
checked the same way, by its ``done`` flags instead of digests; with
``upgrade=True`` its manifest is then written and it becomes version 2, in
place (one atomic rewrite of the group's ``zarr.json`` after the
``checksums`` array).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import zarr

from workbench.errors import InputError
from workbench.workspace._chunk_files import ChunkReader
from workbench.workspace.grid import grid_positions
from workbench.workspace.manifest import (
    DECODE_ERRORS,
    Manifest,
    damaged,
    write_manifest,
)
from workbench.workspace.orientations import cone_orientations, uniform_orientations
from workbench.workspace.store import (
    ARRAYS,
    DONE,
    FORMAT_VERSION,
    UNCHECKED_VERSION,
    get_array_names,
    get_attributes,
    open_arrays_checked,
    read_array,
    read_done_flags,
)

#: ``progress(done, total)``: chunks checked so far and in all.
ProgressCallback = Callable[[int, int], None]


@dataclass(frozen=True, slots=True)
class MapCheck:
    """What :func:`verify_map` checked (the keys of ``workspace verify --json``).

    Attributes:
        store: The map folder.
        format_version: Its format version after the check (2 once upgraded).
        checksums: Whether the chunks were checked against digests (False:
            a version 1 map checked by its done flags only).
        upgraded: Whether the manifest was written by this check.
        arrays: Data arrays checked.
        chunks: Chunks checked (of every data array).
        chunks_stored: Of them, chunk files (the others hold only the fill
            value and are not stored).
        bytes: Bytes of chunk files read.
        values: Values checked (of every data array).
    """

    store: str
    format_version: int
    checksums: bool
    upgraded: bool
    arrays: int
    chunks: int
    chunks_stored: int
    bytes: int
    values: int

    def as_dict(self) -> dict[str, Any]:
        """The check as a JSON-ready dict."""
        return asdict(self)


def verify_map(
    path: str | Path,
    *,
    upgrade: bool = False,
    progress: ProgressCallback | None = None,
) -> MapCheck:
    """Check every chunk and value of the map at ``path`` (module docstring).

    Args:
        path: The map folder (``MAP.zarr``).
        upgrade: Write the manifest of a version 1 map that passes (a no-op
            on a version 2 map).
        progress: Called with ``(done, total)`` chunks.

    Returns:
        What was checked.

    Raises:
        InputError: One line naming the first damage found, or if ``path``
            is no finished map.
    """
    path = Path(path)
    versions = (FORMAT_VERSION, UNCHECKED_VERSION)
    group, arrays = open_arrays_checked(path, mode="r", versions=versions)
    attrs = get_attributes(group)
    version = int(attrs["format_version"])
    names = get_array_names(arrays)
    done = read_done_flags(group, arrays[DONE])
    if not np.all(done == 1):
        raise InputError(
            f"{path} is no finished map ({int(np.sum(done == 1))} of {done.size} "
            "blocks done); run the command that built it again to finish it"
        )
    manifest = None
    if version == FORMAT_VERSION:
        manifest = Manifest(path, arrays, attrs, names)
    readers = {name: ChunkReader(arrays[name]) for name in names}
    total = sum(reader.count for reader in readers.values())
    counted = {"chunks": 0, "stored": 0, "bytes": 0, "values": 0}
    for name, reader in readers.items():
        for index in range(reader.count):
            if manifest is not None:
                values = manifest.read_chunk(name, index)
                size = manifest.stored_size(name, index)  # its file's, on open
            else:
                data = reader.read_bytes(index)
                values = _decoded(path, reader, name, index, data)
                size = None if data is None else len(data)
            _check_range(path, name, index, values, attrs)
            counted["chunks"] += 1
            counted["stored"] += size is not None
            counted["bytes"] += size or 0
            counted["values"] += values.size
            if progress is not None:
                progress(counted["chunks"], total)
    read = manifest.read_single if manifest is not None else partial(read_array, group)
    _check_grid(path, attrs, read)
    upgraded = False
    if upgrade and manifest is None:
        writable = zarr.open_group(path, mode="r+", zarr_format=3)
        write_manifest(writable, names, {"format_version": FORMAT_VERSION})
        upgraded, version = True, FORMAT_VERSION
    return MapCheck(
        store=str(path),
        format_version=version,
        checksums=manifest is not None,
        upgraded=upgraded,
        arrays=len(names),
        chunks=counted["chunks"],
        chunks_stored=counted["stored"],
        bytes=counted["bytes"],
        values=counted["values"],
    )


def _decoded(
    path: Path, reader: ChunkReader, name: str, index: int, data: bytes | None
) -> npt.NDArray[Any]:
    try:
        return reader.decode(data, index)
    except DECODE_ERRORS as err:
        message = " ".join(str(err).split()) or type(err).__name__
        raise damaged(path, f"array {name!r}, chunk {index}: {message}") from None


def _check_range(
    path: Path,
    name: str,
    index: int,
    values: npt.NDArray[Any],
    attrs: dict[str, Any],
) -> None:
    """Raise unless every value of the chunk is NaN or in the array's range."""
    info = ARRAYS[name]
    low, high = info.low, info.high
    if name == "redundancy" and attrs.get("redundancy"):
        low, high = (float(v) for v in attrs["redundancy"]["range"])
        # float32 values of float64 bounds: one float32 ulp of slack
        low, high = float(np.float32(low)), float(np.float32(high))
    finite = values[~np.isnan(values)] if values.dtype.kind == "f" else values
    if finite.size == 0:
        return
    smallest, largest = finite.min(), finite.max()
    if smallest < low or largest > high:
        bad = smallest if smallest < low else largest
        raise damaged(
            path,
            f"array {name!r}, chunk {index}: value {bad} outside [{low:g}, {high:g}]",
        )


def _check_grid(
    path: Path, attrs: dict[str, Any], read: Callable[[str], npt.NDArray[Any]]
) -> None:
    """Raise unless the positions and orientations are re-derived bitwise."""
    grid = attrs["grid"]
    resolution = float(grid["resolution"])
    shape = tuple(int(n) for n in grid["shape"])
    bounds = np.asarray(grid["bounds"], dtype=np.float64)
    low, high = np.rint(bounds[0] / resolution), np.rint(bounds[1] / resolution)
    if tuple(int(n) for n in high - low + 1) != shape or not np.array_equal(
        low * resolution, np.asarray(grid["origin"], dtype=np.float64)
    ):
        raise damaged(
            path, "attribute grid: origin and shape are not those of its bounds"
        )
    positions = grid_positions(grid["origin"], resolution, shape)
    if not np.array_equal(read("positions"), positions):
        raise damaged(path, "array 'positions' is not the grid of its attributes")
    described = attrs["orientation_set"]
    count = int(described["count"])
    if described["construction"] == "super-fibonacci":
        quat, derived = uniform_orientations(count)
    else:
        quat, derived = cone_orientations(
            described["axis"], described["half_angle"], count
        )
    if not np.array_equal(read("orientations"), quat):
        raise damaged(
            path, "array 'orientations' is not the set of its orientation_set"
        )
    for key, value in derived.items():
        stored = described.get(key)
        if stored != value:  # floats too: the same computation, bitwise
            raise damaged(
                path,
                f"attribute orientation_set.{key} is {stored!r}, re-derived {value!r}",
            )
