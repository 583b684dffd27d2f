"""Screenshots of a page in headless Chromium, driven over the DevTools protocol.

Why not ``chromium --screenshot --virtual-time-budget=...``: that one-shot mode
waits for Chromium's *virtual* clock to use up the budget before it captures,
and on a loaded machine the budget sometimes never expires (a known race of the
virtual-time controller; our WebGL pages keep a ``requestAnimationFrame`` loop
running, which makes it likelier). The process then sits until it is killed, and
a retry only hides it. Here every step waits for an explicit condition with a
real-time deadline and fails with a message naming the step:

1. Chromium starts with ``--remote-debugging-port=0`` and writes the port it
   picked to ``DevToolsActivePort`` in its own profile directory;
2. a tab is opened at ``about:blank``, sized, then navigated to the page;
3. we wait for ``document.readyState == "complete"``, run the caller's script,
   then wait for a few rendered animation frames;
4. ``Page.captureScreenshot``, then ``Browser.close``.

The process is spawned in its own session with stdin from ``/dev/null`` and its
output in a log file (no pipes that a lingering helper process such as the crash
handler could hold open), and its whole process group is killed at the end, so
no renderer or GPU process outlives a test.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import itertools
import json
import os
import signal
import subprocess
import time
from pathlib import Path
from typing import Any

from tornado.websocket import WebSocketClientConnection, websocket_connect

CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",  # software WebGL, opted in explicitly
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-breakpad",  # no crash handler process
    "--no-first-run",
    "--no-default-browser-check",
    "--hide-scrollbars",
    "--force-device-scale-factor=1",
    "--remote-debugging-port=0",
)
STEP_TIMEOUT = 60.0  # [s] real time for any single step
FRAMES = 5  # animation frames rendered after the page (and script) settled

_WAIT_FRAMES = (
    "new Promise(function (resolve) { var n = 0; function step() {"
    f" if (++n >= {FRAMES}) resolve(true); else requestAnimationFrame(step); }}"
    " requestAnimationFrame(step); })"
)


class ChromiumError(RuntimeError):
    """A step of the screenshot did not complete; the message names it."""


class _DevTools:
    """Minimal DevTools client on one browser websocket (flattened sessions)."""

    def __init__(self, connection: WebSocketClientConnection):
        self._connection = connection
        self._ids = itertools.count(1)
        self.page_errors: list[str] = []  # console.error calls, uncaught exceptions

    def _note(self, event: dict[str, Any]) -> None:
        """Keep the page's errors from an event (once ``Runtime.enable`` ran)."""
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.consoleAPICalled" and params.get("type") == "error":
            texts = [
                str(a.get("value", a.get("description", ""))) for a in params["args"]
            ]
            self.page_errors.append("console.error: " + " ".join(texts))
        elif method == "Runtime.exceptionThrown":
            details = params.get("exceptionDetails", {})
            text = details.get("exception", {}).get("description") or details.get(
                "text"
            )
            self.page_errors.append(f"uncaught: {text}")

    async def call(
        self, method: str, params: dict[str, Any] | None = None, session: str = ""
    ) -> dict[str, Any]:
        message_id = next(self._ids)
        message: dict[str, Any] = {"id": message_id, "method": method}
        message["params"] = params or {}
        if session:
            message["sessionId"] = session
        await self._connection.write_message(json.dumps(message))
        while True:  # skip events until our answer arrives
            raw = await asyncio.wait_for(
                self._connection.read_message(), timeout=STEP_TIMEOUT
            )
            if raw is None:
                raise ChromiumError(f"{method}: the browser closed the connection")
            answer = json.loads(raw)
            if answer.get("id") != message_id:
                self._note(answer)
                continue
            if "error" in answer:
                raise ChromiumError(f"{method}: {answer['error']}")
            return answer["result"]

    async def evaluate(self, session: str, expression: str) -> Any:
        result = await self.call(
            "Runtime.evaluate",
            {"expression": expression, "awaitPromise": True, "returnByValue": True},
            session,
        )
        if "exceptionDetails" in result:
            details = result["exceptionDetails"]
            text = details.get("exception", {}).get("description") or details
            raise ChromiumError(f"page script failed: {text}")
        return result["result"].get("value")


