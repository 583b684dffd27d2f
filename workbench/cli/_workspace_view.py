"""``workbench workspace view`` and ``workspace report``: a map as a page.

``view MAP.zarr --html FILE`` writes the Meshcat page of the map's voxels
(:func:`workbench.viz.workspace_view.write_workspace_view`), ``report MAP.zarr
--out FILE.html`` the HTML report
(:func:`workbench.reports.workspace_report.build_workspace_report`). The
``workspace`` group (``workbench/cli/workspace.py``) calls :func:`register`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from workbench.atomic_files import check_outputs, write_text_atomic
from workbench.cli._common import (
    add_json_flag,
    add_robot_argument,
    finite_float,
    get_input_paths,
    load_robot_from_args,
    print_json,
)


def register(commands: argparse._SubParsersAction) -> None:
    """Add ``view`` and ``report`` to the ``workspace`` group's subcommands."""
    view = commands.add_parser(
        "view",
        help="3D page of a map: coloured voxels in z layers, slice slider, the arm",
        description="Write a self-contained Meshcat page (works offline) of a "
        "workspace map: each reached voxel a point coloured by its reachability "
        "or best dexterity (viridis; unreached voxels hidden), one scene node "
        "per z layer, a slider that cuts the map from above, the arm in a "
        "reference configuration.",
    )
    view.add_argument("map", type=Path, metavar="MAP.zarr", help="the map folder")
    view.add_argument(
        "--html", required=True, type=Path, metavar="FILE.html", help="page to write"
    )
    view.add_argument(
        "--measure",
        choices=("reachability", "dexterity"),
        default="reachability",
        help="voxel colour: fraction of orientations reached [1], or best "
        "manipulability over the orientations [m³] (default: reachability)",
    )
    view.add_argument(
        "--no-cut-away",
        dest="cut_away",
        action="store_false",
        help="start with every voxel shown (default: the half y > 0 hidden, so "
        "the section through the base axis and the arm show)",
    )
    add_robot_argument(
        view,
        help_text="the map's robot when it is no catalog name: path to its .urdf "
        "(default: the map's robot attribute)",
    )
    view.set_defaults(run=run_view, progress_message="workspace view: drawing…")

    report = commands.add_parser(
        "report",
        help="HTML report of a map: key numbers, slices, sections, histograms",
        description="Write a self-contained HTML report (figures embedded) of a "
        "workspace map: metadata, reachable and dexterous volume, horizontal "
        "slices of reachability and best dexterity, a vertical section through "
        "the base axis, histograms and the singular regions.",
    )
    report.add_argument("map", type=Path, metavar="MAP.zarr", help="the map folder")
    report.add_argument(
        "--out", required=True, type=Path, metavar="FILE.html", help="report to write"
    )
    report.add_argument(
        "--heights",
        nargs="+",
        type=finite_float,
        metavar="Z",
        help="heights of the horizontal slices [m] (default: six spread over the "
        "reached layers)",
    )
    add_json_flag(report)
    report.set_defaults(
        run=run_report, progress_message="workspace report: computing figures…"
    )


def run_view(args: argparse.Namespace) -> int:
    """Write the 3D page of a map; returns the exit code."""
    from workbench.viz.workspace_view import write_workspace_view
    from workbench.workspace.store import open_map

    check_outputs([args.html], [*get_input_paths(args), args.map])
    workspace_map = open_map(args.map)
    robot = load_robot_from_args(args) if args.robot is not None else None
    path = write_workspace_view(
        workspace_map,
        args.html,
        measure=args.measure,
        robot=robot,
        cut_away=args.cut_away,
    )
    print(f"wrote {path} ({path.stat().st_size / 1e6:.2f} MB)")
    return 0


def run_report(args: argparse.Namespace) -> int:
    """Write the HTML report of a map; returns the exit code."""
    from workbench.reports.workspace_report import build_workspace_report
    from workbench.workspace.store import open_map

    check_outputs([args.out], [*get_input_paths(args), args.map])
    workspace_map = open_map(args.map)
    report = build_workspace_report(workspace_map, heights=args.heights)
    write_text_atomic(args.out, report.html)
    summary = {"out": str(args.out), **report.summary}
    if args.json:
        print_json(summary)
        return 0
    print(f"wrote {args.out} ({args.out.stat().st_size / 1e6:.2f} MB)")
    print(
        f"reachable volume {summary['reachable_volume_m3']:.4g} m³ "
        f"({summary['reachable_voxels']} of {summary['voxels']} voxels); fully "
        f"dexterous {summary['dexterous_volume_m3']:.4g} m³"
    )
    return 0
