"""Write files and folders all at once: a temporary sibling, renamed on success."""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from workbench.errors import InputError


def check_output(path: Path, *, folder: bool = False) -> None:
    """Raise a clear error if ``path`` cannot be written.

    Raises:
        InputError: If the parent folder is missing, ``path`` is a folder (for
            a file), or already exists (for a folder: bags are never replaced).
    """
    if not path.parent.resolve().is_dir():
        raise InputError(f"cannot write {path}: folder {path.parent} does not exist")
    if folder and path.exists():
        raise InputError(f"cannot write {path}: it already exists")
    if not folder and path.is_dir():
        raise InputError(f"cannot write {path}: it is a folder")


@contextlib.contextmanager
def atomic_file(path: str | Path) -> Iterator[Path]:
    """Yield a temporary file next to ``path``; it replaces ``path`` on success.

    On an exception the temporary file is removed and ``path`` is untouched.

    Raises:
        InputError: If the folder does not exist or ``path`` is a folder.
    """
    path = Path(path)
    check_output(path)
    handle, name = tempfile.mkstemp(  # same suffix: writers may check it
        dir=path.parent, prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}"
    )
    os.close(handle)
    tmp = Path(name)
    try:
        yield tmp
        mask = os.umask(0)  # mkstemp makes 0600 files: give the usual mode
        os.umask(mask)
        tmp.chmod(0o666 & ~mask)
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)


@contextlib.contextmanager
def atomic_folder(path: str | Path) -> Iterator[Path]:
    """Yield a path for a new folder next to ``path``; renamed onto it on success.

    The yielded path does not exist yet (writers such as rosbags create it).

    Raises:
        InputError: If the parent is missing or ``path`` already exists.
    """
    path = Path(path)
    check_output(path, folder=True)
    parent = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}."))
    tmp = parent / path.name
    try:
        yield tmp
        tmp.rename(path)
    finally:
        shutil.rmtree(parent, ignore_errors=True)
