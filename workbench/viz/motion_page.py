"""The page of a planned motion in its scene (``motion plan --html``, the demo).

The motion plays as an animation with the scene drawn and contacts coloured,
the planner's inner waypoints as translucent ghosts (of the collision
geometry: what the planner checked, and light), the tool frame as a
triad, and, optionally, the tool path of another motion (e.g. the direct
spline the plan replaces) as a second line for comparison. The camera keeps
the default framing's distance but looks from the side away from the
obstacles, so that a shelf or a wall does not hide the arm.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import numpy.typing as npt

from workbench.collision import CollisionChecker, Scene
from workbench.model.robot import Robot
from workbench.trajectory.csv_io import JointTrajectorySamples
from workbench.viz import _legend
from workbench.viz.viewer import Viewer

#: Colour of the compared motion's tool path (RGB in [0, 1]).
COMPARED_PATH_COLOR = (0.85, 0.35, 0.1)
#: Camera elevation above the horizontal [rad].
ELEVATION = math.radians(35.0)


def write_motion_html(
    robot: Robot,
    scene: Scene | None,
    samples: JointTrajectorySamples,
    path: str | Path,
    *,
    waypoints: npt.ArrayLike | None = None,
    compared: npt.ArrayLike | None = None,
    compared_label: str = "direct motion",
    title: str | None = None,
) -> Path:
    """Write a self-contained page that plays a motion in its scene.

    Args:
        robot: The robot.
        scene: Obstacles in the base frame, or None.
        samples: The motion: ``t`` (K,) [s], ``q`` (K, nq) [rad].
        path: Output file (``.html``).
        waypoints: The planner's waypoints (M, nq) [rad]; the inner ones
            (without the first and the last) are drawn as ghosts.
        compared: Configurations (L, nq) [rad] of another motion whose tool
            path is drawn as a second line (:data:`COMPARED_PATH_COLOR`).
        compared_label: Its legend entry.
        title: Page title; default names the robot.

    Returns:
        ``path`` as a Path.

    Raises:
        DimensionError: If the configurations do not have ``robot.nq`` columns.
        InputError: If the times do not increase or the file cannot be written.
    """
    viewer = Viewer(
        robot,
        samples.q[0],
        title=title or f"workbench motion: {Path(robot.name).name}",
    )
    viewer.show_collisions(CollisionChecker(robot, scene))
    inner = np.zeros((0, robot.nq)) if waypoints is None else np.asarray(waypoints)
    inner = inner[1:-1]
    if len(inner):
        labels = [f"waypoint{k + 1}" for k in range(len(inner))]
        viewer.show_ghosts(
            inner, labels=labels, legend="waypoints", opacity=0.2, collision=True
        )
    viewer.show_frames()
    viewer.play_trajectory(samples.t, samples.q)
    if compared is not None:
        viewer.show_tool_path(compared, name="compared_path", color=COMPARED_PATH_COLOR)
        viewer.add_legend(
            "compared_path", _legend.line(COMPARED_PATH_COLOR, compared_label)
        )
    if scene is not None and scene.obstacles:
        _look_from_the_robots_side(viewer, scene)
    return viewer.save_html(path)


def _look_from_the_robots_side(viewer: Viewer, scene: Scene) -> None:
    """Keep the framing's distance, but look from the side away from the scene."""
    camera = viewer.get_camera()
    target = np.array(camera.target)
    distance = float(np.linalg.norm(np.array(camera.position) - target))
    centre = np.mean([o.placement.translation for o in scene.obstacles], axis=0)
    away = target - centre
    away[2] = 0.0
    if np.linalg.norm(away) < 1e-6:
        return
    direction = math.cos(ELEVATION) * away / np.linalg.norm(away)
    direction[2] = math.sin(ELEVATION)
    viewer.set_camera(target + distance * direction, target, fov_deg=camera.fov_deg)


__all__ = ["COMPARED_PATH_COLOR", "write_motion_html"]
