"""Stick figures of an arm for matplotlib 3D axes (no matplotlib import here).

The figure joins the origins of the DH frames ``frame0`` … ``frame{nq}`` of
the generated PUMA URDFs (shoulder offset, upper arm, forearm, wrist), or, for
an arm without them, the joint origins, then the tool frame. A short segment
along the x axis of ``frame4`` shows the wrist: its flip twin turns it by π.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]


def compute_arm_points(robot: Robot, q: npt.ArrayLike) -> FloatArray:
    """Points of the stick figure at configuration ``q``.

    Args:
        robot: Any robot.
        q: Configuration, shape (nq,) [rad].

    Returns:
        Shape (K, 3) [m], base frame: the DH frame origins ``frame0`` …
        ``frame{nq}`` when the model has them, else the origins of the base
        and of every joint; then the tool frame origin if it differs from the
        last point.
    """
    names = set(robot.frame_names)
    dh_frames = [f"frame{i}" for i in range(robot.nq + 1)]
    if all(name in names for name in dh_frames):
        points = [robot.fk(q, name).translation for name in dh_frames]
    else:
        robot.fk(q)  # updates robot.data.oMi
        points = [np.zeros(3)] + [m.translation.copy() for m in robot.data.oMi[1:]]
    tool = robot.fk(q).translation
    if np.linalg.norm(points[-1] - tool) > 1e-12:
        points.append(tool)
    return np.array(points)


def plot_arm(
    ax: Any,
    robot: Robot,
    q: npt.ArrayLike,
    *,
    color: str = "tab:blue",
    label: str | None = None,
    axis_frame: str = "frame4",
    axis_length: float = 0.08,
) -> list[Any]:
    """Draw the arm at ``q`` on a matplotlib 3D axes as a stick figure.

    Args:
        ax: Axes made with ``projection="3d"``.
        robot: Any robot.
        q: Configuration, shape (nq,) [rad].
        color: Matplotlib colour of links and joints.
        label: Legend label of the links.
        axis_frame: Frame whose x axis is drawn (skipped if not in the model).
        axis_length: Length of that segment [m]; 0 to skip it.

    Returns:
        The artists drawn: links (line), joints (markers), tool (marker), and
        the x axis of ``axis_frame`` (line) when drawn.
    """
    p = compute_arm_points(robot, q)
    links = ax.plot(p[:, 0], p[:, 1], p[:, 2], "-", color=color, lw=3, label=label)
    joints = ax.plot(p[:-1, 0], p[:-1, 1], p[:-1, 2], "o", color=color, ms=4)
    tool = ax.plot(p[-1:, 0], p[-1:, 1], p[-1:, 2], "*", color="tab:red", ms=10)
    artists = [*links, *joints, *tool]
    if axis_length > 0.0 and axis_frame in robot.frame_names:
        frame = robot.fk(q, axis_frame)
        ends = np.array([frame.translation, frame * np.array([axis_length, 0, 0])])
        artists += ax.plot(*ends.T, "-", color="tab:orange", lw=2)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    return artists


def set_equal_axes(ax: Any, points: npt.ArrayLike, *, margin: float = 0.05) -> None:
    """Give a 3D axes equal scales on x, y, z around ``points`` (K, 3) [m]."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    centre = (p.max(axis=0) + p.min(axis=0)) / 2.0
    half = float(np.max(p.max(axis=0) - p.min(axis=0))) / 2.0 + margin
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre, strict=True):
        setter(c - half, c + half)
    ax.set_box_aspect((1.0, 1.0, 1.0))
