"""The ``workbench`` command line: one module per command, one parser here.

Exit codes: 0 success, 2 bad input, 3 infeasible request. Errors print a single
line on stderr and no traceback (set ``WORKBENCH_DEBUG=1`` to see one).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

from workbench.cli import (
    demo,
    export,
    fishcut,
    fk,
    ik,
    plan,
    report,
    singularities,
    urdf,
    view,
)
from workbench.errors import InfeasibleError, InputError, WorkbenchError

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_BAD_INPUT = 2
EXIT_INFEASIBLE = 3

_COMMANDS = (fk, ik, urdf, demo, singularities, report, plan, view, fishcut, export)


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line on stderr and exit code 2."""

    def error(self, message: str) -> None:
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every command registered."""
    parser = _Parser(
        prog="workbench",
        description="Kinematics workbench for the PUMA 560 and any URDF arm.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in _COMMANDS:
        module.register(commands)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.run(args) or EXIT_OK)
    except InputError as err:
        return _fail(err, EXIT_BAD_INPUT)
    except InfeasibleError as err:
        return _fail(err, EXIT_INFEASIBLE)
    except WorkbenchError as err:
        return _fail(err, EXIT_BAD_INPUT)
    except KeyboardInterrupt:
        return 130
    except Exception as err:  # a bug: still one line, exit 1
        return _fail(err, EXIT_INTERNAL, prefix="internal error")


def _fail(err: BaseException, code: int, prefix: str = "error") -> int:
    if os.environ.get("WORKBENCH_DEBUG"):
        raise err
    message = " ".join(str(err).split()) or type(err).__name__
    print(f"workbench: {prefix}: {message}", file=sys.stderr)
    return code


if __name__ == "__main__":
    sys.exit(main())
