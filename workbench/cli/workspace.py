"""``workbench workspace``: reachability and dexterity maps, base placement, views.

``workspace map`` builds a map (:func:`workbench.workspace.build.build_map`);
``place``, ``view``, ``report`` and ``verify`` are registered by their own
modules (:mod:`workbench.cli._workspace_place`,
:mod:`workbench.cli._workspace_view`, :mod:`workbench.cli._workspace_verify`),
each with a ``register(subcommands)`` function.
"""

from __future__ import annotations

import argparse
import functools
import math
from pathlib import Path
from typing import TYPE_CHECKING

from workbench.atomic_files import check_output
from workbench.cli import _workspace_place, _workspace_verify, _workspace_view
from workbench.cli._collision import build_checker
from workbench.cli._common import (
    add_json_flag,
    add_robot_argument,
    bounded_float,
    bounded_int,
    finite_float,
    get_input_paths,
    load_robot_from_args,
    print_json,
)
from workbench.collision import read_scene
from workbench.errors import InputError
from workbench.workspace.grid import (
    DEFAULT_BLOCK_VOXELS,
    DEFAULT_ORIENTATIONS,
    DEFAULT_RESOLUTION,
    make_pose_grid,
)
from workbench.workspace.redundant import (
    DEFAULT_REDUNDANCY_SAMPLES,
    MAX_REDUNDANCY_SAMPLES,
)

if TYPE_CHECKING:
    from workbench.workspace.build import MapSummary

