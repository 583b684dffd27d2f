"""One line on stderr on every error path, and bounds on every number and name.

Cases found by the robustness round over ``workspace map|place|view|report``,
``export``, ``plan``, ``view --serve`` and the seven-axis options: a bad Dask
scheduler address, a robot a sampled map cannot take, blocks larger than the
machine's memory, libraries' warnings and log records (Zarr, Dask, asyncio),
a browser tab that goes away, Ctrl-C, rates and counts below their minimum,
empty names, temporary files of killed writers, a name too long for the file
system, a symbolic-link loop. Each keeps the contract of ``tests/_cli_fuzz.py``
(exit 0, 2 or 3, one line on stderr, no file changed by a failed run).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import socket
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests._cli_fuzz import (
    SMALL_MAP,
    URSCRIPT,
    VIEW_SEVEN,
    contract_violations,
    run_case,
    write_inputs,
)
from workbench import _dask
from workbench.cli import main
from workbench.errors import InputError
from workbench.workspace import build

#: ``workspace map`` of the small map with the address that follows.
_ON_SCHEDULER = [*SMALL_MAP[:-3], "--scheduler"]


def _catalog_urdf(name: str = "puma560") -> str:
    from workbench import load_robot

    return Path(load_robot(name).urdf_path).read_text()


def _run(tmp_path: Path, *argv: str) -> tuple[int, str, str]:
    """Run a case in ``tmp_path`` (its inputs written) and check the contract."""
    write_inputs(tmp_path, workspace=True)
    outcome = run_case(list(argv), tmp_path)
    assert contract_violations(outcome) == [], outcome
    return outcome.code, outcome.stdout, outcome.stderr


def _run_loud(
    folder: Path, argv: list[str], monkeypatch: pytest.MonkeyPatch
) -> tuple[int, str]:
    """Run ``workbench *argv`` in ``folder`` without ``-q``: (exit code, stderr)."""
    monkeypatch.setenv("WORKBENCH_PROGRESS", "0")
    monkeypatch.chdir(folder)
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, err.getvalue()


def _no_map_left(folder: Path, name: str = "x.zarr") -> bool:
    return not (folder / name).exists() and not (folder / f"{name}.partial").exists()


# --- the scheduler address: parsed and probed before the store ----------------
@pytest.mark.parametrize(
    ("address", "fragment"),
    [
        ("notanaddress", "is not tcp://HOST:PORT"),
        ("", "is not tcp://HOST:PORT"),
        ("http://127.0.0.1:1", "is not tcp://HOST:PORT"),
        ("inproc://x", "is not tcp://HOST:PORT"),
        ("tcp://127.0.0.1", "is not tcp://HOST:PORT"),
        ("tcp://127.0.0.1:70000", "PORT 1..65535"),
        ("tcp://127.0.0.1:1", "cannot reach the Dask scheduler at tcp://127.0.0.1:1"),
    ],
)
def test_bad_scheduler_address_exits_2_before_the_store(
    tmp_path: Path, address: str, fragment: str
) -> None:
    code, out, err = _run(tmp_path, *_ON_SCHEDULER, address, "--out", "x.zarr")
    assert (code, out) == (2, "") and fragment in err, err
    assert "Traceback" not in err and _no_map_left(tmp_path)


@contextlib.contextmanager
def _silent_listener() -> Iterator[int]:
    """A TCP port that accepts connections and never answers; its number."""
    server = socket.create_server(("127.0.0.1", 0))
    accepted: list[socket.socket] = []
    stop = threading.Event()

    def accept() -> None:
        server.settimeout(0.1)
        while not stop.is_set():
            with contextlib.suppress(TimeoutError):
                accepted.append(server.accept()[0])

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    try:
        yield server.getsockname()[1]
    finally:
        stop.set()
        thread.join()
        for connection in accepted:
            connection.close()
        server.close()


def test_a_server_that_is_no_scheduler_exits_2_before_the_store(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(_dask, "PROBE_TIMEOUT", 0.3)
    with _silent_listener() as port:
        code, out, err = _run(
            tmp_path, *_ON_SCHEDULER, f"127.0.0.1:{port}", "--out", "x.zarr"
        )
    assert (code, out) == (2, "") and "is no Dask scheduler" in err, err
    assert _no_map_left(tmp_path)


# --- what a build cannot do is found before its partial store ------------------
def _puma_variant(tmp_path: Path, kind: str) -> Path:
    text = _catalog_urdf()
    joint = '<joint name="joint6" type="revolute">'
    if kind == "continuous":
        text = text.replace(joint, '<joint name="joint6" type="continuous">')
    else:  # joint 6 follows joint 5
        end = text.index("</joint>", text.index(joint))
        text = text[:end] + '<mimic joint="joint5"/>' + text[end:]
    path = tmp_path / f"{kind}.urdf"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("kind", "fragment"),
    [("continuous", "no continuous joints"), ("mimic", "joint6 follows joint5")],
)
def test_a_robot_no_sampled_map_takes_exits_2_before_the_store(
    tmp_path: Path, kind: str, fragment: str
) -> None:
    urdf = _puma_variant(tmp_path, kind)
    argv = [*SMALL_MAP, "x.zarr"]
    argv[argv.index("puma560")] = str(urdf)
    code, out, err = _run(tmp_path, *argv)
    assert (code, out) == (2, "") and fragment in err, err
    assert _no_map_left(tmp_path)


def test_blocks_beyond_the_memory_exit_2_before_the_store(tmp_path: Path) -> None:
    argv = [*SMALL_MAP, "x.zarr"]
    argv[argv.index("--orientations") + 1] = "100000"
    code, out, err = _run(tmp_path, *argv, "--block-voxels", str(1 << 20))
    assert (code, out) == (2, "") and "GiB of memory here" in err, err
    assert "lower --block-voxels" in err and _no_map_left(tmp_path)


def test_a_failed_build_prints_its_error_line_only(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def failing(*args: object, **kwargs: object) -> None:
        raise InputError("a block task failed")

    write_inputs(tmp_path, workspace=True)
    monkeypatch.setattr(build, "run_tasks", failing)
    code, err = _run_loud(tmp_path, [*SMALL_MAP, "x.zarr"], monkeypatch)
    assert code == 2 and err == "workbench: error: a block task failed\n", err


def test_ctrl_c_prints_one_line_telling_how_to_resume(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    write_inputs(tmp_path, workspace=True)
    monkeypatch.setattr(build, "run_tasks", interrupted)
    code, err = _run_loud(tmp_path, [*SMALL_MAP, "x.zarr"], monkeypatch)
    assert code == 130 and err.count("\n") == 1, err
    assert "the same command resumes the build" in err
    assert (tmp_path / "x.zarr.partial").is_dir()


# --- libraries' messages: kept, one line at most -------------------------------
def test_zarr_warnings_of_an_edited_map_are_not_printed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    write_inputs(tmp_path, workspace=True)
    group = tmp_path / "map.zarr" / "zarr.json"
    group.write_text(group.read_text().replace('"zarr_format": 3', '"zarr_format": 2'))
    argv = ["workspace", "report", "map.zarr", "--out", "r.html"]
    code, err = _run_loud(tmp_path, argv, monkeypatch)
    assert code == 2 and err.count("\n") == 1, err
    assert "workspace map" in err and "ZarrUserWarning" not in err


def test_library_warnings_of_a_command_that_succeeds_are_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import logging
    import warnings

    from workbench.cli import fk

    def run(args: object) -> int:
        for k in range(20):
            warnings.warn(f"library warning {k}", UserWarning, stacklevel=1)
            logging.getLogger("distributed.client").warning("client message %d", k)
        return 0

    monkeypatch.setattr(fk, "run", run)  # registered by the next main()
    monkeypatch.setenv("WORKBENCH_PROGRESS", "0")
    parser_run = ["fk", "--robot", "puma560", "--rad", *["0"] * 6]
    assert main(parser_run) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert "40 messages from tests, distributed" in err and "-v shows them" in err
    assert main(["-q", *parser_run]) == 0
    assert capsys.readouterr().err == ""


#: A command that leaves, for the interpreter's shutdown, an event-loop task
#: destroyed while pending and an object whose ``__del__`` raises (what Zarr's
#: and Dask's loops and clients leave after an error).
_LEAVES_GARBAGE = """
import asyncio, sys
import workbench.cli as cli
from workbench.cli import fk

