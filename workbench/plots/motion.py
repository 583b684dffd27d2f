"""A motion planned around the scene next to the direct one it replaces (matplotlib).

:func:`plot_planned_around` draws a :class:`~workbench.motion.PlannedAround`
record: on the left the tool paths in 3D (base frame) with the scene's boxes
and cylinders as wire frames, the direct motion dashed with its contacts
marked, the planned one solid with its waypoints; on the right every joint
against time, both motions, from t = 0. Loaded on first use (it imports
matplotlib), like :mod:`workbench.plots.trajectory`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from matplotlib.figure import Figure

from workbench.collision.scene import Obstacle, Scene
from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.motion.around import PlannedAround
from workbench.plots.arm import set_equal_axes
from workbench.plots.trajectory import save_figure

FloatArray = npt.NDArray[np.float64]

#: Samples of each motion drawn.
SAMPLES = 600
DIRECT_COLOR = "tab:orange"
PLANNED_COLOR = "tab:blue"
CONTACT_COLOR = "tab:red"


def plot_planned_around(
    record: PlannedAround,
    path: str | Path | None = None,
    *,
    scene: Scene | None = None,
    fig: Figure | None = None,
    title: str | None = None,
) -> Figure:
    """Direct vs planned: tool paths in 3D and joint angles over time.

    Args:
        record: A solved record of :func:`workbench.motion.plan_around`
            whose direct motion collides (``needed``).
        path: Figure file to write (``.png``, ...); None writes nothing.
        scene: The scene to draw (boxes and cylinders as wire frames).
        fig: Figure to draw into (cleared first); None makes a new one.
        title: Figure title; default names the robot and the numbers.

    Returns:
        The Figure: one 3D axes and one panel per joint, with legends.

    Raises:
        InputError: If no motion was planned (``needed`` False or not
            ``solved``).
    """
    planned = record.trajectory
    if not record.needed or planned is None:
        raise InputError(
            "plot_planned_around needs a record whose direct motion collides "
            "and a planned motion (needed and solved)"
        )
    robot = record.direct.robot
    direct = record.direct
    t_direct = np.linspace(0.0, direct.duration, SAMPLES)
    t_planned = np.linspace(0.0, planned.duration, SAMPLES)
    q_direct = direct.sample(t_direct)[0]
    q_planned = planned.sample(t_planned)[0]
    p_direct = _tool_points(robot, q_direct)
    p_planned = _tool_points(robot, q_planned)
    p_waypoints = _tool_points(robot, record.waypoints)
    in_contact = np.zeros(SAMPLES, dtype=bool)
    for contact in record.direct_clearance.contacts:
        in_contact |= (t_direct >= contact.t_start) & (t_direct <= contact.t_end)

    if fig is None:
        fig = Figure(figsize=(14.0, 7.5), layout="constrained")
    else:
        fig.clear()
    halves: Any = fig.subfigures(1, 2, width_ratios=(1.1, 1.0))
    left, right = halves[0], halves[1]
    ax = left.add_subplot(projection="3d")
    if scene is not None:
        for obstacle in scene.obstacles:
            _draw_obstacle(ax, obstacle)
    ax.plot(*p_direct.T, "--", color=DIRECT_COLOR, lw=1.8, label="direct spline")
    ax.plot(
        *p_direct[in_contact].T,
        "o",
        color=CONTACT_COLOR,
        ms=2.5,
        label=f"direct spline in contact ({1e3 * record.penetration:.0f} mm deep)",
    )
    ax.plot(*p_planned.T, "-", color=PLANNED_COLOR, lw=2.2, label="planned around")
    ax.plot(*p_waypoints.T, "s", color=PLANNED_COLOR, ms=5, label="waypoints")
    ax.plot(*p_direct[:1].T, "^", color="black", ms=9, label="pick (start)")
    ax.plot(*p_direct[-1:].T, "v", color="black", ms=9, label="place (goal)")
    set_equal_axes(ax, np.vstack([p_direct, p_planned]))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title("tool frame origin, base frame", fontsize=10)
    ax.legend(loc="upper left", fontsize=8)

    axes = right.subplots(robot.nq, 1, sharex=True, squeeze=False)[:, 0]
    for joint, axj in enumerate(axes):
        axj.plot(
            t_direct,
            np.rad2deg(q_direct[:, joint]),
            "--",
            color=DIRECT_COLOR,
            label="direct spline",
        )
        axj.plot(
            t_planned,
            np.rad2deg(q_planned[:, joint]),
            "-",
            color=PLANNED_COLOR,
            label="planned around",
        )
        times = getattr(planned, "times", None)
        if times is not None:
            axj.plot(
                times,
                np.rad2deg(record.waypoints[:, joint]),
                "s",
                color=PLANNED_COLOR,
                ms=3,
                label="waypoints",
            )
        axj.set_ylabel(f"{robot.joint_names[joint]}\n[deg]", fontsize=9)
        axj.grid(alpha=0.3)
    axes[0].legend(loc="best", fontsize=8, ncols=3)
    axes[-1].set_xlabel("t [s]")
    right.suptitle("joint angles", fontsize=10)
    fig.suptitle(
        title
        or f"{robot.name}: the direct spline ({direct.duration:g} s) collides; "
        f"planned around: {len(record.waypoints)} waypoints, "
        f"{planned.duration:.2f} s, min clearance {1e3 * record.clearance:.1f} mm"
    )
    if path is not None:
        save_figure(fig, path)
    return fig


def _tool_points(robot: Robot, q: npt.ArrayLike) -> FloatArray:
    """Tool frame origins (K, 3) [m] of configurations (K, nq)."""
    return np.array([robot.fk(qk).translation for qk in np.asarray(q)])


def _draw_obstacle(ax: Any, obstacle: Obstacle) -> None:
    """A box's twelve edges or a cylinder's two rims and four sides, grey."""
    pose = obstacle.placement
    style = {"color": "0.45", "lw": 0.9}
    if obstacle.shape == "box":
        half = np.asarray(obstacle.size, dtype=np.float64) / 2.0
        corners = np.array(
            [[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
        )
        for a in range(8):
            for b in range(a + 1, 8):
                if np.sum(corners[a] != corners[b]) == 1:
                    ends = np.array([pose * (corners[k] * half) for k in (a, b)])
                    ax.plot(*ends.T, **style)
    elif obstacle.shape == "cylinder":
        radius, length = obstacle.size[0], obstacle.size[1]
        angle = np.linspace(0.0, 2.0 * np.pi, 49)
        for z in (-length / 2.0, length / 2.0):
            rim = np.stack(
                [radius * np.cos(angle), radius * np.sin(angle), np.full(49, z)]
            )
            ax.plot(*np.array([pose * p for p in rim.T]).T, **style)
        for a in angle[:-1:12]:
            ends = np.array(
                [
                    pose * np.array([radius * np.cos(a), radius * np.sin(a), z])
                    for z in (-length / 2.0, length / 2.0)
                ]
            )
            ax.plot(*ends.T, **style)


__all__ = ["plot_planned_around"]
