"""The ``workbench`` command line: one module per command, one parser here.

Exit codes: 0 success, 2 bad input, 3 infeasible request (with ``--json``, the
JSON is printed all the same), 130 on Ctrl-C (SIGINT) at any moment, 141 when
the reader of stdout went away (``workbench ... | head``: a quiet exit, as for
SIGPIPE). Errors print a single line on stderr and no traceback (set
``WORKBENCH_DEBUG=1`` to see one); NumPy's floating-point warnings are silenced
(every result is checked for finiteness). The package's log messages go to
stderr: warnings by default, ``-v`` adds info, ``-vv`` debug, ``-q`` keeps only
errors (and no progress line; ``WORKBENCH_PROGRESS=0`` turns off only the
progress line).

A command imports what it uses when it runs: :func:`main` imports only the
module of the command it is given (every command's, to list them, when it is
given none), and :func:`build_parser` every command's.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import os
import re
import signal
import sys
import threading
import warnings
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

import workbench
from workbench._sigint import EXIT_INTERRUPTED, is_workbench_command
from workbench.cli._common import EXIT_INFEASIBLE, print_json
from workbench.cli._interrupt_guard import interrupts_wait_for_compiler
from workbench.errors import InfeasibleError, InputError, WorkbenchError
from workbench.progress import Progress

__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_BROKEN_PIPE",
    "EXIT_INFEASIBLE",
    "EXIT_INTERNAL",
    "EXIT_OK",
    "build_parser",
    "main",
]

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_BAD_INPUT = 2
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE, what a shell reports for `yes | head`

#: The commands, in the order ``workbench --help`` lists them: each is the
#: module ``workbench.cli.<name>``, with ``register`` (its arguments) and the
#: ``run`` it sets as default.
_COMMANDS = (
    "fk",
    "ik",
    "urdf",
    "demo",
    "singularities",
    "report",
    "plan",
    "view",
    "fishcut",
    "export",
    "workspace",
    "motion",
)
#: Options of the top-level parser that take no value (before the command).
_TOP_FLAGS = frozenset({"-v", "-vv", "-vvv", "--verbose", "-q", "--quiet"})

#: A number, as typed: ``-1``, ``-.5``, ``-1e-10``, ``-2.5E+3`` are values, not
#: options (argparse's own pattern misses exponents).
_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line on stderr and exit code 2.

    Negative numbers in every notation are values (see :data:`_NUMBER`).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NUMBER

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def build_parser(commands: Sequence[str] = _COMMANDS) -> argparse.ArgumentParser:
    """The top-level parser with ``commands`` registered (default: every command).

    Args:
        commands: Names of the commands to register (each imports its module).
    """
    parser = _Parser(
        prog="workbench",
        description="Kinematics workbench for the PUMA 560 and any URDF arm.",
    )
    parser.add_argument(
        "--version",
        action="version",
        version=f"%(prog)s {workbench.__version__} "
        f"(distribution {workbench.DISTRIBUTION})",
    )
    verbosity = parser.add_mutually_exclusive_group()
    verbosity.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=0,
        help="more messages on stderr (-v info, -vv debug)",
    )
    verbosity.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="only errors on stderr (no warnings, no progress line)",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in commands:
        importlib.import_module(f"workbench.cli.{name}").register(subparsers)
    return parser


def _commands_for(argv: Sequence[str]) -> Sequence[str]:
    """The command that ``argv`` names, alone; every command if it names none.

    The command is the first word after the top-level flags (``-v``, ``-q``);
    anything else there (``--help``, ``--version``, a typo) gets the whole
    parser, which lists every command or says what is wrong.
    """
    for word in argv:
        if word in _TOP_FLAGS:
            continue
        return (word,) if word in _COMMANDS else _COMMANDS
    return _COMMANDS


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code.

    Ctrl-C at any moment returns 130 (writers remove their temporary files
    first); run as the ``workbench`` command, the process then ends at once
    with 130 (no shutdown: background threads cut short would print their
    tracebacks). Run as the ``workbench`` command, a Ctrl-C after this function
    returned is ignored: the command is done and its exit code decided (while
    the interpreter shuts down, Python's handler is gone: the signal would kill
    the process).
    """
    command = is_workbench_command()
    in_main_thread = threading.current_thread() is threading.main_thread()
    if in_main_thread and signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        return _main(argv)
    except KeyboardInterrupt:
        if command:  # end here: at the interpreter's shutdown, the tasks of
            # background event loops (Zarr's) cut short would print tracebacks
            for stream in (sys.stdout, sys.stderr):
                with contextlib.suppress(OSError, ValueError):
                    stream.flush()
            os._exit(EXIT_INTERRUPTED)
        return EXIT_INTERRUPTED
    finally:
        if command:
            _quiet_after_the_command()
        if command and in_main_thread:
            signal.signal(signal.SIGINT, signal.SIG_IGN)


