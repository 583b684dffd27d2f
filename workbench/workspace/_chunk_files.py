"""The chunk files of a map's arrays, written and read without Zarr's event loop.

A map is a folder (a Zarr ``LocalStore``); each chunk of an array is one file
``ARRAY/c/i/j``, the chunk's values through the array's codecs (bytes, then
Blosc). :class:`ChunkWriter` stores a whole chunk the way Zarr's own
``array[rows] = values`` does, bitwise; :class:`ChunkReader` reads a chunk
file's bytes (whose digest, :func:`chunk_digest`, the map's manifest holds)
and decodes them. Both run in the calling thread: Zarr's ``getitem`` and
``setitem`` send every chunk through its single I/O event-loop thread.
"""

from __future__ import annotations

import hashlib
import os
import uuid
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import zarr
import zarr.storage
from zarr.abc.codec import ArrayArrayCodec, SupportsSyncCodec
from zarr.core.buffer import default_buffer_prototype

#: Bytes of a chunk digest (BLAKE2b), stored as one uint64.
DIGEST_BYTES = 8
#: The digest recorded for a chunk that is not stored (it holds only the fill value).
NOT_STORED = 0


def chunk_digest(data: bytes | memoryview) -> int:
    """The digest of a chunk file's bytes: BLAKE2b-64 as a uint64, never 0.

    0 is :data:`NOT_STORED`; the one digest in 2⁶⁴ that is 0 is recorded as 1.
    """
    value = int.from_bytes(
        hashlib.blake2b(data, digest_size=DIGEST_BYTES).digest(), "little"
    )
    return value or 1


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


class _ChunkFiles:
    """Where the chunk files of one array are, and its codecs.

    ``folder`` is None where the array's store is not a local folder, or a
    codec has no synchronous path (then the callers go through Zarr).
    """

    def __init__(self, array: zarr.Array):
        self.array = array
        metadata = array.metadata
        store = array.store_path.store
        codecs = getattr(metadata, "codecs", ())
        self.folder: Path | None = None
        if (
            isinstance(store, zarr.storage.LocalStore)
            and codecs
            and all(isinstance(codec, SupportsSyncCodec) for codec in codecs)
            and not any(isinstance(codec, ArrayArrayCodec) for codec in codecs)
        ):
            self.folder = Path(store.root) / array.store_path.path
        self.codecs = codecs
        self.length: int = array.chunks[0]
        self.spec = metadata.get_chunk_spec(
            (0,) * array.ndim, array.async_array.config, default_buffer_prototype()
        )

    @property
    def count(self) -> int:
        """Chunks along the first axis (the only chunked one)."""
        return -(-self.array.shape[0] // self.length) if self.array.shape[0] else 0

    def path(self, index: int) -> Path:
        """The file of chunk ``index`` (along the first axis)."""
        if self.folder is None:
            raise ValueError("the array is not stored in a local folder")
        coords = (index,) + (0,) * (self.array.ndim - 1)
        return self.folder / self.array.metadata.encode_chunk_key(coords)

    def rows(self, index: int) -> slice:
        """The rows of the array that chunk ``index`` holds."""
        start = index * self.length
        return slice(start, min(start + self.length, self.array.shape[0]))


class ChunkWriter(_ChunkFiles):
    """Writes whole chunks of one array in the calling thread.

    What Zarr's ``array[start:stop] = values`` stores for a selection that is
    one whole chunk (the last one padded with the fill value; nothing, and
    any older file removed, for a chunk of fill values only), bitwise: the
    chunk goes through the array's own codecs (their synchronous
    ``_encode_sync``) and is written like Zarr's local store does
    (``NAME.<uuid4 hex>.partial``, then renamed), and flushed to disk
    first, so that a block's ``done`` flag never outlives its data in a
    crash (and the final flush of the map finds little left). Arrays whose
    store or codecs do not allow it (another store, an asynchronous-only
    codec) are written through Zarr.

    Args:
        array: A Zarr v3 array chunked along its first axis only.
    """

    def write(self, start: int, values: np.ndarray) -> None:
        """Store ``values`` at rows ``start:`` (one whole chunk, or the last)."""
        array, length = self.array, self.length
        if start % length or len(values) > length:
            raise ValueError(f"rows {start}:+{len(values)} are not one chunk")
        if self.folder is None:
            array[start : start + len(values)] = values
            return
        spec = self.spec
        chunk = np.asarray(values, dtype=array.dtype)
        if chunk.shape != spec.shape:  # the last chunk, cut by the array's end
            padded = np.full(spec.shape, spec.fill_value, dtype=array.dtype)
            padded[: len(chunk)] = chunk
            chunk = padded
        path = self.path(start // length)
        encoded: Any = spec.prototype.nd_buffer.from_numpy_array(
            np.ascontiguousarray(chunk)
        )
        if not spec.config.write_empty_chunks and _only_fill(chunk, spec.fill_value):
            path.unlink(missing_ok=True)
            return
        for codec in self.codecs:
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


class ChunkReader(_ChunkFiles):
    """Reads the chunk files of one array stored in a local folder.

    Args:
        array: A Zarr v3 array chunked along its first axis only, in a local
            folder, with synchronous codecs (every array of a map).

    Raises:
        ValueError: If the array is stored otherwise.
    """

    def __init__(self, array: zarr.Array):
        super().__init__(array)
        if self.folder is None:
            raise ValueError("the array is not stored in a local folder")

    def read_bytes(self, index: int) -> bytes | None:
        """The bytes of chunk ``index``'s file; None where there is no file."""
        try:
            return self.path(index).read_bytes()
        except FileNotFoundError:
            return None

    def decode(self, data: bytes | None, index: int) -> npt.NDArray[Any]:
        """The values of chunk ``index`` (its rows of the array) from its bytes.

        ``data`` None is a chunk not stored: the fill value.

        Raises:
            RuntimeError, ValueError: If the bytes do not decode to the chunk
                (Blosc's and Zarr's errors).
        """
        spec, rows = self.spec, self.rows(index)
        if data is None:
            values = np.full(spec.shape, spec.fill_value, dtype=self.array.dtype)
        else:
            buffer: Any = spec.prototype.buffer.from_bytes(data)
            for codec in reversed(self.codecs):
                buffer = codec._decode_sync(buffer, spec)
            values = buffer.as_numpy_array()
            if values.shape != spec.shape:
                raise ValueError(
                    f"chunk {index} decodes to shape {values.shape}, not {spec.shape}"
                )
        return values[: rows.stop - rows.start]

    def read_all(self) -> npt.NDArray[Any]:
        """The whole array, chunk by chunk (unchecked: see the manifest's reader).

        Raises:
            RuntimeError, ValueError: If a chunk does not decode.
        """
        out = np.empty(self.array.shape, dtype=self.array.dtype)
        for index in range(self.count):
            out[self.rows(index)] = self.decode(self.read_bytes(index), index)
        return out
