"""Files written all at once: checks before work, old files kept, no leftovers."""

from __future__ import annotations

import errno
import os
import subprocess
import sys
from pathlib import Path

import pytest

from workbench.atomic_files import (
    atomic_files,
    check_outputs,
    get_temporaries,
    remove_stale_temporaries,
    write_text_atomic,
)
from workbench.errors import InputError


def test_a_set_is_written_together_or_not_at_all(tmp_path: Path) -> None:
    a, b = tmp_path / "a.csv", tmp_path / "b.png"
    a.write_text("old a")
    with pytest.raises(RuntimeError), atomic_files(a, b) as (ta, tb):
        ta.write_text("new a")
        assert tb.suffix == ".png" and tb.parent == tmp_path
        raise RuntimeError("the second writer fails")
    assert a.read_text() == "old a" and sorted(tmp_path.iterdir()) == [a]
    with atomic_files(a, b) as (ta, tb):
        ta.write_text("new a")
        tb.write_text("new b")
    assert (a.read_text(), b.read_text()) == ("new a", "new b")
    assert oct(a.stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@pytest.mark.parametrize(
    ("outputs", "inputs", "fragment"),
    [
        (["nodir/x.csv"], [], "does not exist"),
        (["."], [], "is a folder"),
        (["in.json"], ["in.json"], "also an input"),
        (["./sub/../in.json"], ["in.json"], "also an input"),
        (["x.csv", "./x.csv"], [], "twice"),
    ],
)
def test_outputs_are_checked_first(
    tmp_path: Path, monkeypatch, outputs: list[str], inputs: list[str], fragment: str
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "in.json").write_text("{}")
    (tmp_path / "sub").mkdir()
    with pytest.raises(InputError, match=fragment):
        check_outputs(outputs, inputs)


def test_a_write_failure_is_an_input_error(tmp_path: Path) -> None:
    target = tmp_path / "x.txt"
    target.write_text("old")
    with pytest.raises(InputError, match="No space left"), atomic_files(target) as (t,):
        t.write_text("partial")
        raise OSError(errno.ENOSPC, "No space left on device", str(target))
    assert target.read_text() == "old" and sorted(tmp_path.iterdir()) == [target]


@pytest.mark.subprocess
def test_a_killed_writer_leaves_a_temporary_file_the_next_write_removes(
    tmp_path: Path,
) -> None:
    target = tmp_path / "x.csv"
    code = (
        "import os, sys; from workbench.atomic_files import atomic_file\n"
        f"with atomic_file({str(target)!r}) as t:\n"
        "    t.write_text('partial'); os.kill(os.getpid(), 9)\n"
    )
    subprocess.run([sys.executable, "-c", code], check=False)
    (left, _), *more = get_temporaries(target)
    assert more == [] and left.read_text() == "partial" and not target.exists()
    remove_stale_temporaries(target)
    assert not left.exists()
    write_text_atomic(target, "whole")
    assert sorted(tmp_path.iterdir()) == [target]
