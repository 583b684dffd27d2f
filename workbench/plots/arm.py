"""Stick figures of an arm on matplotlib 3D axes.

The figure joins the origins of the DH frames ``frame0`` … ``frame{nq}`` of
the generated PUMA URDFs (shoulder offset, upper arm, forearm, wrist), or, for
an arm without them, the joint origins, then the tool frame. A short segment
along the x axis of ``frame4`` shows the wrist: its flip twin turns it by π.

:func:`plot_arm` follows matplotlib's convention (``ax=`` optional, returns the
Figure, writes a file only when ``path`` is given); matplotlib is imported when
it is called, so importing this module stays cheap.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from workbench.model.robot import Robot

if TYPE_CHECKING:
    from matplotlib.figure import Figure

FloatArray = npt.NDArray[np.float64]

#: Legend label of the tool frame origin (the red star).
TOOL_LABEL = "tool frame origin"


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
    robot: Robot,
    q: npt.ArrayLike,
    path: str | Path | None = None,
    *,
    ax: Any = None,
    color: str = "tab:blue",
    label: str | None = None,
    axis_frame: str = "frame4",
    axis_length: float = 0.08,
) -> Figure:
    """Draw the arm at ``q`` as a stick figure on matplotlib 3D axes.

    Args:
        robot: Any robot.
        q: Configuration, shape (nq,) [rad].
        path: PNG file to write; None writes nothing.
        ax: 3D axes (``projection="3d"``) to draw on, keeping its limits; None
            makes a new Figure with one 3D axes scaled equally around the arm.
        color: Matplotlib colour of links and joints.
        label: Legend label of the links.
        axis_frame: Frame whose x axis is drawn (skipped if not in the model).
        axis_length: Length of that segment [m]; 0 to skip it.

    Returns:
        The Figure of ``ax``. It holds the links (line), the joints (markers),
        the tool (red star, labelled :data:`TOOL_LABEL`) and the x axis of
        ``axis_frame`` (orange line, labelled ``"x axis of frame4"``); the
        star and the axis are labelled once per axes, so that ``ax.legend()``
        names each once however many arms are drawn. A new Figure gets a
        title and that legend.
    """
    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=(5.0, 5.0)).add_subplot(projection="3d")
        new_axes = True
    else:
        new_axes = False
    p = compute_arm_points(robot, q)
    ax.plot(p[:, 0], p[:, 1], p[:, 2], "-", color=color, lw=3, label=label)
    ax.plot(p[:-1, 0], p[:-1, 1], p[:-1, 2], "o", color=color, ms=4)
    tool = _first_label(ax, TOOL_LABEL)
    ax.plot(p[-1:, 0], p[-1:, 1], p[-1:, 2], "*", color="tab:red", ms=10, label=tool)
    if axis_length > 0.0 and axis_frame in robot.frame_names:
        frame = robot.fk(q, axis_frame)
        ends = np.array([frame.translation, frame * np.array([axis_length, 0, 0])])
        wrist = _first_label(ax, f"x axis of {axis_frame}")
        ax.plot(*ends.T, "-", color="tab:orange", lw=2, label=wrist)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    if new_axes:
        set_equal_axes(ax, p)
        ax.set_title(f"{robot.name}, base frame", fontsize=10)
        ax.legend(loc="upper left", fontsize=8)
    fig = ax.get_figure()
    if path is not None:
        from workbench.plots.trajectory import save_figure

        save_figure(fig, path)
    return fig


def _first_label(ax: Any, label: str) -> str:
    """``label``, or ``"_"`` + it (left out of legends) when ``ax`` has it already."""
    taken = {line.get_label() for line in ax.lines}
    return "_" + label if label in taken else label


def set_equal_axes(ax: Any, points: npt.ArrayLike, *, margin: float = 0.05) -> None:
    """Give a 3D axes equal scales on x, y, z around ``points`` (K, 3) [m]."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    centre = (p.max(axis=0) + p.min(axis=0)) / 2.0
    half = float(np.max(p.max(axis=0) - p.min(axis=0))) / 2.0 + margin
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre, strict=True):
        setter(c - half, c + half)
    ax.set_box_aspect((1.0, 1.0, 1.0))
