"""The workspace map on disk: a Zarr v3 group, written block by block.

A map is a folder ``MAP.zarr`` holding a Zarr v3 group (``docs/workspace.md``
lists every array and attribute, for readers without the workbench):

* ``positions`` (V, 3) float64 [m] voxel centres and ``orientations`` (O, 4)
  float64 unit quaternions x y z w, the pose grid;
* the per-pose arrays (V, O) and per-voxel arrays (V,) of
  :func:`workbench.workspace.measures.evaluate_block` (or of a sampled map),
  in chunks of ``(block_voxels, O)`` and ``(block_voxels,)``: one block of
  voxels is one chunk of each array, written by one task;
* ``done`` (n_blocks,) uint8, one chunk per block, set to 1 after the block's
  data: a build that stops resumes from the blocks marked done.

A build writes ``MAP.zarr.partial`` and renames it ``MAP.zarr`` when every
block is done (:mod:`workbench.workspace.build`), so a folder named ``MAP.zarr``
is always a whole map. Chunks are compressed with Blosc LZ4 (bit shuffle), which
compresses and decompresses at memory speed; chunks that hold only the fill
value (NaN, 0: poses out of reach) are not written at all.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt
import zarr
import zarr.errors
import zarr.storage
from zarr.abc.codec import ArrayArrayCodec, SupportsSyncCodec
from zarr.codecs import BloscCodec
from zarr.core.buffer import default_buffer_prototype

from workbench.atomic_files import atomic_folder
from workbench.errors import InputError
from workbench.workspace.grid import PoseGrid
from workbench.workspace.map_query import (
    READ_ERRORS,
    MapQuery,
    damaged_array,
    query_map,
)
from workbench.workspace.orientations import rotations_from_quat_xyzw

#: The ``format`` attribute of every map.
FORMAT = "workbench-workspace-map"
#: The layout version this module writes and reads.
FORMAT_VERSION = 1
#: Suffix of the folder a build writes before renaming it onto the target.
PARTIAL_SUFFIX = ".partial"
#: Arrays of the grid (not per block).
GRID_ARRAYS = ("positions", "orientations")
#: The array of block flags.
DONE = "done"


@dataclass(frozen=True, slots=True)
class ArrayInfo:
    """What one data array of a map holds.

    Attributes:
        dtype: NumPy dtype name (``"uint8"``, ``"float32"``).
        per_pose: True for shape (V, O), False for (V,).
        units: Unit of the values (``"1"`` for counts and fractions).
        description: One line, stored as the array's ``description`` attribute.
    """

    dtype: str
    per_pose: bool
    units: str
    description: str

    @property
    def fill_value(self) -> float | int:
        """NaN for floats (no value), 0 for counts."""
        return float("nan") if self.dtype.startswith("float") else 0


#: Every data array a map may hold, by name (a map holds a subset: see
#: :func:`get_array_names`).
ARRAYS: dict[str, ArrayInfo] = {
    "reached": ArrayInfo(
        "uint8", True, "1", "closed-form branches that reach the pose (0..8)"
    ),
    "branches": ArrayInfo(
        "uint8", True, "1", "branches reaching the pose within the joint limits"
    ),
    "collision_free": ArrayInfo(
        "uint8", True, "1", "in-limit branches free of collision with the scene"
    ),
    "dexterity": ArrayInfo(
        "float32",
        True,
        "m^3",
        "manipulability |det J| of the best usable branch; NaN: none",
    ),
    "shoulder": ArrayInfo(
        "float32", True, "m", "|s| shoulder-singularity distance of the best branch"
    ),
    "elbow": ArrayInfo(
        "float32", True, "1", "|e| elbow-singularity sine of the best branch"
    ),
    "wrist": ArrayInfo(
        "float32", True, "1", "|w| wrist-singularity sine of the best branch"
    ),
    "limit_margin": ArrayInfo(
        "float32",
        True,
        "rad",
        "smallest distance of the best branch's joints to their limits",
    ),
    "redundancy": ArrayInfo(
        "float32",
        True,
        "rad",
        "seven-axis maps: the redundancy parameter (arm angle or q7) of the best "
        "candidate",
    ),
    "reachability": ArrayInfo(
        "float32", False, "1", "fraction of orientations with a usable branch"
    ),
    "dexterity_best": ArrayInfo(
        "float32", False, "m^3", "largest dexterity over the orientations"
    ),
    "dexterity_median": ArrayInfo(
        "float32", False, "m^3", "median dexterity over the reached orientations"
    ),
    "near_singular_fraction": ArrayInfo(
        "float32",
        False,
        "1",
        "fraction of the reached orientations with singularity margin < 1",
    ),
}


def get_compressor() -> BloscCodec:
    """The codec of every chunk: Blosc LZ4, bit shuffle (fast; lossless)."""
    return BloscCodec(cname="lz4", clevel=5, shuffle="bitshuffle")


def get_partial_path(path: str | Path) -> Path:
    """``MAP.zarr.partial``: where a build of ``MAP.zarr`` writes until it is whole."""
    path = Path(path)
    return path.with_name(path.name + PARTIAL_SUFFIX)


def get_block_count(voxel_count: int, block_voxels: int) -> int:
    """Number of blocks of ``block_voxels`` voxels (the last one may be shorter)."""
    return -(-voxel_count // block_voxels)


def create_store(
    path: str | Path,
    grid: PoseGrid,
    *,
    names: Sequence[str],
    block_voxels: int,
    attrs: Mapping[str, Any],
    blocks: int | None = None,
) -> None:
    """Create an empty map (grid, empty data arrays, no block done) at ``path``.

    Written in a temporary sibling folder renamed onto ``path``, so ``path``
    appears whole or not at all.

    Args:
        path: The new folder; must not exist.
        grid: The pose grid (written as ``positions`` and ``orientations``).
        names: Data arrays to create (keys of :data:`ARRAYS`).
        block_voxels: Voxels per block, the chunk length of the data arrays.
        attrs: The group's attributes (JSON-ready).
        blocks: Number of ``done`` flags; default one per block of voxels.

    Raises:
        InputError: If ``path`` exists or cannot be written.
    """
    path = Path(path)
    count = (
        get_block_count(grid.voxel_count, block_voxels) if blocks is None else blocks
    )
    try:
        with atomic_folder(path) as tmp:
            group = zarr.open_group(
                tmp, mode="w-", zarr_format=3, attributes=dict(attrs)
            )
            _create_arrays(group, grid, names, block_voxels, count)
    except OSError as err:
        raise InputError(f"cannot write {path}: {err.strerror or err}") from err


def _create_arrays(
    group: zarr.Group,
    grid: PoseGrid,
    names: Sequence[str],
    block_voxels: int,
    count: int,
) -> None:
    """The grid arrays (written), the empty data arrays and ``done``."""
    compressors = [get_compressor()]
    for name, values in (
        ("positions", grid.positions),
        ("orientations", grid.orientations),
    ):
        array = group.create_array(
            name,
            shape=values.shape,
            dtype="float64",
            chunks=values.shape,
            compressors=compressors,
        )
        array[...] = values
    voxels, orientations = grid.voxel_count, grid.orientation_count
    for name in names:
        info = ARRAYS[name]
        per_pose = info.per_pose
        group.create_array(
            name,
            shape=(voxels, orientations) if per_pose else (voxels,),
            chunks=(block_voxels, orientations) if per_pose else (block_voxels,),
            dtype=info.dtype,
            fill_value=info.fill_value,
            compressors=compressors,
            attributes={"units": info.units, "description": info.description},
        )
    group.create_array(
        DONE,
        shape=(count,),
        chunks=(1,),
        dtype="uint8",
        fill_value=0,
        compressors=None,
        attributes={"description": "1 once the block's data are written"},
    )


class BlockWriter:
    """Writes blocks into a map being built (its arrays opened once).

    Each chunk is encoded and written by the calling thread
    (``_ChunkWriter``): the blocks of a build are written by as many
    threads as compute them, not by Zarr's one I/O thread.

    Args:
        path: The map folder (being built).

    Raises:
        InputError: If ``path`` is not a map (:func:`open_group_checked`).
    """

    def __init__(self, path: str | Path):
        group = open_group_checked(path, mode="r+")
        self._arrays = {
            name: _ChunkWriter(get_array(group, name))
            for name in get_array_names(group)
        }
        self._done = _ChunkWriter(get_array(group, DONE))

    def write(self, block: int, start: int, data: Mapping[str, Any]) -> None:
        """Write one block's arrays at voxels ``start:``, then its ``done`` flag.

        The flag is written only once every array of the block is stored.

        Args:
            block: Block index (its flag in ``done``).
            start: First voxel of the block (a multiple of the chunk length).
            data: Arrays by name, (B, O) or (B,) each, B the block's voxels.
        """
        for name, values in data.items():
            self._arrays[name].write(start, np.asarray(values))
        self._done.write(block, _DONE_FLAG)


#: The value of a block's ``done`` chunk.
_DONE_FLAG = np.ones(1, dtype=np.uint8)


def _only_fill(chunk: np.ndarray, fill: Any) -> bool:
    """Whether ``chunk`` holds only ``fill`` (Zarr's ``NDBuffer.all_equal``).

    NaN: every value NaN; 0 of an integer array: no value set. Other fills
    go through Zarr's comparison (a float 0 compares bit patterns there).
    """
    fill = np.asarray(fill)
    if fill.dtype.kind == "f" and np.isnan(fill):
        return bool(np.isnan(chunk).all())
    if chunk.dtype.kind in "iub" and fill == 0:
        return not chunk.any()
    buffer = default_buffer_prototype().nd_buffer.from_numpy_array(chunk)
    return bool(buffer.all_equal(fill))


class _ChunkWriter:
    """Writes whole chunks of one array in the calling thread.

    What Zarr's ``array[start:stop] = values`` stores for a selection that is
    one whole chunk (the last one padded with the fill value; nothing, and
    any older file removed, for a chunk of fill values only), bitwise: the
    chunk goes through the array's own codecs (their synchronous
    ``_encode_sync``) and is written like Zarr's local store does
    (``NAME.<uuid4 hex>.partial``, then renamed), and flushed to disk
    first, so that a block's ``done`` flag never outlives its data in a
    crash (and the final flush of the map finds little left). Zarr's own ``setitem``
    sends every chunk through its single I/O event-loop thread, which made
    storing the serial part of a build on several threads. Arrays whose
    store or codecs do not allow it (another store, an asynchronous-only
    codec) are written through Zarr.

    Args:
        array: A Zarr v3 array chunked along its first axis only.
    """

    def __init__(self, array: zarr.Array):
        self._array = array
        metadata = array.metadata
        store = array.store_path.store
        codecs = getattr(metadata, "codecs", ())
        self._folder: Path | None = None
        if (
            isinstance(store, zarr.storage.LocalStore)
            and codecs
            and all(isinstance(codec, SupportsSyncCodec) for codec in codecs)
            and not any(isinstance(codec, ArrayArrayCodec) for codec in codecs)
        ):
            self._folder = Path(store.root) / array.store_path.path
        self._codecs = codecs
        self._length = array.chunks[0]
        self._spec = (
            None
            if self._folder is None
            else metadata.get_chunk_spec(
                (0,) * array.ndim, array.async_array.config, default_buffer_prototype()
            )
        )

    def write(self, start: int, values: np.ndarray) -> None:
        """Store ``values`` at rows ``start:`` (one whole chunk, or the last)."""
        array, length = self._array, self._length
        if start % length or len(values) > length:
            raise ValueError(f"rows {start}:+{len(values)} are not one chunk")
        if self._folder is None or self._spec is None:
            array[start : start + len(values)] = values
            return
        spec = self._spec
        chunk = np.asarray(values, dtype=array.dtype)
        if chunk.shape != spec.shape:  # the last chunk, cut by the array's end
            padded = np.full(spec.shape, spec.fill_value, dtype=array.dtype)
            padded[: len(chunk)] = chunk
            chunk = padded
        coords = (start // length,) + (0,) * (array.ndim - 1)
        path = self._folder / array.metadata.encode_chunk_key(coords)
        encoded: Any = spec.prototype.nd_buffer.from_numpy_array(
            np.ascontiguousarray(chunk)
        )
        if not spec.config.write_empty_chunks and _only_fill(chunk, spec.fill_value):
            path.unlink(missing_ok=True)
            return
        for codec in self._codecs:
            encoded = codec._encode_sync(encoded, spec)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f"{path.name}.{uuid.uuid4().hex}.partial")
        try:
            with tmp.open("wb") as file:
                file.write(encoded.as_buffer_like())
                file.flush()
                os.fsync(file.fileno())  # on disk before the block's done flag
            tmp.replace(path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise


def read_done(path: str | Path) -> npt.NDArray[np.bool_]:
    """The ``done`` flags of a map (being built), (n_blocks,) bool."""
    group = open_group_checked(path, mode="r")
    return read_array(group, DONE) == 1


def get_array(group: zarr.Group, name: str) -> zarr.Array:
    """Array ``name`` of a map's group.

    Raises:
        InputError: If there is no such array.
    """
    try:
        array = group[name]
    except KeyError:
        array = None
    if not isinstance(array, zarr.Array):
        raise InputError(f"{group.store_path} has no array {name!r}")
    return array


def read_array(group: zarr.Group, name: str) -> npt.NDArray[Any]:
    """The whole array ``name`` of a map's group, as NumPy.

    Raises:
        InputError: If there is no such array, or its chunks cannot be read
            (truncated, corrupt).
    """
    array = get_array(group, name)
    try:
        return np.asarray(array[...])
    except READ_ERRORS as err:
        raise damaged_array(group, name, err) from err


def get_attributes(group: zarr.Group) -> dict[str, Any]:
    """The group attributes of a map, as a plain dict (a copy)."""
    attrs: dict[str, Any] = dict(group.attrs.asdict())
    return attrs


def open_group_checked(
    path: str | Path, *, mode: Literal["r", "r+"] = "r"
) -> zarr.Group:
    """The Zarr group of a map at ``path``, checked to be one of this format.

    Raises:
        InputError: If ``path`` does not exist, is no Zarr v3 group, is not a
            workspace map, is of another format version, or misses arrays.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"no workspace map at {path}: not found")
    if not (path / "zarr.json").is_file():
        raise InputError(f"{path} is not a workspace map (no Zarr v3 zarr.json in it)")
    try:
        group = zarr.open_group(path, mode=mode, zarr_format=3)
        attrs = get_attributes(group)
    except (OSError, ValueError, KeyError, TypeError, zarr.errors.BaseZarrError) as err:
        message = " ".join(str(err).split()) or type(err).__name__
        raise InputError(f"{path} is not a workspace map ({message})") from err
    if attrs.get("format") != FORMAT:
        raise InputError(
            f"{path} is not a workspace map (attribute format is "
            f"{attrs.get('format')!r}, not {FORMAT!r})"
        )
    version = attrs.get("format_version")
    if version != FORMAT_VERSION:
        raise InputError(
            f"{path} is a workspace map of format version {version!r}; this "
            f"workbench reads version {FORMAT_VERSION}"
        )
    _check_arrays(path, group, attrs)
    return group


