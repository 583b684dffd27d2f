"""The manifest of a finished map: digests of its attributes, metadata and chunks.

When a build finishes (:func:`write_manifest`, before the partial folder is
renamed onto the map), every chunk file of every data array is digested
(BLAKE2b-64 of the file's bytes, :func:`~._chunk_files.chunk_digest`; 0 for
a chunk not stored because it holds only the fill value) into the array
``checksums`` (n_chunks, n_arrays, 2) uint64 with the size of each file
[bytes] (0 and 0: not stored), and the group attribute
``manifest`` records:

* ``algorithm``: ``"blake2b-64"``;
* ``arrays``: the data arrays, in the order of the columns of ``checksums``;
* ``attributes``: the digest of each other group attribute (its JSON, keys
  sorted);
* ``metadata``: the digest of each array's ``zarr.json`` (its JSON, keys
  sorted): shapes, chunks, codecs, fill values;
* ``chunks``: the digests of the one chunk of ``positions``,
  ``orientations`` and ``checksums``.

:class:`Manifest` checks the attributes, the metadata and ``checksums``
when a map is opened (small files), and that every chunk file is there with
its size (one ``stat`` each), and every chunk a reader touches when it is
read (:meth:`Manifest.read_chunk`): a chunk file missing where a
digest is recorded, present where none is, of other bytes, or that does not
decode is damage, reported in one line naming the array and the chunk. A
missing chunk of a finished map is never read as "unreached".
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import zarr

from workbench.errors import InputError
from workbench.workspace._chunk_files import NOT_STORED, ChunkReader, chunk_digest

#: The group attribute holding the manifest.
MANIFEST = "manifest"
#: The array of chunk digests and sizes, (n_chunks, n_arrays, 2) uint64.
CHECKSUMS = "checksums"
#: The digest of every entry of the manifest.
ALGORITHM = "blake2b-64"
#: The arrays of one chunk each whose digests the manifest holds itself.
SINGLE_CHUNK_ARRAYS = ("positions", "orientations", CHECKSUMS)
#: What the decoding of a chunk raises on bytes that are not one.
DECODE_ERRORS = (RuntimeError, ValueError, TypeError, OverflowError, MemoryError)


def damaged(path: Path, what: str) -> InputError:
    """The one-line error for damage ``what`` of the map at ``path``."""
    return InputError(f"{path} is a damaged workspace map ({what})")


def _canonical(value: Any) -> bytes:
    """``value`` as JSON with sorted keys and no spaces (NaN written as NaN)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":")).encode()


def _hex(digest: int) -> str:
    return f"{digest:016x}"


def _digest_of(value: Any) -> str:
    return _hex(chunk_digest(_canonical(value)))


def _metadata_digest(array: zarr.Array) -> str | None:
    """The digest of ``array``'s ``zarr.json``; None if unreadable."""
    store, key = array.store_path.store, array.store_path.path
    file = Path(store.root) / key / "zarr.json"  # type: ignore[attr-defined]
    try:
        return _digest_of(json.loads(file.read_bytes()))
    except (OSError, ValueError):
        return None


def _attribute_digests(attrs: Mapping[str, Any]) -> dict[str, str]:
    return {key: _digest_of(attrs[key]) for key in sorted(attrs) if key != MANIFEST}


def _single_chunk_digest(array: zarr.Array) -> str | None:
    data = ChunkReader(array).read_bytes(0)
    return None if data is None else _hex(chunk_digest(data))


