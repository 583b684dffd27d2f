"""The demo's summary as text: what ``workbench demo`` prints for a person."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from workbench.demo.avoid import format_avoid
from workbench.demo.base_placement import format_base_placement
from workbench.demo.pick_and_place import format_pick_and_place
from workbench.demo.run import format_fish_cutting


def format_demo_summary(summary: dict[str, Any], out: Path) -> str:
    """The summary of :func:`~workbench.demo.run.run_demo` as text, for a person.

    Args:
        summary: What ``run_demo(robot, out)`` returned.
        out: The folder it wrote into.

    Returns:
        Table II compared, the pick-and-place, its path planned around an
        obstacle, the fish cutting and the base placement, the pages written
        and the folder, one paragraph each.
    """
    verdict = "match" if summary["table2_matches"] else "DO NOT match"
    lines = [
        "Angeles et al. (1988), Table II reproduced by FK of Table III "
        "on the puma560 model (Table I):\n",
        summary["table2_markdown"],
        f"\nAll values rounded to the paper's two decimals {verdict} Table II.\n",
        format_pick_and_place(summary["pick_and_place"]),
        format_avoid(summary["avoid"]),
        "",
        format_fish_cutting(summary["fish_cutting"]),
        format_base_placement(summary["base_placement"]),
    ]
    pages = summary.get("pages", {})
    if pages:
        lines.append(f"\n3D preview (open in a browser): {pages['preview']}")
        lines.append(f"Singularity report: {pages['singularity_report']}")
        lines.append(f"Fish cutting preview: {out / 'fishcut.html'}")
    if summary["avoid"].get("html"):
        lines.append(f"Planned around the obstacle: {summary['avoid']['html']}")
    lines.append(f"\nResults written to {out}/")
    return "\n".join(lines)


__all__ = ["format_demo_summary"]