def _main(argv: Sequence[str] | None) -> int:
    try:
        argv = sys.argv[1:] if argv is None else list(argv)
        args = build_parser(_commands_for(argv)).parse_args(argv)
    except SystemExit as stop:  # --help, --version (0), a usage error (2)
        return stop.code if isinstance(stop.code, int) else EXIT_BAD_INPUT
    message = getattr(args, "progress_message", f"{args.command}: working")
    with (
        _log_to_stderr(_log_level(args)) as libraries,
        _quiet_numpy(),
        interrupts_wait_for_compiler(),
        Progress(message, enabled=_progress_wanted(args)) as progress,
    ):
        args.progress = progress
        try:
            code = int(args.run(args) or EXIT_OK)
            sys.stdout.flush()  # a closed pipe shows here, not at exit
            if code == EXIT_OK:
                libraries.summarise()
            return code
        except BrokenPipeError:
            return _quiet_on_broken_pipe()
        except InputError as err:
            return _fail(err, EXIT_BAD_INPUT)
        except InfeasibleError as err:
            _print_error_json(args, err)
            return _fail(err, EXIT_INFEASIBLE)
        except WorkbenchError as err:
            return _fail(err, EXIT_BAD_INPUT)
        except (MemoryError, OverflowError, RecursionError) as err:
            return _fail(_too_large(err), EXIT_BAD_INPUT)
        except Exception as err:  # a bug: still one line, exit 1
            return _fail(err, EXIT_INTERNAL, prefix="internal error")


def _too_large(err: Exception) -> InputError:
    """The input asked for more than this machine can compute or hold."""
    what = "a number too large"
    if isinstance(err, MemoryError):  # NumPy's _ArrayMemoryError too
        what = "not enough memory"
    elif isinstance(err, RecursionError):
        what = "input nested too deeply"
    return InputError(f"the request is too large ({what}: {err or type(err).__name__})")


def _print_error_json(args: argparse.Namespace, err: InfeasibleError) -> None:
    """With ``--json``, the infeasible result as JSON: ``{command, error}``.

    Commands that print their own JSON for an infeasible result return 3
    instead of raising, so this JSON is the only one on stdout.
    """
    if getattr(args, "json", False):
        print_json(
            {
                "command": args.command,
                "feasible": False,
                "error": " ".join(str(err).split()),
            }
        )


@contextlib.contextmanager
def _quiet_numpy() -> Iterator[None]:
    """No NumPy floating-point warnings (overflow in a product, ...) on stderr.

    Every result is checked for finiteness where it matters, and an error is
    one line; a RuntimeWarning with its source line would be two more.
    """
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        yield


def _progress_wanted(args: argparse.Namespace) -> bool:
    """Progress lines unless ``-q`` or ``WORKBENCH_PROGRESS=0`` (e.g. in CI logs)."""
    return not args.quiet and os.environ.get("WORKBENCH_PROGRESS", "1") != "0"


def _log_level(args: argparse.Namespace) -> int:
    if args.quiet:
        return logging.ERROR
    return {0: logging.WARNING, 1: logging.INFO}.get(args.verbose, logging.DEBUG)


@contextlib.contextmanager
def _log_to_stderr(level: int) -> Iterator[_LibraryMessages]:
    """Show the package's log records of ``level`` and above on stderr.

    Python warnings (``warnings.warn``) of the package are routed through
    logging as well, so ``-q`` hides them too. The log records and warnings of
    the libraries a command runs on (:data:`_LIBRARY_LOGGERS`: Dask, Zarr and
    their event loops) are kept instead (shown as they come with ``-v``), for
    one line at the end of a successful command
    (:meth:`_LibraryMessages.summarise`); a failed command prints its error
    line only. Everything is restored on exit (the tests call :func:`main`
    many times in one process).
    """
    handler = _StderrHandler()
    handler.setFormatter(logging.Formatter("workbench: %(levelname)s: %(message)s"))
    libraries = _LibraryMessages(level, handler)
    loggers = [logging.getLogger("workbench"), logging.getLogger("py.warnings")]
    others = [logging.getLogger(name) for name in _LIBRARY_LOGGERS]
    saved = [(lg.level, lg.propagate, lg.handlers[:]) for lg in (*loggers, *others)]
    for logger in loggers:
        logger.addHandler(handler)
        logger.setLevel(level)
        logger.propagate = False
    for logger in others:
        logger.handlers[:] = [libraries]
        logger.setLevel(min(level, logging.WARNING))
        logger.propagate = False
    shown = warnings.showwarning
    warnings.showwarning = libraries.show_warning
    try:
        yield libraries
    finally:
        warnings.showwarning = shown
        for logger, (old_level, propagate, handlers) in zip(
            (*loggers, *others), saved, strict=True
        ):
            logger.removeHandler(handler)
            logger.handlers[:] = handlers
            logger.setLevel(old_level)
            logger.propagate = propagate