class Leaky:
    def __del__(self):
        raise RuntimeError("Event loop is closed")

kept = []

def run(args):
    loop = asyncio.new_event_loop()
    kept.append(loop.create_task(asyncio.sleep(3600)))
    kept.append(Leaky())
    print("done")
    return 0

fk.run = run
cli.is_workbench_command = lambda: True
sys.exit(cli.main(["fk", "--robot", "puma560", "--rad", *["0"] * 6]))
"""


@pytest.mark.subprocess
def test_what_libraries_leave_for_the_shutdown_prints_nothing(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-c", _LEAVES_GARBAGE],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=False,
        env={**os.environ, "WORKBENCH_PROGRESS": "0"},
    )
    assert (done.returncode, done.stdout, done.stderr) == (0, "done\n", "")


# --- the live server: a page that goes away while the scene is sent -----------
def _open_and_drop(port: int) -> None:
    """Open the scene's websocket like a page, then reset the connection."""
    import base64
    import struct

    key = base64.b64encode(os.urandom(16)).decode()
    with socket.create_connection(("127.0.0.1", port), timeout=5.0) as page:
        page.sendall(
            f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
            f"Origin: http://127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
            f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
            "Sec-WebSocket-Version: 13\r\n\r\n".encode()
        )
        assert page.recv(12) == b"HTTP/1.1 101"  # switched; the scene follows
        page.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))


