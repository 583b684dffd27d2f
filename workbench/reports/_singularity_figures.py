"""Figures of the singularity report (matplotlib, no pyplot).

Imported lazily by :mod:`workbench.reports.singularity_report`. Each ``plot_*``
function follows matplotlib's convention: ``ax=`` (or ``fig=`` when it draws
several axes) is optional, the Figure is returned, and a PNG is written only
when ``path`` is given; :func:`png_bytes` gives the bytes the report embeds.
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt
from matplotlib import patheffects
from matplotlib.artist import Artist
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
#: Smallest σmin drawn on the log scale (zeros would be -inf).
SIGMA_FLOOR = 1e-6
#: Largest condition number drawn on the log scale (singular points are inf).
CONDITION_CEILING = 1e6


def png_bytes(fig: Figure, *, tight: bool = True) -> bytes:
    """PNG bytes; ``tight=False`` saves the second draw that cropping costs."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=_DPI, bbox_inches="tight" if tight else None)
    return buffer.getvalue()


def _axes(ax: Any, figsize: tuple[float, float]) -> tuple[Figure, Any]:
    """``ax`` and its Figure, or a new Figure with one axes."""
    if ax is None:
        fig = Figure(figsize=figsize)
        return fig, fig.add_subplot()
    return ax.get_figure(), ax


def _figure(
    fig: Figure | None,
    figsize: tuple[float, float],
    layout: Literal["constrained"] | None = None,
) -> Figure:
    if fig is None:
        return Figure(figsize=figsize, layout=layout)
    fig.clear()
    return fig


def _finish(fig: Figure, path: str | Path | None, *, tight: bool = True) -> Figure:
    if path is not None:
        Path(path).write_bytes(png_bytes(fig, tight=tight))
    return fig


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
    label = "singular configuration (numbered)"
    for k, (name, q) in enumerate(examples.items()):
        if name == "wrist":  # θ5 = 0: not on this θ5 = 90° map
            continue
        px = x[0] + np.mod(np.degrees(q[j2]) - x[0], 360.0)
        py = y[0] + np.mod(np.degrees(q[j3]) - y[0], 360.0)
        ax.plot(px, py, "o", mfc="white", mec="black", ms=7, label=label)
        label = "_" + label  # named once
        ax.annotate(str(k + 1), (px, py), xytext=(5, 5), textcoords="offset points")
    ax.set_xlim(x[0], x[-1])
    ax.set_ylim(y[0], y[-1])
    ax.set_xlabel(f"θ{j2 + 1} [deg]")
    ax.set_ylabel(f"θ{j3 + 1} [deg]")
    ax.legend(loc="upper right", fontsize=8, framealpha=0.9)


def plot_det_map(
    robot: Robot,
    grid: JointGrid,
    path: str | Path | None = None,
    *,
    ax: Any = None,
    shoulder: tuple[FloatArray, FloatArray, FloatArray] | None,
    elbow_theta3: FloatArray | None,
    examples: Mapping[str, FloatArray],
) -> Figure:
    """Det J over (θ2, θ3), diverging colours, loci overlaid.

    Args:
        robot: The robot of the grid.
        grid: Joint grid with ``values["det_j"]`` [m³].
        path: PNG file to write; None writes nothing.
        ax: Axes to draw on; None makes a new Figure.
        shoulder: Optional (θ2 axis, θ3 axis, shoulder condition) to contour.
        elbow_theta3: Elbow-singular θ3 values [rad] (horizontal lines).
        examples: Named configurations (nq,) [rad] to mark.

    Returns:
        The Figure.
    """
    fig, ax = _axes(ax, (7.2, 5.8))
    det = grid.values["det_j"]
    vmax = float(np.max(np.abs(det))) or 1.0
    title = f"{robot.name}: det J over (θ2, θ3)"
    _image(ax, grid, det, "RdBu_r", "det J [m³]", title, vmin=-vmax, vmax=vmax)
    _overlay(ax, robot, grid, shoulder, elbow_theta3, examples)
    return _finish(fig, path)


def plot_sigma_map(
    robot: Robot,
    grid: JointGrid,
    path: str | Path | None = None,
    *,
    ax: Any = None,
    shoulder: tuple[FloatArray, FloatArray, FloatArray] | None,
    elbow_theta3: FloatArray | None,
    examples: Mapping[str, FloatArray],
) -> Figure:
    """log10 σmin over (θ2, θ3), loci overlaid.

    Args:
        robot: The robot of the grid.
        grid: Joint grid with ``values["sigma_min"]`` (mixed units).
        path: PNG file to write; None writes nothing.
        ax: Axes to draw on; None makes a new Figure.
        shoulder: As in :func:`plot_det_map`.
        elbow_theta3: As in :func:`plot_det_map`.
        examples: As in :func:`plot_det_map`.

    Returns:
        The Figure.
    """
    fig, ax = _axes(ax, (7.2, 5.8))
    sigma = np.log10(np.maximum(grid.values["sigma_min"], SIGMA_FLOOR))
    title = f"{robot.name}: smallest singular value of J"
    _image(
        ax,
        grid,
        sigma,
        "viridis",
        "log10 σmin, σmin in mixed units m/rad and 1 (clipped at 1e-6)",
        title,
    )
    _overlay(ax, robot, grid, shoulder, elbow_theta3, examples, thin=True)
    return _finish(fig, path)


