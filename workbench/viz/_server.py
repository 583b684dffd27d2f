"""Live viewer server on 127.0.0.1: the page over HTTP, the scene over a websocket.

Runs Tornado on its own event loop in a daemon thread, so it works from a
script, from the CLI and inside a Jupyter kernel alike. It only ever binds the
loopback interface, and answers only requests whose ``Host`` (and ``Origin``,
when sent) names that interface with the server's port: a page of another site
cannot reach it through DNS rebinding. Nothing is logged per request, and what a
page sends over the websocket is ignored.
"""

from __future__ import annotations

import asyncio
import logging
import threading
from collections.abc import Callable
from typing import Any
from urllib.parse import urlsplit

import tornado.httpserver
import tornado.ioloop
import tornado.netutil
import tornado.web
import tornado.websocket

from workbench.errors import InputError
from workbench.viz._scene import SceneRecorder

logger = logging.getLogger(__name__)

HOST = "127.0.0.1"
#: Names of the loopback interface a ``Host`` or ``Origin`` header may use.
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "[::1]")
#: Body of the 403 answer to a request from another host or origin.
FORBIDDEN_MESSAGE = "forbidden: this server answers only loopback pages\n"


def get_allowed_hosts(port: int) -> frozenset[str]:
    """``Host`` header values the server on ``port`` accepts (lower case)."""
    hosts = {f"{name}:{port}" for name in LOOPBACK_NAMES}
    if port == 80:  # a browser leaves out the default port
        hosts |= set(LOOPBACK_NAMES)
    return frozenset(hosts)


def is_allowed_origin(origin: str, port: int) -> bool:
    """Whether an ``Origin`` header is ``http://`` one of the allowed hosts."""
    parts = urlsplit(origin.strip().lower())
    return (
        parts.scheme == "http"
        and parts.netloc in get_allowed_hosts(port)
        and parts.path in ("", "/")
    )


def _log_nothing(handler: tornado.web.RequestHandler) -> None:
    """Tornado's per-request log function: no access log on stderr."""


class _LoopbackHandler(tornado.web.RequestHandler):
    """Answers 403 unless ``Host`` and ``Origin`` name the loopback server."""

    def initialize(self, server: LiveServer) -> None:
        self._server = server

    def prepare(self) -> None:
        host = self.request.headers.get("Host", "").strip().lower()
        origin = self.request.headers.get("Origin")
        port = self._server.port
        if host not in get_allowed_hosts(port) or (
            origin is not None and not is_allowed_origin(origin, port)
        ):
            self.set_status(403)
            self.set_header("Content-Type", "text/plain; charset=utf-8")
            self.finish(FORBIDDEN_MESSAGE)

    def write_error(self, status_code: int, **kwargs: Any) -> None:
        """A one-line plain-text body, never a traceback."""
        self.set_header("Content-Type", "text/plain; charset=utf-8")
        self.finish(f"{status_code} {self._reason}\n")


class _NotFound(_LoopbackHandler):
    def get(self) -> None:
        raise tornado.web.HTTPError(404)


class _PageHandler(_LoopbackHandler):
    def get(self) -> None:
        self.set_header("Content-Type", "text/html; charset=utf-8")
        self.set_header("Cache-Control", "no-store")
        self.write(self._server.render())


def _take_failure(sent: asyncio.Future[None]) -> None:
    """Take a finished write's exception (a page that closed): nothing printed."""
    if not sent.cancelled():
        sent.exception()


class _NoIcon(_LoopbackHandler):
    def get(self) -> None:
        self.set_status(204)


class _SceneSocket(tornado.websocket.WebSocketHandler, _LoopbackHandler):
    def check_origin(self, origin: str) -> bool:
        return is_allowed_origin(origin, self._server.port)

    def open(self, *args: str, **kwargs: str) -> None:
        self._server.on_open(self)

    def on_message(self, message: str | bytes) -> None:
        """The page only listens: whatever it sends is ignored."""

    def on_close(self) -> None:
        self._server.on_close(self)


