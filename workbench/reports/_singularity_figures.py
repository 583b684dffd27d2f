"""Figures of the singularity report, as PNG bytes (matplotlib, Agg, no pyplot).

Imported lazily by :mod:`workbench.reports.singularity_report` only.
"""

from __future__ import annotations

import io
from collections.abc import Mapping

import numpy as np
import numpy.typing as npt
from matplotlib import patheffects
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from workbench.model.robot import Robot
from workbench.singularities.along_path import ClosestApproach
from workbench.singularities.directions import DegenerateDirection
from workbench.singularities.measures import JointGrid

FloatArray = npt.NDArray[np.float64]

_SHOULDER_COLOR = "#2ca02c"
_ELBOW_COLOR = "#ff7f0e"
_LIMIT_COLOR = "#333333"
_DPI = 110
_HALO = [patheffects.withStroke(linewidth=4.5, foreground="white")]


def _png(fig: Figure, *, tight: bool = True) -> bytes:
    """PNG bytes; ``tight=False`` saves the second draw that cropping costs."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=_DPI, bbox_inches="tight" if tight else None)
    return buffer.getvalue()


def _overlay(
    ax,
    robot: Robot,
    grid: JointGrid,
    shoulder: tuple[FloatArray, FloatArray, FloatArray] | None,
    elbow_theta3: FloatArray | None,
    examples: Mapping[str, FloatArray],
    *,
    thin: bool = False,
) -> None:
    """Loci, joint-limit box and example configurations on a (θ2, θ3) map.

    ``thin`` draws the loci as thin lines without halo, so that what lies
    under them (the troughs of σmin) stays visible.
    """
    lw, halo = (1.0, None) if thin else (2.0, _HALO)
    x, y = np.degrees(grid.x), np.degrees(grid.y)
    j2, j3 = grid.joints
    if shoulder is not None:
        sx, sy, field = shoulder
        ax.contour(
            np.degrees(sx),
            np.degrees(sy),
            field,
            levels=[0.0],
            colors=_SHOULDER_COLOR,
            linewidths=lw,
            linestyles="-" if not thin else ":",
        ).set(path_effects=halo)
        ax.plot([], [], color=_SHOULDER_COLOR, lw=lw, label="shoulder locus (x1 = 0)")
    if elbow_theta3 is not None:
        for k, value in enumerate(np.degrees(elbow_theta3)):
            shifted = y[0] + np.mod(value - y[0], 360.0)
            ax.axhline(
                shifted,
                color=_ELBOW_COLOR,
                lw=lw,
                ls="--",
                label="elbow locus" if k == 0 else None,
                path_effects=halo,
            )
    lower, upper = np.degrees(robot.lower), np.degrees(robot.upper)
    box = Rectangle(
        (lower[j2], lower[j3]),
        upper[j2] - lower[j2],
        upper[j3] - lower[j3],
        fill=False,
        ec=_LIMIT_COLOR,
        lw=1.2,
        ls=":",
        label="joint limits",
    )
    ax.add_patch(box)
    for k, (name, q) in enumerate(examples.items()):
        if name == "wrist":  # θ5 = 0: not on this θ5 = 90° map
            continue
        px = x[0] + np.mod(np.degrees(q[j2]) - x[0], 360.0)
        py = y[0] + np.mod(np.degrees(q[j3]) - y[0], 360.0)
        ax.plot(px, py, "o", mfc="white", mec="black", ms=7)
        ax.annotate(str(k + 1), (px, py), xytext=(5, 5), textcoords="offset points")
    ax.set_xlim(x[0], x[-1])
    ax.set_ylim(y[0], y[-1])
    ax.set_xlabel(f"θ{j2 + 1} [deg]")
    ax.set_ylabel(f"θ{j3 + 1} [deg]")
    ax.legend(loc="upper right", fontsize=8, framealpha=0.9)


def figure_det_map(
    robot: Robot,
    grid: JointGrid,
    *,
    shoulder: tuple[FloatArray, FloatArray, FloatArray] | None,
    elbow_theta3: FloatArray | None,
    examples: Mapping[str, FloatArray],
) -> bytes:
    """Det J over (θ2, θ3), diverging colours, loci overlaid."""
    fig = Figure(figsize=(7.2, 5.8))
    ax = fig.add_subplot()
    det = grid.values["det_j"]
    vmax = float(np.max(np.abs(det))) or 1.0
    extent = np.degrees([grid.x[0], grid.x[-1], grid.y[0], grid.y[-1]])
    image = ax.imshow(
        det,
        origin="lower",
        extent=tuple(extent),
        aspect="auto",
        cmap="RdBu_r",
        vmin=-vmax,
        vmax=vmax,
        interpolation="nearest",
    )
    fig.colorbar(image, ax=ax, label="det J [m³]")
    _overlay(ax, robot, grid, shoulder, elbow_theta3, examples)
    ax.set_title(
        f"{robot.name}: det J over (θ2, θ3), {grid.x.size} × {grid.y.size} grid",
        fontsize=10,
    )
    return _png(fig)


def figure_sigma_map(
    robot: Robot,
    grid: JointGrid,
    *,
    shoulder: tuple[FloatArray, FloatArray, FloatArray] | None,
    elbow_theta3: FloatArray | None,
    examples: Mapping[str, FloatArray],
) -> bytes:
    """log10 σmin over (θ2, θ3), loci overlaid."""
    fig = Figure(figsize=(7.2, 5.8))
    ax = fig.add_subplot()
    sigma = np.log10(np.maximum(grid.values["sigma_min"], 1e-6))
    extent = np.degrees([grid.x[0], grid.x[-1], grid.y[0], grid.y[-1]])
    image = ax.imshow(
        sigma,
        origin="lower",
        extent=tuple(extent),
        aspect="auto",
        cmap="viridis",
        interpolation="nearest",
    )
    fig.colorbar(image, ax=ax, label="log10 σmin (clipped at 1e-6)")
    _overlay(ax, robot, grid, shoulder, elbow_theta3, examples, thin=True)
    ax.set_title(
        f"{robot.name}: smallest singular value of J, {grid.x.size} × {grid.y.size}",
        fontsize=10,
    )
    return _png(fig)


def figure_arms(
    robot: Robot,
    examples: Mapping[str, FloatArray],
    directions: Mapping[str, DegenerateDirection],
) -> bytes:
    """The arm in each shoulder and elbow singular configuration (Kang Figs. 2-3).

    Each panel shows the stick figure through the DH frame origins
    (:mod:`workbench.plots.arm`), the base axis z0, the degenerate direction u
    at the wrist centre (red), Kang's stated axis (dashed) and, for the
    shoulder, the singular plane x1 = 0; for the elbow, the shoulder-to-wrist
    line along which u points.
    """
    from workbench.plots.arm import compute_arm_points, plot_arm, set_equal_axes

    names = [n for n in examples if not n.startswith("wrist")]
    rows = (len(names) + 1) // 2
    fig = Figure(figsize=(9.0, 4.3 * rows))
    legend: dict[str, object] = {}
    for k, name in enumerate(names):
        ax = fig.add_subplot(rows, 2, k + 1, projection="3d")
        q = examples[name]
        plot_arm(ax, robot, q, label="arm (DH frame origins)", axis_length=0.0)
        d = directions[name]
        frame1 = robot.fk(q, "frame1")
        centre = robot.fk(q, "frame4").translation
        ax.plot([0, 0], [0, 0], [-0.25, 0.6], color="grey", lw=1, ls="-.", label="z0")
        if d.kind == "shoulder":
            _plane(ax, frame1.translation, np.array([0, 0, 1.0]), frame1.rotation[:, 2])
        else:
            line = np.stack([frame1.translation, centre]).T
            ax.plot(*line, color="crimson", lw=1, ls=":", label="shoulder → wrist")
        tips = [_arrow(ax, centre, d.direction[:3], "crimson", "u (degenerate)")]
        if d.paper_direction is not None:
            label = "Kang's axis (x1 or z1)"
            tips.append(_arrow(ax, centre, d.paper_direction, "black", label, "--"))
        points = np.vstack([compute_arm_points(robot, q), *tips, [[0, 0, -0.25]]])
        set_equal_axes(ax, points)
        ax.view_init(elev=18.0, azim=-55.0)
        ax.tick_params(labelsize=7)
        ax.set_title(f"{list(examples).index(name) + 1}. {name}", fontsize=10)
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            legend.setdefault(label, handle)
    fig.legend(
        list(legend.values()), list(legend), loc="lower center", ncol=3, fontsize=8
    )
    fig.subplots_adjust(left=0.0, right=0.95, top=0.95, bottom=0.1, wspace=0.1)
    return _png(fig, tight=False)


def _plane(ax, origin: FloatArray, e1: FloatArray, e2: FloatArray) -> None:
    """A translucent patch of the plane through ``origin`` spanned by e1, e2."""
    a, b = np.meshgrid([-0.25, 0.6], [-0.3, 0.3])
    points = origin[:, None, None] + e1[:, None, None] * a + e2[:, None, None] * b
    ax.plot_surface(*points, color=_SHOULDER_COLOR, alpha=0.15, lw=0)
    ax.plot([], [], color=_SHOULDER_COLOR, alpha=0.4, lw=6, label="plane x1 = 0")


def _arrow(
    ax, start: FloatArray, direction: FloatArray, color: str, label: str, ls: str = "-"
) -> FloatArray:
    """A 0.25 m arrow from ``start``; returns its tip [m]."""
    tip = start + 0.25 * direction / np.linalg.norm(direction)
    width = 3.5 if ls == "-" else 1.6  # u stays visible under a coinciding axis
    ax.plot(*np.stack([start, tip]).T, color=color, lw=width, ls=ls, label=label)
    ax.scatter(*tip, color=color, s=18)
    return tip


def figure_trajectory(
    t: FloatArray,
    signals: Mapping[str, FloatArray],
    approaches: Mapping[str, ClosestApproach],
) -> bytes:
    """Signed distances along a trajectory, closest approaches marked."""
    fig = Figure(figsize=(8.0, 1.9 * len(signals) + 0.6))
    first = None
    for k, (kind, values) in enumerate(signals.items()):
        ax = fig.add_subplot(len(signals), 1, k + 1, sharex=first)
        first = first or ax
        ax.plot(t, values, lw=1.5)
        ax.axhline(0.0, color="grey", lw=0.8)
        a = approaches[kind]
        ax.plot(a.t, a.distance, "o", color="crimson")
        for tc in a.crossings:
            ax.axvline(tc, color="crimson", ls=":", lw=1)
        ax.set_ylabel(f"{kind}\n[{a.unit}]")
        if k == len(signals) - 1:
            ax.set_xlabel("t [s]")
        else:
            ax.tick_params(labelbottom=False)
    fig.suptitle("Signed distances along the trajectory (● closest, ┆ crossing)")
    return _png(fig)