def _check_arrays(path: Path, group: zarr.Group, attrs: Mapping[str, Any]) -> None:
    """Raise unless the grid, data and ``done`` arrays are there with their shapes."""
    try:
        names = set(group.array_keys())
        shape = tuple(attrs["grid"]["shape"])
        voxels = int(np.prod(shape))
        orientations = int(attrs["orientation_set"]["count"])
    except (KeyError, TypeError, ValueError) as err:
        raise InputError(f"{path} is a damaged workspace map ({err!r})") from err
    expected: dict[str, tuple[tuple[int, ...], str]] = {
        "positions": ((voxels, 3), "float64"),
        "orientations": ((orientations, 4), "float64"),
    }
    for name in sorted(names & set(ARRAYS)):
        info = ARRAYS[name]
        per_pose = (voxels, orientations)
        expected[name] = (per_pose if info.per_pose else (voxels,), info.dtype)
    for name, (size, dtype) in expected.items():
        if name not in names:
            raise InputError(f"{path} is a damaged workspace map (no array {name!r})")
        array = get_array(group, name)
        if array.shape != size or str(array.dtype) != dtype:
            raise InputError(
                f"{path} is a damaged workspace map (array {name!r} is "
                f"{array.shape} {array.dtype}, expected {size} {dtype})"
            )
    if DONE not in names:
        raise InputError(f"{path} is a damaged workspace map (no array 'done')")


