"""The live viewer server: loopback hosts and origins only, quiet, deaf to pages."""

from __future__ import annotations

import asyncio
import http.client
import logging
import signal
import subprocess
import sys
import time

import pytest
from tornado.httpclient import HTTPClientError, HTTPRequest
from tornado.websocket import websocket_connect

from tests._interrupts import take_sigint
from tests.test_viz import free_port
from workbench.viz import Viewer
from workbench.viz._server import (
    FORBIDDEN_MESSAGE,
    get_allowed_hosts,
    is_allowed_origin,
)

FOREIGN_HOST = "evil.example"
FOREIGN_ORIGIN = "http://evil.example"
#: Seconds a test waits for the server to answer (never asserted on).
TIMEOUT = 10.0


def request(
    port: int, path: str = "/", headers: dict[str, str] | None = None
) -> tuple[int, str]:
    """GET ``path``; ``headers`` may replace Host. Returns (status, body)."""
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=TIMEOUT)
    try:
        headers = dict(headers or {})
        connection.putrequest("GET", path, skip_host="Host" in headers)
        for name, value in headers.items():
            connection.putheader(name, value)
        connection.endheaders()
        response = connection.getresponse()
        return response.status, response.read().decode("utf-8")
    finally:
        connection.close()


async def talk(port: int, origin: str | None = None) -> int:
    """Open the scene socket, send it messages, then read the whole scene.

    Returns:
        How many scene commands arrived after the page had spoken.
    """
    headers = {} if origin is None else {"Origin": origin}
    url = f"ws://127.0.0.1:{port}/ws"
    connection = await websocket_connect(HTTPRequest(url, headers=headers))
    await connection.write_message("hello")
    await connection.write_message(b"\x00\x01", binary=True)
    received = 0
    while True:
        try:
            message = await asyncio.wait_for(connection.read_message(), 1.0)
        except TimeoutError:
            break
        assert message is not None, "the server closed the socket"
        received += 1
    connection.close()
    return received


@pytest.fixture
def served(puma):
    """A viewer served on a free loopback port; yields (viewer, port)."""
    viewer = Viewer(puma)
    url = viewer.start_server()
    port = int(url.rstrip("/").rsplit(":", 1)[1])
    yield viewer, port
    viewer.stop_server()


def test_allowed_hosts_and_origins() -> None:
    assert get_allowed_hosts(8000) == {
        "localhost:8000",
        "127.0.0.1:8000",
        "[::1]:8000",
    }
    assert "localhost" in get_allowed_hosts(80)
    assert is_allowed_origin("http://localhost:8000", 8000)
    assert is_allowed_origin("HTTP://127.0.0.1:8000", 8000)
    for origin in (
        "http://localhost:8001",
        "https://localhost:8000",
        "http://evil.example:8000",
        "null",
        "",
        "http://127.0.0.1:8000.evil.example",
    ):
        assert not is_allowed_origin(origin, 8000), origin


@pytest.mark.parametrize("name", ["localhost", "127.0.0.1", "[::1]"])
def test_loopback_hosts_get_the_page(served, name: str) -> None:
    _, port = served
    origin = f"http://{name}:{port}"
    status, body = request(port, headers={"Host": f"{name}:{port}", "Origin": origin})
    assert status == 200
    assert "MeshCat.Viewer" in body


@pytest.mark.parametrize(
    "headers",
    [
        {"Host": FOREIGN_HOST},
        {"Host": f"{FOREIGN_HOST}:PORT"},
        {"Host": "127.0.0.1:1"},  # a loopback name, another port
        {"Host": "localhost"},  # port 80 implied
        {"Host": "127.0.0.1:PORT", "Origin": FOREIGN_ORIGIN},
        {"Host": "127.0.0.1:PORT", "Origin": "null"},
        {"Host": FOREIGN_HOST, "Origin": FOREIGN_ORIGIN},
    ],
)
@pytest.mark.parametrize("path", ["/", "/ws", "/favicon.ico", "/elsewhere"])
def test_foreign_host_or_origin_is_refused(served, headers, path: str) -> None:
    _, port = served
    headers = {k: v.replace("PORT", str(port)) for k, v in headers.items()}
    status, body = request(port, path, headers)
    assert (status, body) == (403, FORBIDDEN_MESSAGE)


def test_foreign_origin_websocket_is_refused(served) -> None:
    viewer, port = served
    with pytest.raises(HTTPClientError) as error:
        asyncio.run(talk(port, origin=FOREIGN_ORIGIN))
    assert error.value.code == 403
    assert viewer.wait_for_browser(timeout=0.01) is False


def test_page_messages_are_ignored_quietly(served, puma, caplog) -> None:
    viewer, port = served
    caplog.set_level(logging.DEBUG)
    received = asyncio.run(talk(port, origin=f"http://127.0.0.1:{port}"))
    assert received == len(viewer._recorder.get_commands()) > 0
    assert viewer.wait_for_browser(timeout=TIMEOUT) is True
    assert request(port)[0] == 200  # still serving
    assert [r for r in caplog.records if r.levelno >= logging.WARNING] == []


def test_unknown_path_is_a_short_404(served, caplog) -> None:
    _, port = served
    caplog.set_level(logging.DEBUG)
    assert request(port, "/elsewhere") == (404, "404 Not Found\n")
    assert [r.name for r in caplog.records if r.name.startswith("tornado")] == []


@pytest.mark.slow
@pytest.mark.subprocess
def test_served_cli_writes_nothing_on_stderr() -> None:
    """Normal, 403, 404 requests and page messages: stderr stays empty."""
    port = free_port()
    argv = ["view", "--robot", "puma560", "--serve", "--port", str(port)]
    process = subprocess.Popen(
        [sys.executable, "-m", "workbench", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        preexec_fn=take_sigint,  # a background job (`cmd &`) inherits it ignored
        text=True,
    )
    try:
        deadline = time.monotonic() + 60.0
        while True:
            try:
                status, _ = request(port)
                break
            except OSError:
                assert process.poll() is None, process.communicate()[1]
                assert time.monotonic() < deadline, "server did not come up"
                time.sleep(0.2)
        assert status == 200
        assert request(port, headers={"Host": FOREIGN_HOST})[0] == 403
        assert request(port, headers={"Origin": FOREIGN_ORIGIN})[0] == 403
        assert request(port, "/elsewhere")[0] == 404
        assert asyncio.run(talk(port)) > 0
        assert request(port)[0] == 200
        assert process.poll() is None
    finally:
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=30)
    assert process.returncode == 0
    assert err == ""
    assert f"http://127.0.0.1:{port}/" in out