def write_manifest(
    group: zarr.Group,
    names: Sequence[str],
    attributes: Mapping[str, Any] | None = None,
) -> None:
    """Digest every chunk of a finished build and write ``checksums`` and ``manifest``.

    Args:
        group: The map's group, opened ``r+`` (the partial folder, every
            block done).
        names: Its data arrays, every one chunked alike along the voxels.
        attributes: Group attributes to set with the manifest (in the same
            write of the group's ``zarr.json``).
    """
    arrays = {name: array for name, array in group.arrays() if name != CHECKSUMS}
    readers = [ChunkReader(arrays[name]) for name in names]
    count = max((reader.count for reader in readers), default=0)
    table = np.zeros((count, len(names), 2), dtype=np.uint64)
    for column, reader in enumerate(readers):
        for index in range(reader.count):
            data = reader.read_bytes(index)
            if data is not None:
                table[index, column] = chunk_digest(data), len(data)
    if CHECKSUMS in group:
        del group[CHECKSUMS]
    arrays[CHECKSUMS] = group.create_array(
        CHECKSUMS,
        shape=table.shape,
        chunks=table.shape,
        dtype="uint64",
        fill_value=0,
        compressors=None,
        attributes={
            "description": f"of each chunk file (rows) of each data array (columns: "
            f"the manifest's arrays): its {ALGORITHM} digest and its size [bytes]; "
            "0 and 0 where not stored"
        },
    )
    arrays[CHECKSUMS][...] = table
    attrs = dict(group.attrs.asdict()) | dict(attributes or {})
    manifest: dict[str, Any] = {
        "algorithm": ALGORITHM,
        "arrays": list(names),
        "attributes": _attribute_digests(attrs),
        "metadata": {name: _metadata_digest(arrays[name]) for name in sorted(arrays)},
        "chunks": {
            name: _single_chunk_digest(arrays[name]) for name in SINGLE_CHUNK_ARRAYS
        },
    }
    group.attrs.update(dict(attributes or {}) | {MANIFEST: manifest})


