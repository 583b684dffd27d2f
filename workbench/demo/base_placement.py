"""A coarse workspace map of the PUMA and the base placement of Angeles' cell.

For ``workbench demo``: the map of the ``puma560`` model (10 cm voxels × 64
orientations over its reach, in memory), then where to put its base so that it
reaches both poses of Angeles' Table III (the forward kinematics of the
printed joint values), on a 5 cm lattice over a 1.2 m × 1.2 m square around
the paper's base, yaw in 15° steps
(:func:`workbench.workspace.placement.place_base`), and the paper's own base
evaluated the same way. With plots, the map's reachability in three
horizontal slices (``workspace_slices.png``).
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from workbench import paper_data
from workbench.model.robot import Robot
from workbench.workspace.grid import default_bounds
from workbench.workspace.placement import place_base
from workbench.workspace.task_map import TaskMap, build_task_map

#: The coarse map: voxel edge [m] and orientations per voxel.
MAP_RESOLUTION = 0.10
MAP_ORIENTATIONS = 64
#: Where the base may go: ``(xmin, xmax, ymin, ymax)`` [m] around the paper's base.
REGION = (-0.6, 0.6, -0.6, 0.6)
#: Spacing of the candidate positions [m] and step of their yaws [rad].
RESOLUTION = 0.05
YAW_STEP = math.radians(15.0)
#: Placements kept.
TOP = 5
#: Heights of the figure's slices [m], base frame.
SLICE_HEIGHTS = (-0.3, 0.0, 0.3)
#: The figure written with plots.
FIGURE = "workspace_slices.png"


def run_base_placement_demo(
    robot: Robot, out_dir: Path, *, plots: bool = True
) -> dict[str, Any]:
    """The coarse map and the base placement of Table III's two poses.

    Args:
        robot: Angeles' PUMA (``puma560``).
        out_dir: Folder of the figure (exists).
        plots: Write the figure of the map's reachability slices.

    Returns:
        A JSON-ready summary: ``map`` (resolution [m], orientations, voxels,
        reachable fraction of the poses, seconds), ``region`` [m],
        ``candidates``, ``placements`` (best first, as ``Placement.as_dict``),
        ``paper_base`` (the base at the world origin), ``seconds`` of the
        placement, and ``figure`` with plots.
    """
    started = time.perf_counter()
    atlas = build_task_map(
        robot,
        default_bounds(robot)[:, 2],
        resolution=MAP_RESOLUTION,
        orientations=MAP_ORIENTATIONS,
    )
    built = time.perf_counter()
    poses = np.array(
        [
            robot.fk(np.deg2rad(q)).homogeneous
            for q in (paper_data.ANGELES_PICK_Q_DEG, paper_data.ANGELES_PLACE_Q_DEG)
        ]
    )
    placements = place_base(
        robot,
        poses,
        region=REGION,
        resolution=RESOLUTION,
        yaw_step=YAW_STEP,
        map=atlas,
        top=TOP,
    )
    (paper,) = place_base(robot, poses, mounts=[(0.0, 0.0, 0.0, 0.0)])
    done = time.perf_counter()
    usable = atlas["branches"] > 0
    side = round((REGION[1] - REGION[0]) / RESOLUTION) + 1
    summary: dict[str, Any] = {
        "map": {
            "resolution": MAP_RESOLUTION,
            "orientations": MAP_ORIENTATIONS,
            "voxels": atlas.grid.voxel_count,
            "reachable_fraction": float(np.mean(usable)),
            "seconds": built - started,
        },
        "region": list(REGION),
        "candidates": side * side * round(2.0 * math.pi / YAW_STEP),
        "placements": [p.as_dict() for p in placements],
        "paper_base": paper.as_dict(),
        "seconds": done - built,
    }
    if plots:
        summary["figure"] = str(_plot_slices(robot, atlas, out_dir / FIGURE))
    return summary


def _plot_slices(robot: Robot, atlas: TaskMap, path: Path) -> Path:
    """The reachability of each voxel in horizontal slices, as a PNG."""
    from workbench.plots.workspace import VoxelField, plot_horizontal_slices

    reachability = np.mean(atlas["branches"] > 0, axis=1)  # (V,) [1]
    field = VoxelField(
        "reachability",
        "reachability [fraction of orientations]",
        np.where(reachability > 0.0, reachability, np.nan),  # grey: none
        0.0,
        1.0,
    )
    title = (
        f"{robot.name}: share of {MAP_ORIENTATIONS} tool orientations reached in "
        f"each {100 * MAP_RESOLUTION:g} cm voxel, seen from above (base frame)"
    )
    plot_horizontal_slices(atlas.grid, field, SLICE_HEIGHTS, path, title=title)
    return path


def format_base_placement(summary: dict[str, Any]) -> str:
    """Short human summary of :func:`run_base_placement_demo`."""
    coarse = summary["map"]
    lines = [
        f"Base placement for Table III's poses: coarse map {coarse['voxels']} voxels "
        f"× {coarse['orientations']} orientations ({coarse['seconds']:.2f} s), "
        f"{summary['candidates']} candidate bases ({summary['seconds']:.2f} s)"
    ]
    for p in summary["placements"][:3]:
        lines.append(
            f"  x {p['x']:+.2f} m, y {p['y']:+.2f} m, yaw "
            f"{math.degrees(p['yaw']):5.1f} deg: worst |det J| "
            f"{p['min_dexterity']:.4f} m³, worst margin "
            f"{p['min_singularity_margin']:.1f}"
        )
    paper = summary["paper_base"]
    lines.append(
        f"  the paper's base: worst |det J| {paper['min_dexterity']:.4f} m³, "
        f"worst margin {paper['min_singularity_margin']:.1f}"
    )
    return "\n".join(lines)
