"""Angeles' cell with an obstacle on the paper's path, planned around (the demo).

Table III's pick-and-place (the normal spline, T = 10 s) in
:func:`workbench.collision.get_angeles_obstacle_scene`: the pedestal, the pick
table and a 10 cm cube where the straight joint motion puts the tool halfway.
The spline runs through the cube (and dips into the pick table,
``docs/collision.md``); :func:`workbench.motion.plan_around` plans a motion
between the same pick and place around them, time-scaled within the joint
limits and verified on the exact meshes. The PUMA's URDF gives no acceleration
limits, so the demo assumes :data:`ACCELERATION_LIMIT` for every joint (the
speed limits are the model's). Written: the planned motion as the trajectory
CSV (``avoid.csv``), and with plots the before/after figure
(``avoid_before_after.png``) and the page of the planned motion in its scene,
with the spline's tool path beside it (``avoid.html``).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from workbench import paper_data
from workbench.collision import get_angeles_obstacle_scene
from workbench.model.robot import Robot
from workbench.motion import plan_around
from workbench.trajectory import pick_and_place
from workbench.trajectory.csv_io import write_trajectory_csv

#: Acceleration limit assumed for every joint [rad/s²] (the URDF gives none).
ACCELERATION_LIMIT = 4.0
#: Seed of the planner.
SEED = 0
#: Planning budget [s]: generous, as the path depends on the seed only and a
#: first call on a loaded machine spends part of it loading compiled kernels.
TIME_LIMIT = 10.0
#: Sample rate of ``avoid.csv`` [Hz].
CSV_RATE_HZ = 100.0
#: Files written (the figure and the page with plots only).
FILES = {
    "csv": "avoid.csv",
    "figure": "avoid_before_after.png",
    "html": "avoid.html",
}


def run_avoid_demo(
    robot: Robot, out_dir: Path, *, plots: bool = True
) -> dict[str, Any]:
    """Table III's spline in the obstacle scene, and the motion planned around.

    Args:
        robot: Angeles' PUMA (``puma560``).
        out_dir: Output folder (exists).
        plots: Also write the figure and the page.

    Returns:
        A JSON-ready summary: ``scene``, ``obstacle: {position, size}`` [m],
        ``acceleration_limit`` [rad/s²], ``seed``, the keys of
        :meth:`workbench.motion.PlannedAround.as_dict`, ``direct_contacts``
        (``[{body_a, body_b, distance, t, t_start, t_end}]``, the spline's),
        ``obstacle_penetration`` [m] (the spline's deepest into the cube),
        ``seconds`` (planning around, including the spline's check), ``csv``,
        and with plots ``figure`` and ``html``.
    """
    limited = robot.with_limits(acceleration_limit=ACCELERATION_LIMIT)
    scene = get_angeles_obstacle_scene(limited)
    direct = pick_and_place(
        limited,
        np.deg2rad(paper_data.ANGELES_PICK_Q_DEG),
        np.deg2rad(paper_data.ANGELES_PLACE_Q_DEG),
        paper_data.ANGELES_DURATION,
    )
    started = time.perf_counter()
    record = plan_around(limited, scene, direct, seed=SEED, time_limit=TIME_LIMIT)
    seconds = time.perf_counter() - started
    files = {key: out_dir / name for key, name in FILES.items()}
    cube = next(o for o in scene.obstacles if o.name == "obstacle")
    summary: dict[str, Any] = {
        "scene": scene.name,
        "obstacle": {"position": cube.placement.translation, "size": list(cube.size)},
        "acceleration_limit": ACCELERATION_LIMIT,
        "seed": SEED,
        **record.as_dict(),
        "direct_contacts": [c.as_dict() for c in record.direct_clearance.contacts],
        "obstacle_penetration": record.get_penetration("obstacle"),
        "seconds": seconds,
        "csv": None,
    }
    motion = record.trajectory
    if motion is None:
        return summary
    samples = motion.sample_uniform(CSV_RATE_HZ)
    write_trajectory_csv(files["csv"], samples, joint_names=limited.joint_names)
    summary["csv"] = str(files["csv"])
    if plots and record.needed:
        from workbench.plots.motion import plot_planned_around
        from workbench.viz import write_motion_html

        plot_planned_around(record, files["figure"], scene=scene)
        write_motion_html(
            limited,
            scene,
            samples,
            files["html"],
            waypoints=record.waypoints,
            compared=direct.sample_uniform(CSV_RATE_HZ).q,
            compared_label="Table III's spline (collides)",
            title="Angeles et al. (1988) Sec. V with an obstacle: planned around, "
            f"{limited.name}",
        )
        summary["figure"] = str(files["figure"])
        summary["html"] = str(files["html"])
    return summary


def format_avoid(summary: dict[str, Any]) -> str:
    """Short human summary of :func:`run_avoid_demo`."""
    lines = [
        f"Obstacle on the path (scene {summary['scene']}, a "
        f"{100 * summary['obstacle']['size'][0]:g} cm cube): Table III's spline "
        f"goes {1e3 * summary['obstacle_penetration']:.1f} mm into it "
        f"({len(summary['direct_contacts'])} contact interval(s), deepest "
        f"{1e3 * summary['direct_penetration']:.1f} mm)"
    ]
    if not summary["solved"]:
        lines.append(f"  no motion around it: {summary['reason']}: {summary['detail']}")
        return "\n".join(lines)
    lines.append(
        f"  planned around (seed {summary['seed']}, acceleration limit "
        f"{summary['acceleration_limit']:g} rad/s² assumed): "
        f"{len(summary['waypoints'])} waypoints, {summary['duration']:.2f} s "
        f"(the spline: {summary['direct_duration']:g} s), min clearance "
        f"{1e3 * summary['min_clearance']:.1f} mm on the exact meshes, "
        f"{summary['seconds']:.2f} s"
    )
    return "\n".join(lines)


__all__ = ["ACCELERATION_LIMIT", "FILES", "format_avoid", "run_avoid_demo"]