#: Loggers of the libraries under the commands (Dask, Zarr, their codecs and
#: event loops): their records are summarised, not printed one by one.
_LIBRARY_LOGGERS = (
    "asyncio",
    "distributed",
    "tornado",
    "dask",
    "zarr",
    "numcodecs",
    "fsspec",
)
#: The package's folder: a warning issued from a file in it is the package's own.
_PACKAGE_FOLDER = str(Path(workbench.__file__).parent) + os.sep


class _LibraryMessages(logging.Handler):
    """Keeps the libraries' log records and warnings of one command.

    Args:
        level: The command's log level; at INFO or below (``-v``) every
            message is also shown as it comes.
        stderr: The handler that shows the package's records.
    """

    def __init__(self, level: int, stderr: logging.Handler) -> None:
        super().__init__(logging.DEBUG)
        self._level, self._stderr = level, stderr
        self.count = 0
        self.sources: dict[str, None] = {}  # in order of arrival
        self.first = ""

    def emit(self, record: logging.LogRecord) -> None:
        if record.levelno < logging.WARNING and self._level > record.levelno:
            return
        text = " ".join(record.getMessage().split())
        self._keep(record.name.split(".")[0], text)
        if self._level <= logging.INFO:
            self._stderr.handle(record)

    def show_warning(
        self,
        message: Warning | str,
        category: type[Warning],
        filename: str,
        lineno: int,
        file: Any = None,
        line: str | None = None,
    ) -> None:
        """``warnings.showwarning``: the package's own warnings are logged."""
        text = " ".join(f"{category.__name__}: {message}".split())
        if filename.startswith(_PACKAGE_FOLDER):
            logging.getLogger("py.warnings").warning("%s", text)
            return
        source = category.__module__.split(".")[0]
        if source in ("builtins", "warnings"):
            source = Path(filename).parent.name or "python"
        self._keep(source, text)
        if self._level <= logging.INFO:
            logging.getLogger("py.warnings").warning(
                "%s (%s:%d)", text, filename, lineno
            )

    def _keep(self, source: str, text: str) -> None:
        self.count += 1
        self.sources.setdefault(source)
        self.first = self.first or text

    def summarise(self) -> None:
        """One line on stderr for the libraries' messages, if any were kept.

        Not with ``-q`` (nor with ``-v``: they were shown as they came).
        """
        if self.count == 0 or self._level != logging.WARNING:
            return
        first = self.first if len(self.first) <= 160 else self.first[:157] + "..."
        logging.getLogger("workbench").warning(
            "%d message%s from %s (the first: %s); -v shows them",
            self.count,
            "" if self.count == 1 else "s",
            ", ".join(self.sources),
            first,
        )


def _quiet_after_the_command() -> None:
    """After the command: what libraries print at the interpreter's shutdown goes.

    Tasks of Zarr's and Dask's event loops destroyed while pending, a Dask
    client's ``__del__`` timing out: the command's result and exit code are
    decided, and its stderr is complete (an error is one line).
    """
    for name in _LIBRARY_LOGGERS:
        logger = logging.getLogger(name)
        logger.handlers[:] = [logging.NullHandler()]
        logger.propagate = False
    sys.unraisablehook = _ignore_unraisable
    warnings.simplefilter("ignore")


def _ignore_unraisable(unraisable: Any) -> None:
    """``sys.unraisablehook`` after the command: nothing printed."""


class _StderrHandler(logging.Handler):
    """Writes to the current ``sys.stderr`` (which tests may swap)."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            sys.stderr.write(self.format(record) + "\n")
        except Exception:
            self.handleError(record)


def _quiet_on_broken_pipe() -> int:
    """The reader of stdout is gone: stop without a word (no flush error at exit)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # stdout has no file descriptor (tests)
        pass
    return EXIT_BROKEN_PIPE


def _fail(err: BaseException, code: int, prefix: str = "error") -> int:
    if os.environ.get("WORKBENCH_DEBUG"):
        raise err
    message = " ".join(str(err).split()) or type(err).__name__
    print(f"workbench: {prefix}: {message}", file=sys.stderr)
    return code


if __name__ == "__main__":
    sys.exit(main())
