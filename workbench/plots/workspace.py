"""Figures of a workspace map: horizontal slices, vertical sections, histograms.

A map gives one value per voxel of its grid (reachability, best dexterity,
near-singular fraction, …), flat in the grid's C order over ``shape`` (nx, ny,
nz). A :class:`VoxelField` bundles such values with their name, unit and colour
scale; the ``plot_*`` functions draw them in the base frame, axes in metres,
colour bars with units, voxels without a value (nothing reachable) in light
grey and the robot's base axis marked. Each follows matplotlib's convention
(``fig=`` optional, the Figure returned, a PNG written only when ``path`` is
given); matplotlib is imported when one is called, without pyplot.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import numpy.typing as npt

from workbench.errors import DimensionError, InputError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

FloatArray = npt.NDArray[np.float64]

#: Colour of voxels without a value (nothing reachable there).
EMPTY_COLOR = "#e4e4e4"
#: Colour of the base axis marker.
BASE_COLOR = "#d62728"
#: Legend text of the light grey voxels.
EMPTY_LABEL = "no value (nothing reachable)"


class VoxelGridLike(Protocol):
    """What the figures need of a grid (:class:`~workbench.workspace.PoseGrid`)."""

    @property
    def origin(self) -> Any:
        """Centre of voxel (0, 0, 0), shape (3,) [m], base frame."""

    @property
    def resolution(self) -> float:
        """Voxel edge [m]."""

    @property
    def shape(self) -> tuple[int, ...]:
        """Voxels along x, y, z."""


@dataclass(frozen=True, slots=True)
class VoxelField:
    """One value per voxel, with what it means and how to colour it.

    Attributes:
        name: Short name, e.g. ``"reachability"``.
        label: Colour bar and axis label with its unit, e.g.
            ``"reachability [fraction of orientations]"``.
        values: Shape (V,), flat in the grid's C order; NaN where there is
            nothing to draw.
        vmin: Value at the bottom of the colour scale.
        vmax: Value at the top of the colour scale (> ``vmin``).
        cmap: A perceptually uniform matplotlib colour map name.
    """

    name: str
    label: str
    values: FloatArray
    vmin: float
    vmax: float
    cmap: str = "viridis"


def get_volume(grid: VoxelGridLike, values: npt.ArrayLike) -> FloatArray:
    """Per-voxel values as a volume, shape (nx, ny, nz), float64.

    Raises:
        DimensionError: If ``values`` does not hold one value per voxel.
    """
    shape = tuple(int(n) for n in grid.shape)
    flat = np.asarray(values, dtype=np.float64)
    if flat.shape != (int(np.prod(shape)),):
        raise DimensionError("voxel values", (int(np.prod(shape)),), flat.shape)
    return flat.reshape(shape)


def get_layer_coordinates(grid: VoxelGridLike, axis: int) -> FloatArray:
    """Voxel centre coordinates along ``axis`` (0 x, 1 y, 2 z), shape (n,) [m]."""
    n = int(grid.shape[axis])
    centres = float(grid.origin[axis]) + float(grid.resolution) * np.arange(n)
    return centres.astype(np.float64)


def get_nearest_layer(grid: VoxelGridLike, axis: int, coordinate: float) -> int:
    """Index of the layer whose voxel centres lie nearest ``coordinate`` [m]."""
    centres = get_layer_coordinates(grid, axis)
    return int(np.argmin(np.abs(centres - coordinate)))


def _extent(grid: VoxelGridLike, axes: tuple[int, int]) -> list[float]:
    half = 0.5 * float(grid.resolution)
    extent: list[float] = []
    for axis in axes:
        centres = get_layer_coordinates(grid, axis)
        extent += [float(centres[0]) - half, float(centres[-1]) + half]
    return extent


def _figure(fig: Figure | None, figsize: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure

    if fig is None:
        return Figure(figsize=figsize, layout="constrained")
    fig.clear()
    return fig


def _finish(fig: Figure, path: str | Path | None) -> Figure:
    """Write ``fig`` whole (``plots.trajectory.save_figure``) when a path is given."""
    if path is not None:
        from workbench.plots.trajectory import save_figure  # imports matplotlib

        save_figure(fig, path)
    return fig


def _image(ax: Any, image: FloatArray, extent: list[float], field: VoxelField) -> Any:
    """Draw ``image`` (rows: 2nd axis, columns: 1st axis) on ``field``'s scale."""
    from matplotlib import colormaps

    cmap = colormaps[field.cmap].with_extremes(bad=EMPTY_COLOR)
    ax.set_facecolor(EMPTY_COLOR)
    return ax.imshow(
        np.ma.masked_invalid(image),
        origin="lower",
        extent=extent,
        cmap=cmap,
        vmin=field.vmin,
        vmax=field.vmax,
        interpolation="nearest",
    )


