"""``workbench urdf from-dh``: a URDF from a standard DH table."""

from __future__ import annotations

import argparse
from pathlib import Path

from workbench.atomic_files import check_outputs, write_text_atomic
from workbench.cli._common import (
    add_json_flag,
    add_robot_argument,
    get_input_paths,
    load_robot_from_args,
    print_json,
)
from workbench.errors import InputError
from workbench.model.dh import DHTable
from workbench.model.urdf_generator import generate_urdf


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``urdf`` command group."""
    parser = commands.add_parser("urdf", help="URDF tools")
    actions = parser.add_subparsers(
        dest="urdf_command", metavar="ACTION", required=True
    )
    from_dh = actions.add_parser(
        "from-dh",
        help="generate a URDF from a DH table (JSON)",
        description="Generate a URDF from a standard DH table in JSON (SI units); "
        "see docs/interface.md for the format.",
    )
    from_dh.add_argument("table", type=Path, metavar="TABLE", help="DH table, JSON")
    from_dh.add_argument("--out", type=Path, required=True, help="URDF file to write")
    add_json_flag(from_dh)
    from_dh.set_defaults(run=run_from_dh, progress_message="urdf: generating the URDF…")
    srdf = actions.add_parser(
        "srdf",
        help="write the self-collision filter of a robot (SRDF disable_collisions)",
        description="The link pairs excluded from self-collision checks: links on "
        "the same or consecutive joints, links in contact at the zero pose "
        "(docs/collision.md), as SRDF <disable_collisions> lines.",
    )
    add_robot_argument(srdf)
    srdf.add_argument("--out", type=Path, help="SRDF file to write (default: stdout)")
    add_json_flag(srdf)
    srdf.set_defaults(
        run=run_srdf, progress_message="urdf: writing the collision filter…"
    )


def run_from_dh(args: argparse.Namespace) -> int:
    """Write the URDF; returns the exit code."""
    check_outputs([args.out], [args.table])
    table = DHTable.from_json(args.table)
    write_text_atomic(args.out, generate_urdf(table))
    if args.json:
        print_json(
            {
                "robot": table.name,
                "joints": table.nq,
                "tool_frame": table.tool_frame,
                "out": str(args.out),
            }
        )
    else:
        print(
            f"wrote {args.out} ({table.name}: {table.nq} joints, "
            f"tool frame {table.tool_frame})"
        )
    return 0


def run_srdf(args: argparse.Namespace) -> int:
    """Print or write the self-collision filter; returns the exit code.

    With ``--json``: ``{robot, out, disabled: [{link_a, link_b, reason}],
    srdf}`` (``out`` None when the SRDF is not written to a file; ``srdf`` is
    its text).
    """
    from workbench.collision import compute_self_collision_filter

    check_outputs([args.out], get_input_paths(args))
    robot = load_robot_from_args(args)
    if robot.collision_model.ngeoms == 0:
        raise InputError(f"robot {robot.name!r} has no collision geometry")
    pairs = compute_self_collision_filter(robot)
    text = pairs.to_srdf()
    if args.out is not None:
        write_text_atomic(args.out, text)
    if args.json:
        print_json(
            {
                "robot": robot.name,
                "out": None if args.out is None else str(args.out),
                "disabled": [d.as_dict() for d in pairs.disabled],
                "srdf": text,
            }
        )
    elif args.out is None:
        print(text, end="")
    else:
        print(f"wrote {args.out}")
    return 0