class Manifest:
    """The manifest of a finished map, checked against what the map holds.

    Opening checks the attributes, every array's metadata and the
    ``checksums`` table; the chunks are checked as they are read.

    Args:
        path: The map folder (for messages).
        arrays: Its arrays by name (every array of the group).
        attrs: Its attributes.
        names: Its data arrays (in the order of :data:`~.store.ARRAYS`).

    Attributes:
        arrays: The map's arrays by name.
        names: Its data arrays.

    Raises:
        InputError: If the manifest is missing or malformed, or an
            attribute, an array's metadata or ``checksums`` differ from it,
            or a chunk file is missing, unexpected or of another size.
    """

    def __init__(
        self,
        path: Path,
        arrays: Mapping[str, zarr.Array],
        attrs: Mapping[str, Any],
        names: Sequence[str],
    ):
        self.path, self.arrays = path, dict(arrays)
        manifest = attrs.get(MANIFEST)
        if not isinstance(manifest, Mapping):
            raise self.damaged("no manifest: it was not finished by a build")
        if manifest.get("algorithm") != ALGORITHM:
            raise self.damaged(
                f"manifest algorithm {manifest.get('algorithm')!r}, not {ALGORITHM!r}"
            )
        if manifest.get("arrays") != list(names):
            raise self.damaged(
                f"its data arrays {list(names)} are not those of its manifest "
                f"{manifest.get('arrays')}"
            )
        self.names: tuple[str, ...] = tuple(names)
        self._check_attributes(attrs, manifest.get("attributes"))
        self._check_metadata(manifest.get("metadata"))
        chunks = manifest.get("chunks")
        self._single: dict[str, Any] = (
            dict(chunks) if isinstance(chunks, Mapping) else {}
        )
        self._readers = {
            name: ChunkReader(self.arrays[name])
            for name in (*names, *SINGLE_CHUNK_ARRAYS)
            if name in self.arrays
        }
        counts = {self._readers[name].count for name in names}
        table = self.read_single(CHECKSUMS).astype(np.uint64)
        if table.shape != (max(counts, default=0), len(names), 2):
            raise self.damaged(f"array 'checksums' has shape {table.shape}")
        self._table = table
        for name in names:
            self._check_files(name)

    def _check_files(self, name: str) -> None:
        """Raise unless each chunk file of ``name`` is there with its recorded size.

        One ``stat`` per chunk: what a reader does not touch is checked too,
        for a file deleted, added, truncated or extended.
        """
        reader, column = self._readers[name], self.names.index(name)
        for index in range(reader.count):
            digest, size = (int(v) for v in self._table[index, column])
            try:
                found: int | None = reader.path(index).stat().st_size
            except FileNotFoundError:
                found = None
            where = f"array {name!r}, chunk {index}"
            if found is None and digest != NOT_STORED:
                raise self.damaged(f"{where}: the chunk file is missing")
            if found is not None and digest == NOT_STORED:
                raise self.damaged(
                    f"{where}: a chunk file is there where the map recorded none"
                )
            if found is not None and found != size:
                raise self.damaged(
                    f"{where}: the chunk file was changed ({found} bytes, "
                    f"written {size})"
                )

    def damaged(self, what: str) -> InputError:
        """The one-line error for damage ``what`` of this map."""
        return damaged(self.path, what)

    def _check_attributes(self, attrs: Mapping[str, Any], recorded: Any) -> None:
        if not isinstance(recorded, Mapping):
            raise self.damaged("the manifest has no attribute digests")
        found = _attribute_digests(attrs)
        for key in sorted(set(found) | set(recorded)):
            if key not in found:
                raise self.damaged(f"attribute {key!r} is missing")
            if found[key] != recorded.get(key):
                what = "added" if key not in recorded else "changed"
                raise self.damaged(
                    f"attribute {key!r} was {what} after the map was written"
                )

    def _check_metadata(self, recorded: Any) -> None:
        if not isinstance(recorded, Mapping):
            raise self.damaged("the manifest has no metadata digests")
        for name in sorted(set(self.arrays) | set(recorded)):
            if name not in self.arrays:
                raise self.damaged(f"no array {name!r}")
            if name not in recorded:
                raise self.damaged(f"array {name!r} was added after it was written")
            if _metadata_digest(self.arrays[name]) != recorded[name]:
                raise self.damaged(
                    f"the metadata (zarr.json) of array {name!r} was changed after "
                    "the map was written"
                )

    @property
    def chunk_count(self) -> int:
        """Chunks of each data array."""
        return int(self._table.shape[0])

    def expected(self, name: str, index: int) -> int:
        """The digest recorded for chunk ``index`` of data array ``name``."""
        return int(self._table[index, self.names.index(name), 0])

    def stored_size(self, name: str, index: int) -> int | None:
        """The size [bytes] recorded for that chunk's file; None: not stored."""
        if self.expected(name, index) == NOT_STORED:
            return None
        return int(self._table[index, self.names.index(name), 1])

    def read_single(self, name: str) -> npt.NDArray[Any]:
        """The whole of ``positions``, ``orientations`` or ``checksums``, checked."""
        return self._checked(name, self._readers[name], 0, self._single.get(name))

    def read_chunk(self, name: str, index: int) -> npt.NDArray[Any]:
        """Chunk ``index`` of data array ``name`` (its rows), checked.

        Raises:
            InputError: If the chunk file is missing, unexpected, of other
                bytes than recorded, or does not decode.
        """
        expected = self.expected(name, index)
        return self._checked(
            name,
            self._readers[name],
            index,
            None if expected == NOT_STORED else _hex(expected),
        )

    def _checked(
        self, name: str, reader: ChunkReader, index: int, expected: str | None
    ) -> npt.NDArray[Any]:
        data = reader.read_bytes(index)
        where = f"array {name!r}, chunk {index}"
        if data is None and expected is not None:
            raise self.damaged(f"{where}: the chunk file is missing")
        if data is not None and expected is None:
            raise self.damaged(
                f"{where}: a chunk file is there where the map recorded none"
            )
        if data is not None and _hex(chunk_digest(data)) != expected:
            raise self.damaged(f"{where}: the chunk file was changed (checksum)")
        try:
            return reader.decode(data, index)
        except DECODE_ERRORS as err:
            message = " ".join(str(err).split()) or type(err).__name__
            raise self.damaged(f"{where}: {message}") from None

    def read_array(self, name: str) -> npt.NDArray[Any]:
        """The whole data array ``name``, every chunk checked."""
        reader = self._readers[name]
        out = np.empty(reader.array.shape, dtype=reader.array.dtype)
        for index in range(reader.count):
            out[reader.rows(index)] = self.read_chunk(name, index)
        return out

    def gather(
        self, name: str, rows: npt.NDArray[np.int64], cols: npt.NDArray[np.int64] | None
    ) -> npt.NDArray[Any]:
        """``array[rows, cols]`` (or ``array[rows]``) of data array ``name``.

        Reads and checks only the chunks holding ``rows``.
        """
        reader = self._readers[name]
        out = np.empty(len(rows), dtype=reader.array.dtype)
        chunk = rows // reader.length
        order = np.argsort(chunk, kind="stable")
        bounds = np.searchsorted(chunk[order], np.arange(reader.count + 1))
        for index in np.flatnonzero(np.diff(bounds)):
            picked = order[bounds[index] : bounds[index + 1]]
            values = self.read_chunk(name, int(index))
            local = rows[picked] - int(index) * reader.length
            out[picked] = values[local] if cols is None else values[local, cols[picked]]
        return out
