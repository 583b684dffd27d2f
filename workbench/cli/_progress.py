"""One progress line on stderr for commands that take a while.

A command that is still running after :data:`PROGRESS_DELAY` seconds prints
one line saying what it is doing; the first Numba compilation of the process
(a cold cache: the first run after an install or an upgrade) prints one line
saying so as soon as it starts. ``-q`` silences both. Nothing is printed for a
command that finishes quickly, so scripted output stays clean. A process forked
by the command (``workbench demo`` runs a section in one) prints nothing: the
command's own process speaks for it.
"""

from __future__ import annotations

import os
import sys
import threading
import weakref
from types import TracebackType
from typing import TextIO

from workbench.cli._interrupt_guard import block_interrupts_in_this_thread

PROGRESS_DELAY = 1.0  # [s] before a running command prints its line
COMPILING = "compiling the Numba kernels on first use (cached for later runs)…"
#: The environment variable that turns progress lines off (``0``); set while a
#: command runs, so that ``workbench._compiled`` leaves its compile line to it.
_ENVIRON = "WORKBENCH_PROGRESS"


class Progress:
    """Context manager printing at most one line per phase on ``stream``.

    Args:
        message: What the command does, e.g. ``"demo: running the examples"``.
        enabled: False prints nothing (``-q``).
        delay: Seconds [s] after which the line is printed if still running;
            None means :data:`PROGRESS_DELAY`.
        stream: Where to print; None means ``sys.stderr`` at print time.
    """

    def __init__(
        self,
        message: str,
        *,
        enabled: bool = True,
        delay: float | None = None,
        stream: TextIO | None = None,
    ):
        self.message = message
        self.enabled = enabled
        self.delay = PROGRESS_DELAY if delay is None else delay
        self._stream = stream
        self._lock = threading.Lock()
        self._timer: threading.Timer | None = None
        self._finished = False
        self._said_compiling = False
        self._listener: object | None = None
        self._environ: str | None = None
        _LIVE.add(self)

    def __enter__(self) -> Progress:
        # the command speaks for compiles: the library's own line is off
        self._environ = os.environ.get(_ENVIRON)
        os.environ[_ENVIRON] = "0"
        if not self.enabled:
            return self
        self._timer = _Timer(self.delay, self._say, args=(self.message,))
        self._timer.daemon = True
        self._timer.start()
        self._listener = _listen_to_numba(self)
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.finish()
        if self._environ is None:
            os.environ.pop(_ENVIRON, None)
        else:
            os.environ[_ENVIRON] = self._environ
        if self._listener is not None:
            from numba.core import event

            event.unregister("numba:compile", self._listener)
            self._listener = None

    def finish(self) -> None:
        """No more lines: the command is done or now waits on the user (a server)."""
        with self._lock:
            self._finished = True
        if self._timer is not None:
            self._timer.cancel()

    def on_compile(self) -> None:
        """Numba started compiling: say so once per process run."""
        with self._lock:
            if self._said_compiling or self._finished:
                return
            self._said_compiling = True
        self._say(COMPILING, check=False)

    def _say(self, text: str, check: bool = True) -> None:
        with self._lock:
            if check and self._finished:
                return
            stream = self._stream if self._stream is not None else sys.stderr
            try:
                stream.write(f"workbench: {text}\n")
                stream.flush()
            except (OSError, ValueError):  # stderr closed: progress is optional
                pass


class _Timer(threading.Timer):
    """A timer thread that leaves Ctrl-C to the main thread."""

    def run(self) -> None:
        block_interrupts_in_this_thread()
        super().run()


#: Every Progress of the process, silenced in a forked child.
_LIVE: weakref.WeakSet[Progress] = weakref.WeakSet()


def _silence_in_child() -> None:
    """After a fork, in the child: no lines; fresh locks (a thread's is copied)."""
    for progress in _LIVE:
        progress._lock = threading.Lock()
        progress._finished = True
        progress._timer = None  # its thread did not come along


if hasattr(os, "register_at_fork"):  # not on Windows (no fork)
    os.register_at_fork(after_in_child=_silence_in_child)


def _listen_to_numba(progress: Progress) -> object | None:
    """Register a Numba compile listener calling ``progress.on_compile``."""
    try:
        from numba.core import event
    except ImportError:  # numba is a dependency; stay robust without it
        return None

    class _Listener(event.Listener):
        def on_start(self, event: event.Event) -> None:
            progress.on_compile()

        def on_end(self, event: event.Event) -> None:
            pass

    listener = _Listener()
    event.register("numba:compile", listener)
    return listener