class LiveServer:
    """Serves one scene at ``http://127.0.0.1:PORT/`` and pushes its updates.

    Args:
        recorder: Scene to serve; every later command goes to open pages.
        render: Returns the page HTML (called per request).
        port: TCP port; 0 picks a free one.
    """

    def __init__(
        self, recorder: SceneRecorder, render: Callable[[], str], *, port: int = 0
    ):
        self.render = render
        self._recorder = recorder
        self._requested_port = port
        self._sockets: set[_SceneSocket] = set()
        self._ready = threading.Event()
        self._client = threading.Event()
        self._error: OSError | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self.port = 0

    @property
    def url(self) -> str:
        """Address of the page."""
        return f"http://{HOST}:{self.port}/"

    def start(self) -> str:
        """Start serving in a background thread; returns :attr:`url`.

        Raises:
            InputError: If the port cannot be bound (in use, no permission).
        """
        self._thread = threading.Thread(
            target=self._run, name="workbench-viewer", daemon=True
        )
        self._thread.start()
        self._ready.wait()
        if self._error is not None:
            raise InputError(
                f"cannot listen on {HOST}:{self._requested_port}: {self._error}"
            )
        self._recorder.add_listener(self._forward)
        logger.info("viewer at %s", self.url)
        return self.url

    def _run(self) -> None:
        loop = asyncio.new_event_loop()
        asyncio.set_event_loop(loop)
        app = tornado.web.Application(
            [
                (r"/", _PageHandler, {"server": self}),
                (r"/ws", _SceneSocket, {"server": self}),
                (r"/favicon.ico", _NoIcon, {"server": self}),
            ],
            default_handler_class=_NotFound,
            default_handler_args={"server": self},
            log_function=_log_nothing,
        )
        try:
            sockets = tornado.netutil.bind_sockets(self._requested_port, address=HOST)
        except OSError as err:
            self._error = err
            self._ready.set()
            loop.close()
            return
        http = tornado.httpserver.HTTPServer(app)
        http.add_sockets(sockets)
        self.port = int(sockets[0].getsockname()[1])
        self._loop = loop
        self._ready.set()
        try:
            loop.run_forever()
        finally:
            http.stop()
            for socket in list(self._sockets):
                socket.close()
            loop.run_until_complete(asyncio.sleep(0))
            loop.close()

    def on_open(self, socket: _SceneSocket) -> None:
        """A page connected: send it the whole scene."""
        self._sockets.add(socket)
        for command in self._recorder.get_commands():
            if not self._send(socket, command):
                return  # the page went away while the scene was being sent
        self._client.set()

    def on_close(self, socket: _SceneSocket) -> None:
        """A page went away."""
        self._sockets.discard(socket)

    def _forward(self, command: bytes) -> None:
        loop = self._loop
        if loop is None:
            return
        try:
            loop.call_soon_threadsafe(self._broadcast, command)
        except RuntimeError:  # the loop closed meanwhile
            pass

    def _broadcast(self, command: bytes) -> None:
        for socket in list(self._sockets):
            self._send(socket, command)

    def _send(self, socket: _SceneSocket, command: bytes) -> bool:
        """Send one command; False (the page forgotten) if it went away.

        A page may close while a write is under way: the write's failure is
        taken here, quietly, not left for the event loop to print.
        """
        try:
            sent = socket.write_message(command, binary=True)
        except tornado.websocket.WebSocketClosedError:
            self._sockets.discard(socket)
            return False
        sent.add_done_callback(_take_failure)
        return True

    def wait_for_client(self, timeout: float | None = None) -> bool:
        """Block until a page has connected and received the scene.

        Returns:
            True if one did within ``timeout`` seconds (None: wait forever).
        """
        return self._client.wait(timeout)

    def stop(self) -> None:
        """Stop serving and join the thread (idempotent)."""
        self._recorder.remove_listener(self._forward)
        loop = self._loop
        if loop is not None:
            try:
                loop.call_soon_threadsafe(loop.stop)
            except RuntimeError:  # already closed
                pass
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        self._loop = None
