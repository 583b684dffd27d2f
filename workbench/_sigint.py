"""Ctrl-C while the ``workbench`` command starts: exit 130 at once, no traceback.

Imported first by ``workbench/__init__.py``. When the process is the
``workbench`` command (the console script or ``python -m workbench``), SIGINT
exits with 130 until :func:`workbench.cli.main` takes over (it turns SIGINT
back into ``KeyboardInterrupt``, so that writers remove their temporary
files). Imported as a library, nothing changes. Helper threads (the progress
reporter's timer, :mod:`workbench.progress`) leave SIGINT to the main thread
(:func:`block_interrupts_in_this_thread`).
"""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path
from types import FrameType

#: Exit code after SIGINT (128 + 2, what a shell reports).
EXIT_INTERRUPTED = 130


def is_workbench_command() -> bool:
    """Whether this process runs the ``workbench`` command line."""
    argv = getattr(sys, "orig_argv", sys.argv)
    script = Path(sys.argv[0]).name if sys.argv else ""
    return script in ("workbench", "workbench.exe") or (
        list(argv[1:3]) == ["-m", "workbench"]
    )


def block_interrupts_in_this_thread() -> None:
    """For a helper thread: leave SIGINT to the main thread (Python's handler)."""
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})


def _exit_interrupted(signum: int, frame: FrameType | None) -> None:
    os._exit(EXIT_INTERRUPTED)


def exit_on_interrupt() -> None:
    """SIGINT ends the process with :data:`EXIT_INTERRUPTED`, nothing printed.

    An ignored SIGINT (a background job of a script, ``nohup``) stays ignored.
    """
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
        signal.signal(signal.SIGINT, _exit_interrupted)


if is_workbench_command():
    exit_on_interrupt()