def test_a_page_closed_while_the_scene_is_sent_is_forgotten_quietly(
    puma: object, caplog: pytest.LogCaptureFixture
) -> None:
    import gc
    import time
    import urllib.request

    from workbench.viz import Viewer

    viewer = Viewer(puma)  # type: ignore[arg-type]
    url = viewer.start_server()
    port = int(url.rstrip("/").rsplit(":", 1)[1])
    try:
        with caplog.at_level("WARNING"):
            for _ in range(3):
                _open_and_drop(port)
            deadline = time.monotonic() + 5.0
            while viewer.wait_for_browser(timeout=0.0) is False:
                if time.monotonic() > deadline:  # (no page got the whole scene)
                    break
                time.sleep(0.05)
            with urllib.request.urlopen(url, timeout=5.0) as response:
                assert response.status == 200  # still serving
    finally:
        viewer.stop_server()
    gc.collect()  # a write's task with an untaken failure would log now
    assert [r.getMessage() for r in caplog.records] == []


# --- bounds: minima as well as maxima, the same bound on every command --------
@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        ([*URSCRIPT, "--out", "o.script", "--servo-rate", "1e-9"], "below 1 Hz"),
        ([*URSCRIPT, "--out", "o.script", "--servo-rate", "0.5"], "below 1 Hz"),
        (
            ["plan", "pick-place", "--robot", "iiwa14",
             "--pick-xyz-quat-wxyz", "0.5", "0.1", "0.4", "0", "1", "0", "0",
             "--place-xyz-quat-wxyz", "0.5", "-0.1", "0.4", "0", "1", "0", "0",
             "--duration", "5", "--redundancy", "1e308"],
            "at most 1000 rad",
        ),
        (["fk", "--robot", "ur5", "--frame", "", "--rad", *["0"] * 6], "not empty"),
        ([*VIEW_SEVEN, "--redundancy-sweep", "3", "--branch", ""], "not empty"),
        (["export", "--format", "ros2-bag", "--trajectory", "traj.csv", "--robot",
          "ur5", "--out", "o.mcap", "--topic", " "], "not empty"),
        (["urdf", "from-dh", "long.json", "--out", "o.urdf"], "at most 1000 m"),
    ],
)  # fmt: skip
def test_values_beyond_their_bounds_exit_2(
    tmp_path: Path, argv: list[str], fragment: str
) -> None:
    rows = [{"alpha": 1.5707963267948966, "a": 0.1, "d": 0.2}] * 6
    long = {"name": "long", "joints": [{**rows[0], "a": 1e300}, *rows[1:]]}
    (tmp_path / "long.json").write_text(json.dumps(long))
    code, out, err = _run(tmp_path, *argv)
    assert (code, out) == (2, "") and fragment in err, err
    assert not (tmp_path / "o.script").exists()


