"""``workbench workspace verify``: check a whole map, upgrade an old one.

``verify MAP.zarr`` reads every chunk of the map and checks it against the
map's manifest, every value against its range and the grid against its
attributes (:func:`workbench.workspace.verify.verify_map`); ``--upgrade``
writes the manifest of a map of format version 1 that passes. The
``workspace`` group (``workbench/cli/workspace.py``) calls :func:`register`.
"""

from __future__ import annotations

import argparse
import functools
from pathlib import Path

from workbench.cli._common import add_json_flag, print_json


def register(commands: argparse._SubParsersAction) -> None:
    """Add ``verify`` to the ``workspace`` group's subcommands."""
    verify = commands.add_parser(
        "verify",
        help="check every chunk of a map against its checksums (upgrade old maps)",
        description="Check a whole workspace map: its attributes against the "
        "schema and its manifest, the metadata of every array, every chunk "
        "against its checksum, every value against its range, the voxel centres "
        "and orientations against those re-derived from its attributes. Exit 0 "
        "if whole, 2 with one line naming the first damage.",
    )
    verify.add_argument("map", type=Path, metavar="MAP.zarr", help="the map folder")
    verify.add_argument(
        "--upgrade",
        action="store_true",
        help="a map of format version 1 (no checksums) that passes gets its "
        "manifest and becomes version 2, in place",
    )
    add_json_flag(verify)
    verify.set_defaults(run=run_verify, progress_message="workspace verify: reading…")


def run_verify(args: argparse.Namespace) -> int:
    """Check the map and print what was checked; returns the exit code."""
    from workbench.workspace.verify import verify_map

    check = verify_map(
        args.map,
        upgrade=args.upgrade,
        progress=functools.partial(
            args.progress.count, unit="chunks", label="workspace verify"
        ),
    )
    args.progress.finish()
    if args.json:
        print_json(check.as_dict())
        return 0
    how = "checksums" if check.checksums else "done flags (format version 1)"
    print(f"map               {check.store}: whole")
    print(f"format version    {check.format_version}")
    print(f"checked by        {how}")
    print(
        f"chunks            {check.chunks} in {check.arrays} arrays "
        f"({check.chunks_stored} stored, {check.bytes / 1e6:.2f} MB)"
    )
    print(f"values            {check.values}, each within its range")
    print("grid              positions and orientations re-derived, bitwise")
    if check.upgraded:
        print("upgraded          manifest written: the map is format version 2")
    elif not check.checksums:
        print(
            "advice            'workbench workspace verify --upgrade "
            f"{check.store}' adds the checksums"
        )
    return 0