def get_array_names(group: zarr.Group) -> list[str]:
    """The data arrays a map holds, in the order of :data:`ARRAYS`."""
    present = set(group.array_keys())
    return [name for name in ARRAYS if name in present]


def read_grid(group: zarr.Group) -> PoseGrid:
    """The pose grid stored in a map (bitwise the one it was built on)."""
    attrs = get_attributes(group)
    grid = attrs["grid"]
    orientations = _read_only(read_array(group, "orientations"))
    return PoseGrid(
        positions=_read_only(read_array(group, "positions")),
        origin=_read_only(grid["origin"]),
        resolution=float(grid["resolution"]),
        shape=tuple(int(n) for n in grid["shape"]),  # type: ignore[arg-type]
        bounds=_read_only(grid["bounds"]),
        orientations=orientations,
        orientation_set=dict(attrs["orientation_set"]),
        rotations=_read_only(rotations_from_quat_xyzw(orientations)),
    )


def _read_only(values: npt.ArrayLike) -> npt.NDArray[np.float64]:
    out = np.array(values, dtype=np.float64)
    out.setflags(write=False)
    return out


class WorkspaceMap:
    """A finished workspace map, opened for reading (:func:`open_map`).

    Arrays are read from disk on each access: ``map["dexterity"]`` is a new
    NumPy array (V, O). Keep it if you use it twice.

    Attributes:
        path: The map folder.
        attrs: The group attributes (a copy; ``docs/workspace.md``).
        names: The data arrays it holds (keys of :data:`ARRAYS`).
    """

    def __init__(self, path: Path, group: zarr.Group):
        self.path = path
        self._group = group
        self.attrs = get_attributes(group)
        self.names: tuple[str, ...] = tuple(get_array_names(group))

    def __repr__(self) -> str:
        return f"WorkspaceMap({str(self.path)!r}, robot={self.attrs['robot']!r})"

    @cached_property
    def grid(self) -> PoseGrid:
        """The pose grid of the map."""
        return read_grid(self._group)

    @property
    def sampled(self) -> bool:
        """Whether the map was sampled (no closed form)."""
        return bool(self.attrs["sampled"])

    def __contains__(self, name: object) -> bool:
        return name in self.names

    def __getitem__(self, name: str) -> npt.NDArray[Any]:
        """Array ``name`` (a data array, ``positions``, ``orientations``, ``done``).

        Raises:
            InputError: If the map has no such array.
        """
        if name not in (*self.names, *GRID_ARRAYS, DONE):
            raise InputError(
                f"the map {self.path} has no array {name!r}; it has "
                f"{', '.join(self.names)}"
            )
        return read_array(self._group, name)

    def query(self, poses: npt.ArrayLike) -> MapQuery:
        """The map at the grid poses nearest to ``poses`` (N, 4, 4) or (N, 7).

        See :func:`~workbench.workspace.map_query.query_map`.
        """
        return query_map(self._group, self.grid, poses)


def open_map(path: str | Path) -> WorkspaceMap:
    """Open a finished workspace map for reading.

    Raises:
        InputError: If ``path`` is missing, not a workspace map, of another
            format version, damaged, an unfinished build (a ``.partial``
            folder, or blocks not done).
    """
    path = Path(path)
    group = open_group_checked(path, mode="r")
    done = read_array(group, DONE)
    if path.name.endswith(PARTIAL_SUFFIX) or not np.all(done == 1):
        raise InputError(
            f"{path} is an unfinished map build ({int(np.sum(done == 1))} of "
            f"{done.size} blocks done); run the command that started it again to "
            "finish it"
        )
    return WorkspaceMap(path, group)
