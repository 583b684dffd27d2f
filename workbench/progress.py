"""The progress reporter of long jobs: one line on stderr, counts with time left.

Every long job of the library takes a ``progress`` callable
(:data:`ProgressCallback`, ``progress(done, total)``:
:func:`~workbench.workspace.build_map` in blocks,
:func:`~workbench.workspace.place_base` in yaws and candidates,
:func:`~workbench.workspace.compute_joint_space_map` and
:func:`~workbench.singularities.compute_joint_grid` in configurations; the
singularity report ``progress(stage, done, total)`` per map). :class:`Progress`
is the reporter the command line gives them, and Python callers can give it
too::

    with Progress("workspace map: building") as progress:
        build_map(robot, grid, "map.zarr", progress=progress.count)

A job still running after :data:`PROGRESS_DELAY` seconds prints one line
saying what it is doing; the first Numba compilation of the process (a cold
cache: the first run after an install or an upgrade) prints one line saying
so as soon as it starts. A job that counts its steps (:meth:`Progress.count`)
adds a line with the steps done, the time elapsed and an estimate of the time
left: on a terminal one line redrawn in place, elsewhere (a log) a new line
every :data:`COUNT_INTERVAL` seconds. ``enabled=False`` (the command line's
``-q``) silences them all. Nothing is printed for a job that finishes
quickly, so scripted output stays clean. A process forked by the job
(``workbench demo`` runs a section in one) prints nothing: the job's own
process speaks for it.
"""

from __future__ import annotations

import math
import os
import sys
import threading
import time
import weakref
from collections.abc import Callable
from types import TracebackType
from typing import TextIO

from workbench._lazy import call_when_imported
from workbench._sigint import block_interrupts_in_this_thread

#: ``progress(done, total)``: what every long job calls after each chunk of
#: work (``done`` of ``total`` steps); :meth:`Progress.count` is one.
ProgressCallback = Callable[[int, int], None]
#: ``progress(stage, done, total)``: a job of several stages, each counted on
#: its own (``stage`` names it: the singularity report's maps, a motion plan's
#: sphere cover and pair tables); :meth:`Progress.stages` makes one.
StageProgress = Callable[[str, int, int], None]

PROGRESS_DELAY = 1.0  # [s] before a running job prints its line
#: Seconds between two count lines on a stream that is no terminal (a log file).
COUNT_INTERVAL = 10.0
#: Seconds between two redraws of the count line on a terminal.
REDRAW_INTERVAL = 0.25
COMPILING = "compiling the Numba kernels on first use (cached for later runs)…"
#: The environment variable that turns progress lines off (``0``); set while a
#: reporter runs, so that ``workbench._compiled`` leaves its compile line to it.
_ENVIRON = "WORKBENCH_PROGRESS"


class Progress:
    """Context manager printing at most one line per phase on ``stream``.

    Args:
        message: What the job does, e.g. ``"demo: running the examples"``.
        enabled: False prints nothing (the command line's ``-q``).
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
        self._stop_waiting: Callable[[], None] = lambda: None
        self._environ: str | None = None
        self._started = time.monotonic()
        #: (label, time [s], done) at the first count of the current label
        self._first_count: tuple[str, float, int] | None = None
        self._last_count = -math.inf  # time [s] of the last count line
        self._open_line = False  # a count line redrawn in place, not ended
        _LIVE.add(self)

    def __enter__(self) -> Progress:
        # the reporter speaks for compiles: the library's own line is off
        self._started = time.monotonic()
        self._environ = os.environ.get(_ENVIRON)
        os.environ[_ENVIRON] = "0"
        if not self.enabled:
            return self
        self._timer = _Timer(self.delay, self._say, args=(self.message,))
        self._timer.daemon = True
        self._timer.start()
        self._stop_waiting = call_when_imported("numba", self._listen_to_numba)
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
        self._stop_waiting()
        if self._listener is not None:
            from numba.core import event

            event.unregister("numba:compile", self._listener)
            self._listener = None

    def _listen_to_numba(self) -> None:
        """Hear Numba's compiles (called once Numba is imported, if ever)."""
        self._listener = _listen_to_numba(self)

    def finish(self) -> None:
        """No more lines: the job is done or now waits on the user (a server)."""
        with self._lock:
            self._finished = True
            if self._open_line:
                self._write("\n")
        if self._timer is not None:
            self._timer.cancel()

    def count(
        self, done: int, total: int, *, unit: str = "steps", label: str = ""
    ) -> None:
        """``done`` of ``total`` steps finished: a line with the time elapsed and left.

        Nothing within the first ``delay`` seconds. The estimate of the time
        left extrapolates the rate of the steps done since the first call
        with this ``label`` (a resumed job starts with some already done; a
        job of several stages counts each under its own label).

        Args:
            done: Steps done so far.
            total: Steps in all.
            unit: What a step is, for the line (``"blocks"``).
            label: What the job does, before the count (``"workspace
                map"``).
        """
        now = time.monotonic()
        with self._lock:
            if self._first_count is None or self._first_count[0] != label:
                self._first_count = (label, now, done)
            if not self.enabled or self._finished or now - self._started < self.delay:
                return
            stream = self._get_stream()
            terminal = _is_terminal(stream)
            interval = REDRAW_INTERVAL if terminal else COUNT_INTERVAL
            last = done >= total
            if now - self._last_count < interval and not (last and terminal):
                return
            self._last_count = now
            percent = 100 * done // max(total, 1)
            line = f"workbench: {label}{': ' if label else ''}{done}/{total} {unit}"
            line += f" ({percent}%)"
            line += f", {_format_seconds(now - self._started)} elapsed"
            _, start, first = self._first_count
            if done > first and not last:
                left = (now - start) / (done - first) * (total - done)
                line += f", about {_format_seconds(left)} left"
            if terminal:
                self._write(f"\r{line}\x1b[K" + ("\n" if last else ""))
                self._open_line = not last
            else:
                self._write(line + "\n")

    def stages(self, label: str, unit: str = "steps") -> StageProgress:
        """A :data:`StageProgress` counting each stage as ``"label: stage"``.

        Args:
            label: What the job does (``"motion plan"``).
            unit: What a step is, for the lines (``"points"``).
        """

        def count(stage: str, done: int, total: int) -> None:
            self.count(done, total, unit=unit, label=f"{label}: {stage}")

        return count

    def _get_stream(self) -> TextIO:
        return self._stream if self._stream is not None else sys.stderr

    def _write(self, text: str) -> None:
        """Write and flush (the lock held); a closed stream is ignored."""
        try:
            stream = self._get_stream()
            stream.write(text)
            stream.flush()
        except (OSError, ValueError):  # stderr closed: progress is optional
            pass

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
            self._write(("\n" if self._open_line else "") + f"workbench: {text}\n")
            self._open_line = False


def _is_terminal(stream: TextIO) -> bool:
    try:
        return stream.isatty()
    except (OSError, ValueError, AttributeError):
        return False


def _format_seconds(seconds: float) -> str:
    """``"8.1 s"``, ``"4 min 05 s"``, ``"2 h 03 min"``."""
    if seconds < 60.0:
        return f"{seconds:.1f} s"
    minutes, rest = divmod(round(seconds), 60)
    if minutes < 60:
        return f"{minutes} min {rest:02d} s"
    hours, minutes = divmod(minutes, 60)
    return f"{hours} h {minutes:02d} min"


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


__all__ = [
    "COMPILING",
    "COUNT_INTERVAL",
    "PROGRESS_DELAY",
    "REDRAW_INTERVAL",
    "Progress",
    "ProgressCallback",
    "StageProgress",
]
