"""``workbench demo``: the papers' examples end to end."""

from __future__ import annotations

import argparse
from pathlib import Path

from workbench.cli._common import add_json_flag, print_json


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``demo`` command."""
    parser = commands.add_parser(
        "demo",
        help="the papers' examples end to end",
        description="Reproduce the papers' examples (Angeles et al. Tables II, III) "
        "and write the results into an output folder.",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("workbench-demo"),
        help="output folder (default: ./workbench-demo)",
    )
    parser.add_argument(
        "--no-plots", action="store_true", help="skip the PNG figures (faster)"
    )
    add_json_flag(parser)
    parser.set_defaults(
        run=run,
        progress_message="demo: running the papers' examples and writing the results…",
    )


def run(args: argparse.Namespace) -> int:
    """Run the demo; returns the exit code."""
    from workbench.demo import run as demo_run
    from workbench.demo.summary_text import format_demo_summary
    from workbench.model.loading import load_robot

    robot = load_robot("puma560")
    summary = demo_run.run_demo(robot, args.out, plots=not args.no_plots)
    if args.json:
        print_json(summary)
    else:
        print(format_demo_summary(summary, args.out))
    return 0
