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
  data: a build that stops resumes from the blocks marked done;
* ``checksums`` and the ``manifest`` attribute, written when the build
  finishes (:mod:`workbench.workspace.manifest`): the digests of every chunk,
  of the attributes and of every array's metadata, which :func:`open_map`
  checks (the chunks as they are read). The attributes follow a schema
  (:mod:`workbench.workspace.map_schema`), checked on every open.

A build writes ``MAP.zarr.partial`` and renames it ``MAP.zarr`` when every
block is done (:mod:`workbench.workspace.build`), so a folder named ``MAP.zarr``
is always a whole map. Chunks are compressed with Blosc LZ4 (bit shuffle), which
compresses and decompresses at memory speed; chunks that hold only the fill
value (NaN, 0: poses out of reach) are not written at all.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt
import zarr
import zarr.errors
from zarr.codecs import BloscCodec

from workbench.atomic_files import atomic_folder
from workbench.errors import InputError
from workbench.workspace._chunk_files import ChunkReader, ChunkWriter
from workbench.workspace.grid import PoseGrid
from workbench.workspace.manifest import MANIFEST, Manifest
from workbench.workspace.map_query import MapQuery, query_map
from workbench.workspace.map_schema import check_attributes
from workbench.workspace.orientations import rotations_from_quat_xyzw

#: What Zarr raises on chunks that cannot be read (truncated or corrupt files).
READ_ERRORS = (RuntimeError, ValueError, OSError, zarr.errors.BaseZarrError)


def damaged_array(group: zarr.Group, name: str, err: Exception) -> InputError:
    """The error for array ``name`` of a map whose chunks cannot be read."""
    message = " ".join(str(err).split()) or type(err).__name__
    return InputError(
        f"{group.store_path} is a damaged workspace map (array {name!r}: {message})"
    )


#: The ``format`` attribute of every map.
FORMAT = "workbench-workspace-map"
#: The layout version this module writes and reads (2: with a manifest).
FORMAT_VERSION = 2
#: The version of maps without a manifest, which ``verify --upgrade`` upgrades.
UNCHECKED_VERSION = 1
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
        low: Smallest value a map may hold (NaN aside).
        high: Largest value a map may hold (NaN aside).
    """

    dtype: str
    per_pose: bool
    units: str
    description: str
    low: float = 0.0
    high: float = math.inf

    @property
    def fill_value(self) -> float | int:
        """NaN for floats (no value), 0 for counts."""
        return float("nan") if self.dtype.startswith("float") else 0


#: Every data array a map may hold, by name (a map holds a subset: see
#: :func:`get_array_names`).
ARRAYS: dict[str, ArrayInfo] = {
    "reached": ArrayInfo(
        "uint8", True, "1", "closed-form branches that reach the pose (0..8)", high=8
    ),
    "branches": ArrayInfo(
        "uint8", True, "1", "branches reaching the pose within the joint limits", high=8
    ),
    "collision_free": ArrayInfo(
        "uint8", True, "1", "in-limit branches free of collision with the scene", high=8
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
        "float32", True, "1", "|e| elbow-singularity sine of the best branch", high=1
    ),
    "wrist": ArrayInfo(
        "float32", True, "1", "|w| wrist-singularity sine of the best branch", high=1
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
        low=-math.inf,  # within the map's redundancy range (checked by verify)
    ),
    "reachability": ArrayInfo(
        "float32", False, "1", "fraction of orientations with a usable branch", high=1
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
        high=1,
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
    (:class:`~workbench.workspace._chunk_files.ChunkWriter`): the blocks of
    a build are written by as many threads as compute them, not by Zarr's
    one I/O thread.

    Args:
        path: The map folder (being built).

    Raises:
        InputError: If ``path`` is not a map (:func:`open_group_checked`).
    """

    def __init__(self, path: str | Path):
        group = open_group_checked(path, mode="r+")
        self._arrays = {
            name: ChunkWriter(get_array(group, name)) for name in get_array_names(group)
        }
        self._done = ChunkWriter(get_array(group, DONE))

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


def read_done_flags(group: zarr.Group, array: zarr.Array) -> npt.NDArray[np.uint8]:
    """The ``done`` flags (n_blocks,) of a map, ``array`` its ``done`` array.

    One file per block, read here rather than through Zarr's event loop.

    Raises:
        InputError: If a flag's file cannot be read.
    """
    try:
        flags: npt.NDArray[np.uint8] = ChunkReader(array).read_all()
    except READ_ERRORS as err:
        raise damaged_array(group, DONE, err) from err
    return flags


