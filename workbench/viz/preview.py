"""One-call 3D previews of joint trajectories, for ``demo`` and ``fishcut``."""

from __future__ import annotations

from pathlib import Path

from workbench.model.robot import Robot
from workbench.trajectory.csv_io import JointTrajectorySamples
from workbench.viz.viewer import Viewer


def write_trajectory_html(
    robot: Robot,
    samples: JointTrajectorySamples,
    path: str | Path,
    *,
    title: str | None = None,
    color_by_singularity: bool = True,
) -> Path:
    """Write a self-contained HTML page that plays a joint trajectory.

    The page works offline: the arm is animated (play, pause and scrub under
    "Open Controls" → Animations), the tool path is drawn as a line, the tool
    frame as a triad, and the arm is coloured by its distance to the nearest
    singularity.

    Args:
        robot: The robot the trajectory is for.
        samples: ``samples.t`` shape (K,) [s], ``samples.q`` shape (K, nq) [rad]
            (e.g. from :func:`workbench.trajectory.csv_io.read_trajectory_csv`).
        path: Output file (``.html``).
        title: Page title; default names the robot.
        color_by_singularity: Colour the arm red (singular) to green (far).

    Returns:
        ``path`` as a Path.

    Raises:
        DimensionError: If ``samples.q`` does not have ``robot.nq`` columns.
        InputError: If the times do not increase or the file cannot be written.
        URDFLoadError: If the robot's meshes cannot be drawn.
    """
    viewer = Viewer(
        robot,
        samples.q[0] if len(samples.q) else None,
        color_by_singularity=color_by_singularity,
        title=title or f"workbench trajectory preview: {robot.name}",
    )
    viewer.show_frames()
    viewer.play_trajectory(samples.t, samples.q)
    return viewer.save_html(path)
