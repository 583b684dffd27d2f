"""Write files and folders all at once: a temporary sibling, renamed on success.

Every file the workbench writes goes through :func:`atomic_file` (or
:func:`atomic_files` for a set, :func:`write_text_atomic` for text): the data go
to a hidden temporary file in the target's folder
(``.<stem>.<pid>-<random>.tmp<suffix>``), which is flushed to disk (``fsync``)
and renamed onto the target only when the writer returned. A failed or
interrupted run leaves an existing output byte-identical; only a ``kill -9`` in
the middle may leave a temporary file behind (never the target half-written),
which the next write of that target removes (its process is gone). Commands
call :func:`check_outputs` before any work, so a bad output path fails at once.
"""

from __future__ import annotations

import contextlib
import glob
import os
import re
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from workbench.errors import InputError

#: Suffix of the temporary files (``.<name>.<random>`` + this + the suffix).
TEMP_MARK = ".tmp"
#: Bytes of a file name kept for what a write adds to it: the temporary file's
#: ``.<pid>-<random>.tmp`` (twice when nested), a map's ``.partial`` and lock.
TEMP_NAME_ROOM = 64


def check_output(
    path: str | Path, *, folder: bool = False, inputs: Iterable[str | Path | None] = ()
) -> None:
    """Raise a clear error if ``path`` cannot be written.

    Args:
        path: The file (or new folder) to write.
        folder: Whether ``path`` is a new folder (bags are never replaced).
        inputs: Files the command reads (None entries are skipped): ``path``
            must be none of them.

    Raises:
        InputError: If the parent folder is missing or not writable, ``path`` is
            a folder (for a file), already exists (for a folder), or is one of
            ``inputs`` or inside one of them (an input folder, e.g. a map);
            if its name is longer than the file system allows (less
            :data:`TEMP_NAME_ROOM`), or a path is a symbolic-link loop.
    """
    path = Path(path)
    parent = path.parent
    _check_name_length(path)
    if not parent.is_dir():
        raise InputError(f"cannot write {path}: folder {parent} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"cannot write {path}: folder {parent} is not writable")
    if folder and (path.exists() or path.is_symlink()):
        raise InputError(f"cannot write {path}: it already exists")
    if not folder and path.is_dir():
        raise InputError(f"cannot write {path}: it is a folder")
    for source in inputs:
        if source is not None and is_same_file(path, source):
            raise InputError(f"cannot write {path}: it is also an input ({source})")
        if source is not None and Path(source).is_dir():
            if _resolve(source) in _resolve(path).parents:
                raise InputError(
                    f"cannot write {path}: it is inside the input folder {source}"
                )


def check_outputs(
    outputs: Iterable[str | Path | None], inputs: Iterable[str | Path | None] = ()
) -> None:
    """:func:`check_output` for every output file; no two may be the same file.

    Args:
        outputs: Files to write (None entries are skipped).
        inputs: Files the command reads (None entries are skipped).

    Raises:
        InputError: As :func:`check_output`, or if two outputs are one file.
    """
    sources = [Path(p) for p in inputs if p is not None]
    seen: list[Path] = []
    for out in (Path(p) for p in outputs if p is not None):
        check_output(out, inputs=sources)
        for other in seen:
            if is_same_file(out, other):
                raise InputError(f"cannot write {out} twice (also given as {other})")
        seen.append(out)


def is_same_file(a: str | Path, b: str | Path) -> bool:
    """Whether two paths name one file (``samefile`` if both exist, else resolved).

    Raises:
        InputError: If a path cannot be resolved (a symbolic-link loop).
    """
    a, b = Path(a), Path(b)
    try:
        return a.samefile(b)
    except OSError:  # one of them does not exist (yet)
        return _resolve(a) == _resolve(b)


def _resolve(path: str | Path) -> Path:
    """``path`` resolved (symbolic links followed), as far as it exists.

    Raises:
        InputError: On a symbolic-link loop or a name the system refuses.
    """
    try:
        return Path(path).resolve()
    except RuntimeError as err:  # Python 3.11: "Symlink loop from ..."
        raise InputError(f"cannot use {path}: a symbolic-link loop") from err
    except OSError as err:
        raise InputError(f"cannot use {path}: {err.strerror or err}") from err


def _check_name_length(path: Path) -> None:
    """Refuse a name longer than the file system takes, less :data:`TEMP_NAME_ROOM`.

    Raises:
        InputError: Stating the name's length and the limit.
    """
    try:
        limit = os.pathconf(path.parent if path.parent.is_dir() else ".", "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):
        limit = 255  # the common limit (ext4, XFS, APFS, NTFS)
    size = len(os.fsencode(path.name))
    if size > limit - TEMP_NAME_ROOM:
        raise InputError(
            f"cannot write {path.name[:40]}…: its name is {size} bytes, at most "
            f"{limit - TEMP_NAME_ROOM} here (the file system takes {limit}, less "
            f"{TEMP_NAME_ROOM} for the temporary file's name)"
        )


@contextlib.contextmanager
def atomic_files(*paths: str | Path) -> Iterator[list[Path]]:
    """Yield one temporary file per path; all replace their targets on success.

    The temporary files are in the targets' folders and have the targets'
    suffixes (writers such as Matplotlib pick the format from it). When the
    block raises (or is interrupted), they are removed and no target changes.

    Raises:
        InputError: If a target cannot be written (see :func:`check_output`),
            or writing fails (disk full, read-only file system).
    """
    targets = [Path(p) for p in paths]
    temps: list[Path] = []
    try:
        for path in targets:
            check_output(path)
            remove_stale_temporaries(path)
            handle, name = tempfile.mkstemp(
                dir=path.parent,
                prefix=f".{path.stem}.{os.getpid()}-",
                suffix=f"{TEMP_MARK}{path.suffix}",
            )
            os.close(handle)
            temps.append(Path(name))
        yield temps
        mask = os.umask(0)  # mkstemp makes 0600 files: give the usual mode
        os.umask(mask)
        for tmp in temps:
            _sync(tmp)
            tmp.chmod(0o666 & ~mask)
        for tmp, path in zip(temps, targets, strict=True):
            tmp.replace(path)
        for folder in {path.parent for path in targets}:
            _sync_folder(folder)
    except OSError as err:
        where = err.filename or ", ".join(map(str, targets))
        raise InputError(f"cannot write {where}: {err.strerror or err}") from err
    finally:
        for tmp in temps:
            tmp.unlink(missing_ok=True)


@contextlib.contextmanager
def atomic_file(path: str | Path) -> Iterator[Path]:
    """Yield a temporary file next to ``path``; it replaces ``path`` on success.

    On an exception the temporary file is removed and ``path`` is untouched.

    Raises:
        InputError: If the folder does not exist or ``path`` is a folder, or
            writing fails.
    """
    with atomic_files(path) as (tmp,):
        yield tmp


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` all at once; returns ``path``.

    Raises:
        InputError: As :func:`atomic_file`.
    """
    with atomic_file(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


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
        move_folder_into_place(tmp, path)
    finally:
        shutil.rmtree(parent, ignore_errors=True)


def move_folder_into_place(folder: str | Path, path: str | Path) -> None:
    """Flush every file of ``folder`` to disk, then rename ``folder`` to ``path``.

    The rename is atomic: ``path`` appears whole or not at all. Both must be
    on one file system; ``path`` must not exist (or be an empty folder).

    Raises:
        OSError: If a file cannot be flushed or the rename fails.
    """
    folder, path = Path(folder), Path(path)
    for file in folder.rglob("*"):
        if file.is_file():
            _sync(file)
    folder.rename(path)
    _sync_folder(path.parent)


def get_temporaries(path: str | Path) -> list[tuple[Path, int]]:
    """The temporary files of ``path`` in its folder, with their writers' PIDs.

    Nested ones too: a writer given a temporary file as its target (``plan
    --plot`` hands Matplotlib's writer the plot's temporary file) makes a
    temporary file of that one, ``..<stem>.<pid>-<r>.tmp.<pid>-<s>.tmp<suffix>``;
    its PID is the innermost writer's.
    """
    path = Path(path)
    level = re.escape(".") + r"(\d+)-[^.]+" + re.escape(TEMP_MARK)
    pattern = re.compile(
        r"(\.+)" + re.escape(path.stem) + f"((?:{level})+)" + re.escape(path.suffix)
    )
    found = []
    for entry in path.parent.glob(f".*{glob.escape(path.stem)}.*{TEMP_MARK}*"):
        match = pattern.fullmatch(entry.name)
        if match is None:
            continue
        pids = re.findall(level, match.group(2))
        if len(pids) == len(match.group(1)):  # one leading dot per level
            found.append((entry, int(pids[-1])))
    return found


def remove_stale_temporaries(path: str | Path) -> None:
    """Remove temporary files of ``path`` whose writing process is gone (kill -9)."""
    for entry, pid in get_temporaries(path):
        if pid != os.getpid() and not _is_running(pid):
            entry.unlink(missing_ok=True)


def remove_temporaries_of_process(folder: str | Path, pid: int) -> None:
    """Remove the temporary files process ``pid`` has in ``folder`` (its exit)."""
    for entry in Path(folder).glob(f".*.{pid}-*{TEMP_MARK}*"):
        entry.unlink(missing_ok=True)


def _is_running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):  # another user's process, or no kill()
        return True
    return True


def _sync(path: Path) -> None:
    """Flush a written file to disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _sync_folder(folder: Path) -> None:
    """Flush a folder's entries (the rename) to disk, where folders can be opened."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # e.g. Windows
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