def get_attributes(group: zarr.Group) -> dict[str, Any]:
    """The group attributes of a map, as a plain dict (a copy)."""
    attrs: dict[str, Any] = dict(group.attrs.asdict())
    return attrs


def open_group_checked(
    path: str | Path,
    *,
    mode: Literal["r", "r+"] = "r",
    versions: tuple[int, ...] = (FORMAT_VERSION,),
) -> zarr.Group:
    """The Zarr group of a map at ``path``, checked to be one of this format.

    :func:`open_arrays_checked` with only the group.
    """
    return open_arrays_checked(path, mode=mode, versions=versions)[0]


def open_arrays_checked(
    path: str | Path,
    *,
    mode: Literal["r", "r+"] = "r",
    versions: tuple[int, ...] = (FORMAT_VERSION,),
) -> tuple[zarr.Group, dict[str, zarr.Array]]:
    """The Zarr group of a map at ``path`` and its arrays, checked to be of this format.

    The arrays are opened once, together (Zarr opens each one through its
    event loop: a few milliseconds each).

    Args:
        path: The map folder (or a partial build).
        mode: ``"r"`` or ``"r+"``.
        versions: The format versions accepted.

    Raises:
        InputError: If ``path`` does not exist, is no Zarr v3 group, is not a
            workspace map, is of another format version, its attributes do
            not follow the schema (:func:`~.map_schema.check_attributes`), or
            it misses arrays.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"no workspace map at {path}: not found")
    if not (path / "zarr.json").is_file():
        raise InputError(f"{path} is not a workspace map (no Zarr v3 zarr.json in it)")
    try:
        _check_group_metadata(path / "zarr.json")  # before Zarr warns of it
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
    if isinstance(version, bool):
        version = repr(version)  # a JSON true is no version
    if version == UNCHECKED_VERSION and version not in versions:
        raise InputError(
            f"{path} is a workspace map of format version 1, written without "
            "checksums; 'workbench workspace verify --upgrade "
            f"{path}' checks every chunk and adds them"
        )
    if version not in versions:
        raise InputError(
            f"{path} is a workspace map of format version {version!r}; this "
            f"workbench reads version {FORMAT_VERSION}"
        )
    check_attributes(path, attrs)
    try:
        arrays = {name: array for name, array in group.arrays()}
    except (OSError, ValueError, KeyError, TypeError, zarr.errors.BaseZarrError) as err:
        message = " ".join(str(err).split()) or type(err).__name__
        raise InputError(f"{path} is a damaged workspace map ({message})") from err
    _check_arrays(path, arrays, attrs)
    return group, arrays


def _check_group_metadata(file: Path) -> None:
    """Raise ValueError unless ``file`` is the ``zarr.json`` of a Zarr v3 group."""
    metadata = json.loads(file.read_bytes())
    if not isinstance(metadata, dict):
        raise ValueError("zarr.json holds no object")
    if metadata.get("zarr_format") != 3 or metadata.get("node_type") != "group":
        raise ValueError(
            f"zarr.json is of zarr_format {metadata.get('zarr_format')!r} and "
            f"node_type {metadata.get('node_type')!r}, not a Zarr v3 group"
        )


def _check_arrays(
    path: Path, arrays: Mapping[str, zarr.Array], attrs: Mapping[str, Any]
) -> None:
    """Raise unless the grid, data and ``done`` arrays are there with their shapes."""
    try:
        names = set(arrays)
        shape = tuple(attrs["grid"]["shape"])
        voxels = int(np.prod(shape))
        orientations = int(attrs["orientation_set"]["count"])
    except (KeyError, TypeError, ValueError) as err:
        raise InputError(f"{path} is a damaged workspace map ({err!r})") from err
    block = int(attrs["block_voxels"])
    expected: dict[str, tuple[tuple[int, ...], str, tuple[int, ...]]] = {
        "positions": ((voxels, 3), "float64", (voxels, 3)),
        "orientations": ((orientations, 4), "float64", (orientations, 4)),
    }
    for name in sorted(names & set(ARRAYS)):
        info = ARRAYS[name]
        per_pose = (voxels, orientations)
        array_shape = per_pose if info.per_pose else (voxels,)
        chunking = (block, orientations) if info.per_pose else (block,)
        expected[name] = (array_shape, info.dtype, chunking)
    for name, (size, dtype, chunks) in expected.items():
        if name not in names:
            raise InputError(f"{path} is a damaged workspace map (no array {name!r})")
        array = arrays[name]
        if array.shape != size or str(array.dtype) != dtype or array.chunks != chunks:
            raise InputError(
                f"{path} is a damaged workspace map (array {name!r} is "
                f"{array.shape} {array.dtype} in chunks of {array.chunks}, expected "
                f"{size} {dtype} in chunks of {chunks})"
            )
    if DONE not in names:
        raise InputError(f"{path} is a damaged workspace map (no array 'done')")


def get_array_names(group: zarr.Group | Mapping[str, zarr.Array]) -> list[str]:
    """The data arrays a map holds, in the order of :data:`ARRAYS`.

    Args:
        group: The map's group, or its arrays by name.
    """
    present = set(group if isinstance(group, Mapping) else group.array_keys())
    return [name for name in ARRAYS if name in present]


def read_grid(
    group: zarr.Group, read: Callable[[str], npt.NDArray[Any]] | None = None
) -> PoseGrid:
    """The pose grid stored in a map (bitwise the one it was built on).

    Args:
        group: The map's group.
        read: Reads ``positions`` or ``orientations`` (a finished map's
            :meth:`Manifest.read_single`, checked); default Zarr's reading.
    """
    attrs = get_attributes(group)
    grid = attrs["grid"]
    if read is None:
        read = functools.partial(read_array, group)
    orientations = _read_only(read("orientations"))
    return PoseGrid(
        positions=_read_only(read("positions")),
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
    NumPy array (V, O). Keep it if you use it twice. Every chunk read is
    checked against the map's manifest (:mod:`workbench.workspace.manifest`).

    Attributes:
        path: The map folder.
        attrs: The group attributes (a copy; ``docs/workspace.md``).
        names: The data arrays it holds (keys of :data:`ARRAYS`).
    """

    def __init__(self, path: Path, group: zarr.Group, manifest: Manifest):
        self.path = path
        self._group = group
        self._manifest = manifest
        self.attrs = get_attributes(group)
        self.names: tuple[str, ...] = manifest.names

    def __repr__(self) -> str:
        return f"WorkspaceMap({str(self.path)!r}, robot={self.attrs['robot']!r})"

    @cached_property
    def grid(self) -> PoseGrid:
        """The pose grid of the map."""
        return read_grid(self._group, self._manifest.read_single)

    @property
    def sampled(self) -> bool:
        """Whether the map was sampled (no closed form)."""
        return bool(self.attrs["sampled"])

    def __contains__(self, name: object) -> bool:
        return name in self.names

    def __getitem__(self, name: str) -> npt.NDArray[Any]:
        """Array ``name`` (a data array, ``positions``, ``orientations``, ``done``).

        Raises:
            InputError: If the map has no such array, or a chunk of it is
                damaged.
        """
        if name in self.names:
            return self._manifest.read_array(name)
        if name in GRID_ARRAYS:
            return self._manifest.read_single(name)
        if name == DONE:
            return read_done_flags(self._group, self._manifest.arrays[DONE])
        raise InputError(
            f"the map {self.path} has no array {name!r}; it has {', '.join(self.names)}"
        )

    def query(self, poses: npt.ArrayLike) -> MapQuery:
        """The map at the grid poses nearest to ``poses`` (N, 4, 4) or (N, 7).

        See :func:`~workbench.workspace.map_query.query_map`.
        """
        return query_map(self._manifest.gather, self.names, self.grid, poses)