def plot_measure_map(
    robot: Robot,
    grid: JointGrid,
    measure: str,
    path: str | Path | None = None,
    *,
    ax: Any = None,
) -> Figure:
    """Manipulability or log10 condition number over the grid's two joints.

    Dark is near-singular on both maps, as on :func:`plot_sigma_map`.

    Args:
        robot: The robot of the grid.
        grid: Joint grid with ``values[measure]`` (mixed units, see
            :mod:`workbench.singularities.measures`).
        measure: ``"manipulability"`` or ``"condition_number"``.
        path: PNG file to write; None writes nothing.
        ax: Axes to draw on; None makes a new Figure.

    Returns:
        The Figure.
    """
    fig, ax = _axes(ax, (7.2, 5.8))
    values = grid.values[measure]
    if measure == "condition_number":
        shown = np.log10(np.minimum(values, CONDITION_CEILING))
        label = "log10 σmax/σmin, mixed units m/rad and 1 (clipped at 1e6)"
        _image(ax, grid, shown, "viridis_r", label, f"{robot.name}: condition number")
    else:
        label = "manipulability √det(J Jᵀ) [m³]"
        _image(ax, grid, values, "viridis", label, f"{robot.name}: manipulability")
    _overlay(ax, robot, grid, None, None, {}, thin=True)
    return _finish(fig, path)


def _image(
    ax: Any,
    grid: JointGrid,
    values: FloatArray,
    cmap: str,
    label: str,
    title: str,
    **limits: float,
) -> None:
    """``values`` (ny, nx) drawn over the grid's joint angles, with a colour bar.

    ``label`` names the colour bar, ``title`` the map (the grid size is added);
    ``limits`` are ``vmin``/``vmax`` of the colour scale (default: the data's).
    """
    extent = np.degrees([grid.x[0], grid.x[-1], grid.y[0], grid.y[-1]])
    image = ax.imshow(
        values,
        origin="lower",
        extent=tuple(extent),
        aspect="auto",
        cmap=cmap,
        interpolation="nearest",
        **limits,
    )
    ax.get_figure().colorbar(image, ax=ax, label=label)
    ax.set_title(f"{title}, {grid.x.size} × {grid.y.size} grid", fontsize=10)


def plot_singular_arms(
    robot: Robot,
    examples: Mapping[str, FloatArray],
    directions: Mapping[str, DegenerateDirection],
    path: str | Path | None = None,
    *,
    fig: Figure | None = None,
) -> Figure:
    """The arm in each shoulder and elbow singular configuration (Kang Figs. 2-3).

    Each panel shows the stick figure (:mod:`workbench.plots.arm`), the base
    axis (axis 1), the degenerate direction u at the wrist point (red, its
    linear part), Kang's stated axis for the PUMA tables (dashed) and, for the
    shoulder, the singular plane through axis 1 parallel to axis 2; for the
    elbow of an OPW arm, the line of u, which meets axes 1, 2 and 3.

    Args:
        robot: An OPW or UR-type robot (joint axes read with
            :func:`workbench.singularities.directions.compute_joint_axes`).
        examples: Named singular configurations (nq,) [rad]; ``wrist*`` skipped.
        directions: Degenerate direction of each example, by name.
        path: PNG file to write; None writes nothing.
        fig: Figure to draw into (cleared first); None makes a new one.

    Returns:
        The Figure, one 3D panel per example.
    """
    from workbench.plots.arm import compute_arm_points, plot_arm, set_equal_axes
    from workbench.singularities.conditions import get_factorisation
    from workbench.singularities.directions import compute_joint_axes

    spherical_wrist = get_factorisation(robot).spherical_wrist
    names = [n for n in examples if not n.startswith("wrist")]
    rows = (len(names) + 1) // 2
    fig = _figure(fig, (9.0, 4.3 * rows + 0.4))
    legend: dict[str, Artist] = {}
    for k, name in enumerate(names):
        ax = fig.add_subplot(rows, 2, k + 1, projection="3d")
        q = examples[name]
        plot_arm(robot, q, ax=ax, label="arm", axis_length=0.0)
        d = directions[name]
        z, o = compute_joint_axes(robot, q)
        scale = _arm_scale(robot)
        centre = d.reference_point
        base = np.stack([o[0] - 0.25 * scale * z[0], o[0] + 0.6 * scale * z[0]])
        ax.plot(*base.T, color="grey", lw=1, ls="-.", label="axis 1")
        if d.kind == "shoulder":
            _plane(ax, _foot(o[0], z[0], o[1], z[1]), z[0], z[1], scale)
        elif spherical_wrist:  # the line of u, from axis 2 to the wrist centre
            start = _foot(o[1], z[1], centre, d.direction[:3])
            line = np.stack([start, centre]).T
            ax.plot(*line, color="crimson", lw=1, ls=":", label="line of u")
        tips = [_arrow(ax, centre, d.direction[:3], "crimson", "u (degenerate)", scale)]
        if d.paper_direction is not None:
            label = "Kang's axis (x1 or z1)"
            tips.append(
                _arrow(ax, centre, d.paper_direction, "black", label, scale, "--")
            )
        points = np.vstack([compute_arm_points(robot, q), *tips, base])
        set_equal_axes(ax, points)
        ax.view_init(elev=18.0, azim=-55.0)
        ax.tick_params(labelsize=7)
        ax.set_title(f"{list(examples).index(name) + 1}. {name}", fontsize=10)
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            legend.setdefault(label, handle)
    fig.legend(
        list(legend.values()), list(legend), loc="lower center", ncol=3, fontsize=8
    )
    fig.suptitle(
        f"{robot.name}: the arm at each shoulder and elbow singularity "
        "(base frame, axes in m)",
        fontsize=11,
    )
    fig.subplots_adjust(left=0.0, right=0.95, top=0.92, bottom=0.1, wspace=0.1)
    return _finish(fig, path, tight=False)


