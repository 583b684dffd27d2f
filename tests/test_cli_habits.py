"""Command-line habits: --version, -v/-q logging, closed pipes, progress lines."""

from __future__ import annotations

import io
import logging
import subprocess
import sys
import time
import warnings

import numba
import pytest

import workbench
from tests.conftest import run_cli as run
from workbench import progress as progress_module
from workbench.cli import EXIT_BROKEN_PIPE, fk
from workbench.progress import COMPILING, Progress

IK_ARGS = (
    "ik",
    "--robot",
    "puma560",
    "--angeles7",
    *("0.68", "-0.49", "-0.19", "-0.52", "-94.07", "125.40", "-470.55"),
    "--mm",
    "--all",
    "--json",
)


def test_version_names_package_and_distribution(capsys) -> None:
    code, out, _ = run(capsys, "--version")
    assert code == 0
    assert out.strip() == (
        f"workbench {workbench.__version__} (distribution kinematics-workbench)"
    )


def _noisy(args) -> int:
    logger = logging.getLogger("workbench.tests")
    logger.debug("debug detail")
    logger.info("info detail")
    logger.warning("a package warning")
    warnings.warn("a python warning", UserWarning, stacklevel=1)
    return 0


@pytest.mark.parametrize(
    ("flags", "shown", "hidden"),
    [
        ((), ["a package warning", "a python warning"], ["info detail"]),
        (("-q",), [], ["a package warning", "a python warning", "info detail"]),
        (("-v",), ["info detail", "a package warning"], ["debug detail"]),
        (("-vv",), ["debug detail", "info detail", "a package warning"], []),
    ],
)
def test_verbosity_flags_drive_logging(
    capsys, monkeypatch, flags, shown, hidden
) -> None:
    monkeypatch.setattr(fk, "run", _noisy)
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        code, out, err = run(capsys, *flags, "fk", "--robot", "puma560", "--rad", "0")
    assert code == 0 and out == ""
    for text in shown:
        assert text in err
    for text in hidden:
        assert text not in err
    if "a package warning" in shown:
        assert "workbench: WARNING: a package warning" in err
    # The handler is removed again: nothing leaks into the next call.
    assert not any(
        type(h).__name__ == "_StderrHandler"
        for h in logging.getLogger("workbench").handlers
    )


def test_quiet_and_verbose_exclude_each_other(capsys) -> None:
    code, _, err = run(capsys, "-q", "-v", "fk", "--robot", "puma560", "--rad", "0")
    assert code == 2 and "not allowed with" in err


@pytest.mark.subprocess
def test_closed_pipe_exits_quietly() -> None:
    process = subprocess.Popen(
        [sys.executable, "-m", "workbench", *IK_ARGS],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    process.stdout.close()  # the reader is gone before the first write
    _, err = process.communicate(timeout=120)
    assert process.returncode == EXIT_BROKEN_PIPE
    text = err.decode()
    assert "Traceback" not in text and "error" not in text and "Broken" not in text


def test_closed_pipe_in_process(capsys, monkeypatch) -> None:
    class _Closed(io.StringIO):
        def write(self, text: str) -> int:
            raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(sys, "stdout", _Closed())
    code = workbench.cli.main(list(IK_ARGS))
    assert code == EXIT_BROKEN_PIPE
    assert capsys.readouterr().err == ""


def _slow(args) -> int:
    time.sleep(0.3)
    return 0


def test_slow_command_prints_one_progress_line(capsys, monkeypatch) -> None:
    monkeypatch.delenv("WORKBENCH_PROGRESS")  # conftest turns progress off
    monkeypatch.setattr(progress_module, "PROGRESS_DELAY", 0.05)
    monkeypatch.setattr(fk, "run", _slow)
    code, out, err = run(capsys, "fk", "--robot", "puma560", "--rad", "0")
    assert code == 0 and out == ""
    assert err == "workbench: fk: computing the forward kinematics…\n"
    code, _, err = run(capsys, "-q", "fk", "--robot", "puma560", "--rad", "0")
    assert code == 0 and err == ""
    monkeypatch.setenv("WORKBENCH_PROGRESS", "0")
    code, _, err = run(capsys, "fk", "--robot", "puma560", "--rad", "0")
    assert code == 0 and err == ""


def test_fast_command_prints_no_progress_line(capsys, monkeypatch) -> None:
    monkeypatch.delenv("WORKBENCH_PROGRESS")
    monkeypatch.setattr(progress_module, "PROGRESS_DELAY", 5.0)  # a loaded machine
    code, out, err = run(capsys, "fk", "--robot", "puma560", "--rad", *"000000")
    assert code == 0 and out and err == ""


def test_numba_compilation_is_announced_once() -> None:
    stream = io.StringIO()
    with Progress("work", delay=60.0, stream=stream):
        numba.njit(lambda x: x + 1)(1)  # fresh functions: always compiled
        numba.njit(lambda x: x * 2.0)(1.0)
    assert stream.getvalue() == f"workbench: {COMPILING}\n"
    quiet = io.StringIO()
    with Progress("work", enabled=False, stream=quiet):
        numba.njit(lambda x: x - 1)(1)
    assert quiet.getvalue() == ""
    after = io.StringIO()
    with Progress("work", delay=60.0, stream=after):
        pass
    numba.njit(lambda x: x - 2)(1)  # the listener is gone
    assert after.getvalue() == ""


@pytest.mark.slow
@pytest.mark.parametrize("command", ["map", "place", "report"])
def test_workspace_closed_pipe_in_process(
    command: str, capsys, monkeypatch, tmp_path
) -> None:
    from tests._cli_fuzz import PLACE_ON_MAP, SMALL_MAP, write_inputs

    class _Closed(io.StringIO):
        def write(self, text: str) -> int:
            raise BrokenPipeError(32, "Broken pipe")

    write_inputs(tmp_path, workspace=True)
    monkeypatch.chdir(tmp_path)
    argv = {
        "map": [*SMALL_MAP, "x.zarr", "--json"],
        "place": [*PLACE_ON_MAP, "--targets", "task.csv", "--json"],
        "report": ["workspace", "report", "map.zarr", "--out", "r.html"],
    }[command]
    monkeypatch.setattr(sys, "stdout", _Closed())
    code = workbench.cli.main(["-q", *argv])
    assert code == EXIT_BROKEN_PIPE
    assert capsys.readouterr().err == ""
