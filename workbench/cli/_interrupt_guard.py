"""Ctrl-C waits while Numba holds its compiler lock (LLVM's signal handlers).

While LLVM compiles or loads a kernel it may put its own SIGINT handler in
place of Python's for a moment; a Ctrl-C then kills the process by the signal
(exit -2, no cleanup) instead of raising ``KeyboardInterrupt``. Inside
:func:`interrupts_wait_for_compiler`, SIGINT is blocked in the thread that
holds Numba's compiler lock, and in the command's other threads always, so
that a Ctrl-C stays pending until the lock is released; then it is Python's
``KeyboardInterrupt`` as anywhere else.

A command that never compiles (``workbench fk``) never imports Numba: when it
is not imported yet, the guard starts once it is
(:func:`workbench._lazy.call_when_imported`).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from typing import Any

from workbench._lazy import call_when_imported


class _BlockWhileLocked:
    """Blocks SIGINT in the thread holding the compiler lock (nested: counted)."""

    def __init__(self) -> None:
        self._local = threading.local()

    def start(self) -> None:
        depth = getattr(self._local, "depth", 0)
        if depth == 0:
            self._local.mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        self._local.depth = depth + 1

    def end(self) -> None:
        depth = getattr(self._local, "depth", 0)
        if depth == 0:  # registered while the lock was held
            return
        self._local.depth = depth - 1
        if depth == 1:
            signal.pthread_sigmask(signal.SIG_SETMASK, self._local.mask)


@contextlib.contextmanager
def interrupts_wait_for_compiler() -> Iterator[None]:
    """Within the block, a Ctrl-C during a Numba compilation waits for its end."""
    if not hasattr(signal, "pthread_sigmask"):  # Windows: no LLVM signal handlers
        yield
        return
    guard = _BlockWhileLocked()
    listeners: list[Any] = []

    def start_listening() -> None:
        from numba.core import event

        class _Listener(event.Listener):
            def on_start(self, event: event.Event) -> None:
                guard.start()

            def on_end(self, event: event.Event) -> None:
                guard.end()

        listeners.append(_Listener())
        event.register("numba:compiler_lock", listeners[0])

    stop_waiting = call_when_imported("numba", start_listening)
    try:
        yield
    finally:
        stop_waiting()
        if listeners:
            from numba.core import event

            event.unregister("numba:compiler_lock", listeners[0])