def _arm_scale(robot: Robot) -> float:
    """Reach |a2| + forearm of the arm relative to the PUMA 560's 0.864 m."""
    from workbench.singularities.conditions import get_factorisation

    fac = get_factorisation(robot)
    return (abs(fac.a2) + fac.wrist_reach) / 0.864


def _foot(o1: FloatArray, z1: FloatArray, o2: FloatArray, z2: FloatArray) -> FloatArray:
    """The point of line (o1, z1) nearest line (o2, z2) [m]."""
    c = np.cross(z1, z2)
    if float(c @ c) <= 1e-24:
        return o1.copy()
    t = float(np.cross(o2 - o1, z2) @ c) / float(c @ c)
    return o1 + t * z1


def _plane(
    ax, origin: FloatArray, e1: FloatArray, e2: FloatArray, scale: float = 1.0
) -> None:
    """A translucent patch of the plane through ``origin`` spanned by e1, e2."""
    a, b = np.meshgrid(
        np.multiply([-0.25, 0.6], scale), np.multiply([-0.3, 0.3], scale)
    )
    points = origin[:, None, None] + e1[:, None, None] * a + e2[:, None, None] * b
    ax.plot_surface(*points, color=_SHOULDER_COLOR, alpha=0.15, lw=0)
    ax.plot([], [], color=_SHOULDER_COLOR, alpha=0.4, lw=6, label="singular plane")


def _arrow(
    ax,
    start: FloatArray,
    direction: FloatArray,
    color: str,
    label: str,
    scale: float = 1.0,
    ls: str = "-",
) -> FloatArray:
    """A 0.25 m arrow (times ``scale``) from ``start``; returns its tip [m]."""
    tip = start + 0.25 * scale * direction / np.linalg.norm(direction)
    width = 3.5 if ls == "-" else 1.6  # u stays visible under a coinciding axis
    ax.plot(*np.stack([start, tip]).T, color=color, lw=width, ls=ls, label=label)
    ax.scatter(*tip, color=color, s=18)
    return tip


def plot_distances_along_path(
    t: FloatArray,
    signals: Mapping[str, FloatArray],
    approaches: Mapping[str, ClosestApproach],
    path: str | Path | None = None,
    *,
    fig: Figure | None = None,
) -> Figure:
    """Signed distances along a trajectory, closest approaches marked.

    Args:
        t: Sample times, shape (K,) [s].
        signals: Signed distance of each kind, shape (K,) (unit per kind).
        approaches: Closest approach of each kind (same keys as ``signals``).
        path: PNG file to write; None writes nothing.
        fig: Figure to draw into (cleared first); None makes a new one.

    Returns:
        The Figure, one panel per signal.
    """
    from matplotlib.lines import Line2D

    fig = _figure(fig, (8.0, 1.9 * len(signals) + 1.0), layout="constrained")
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
    handles = [
        Line2D([], [], lw=1.5, color="C0"),
        Line2D([], [], color="grey", lw=0.8),
        Line2D([], [], ls="none", marker="o", color="crimson"),
        Line2D([], [], color="crimson", ls=":", lw=1),
    ]
    labels = ["signed distance", "zero: singular", "closest approach", "crossing"]
    fig.legend(handles, labels, loc="outside lower center", ncol=4, fontsize=9)
    fig.suptitle("Signed distances to each singularity along the trajectory")
    return _finish(fig, path)