#: Largest ``--orientations`` (a voxel's row of every per-pose array).
MAX_ORIENTATIONS = 1_000_000
#: Largest ``--samples`` of a sampled map.
MAX_SAMPLES = 10**12
#: Largest ``--workers``.
MAX_WORKERS = 4096
#: Largest ``--block-voxels``.
MAX_BLOCK_VOXELS = 1 << 20


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``workspace`` command group and its subcommands."""
    parser = commands.add_parser(
        "workspace",
        help="reachability and dexterity maps of an arm, base placement",
        description="Workspace atlas: maps of which tool poses an arm reaches "
        "(voxels × orientations), how dexterously and how near a singularity; "
        "base placement for a task; the maps as pages.",
    )
    subcommands = parser.add_subparsers(
        dest="workspace", metavar="SUBCOMMAND", required=True
    )
    _register_map(subcommands)
    _workspace_place.register(subcommands)
    _workspace_view.register(subcommands)
    _workspace_verify.register(subcommands)


def _register_map(subcommands: argparse._SubParsersAction) -> None:
    parser = subcommands.add_parser(
        "map",
        help="build a reachability/dexterity map (Zarr) on local cores or a cluster",
        description="Solve every pose of a grid (voxels over the arm's reach × a "
        "set of tool orientations) in closed form and store per pose the "
        "branches reached and within limits, the dexterity |det J| and the "
        "distances to the singular loci of the best branch, per voxel the "
        "reachability; seven-axis arms of the SRS and Franka families in closed "
        "form at K values of their redundancy parameter (--redundancy-samples); "
        "arms without a closed form get a sampled map. Blocks of "
        "voxels run as Dask tasks on local threads (--workers) or an existing "
        "cluster (--scheduler). The map appears whole at --out when done; an "
        "interrupted build leaves OUT.partial, which the same command resumes.",
    )
    add_robot_argument(parser)
    parser.add_argument(
        "--resolution",
        type=bounded_float(10.0, "m"),
        default=DEFAULT_RESOLUTION,
        metavar="M",
        help=f"voxel edge [m] (default: {DEFAULT_RESOLUTION:g})",
    )
    parser.add_argument(
        "--orientations",
        type=bounded_int(1, MAX_ORIENTATIONS),
        default=DEFAULT_ORIENTATIONS,
        metavar="N",
        help="tool orientations per voxel, spread evenly over all rotations (or "
        f"over the cone of --cone) (default: {DEFAULT_ORIENTATIONS})",
    )
    parser.add_argument(
        "--cone",
        nargs=4,
        type=finite_float,
        metavar=("AXIS_X", "AXIS_Y", "AXIS_Z", "DEG"),
        help="only orientations whose tool z axis is within DEG degrees of "
        "AXIS (base frame), e.g. 0 0 -1 30 for a tool pointing down",
    )
    parser.add_argument(
        "--samples",
        type=bounded_int(1, MAX_SAMPLES),
        metavar="N",
        help="a sampled map of N random configurations (default for arms "
        "without a closed form)",
    )
    parser.add_argument(
        "--redundancy-samples",
        type=bounded_int(1, MAX_REDUNDANCY_SAMPLES),
        metavar="K",
        help="seven-axis arms (SRS, Franka): solve each pose in closed form at K "
        "values of the redundancy parameter (arm angle ψ or q7), the centres of "
        "K equal cells of its range; a pose is reachable when a branch at one of "
        f"them is within the limits (default: {DEFAULT_REDUNDANCY_SAMPLES})",
    )
    parser.add_argument(
        "--scene",
        type=Path,
        metavar="FILE",
        help="obstacles (scene JSON, base frame): the best branch must also be "
        "collision-free, and collision_free counts them",
    )
    where = parser.add_mutually_exclusive_group()
    where.add_argument(
        "--workers",
        type=bounded_int(1, MAX_WORKERS),
        metavar="N",
        help="local worker threads (default: every core)",
    )
    where.add_argument(
        "--scheduler",
        metavar="ADDR",
        help="address of a running Dask scheduler, e.g. tcp://10.0.0.5:8786 "
        "(OUT must be on a file system its workers share, at the same path)",
    )
    parser.add_argument(
        "--block-voxels",
        type=bounded_int(1, MAX_BLOCK_VOXELS),
        default=DEFAULT_BLOCK_VOXELS,
        metavar="N",
        help=f"voxels per task and chunk (default: {DEFAULT_BLOCK_VOXELS})",
    )
    parser.add_argument(
        "--out", required=True, type=Path, metavar="MAP.zarr", help="map to create"
    )
    add_json_flag(parser)
    parser.set_defaults(run=run_map, progress_message="workspace map: building…")


def _refuse_inside_a_store(path: Path) -> None:
    """Refuse a new map inside a Zarr store (a folder holding ``zarr.json``).

    Raises:
        InputError: Naming the store.
    """
    for folder in path.resolve().parents:
        if (folder / "zarr.json").is_file():
            raise InputError(f"cannot write {path}: it is inside the store {folder}")


def run_map(args: argparse.Namespace) -> int:
    """Build the map and print its summary; returns the exit code."""
    check_output(args.out, folder=True, inputs=get_input_paths(args))
    _refuse_inside_a_store(args.out)
    robot = load_robot_from_args(args)
    scene = None
    if args.scene is not None:
        scene = read_scene(args.scene)
        build_checker(robot, scene, explicit=True)  # no collision geometry: error
    cone = None
    if args.cone is not None:
        *axis, degrees = args.cone
        cone = (axis, math.radians(degrees))
    grid = make_pose_grid(
        robot, resolution=args.resolution, orientations=args.orientations, cone=cone
    )
    from workbench.workspace.build import build_map  # (Zarr, Dask: for a map only)

    summary = build_map(
        robot,
        grid,
        args.out,
        workers=args.workers,
        scheduler=args.scheduler,
        scene=scene,
        samples=args.samples,
        block_voxels=args.block_voxels,
        redundancy_samples=args.redundancy_samples,
        progress=functools.partial(
            args.progress.count, unit="blocks", label="workspace map"
        ),
    )
    args.progress.finish()
    if args.json:
        print_json(summary.as_dict())
        return 0
    _print_summary(summary)
    return 0


def _print_summary(summary: MapSummary) -> None:
    kind = f"sampled ({summary.samples} samples)" if summary.sampled else "exact"
    if summary.redundancy_samples is not None:
        kind = (
            f"exact at {summary.redundancy_samples} values of the redundancy "
            "parameter (closed form)"
        )
    print(f"robot             {summary.robot}")
    print(f"map               {kind}, {summary.store}")
    print(
        f"poses             {summary.poses} = {summary.voxels} voxels × "
        f"{summary.orientations} orientations"
    )
    print(f"reachable         {100 * summary.reachable_fraction:.2f} % of the poses")
    resumed = summary.blocks - summary.blocks_computed
    print(
        f"blocks            {summary.blocks}"
        + (f" ({resumed} done by an earlier run)" if resumed else "")
    )
    print(
        f"time              {summary.seconds:.2f} s "
        f"({summary.poses_per_second / 1e6:.2f} M poses/s)"
    )