def open_map(path: str | Path) -> WorkspaceMap:
    """Open a finished workspace map for reading.

    Checks its format, its attributes against the schema and the manifest,
    every array's metadata and the chunk digests (the chunks themselves are
    checked when read).

    Raises:
        InputError: If ``path`` is missing, not a workspace map, of another
            format version (of version 1: upgrade it with ``workbench
            workspace verify --upgrade``), damaged or edited, an unfinished
            build (a ``.partial`` folder, or blocks not done).
    """
    path = Path(path)
    group, arrays = open_arrays_checked(path, mode="r")
    attrs = get_attributes(group)
    done = read_done_flags(group, arrays[DONE])
    finished = not path.name.endswith(PARTIAL_SUFFIX) and MANIFEST in attrs
    if not finished or not np.all(done == 1):
        if finished:
            missing = np.flatnonzero(done != 1)
            raise InputError(
                f"{path} is a damaged workspace map (done flags lost: "
                f"{missing.size} of {done.size} blocks, the first block {missing[0]})"
            )
        raise InputError(
            f"{path} is an unfinished map build ({int(np.sum(done == 1))} of "
            f"{done.size} blocks done); run the command that started it again to "
            "finish it"
        )
    manifest = Manifest(path, arrays, attrs, get_array_names(arrays))
    return WorkspaceMap(path, group, manifest)