def _wait_for_port(profile: Path, process: subprocess.Popen[bytes], log: Path) -> str:
    """The browser websocket URL, once Chromium has written it."""
    active = profile / "DevToolsActivePort"
    deadline = time.monotonic() + STEP_TIMEOUT
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise ChromiumError(
                f"chromium exited with code {process.returncode} at start-up: "
                + log.read_text(errors="replace")[-2000:]
            )
        with contextlib.suppress(FileNotFoundError):
            lines = active.read_text().split("\n")
            if len(lines) >= 2 and lines[1]:
                return f"ws://127.0.0.1:{lines[0]}{lines[1]}"
        time.sleep(0.05)
    raise ChromiumError(f"chromium wrote no DevToolsActivePort in {STEP_TIMEOUT} s")


async def _capture(
    url: str, page_uri: str, width: int, height: int, script: str | None
) -> tuple[bytes, list[str]]:
    connection = await websocket_connect(url, max_message_size=64 * 2**20)
    devtools = _DevTools(connection)
    try:
        target = await devtools.call("Target.createTarget", {"url": "about:blank"})
        attached = await devtools.call(
            "Target.attachToTarget", {"targetId": target["targetId"], "flatten": True}
        )
        session = attached["sessionId"]
        await devtools.call(
            "Emulation.setDeviceMetricsOverride",
            {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
            session,
        )
        await devtools.call("Runtime.enable", {}, session)  # console events
        await devtools.call("Page.navigate", {"url": page_uri}, session)
        deadline = time.monotonic() + STEP_TIMEOUT
        while await devtools.evaluate(session, "document.readyState") != "complete":
            if time.monotonic() > deadline:
                raise ChromiumError(f"page did not load in {STEP_TIMEOUT} s")
            await asyncio.sleep(0.05)
        if script is not None:
            await devtools.evaluate(session, script)
        await devtools.evaluate(session, _WAIT_FRAMES)
        shot = await devtools.call("Page.captureScreenshot", {"format": "png"}, session)
        with contextlib.suppress(ChromiumError):  # the answer may not arrive
            await devtools.call("Browser.close")
        return base64.b64decode(shot["data"]), devtools.page_errors
    finally:
        connection.close()


def take_screenshot(
    chromium: str,
    html: Path,
    png: Path,
    *,
    width: int,
    height: int,
    script: str | None = None,
) -> list[str]:
    """Render ``html`` at ``width`` x ``height`` [px] and save it as ``png``.

    Args:
        chromium: Chromium binary.
        html: Page on disk (opened as a ``file://`` URI, offline).
        png: Output image.
        width: Viewport width [px].
        height: Viewport height [px].
        script: JavaScript run once the page has loaded (may return a promise),
            before the frames are rendered and captured.

    Returns:
        The page's errors up to the capture: each ``console.error`` call and
        uncaught exception, one line each (empty for a clean page).

    Raises:
        ChromiumError: If a step does not complete within ``STEP_TIMEOUT``.
    """
    profile = png.with_name(png.stem + "-profile")
    log = png.with_name(png.stem + "-chromium.log")
    (profile / "DevToolsActivePort").unlink(missing_ok=True)  # from an earlier run
    with log.open("wb") as output:
        process = subprocess.Popen(
            [chromium, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", "about:blank"],
            stdin=subprocess.DEVNULL,
            stdout=output,
            stderr=output,
            start_new_session=True,  # its own process group, killed below
        )
    try:
        url = _wait_for_port(profile, process, log)
        data, errors = asyncio.run(_capture(url, html.as_uri(), width, height, script))
        png.write_bytes(data)
        try:
            process.wait(timeout=STEP_TIMEOUT)
        except subprocess.TimeoutExpired as err:
            raise ChromiumError("chromium did not exit after Browser.close") from err
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGKILL)  # any helper left behind
        process.wait()
    return errors