def test_servo_rate_down_to_the_trajectory_s_own_rate(tmp_path: Path) -> None:
    code, _, err = _run(tmp_path, *URSCRIPT, "--out", "o.script", "--servo-rate", "1")
    assert code == 0, err
    script = (tmp_path / "o.script").read_text()
    assert script.count("servoj(") == 2  # both samples of the 1 s trajectory


# --- temporary files of killed writers, nested ones too -------------------------
@pytest.mark.subprocess
def test_nested_temporary_files_of_a_killed_writer_go_with_the_next_write(
    tmp_path: Path,
) -> None:
    from workbench.atomic_files import get_temporaries, write_text_atomic

    target = tmp_path / "o.png"
    code = (  # as plan --csv --plot: the plot's writer given the plot's temporary
        "import os; from workbench.atomic_files import atomic_file, atomic_files\n"
        f"with atomic_files({str(target)!r}) as (staged,):\n"
        "    with atomic_file(staged) as inner:\n"
        "        inner.write_text('half a PNG'); os.kill(os.getpid(), 9)\n"
    )
    subprocess.run([sys.executable, "-c", code], check=False)
    left = sorted(p.name for p in tmp_path.iterdir())
    assert len(left) == 2 and any(name.startswith("..o.") for name in left), left
    assert len(get_temporaries(target)) == 2
    write_text_atomic(target, "whole")
    assert sorted(tmp_path.iterdir()) == [target]


# --- names the file system refuses ------------------------------------------------
_LONG = "a" * 300


@pytest.mark.parametrize(
    "argv",
    [
        [*SMALL_MAP, f"{_LONG}.zarr"],
        ["workspace", "report", "map.zarr", "--out", f"{_LONG}.html"],
        ["view", "--robot", "ur5", "--rad", *["0"] * 6, "--html", f"{_LONG}.html"],
        ["urdf", "from-dh", "t.json", "--out", f"{_LONG}.urdf"],
    ],
    ids=lambda a: " ".join(a[:2]),
)
def test_an_output_name_too_long_exits_2(tmp_path: Path, argv: list[str]) -> None:
    code, out, err = _run(tmp_path, *argv)
    assert (code, out) == (2, "") and "its name is" in err and "at most" in err, err


@pytest.mark.parametrize(
    "argv",
    [
        ["workspace", "report", "loop.zarr", "--out", "r.html"],
        ["workspace", "view", "loop.zarr", "--html", "v.html"],
    ],
    ids=lambda a: " ".join(a[:2]),
)
def test_a_map_path_that_is_a_symlink_loop_exits_2(
    tmp_path: Path, argv: list[str]
) -> None:
    (tmp_path / "loop.zarr").symlink_to("loop.zarr")
    code, out, err = _run(tmp_path, *argv)
    assert (code, out) == (2, "") and "symbolic-link loop" in err, err
