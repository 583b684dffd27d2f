"""``workbench demo``: the papers' examples end to end."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from workbench.cli._common import add_json_flag, print_json
from workbench.demo.base_placement import format_base_placement
from workbench.demo.pick_and_place import format_pick_and_place
from workbench.demo.run import format_fish_cutting, run_demo
from workbench.model.loading import load_robot


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
    robot = load_robot("puma560")
    summary = run_demo(robot, args.out, plots=not args.no_plots)
    if args.json:
        print_json(summary)
    else:
        print(format_summary(summary, args.out))
    return 0


def format_summary(summary: dict[str, Any], out: Path) -> str:
    """The text ``workbench demo`` prints: its ``summary.json``, for a person."""
    verdict = "match" if summary["table2_matches"] else "DO NOT match"
    lines = [
        "Angeles et al. (1988), Table II reproduced by FK of Table III "
        "on the puma560 model (Table I):\n",
        summary["table2_markdown"],
        f"\nAll values rounded to the paper's two decimals {verdict} Table II.\n",
        format_pick_and_place(summary["pick_and_place"]),
        "",
        format_fish_cutting(summary["fish_cutting"]),
        format_base_placement(summary["base_placement"]),
    ]
    pages = summary.get("pages", {})
    if pages:
        lines.append(f"\n3D preview (open in a browser): {pages['preview']}")
        lines.append(f"Singularity report: {pages['singularity_report']}")
        lines.append(f"Fish cutting preview: {out / 'fishcut.html'}")
    lines.append(f"\nResults written to {out}/")
    return "\n".join(lines)
