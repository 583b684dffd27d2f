"""Live viewer server on 127.0.0.1: the page over HTTP, the scene over a websocket.

Runs Tornado on its own event loop in a daemon thread, so it works from a
script, from the CLI and inside a Jupyter kernel alike. It only ever binds the
loopback interface.
"""

from __future__ import annotations

import asyncio
import logging
import threading
from collections.abc import Callable

import tornado.httpserver
import tornado.ioloop
import tornado.netutil
import tornado.web
import tornado.websocket

from workbench.errors import InputError
from workbench.viz._scene import SceneRecorder

logger = logging.getLogger(__name__)

HOST = "127.0.0.1"


class _PageHandler(tornado.web.RequestHandler):
    def initialize(self, server: LiveServer) -> None:
        self._server = server

    def get(self) -> None:
        self.set_header("Content-Type", "text/html; charset=utf-8")
        self.set_header("Cache-Control", "no-store")
        self.write(self._server.render())


class _NoIcon(tornado.web.RequestHandler):
    def get(self) -> None:
        self.set_status(204)


class _SceneSocket(tornado.websocket.WebSocketHandler):
    def initialize(self, server: LiveServer) -> None:
        self._server = server

    def open(self, *args: str, **kwargs: str) -> None:
        self._server.on_open(self)

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
                (r"/favicon.ico", _NoIcon),
            ]
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
            socket.write_message(command, binary=True)
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
            try:
                socket.write_message(command, binary=True)
            except tornado.websocket.WebSocketClosedError:
                self._sockets.discard(socket)

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