def _mark_base(ax: Any, *, vertical: bool) -> None:
    """The base axis: a cross at x = y = 0, or the line x = 0 and the base origin."""
    from matplotlib import patheffects

    halo = [patheffects.withStroke(linewidth=4, foreground="white")]
    if vertical:
        ax.axvline(0.0, color=BASE_COLOR, lw=1.0, ls=":", path_effects=halo)
        ax.plot(0.0, 0.0, "^", color=BASE_COLOR, ms=9, mec="white", label="robot base")
    else:
        ax.plot(
            0.0,
            0.0,
            "+",
            color=BASE_COLOR,
            ms=12,
            mew=2.5,
            path_effects=halo,
            label="base axis",
        )


def _legend(fig: Figure, *, vertical: bool, empty: bool) -> None:
    """One legend under the panels for the base marks and the grey voxels."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles: list[Any]
    if vertical:
        handles = [
            Line2D([], [], color=BASE_COLOR, ls="none", marker="^", ms=9, mec="white"),
            Line2D([], [], color=BASE_COLOR, ls=":", lw=1.0),
        ]
        labels = ["robot base (origin of the base frame)", "base axis (x = 0)"]
    else:
        marker = Line2D([], [], color=BASE_COLOR, ls="none", marker="+", ms=12, mew=2.5)
        handles, labels = [marker], ["base axis (x = y = 0)"]
    if empty:
        handles.append(Patch(facecolor=EMPTY_COLOR, edgecolor="#999999"))
        labels.append(EMPTY_LABEL)
    fig.legend(
        handles, labels, loc="outside lower center", ncol=len(handles), fontsize=9
    )


def _check_field(grid: VoxelGridLike, field: VoxelField) -> FloatArray:
    if not field.vmax > field.vmin:
        raise InputError(
            f"{field.name}: the colour scale needs vmax > vmin, got "
            f"[{field.vmin}, {field.vmax}]"
        )
    return get_volume(grid, field.values)


def plot_horizontal_slices(
    grid: VoxelGridLike,
    field: VoxelField,
    heights: Sequence[float],
    path: str | Path | None = None,
    *,
    columns: int = 3,
    fig: Figure | None = None,
    title: str | None = None,
) -> Figure:
    """Horizontal slices of one field at several heights, one colour bar.

    Each panel is the voxel layer whose centres lie nearest the asked height
    (its own height in the panel title), seen from above: x right, y up [m].
    A legend under the panels names the base axis cross and, when some are
    drawn, the grey voxels without a value.

    Args:
        grid: The map's grid (origin, resolution, shape).
        field: The values to draw.
        heights: z of each slice [m], base frame (at least one).
        path: PNG file to write, if any.
        columns: Panels per row.
        fig: Figure to draw into (cleared), else a new one.
        title: Figure title; default the field's name and the view.

    Raises:
        InputError: If ``heights`` is empty or the colour scale is empty.
        DimensionError: If the field has not one value per voxel.
    """
    volume = _check_field(grid, field)
    if len(heights) == 0:
        raise InputError("plot_horizontal_slices needs at least one height")
    columns = max(1, min(columns, len(heights)))
    rows = -(-len(heights) // columns)
    fig = _figure(fig, (3.4 * columns + 1.0, 3.2 * rows + 1.0))
    axes = fig.subplots(rows, columns, squeeze=False, sharex=True, sharey=True)
    extent = _extent(grid, (0, 1))
    image: Any = None
    empty = False
    for k, ax in enumerate(axes.flat):
        if k >= len(heights):
            ax.set_visible(False)
            continue
        iz = get_nearest_layer(grid, 2, float(heights[k]))
        z = get_layer_coordinates(grid, 2)[iz]
        image = _image(ax, volume[:, :, iz].T, extent, field)
        empty = empty or bool(np.isnan(volume[:, :, iz]).any())
        _mark_base(ax, vertical=False)
        ax.set_title(f"z = {z:+.3f} m", fontsize=10)
        ax.set_aspect("equal")
        if k % columns == 0:
            ax.set_ylabel("y [m]")
        if k >= len(heights) - columns:
            ax.set_xlabel("x [m]")
    fig.colorbar(image, ax=axes, label=field.label, shrink=0.9)
    _legend(fig, vertical=False, empty=empty)
    default = f"{field.name}: horizontal slices seen from above, base frame"
    fig.suptitle(default if title is None else title, fontsize=11)
    return _finish(fig, path)


def plot_vertical_sections(
    grid: VoxelGridLike,
    fields: Sequence[VoxelField],
    path: str | Path | None = None,
    *,
    y: float = 0.0,
    columns: int = 2,
    fig: Figure | None = None,
    title: str | None = None,
) -> Figure:
    """Vertical sections in the x–z plane through the base axis, one per field.

    A legend under the panels names the base marks and, when some are drawn,
    the grey voxels without a value.

    Args:
        grid: The map's grid.
        fields: One panel each, with its own colour bar.
        path: PNG file to write, if any.
        y: The section's plane [m]; the voxel layer nearest it is drawn
            (default the one through the base axis).
        columns: Panels per row.
        fig: Figure to draw into (cleared), else a new one.
        title: Figure title, followed by the section's plane; default the
            fields' names.

    Raises:
        InputError: If ``fields`` is empty or a colour scale is empty.
        DimensionError: If a field has not one value per voxel.
    """
    if len(fields) == 0:
        raise InputError("plot_vertical_sections needs at least one field")
    volumes = [_check_field(grid, f) for f in fields]
    iy = get_nearest_layer(grid, 1, y)
    y_layer = get_layer_coordinates(grid, 1)[iy]
    columns = max(1, min(columns, len(fields)))
    rows = -(-len(fields) // columns)
    fig = _figure(fig, (4.6 * columns, 3.9 * rows + 0.9))
    axes = fig.subplots(rows, columns, squeeze=False, sharex=True, sharey=True)
    extent = _extent(grid, (0, 2))
    empty = False
    for k, ax in enumerate(axes.flat):
        if k >= len(fields):
            ax.set_visible(False)
            continue
        image = _image(ax, volumes[k][:, iy, :].T, extent, fields[k])
        empty = empty or bool(np.isnan(volumes[k][:, iy, :]).any())
        _mark_base(ax, vertical=True)
        ax.set_aspect("equal")
        ax.set_title(fields[k].name, fontsize=10)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("z [m]")
        fig.colorbar(image, ax=ax, label=fields[k].label, shrink=0.85)
    _legend(fig, vertical=True, empty=empty)
    heading = ", ".join(f.name for f in fields) if title is None else title
    fig.suptitle(
        f"{heading}: section y = {y_layer:+.3f} m (through the base axis), base frame",
        fontsize=11,
    )
    return _finish(fig, path)


def plot_histograms(
    fields: Sequence[VoxelField],
    path: str | Path | None = None,
    *,
    bins: int = 40,
    fig: Figure | None = None,
    title: str | None = None,
) -> Figure:
    """Histogram of each field over the voxels that have a value (log counts).

    Args:
        fields: One panel each; NaN values are left out, the x range is the
            field's colour scale.
        path: PNG file to write, if any.
        bins: Bins per histogram.
        fig: Figure to draw into (cleared), else a new one.
        title: Figure title; default says what is counted.

    Raises:
        InputError: If ``fields`` is empty or a colour scale is empty.
    """
    if len(fields) == 0:
        raise InputError("plot_histograms needs at least one field")
    from matplotlib import colormaps

    fig = _figure(fig, (4.0 * len(fields), 3.2))
    axes = fig.subplots(1, len(fields), squeeze=False)[0]
    for ax, field in zip(axes, fields, strict=True):
        if not field.vmax > field.vmin:
            raise InputError(f"{field.name}: the histogram range is empty")
        values = np.asarray(field.values, dtype=np.float64)
        values = values[np.isfinite(values)]
        edges = np.linspace(field.vmin, field.vmax, bins + 1)
        counts, _ = np.histogram(np.clip(values, field.vmin, field.vmax), edges)
        middle = 0.5 * (edges[:-1] + edges[1:])
        colors = colormaps[field.cmap](
            (middle - field.vmin) / (field.vmax - field.vmin)
        )
        ax.bar(
            edges[:-1],
            counts,
            width=np.diff(edges),
            align="edge",
            color=colors,
            edgecolor="#444444",
            linewidth=0.4,
        )
        ax.set_xlim(field.vmin, field.vmax)
        ax.set_xlabel(field.label)
        ax.set_ylabel("voxels")
        if counts.any():  # a few bins (full reach, none singular) hold most
            ax.set_yscale("log")
            ax.set_ylabel("voxels (log scale)")
        ax.set_title(f"{field.name} ({values.size} voxels)", fontsize=10)
    default = "voxels per value, over the voxels that have one"
    fig.suptitle(default if title is None else title, fontsize=11)
    return _finish(fig, path)


__all__ = [
    "EMPTY_COLOR",
    "EMPTY_LABEL",
    "VoxelField",
    "VoxelGridLike",
    "get_layer_coordinates",
    "get_nearest_layer",
    "get_volume",
    "plot_histograms",
    "plot_horizontal_slices",
    "plot_vertical_sections",
]
