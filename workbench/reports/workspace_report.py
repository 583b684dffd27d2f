"""The workspace report: one self-contained HTML file about a workspace map.

What the map is (robot, grid, orientation set with its covering radius, exact
or sampled, counts, versions), its key numbers (reachable volume, dexterous
volume, best dexterity, …), horizontal slices of reachability and best
dexterity at several heights, a vertical section through the base axis,
histograms, and where the arm is near a singularity: the fraction of each
voxel's reached orientations whose best branch is near-singular, and the median
shoulder, elbow and wrist distances of the best branches. Figures are PNGs
embedded in the page; matplotlib is imported only when a report is built.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from workbench.atomic_files import write_text_atomic
from workbench.errors import InputError
from workbench.plots.workspace import (
    VoxelField,
    VoxelGridLike,
    get_layer_coordinates,
    get_nearest_layer,
)
from workbench.reports.html_report import HtmlReport
from workbench.singularities.conditions import ELBOW_TOL, SHOULDER_TOL, WRIST_TOL

if TYPE_CHECKING:
    from workbench.workspace.store import WorkspaceMap

FloatArray = npt.NDArray[np.float64]

#: Horizontal slices drawn per measure (evenly spread over the reached heights).
SLICE_COUNT = 6
#: Singularity kinds and the per-pose array of each one's distance.
SINGULAR_KINDS = ("shoulder", "elbow", "wrist")
_SYMBOLS = {"shoulder": "|s|", "elbow": "|e|", "wrist": "|w|"}
_UNITS = {"shoulder": "m", "elbow": "1", "wrist": "1"}
#: The colour scale of a median singularity distance ends at this quantile of
#: its values (a few far voxels would otherwise wash the near ones out).
DISTANCE_SCALE_QUANTILE = 0.98
#: Decimals of the slice heights in the summary [m]: drops the float noise of
#: ``origin + k · resolution``.
HEIGHT_DECIMALS = 9
#: Per-voxel arrays every map holds.
VOXEL_ARRAYS = ("reachability", "dexterity_best")


@dataclass(frozen=True, slots=True)
class WorkspaceReport(HtmlReport):
    """A built workspace report (``html``, ``summary``, ``figures``)."""


def get_array(workspace_map: WorkspaceMap, name: str) -> FloatArray | None:
    """One array of the map as float64, or None when the map does not hold it."""
    if name not in workspace_map.names:
        return None
    return np.asarray(workspace_map[name], dtype=np.float64)


def choose_heights(
    grid: VoxelGridLike, reachability: FloatArray, count: int = SLICE_COUNT
) -> list[float]:
    """Heights [m] of ``count`` layers spread evenly over the reached ones.

    The lowest and highest reached layers hold few voxels, so the slices are
    taken at the inner points of an even division of the reached z range
    (each then snapped to its nearest layer; repeats dropped).
    """
    z = get_layer_coordinates(grid, 2)
    reached = (np.nan_to_num(reachability) > 0.0).reshape(tuple(grid.shape))
    layers = np.nonzero(reached.any(axis=(0, 1)))[0]
    if layers.size == 0:
        return [float(z[len(z) // 2])]
    lo, hi = z[layers[0]], z[layers[-1]]
    wanted = np.linspace(lo, hi, count + 2)[1:-1] if hi > lo else np.array([lo])
    snapped = [float(z[np.argmin(np.abs(z - w))]) for w in wanted]
    return sorted(set(snapped))


def compute_singular_distances(
    workspace_map: WorkspaceMap, tolerances: dict[str, float]
) -> tuple[dict[str, FloatArray], dict[str, FloatArray]]:
    """Per voxel, how near each singularity the best branches are.

    For each kind whose per-pose array the map holds (``shoulder`` |s| [m],
    ``elbow`` |e| [1], ``wrist`` |w| [1] of the best branch; a sampled map
    has none), over the orientations with a usable branch (finite distance):

    * the median distance;
    * the fraction of those orientations whose distance is below the map's
      tolerance of that kind (near-singular of that kind).

    Both are NaN where a voxel has no usable orientation.

    Returns:
        ``(medians, fractions)``: kind -> (V,) array each.
    """
    medians: dict[str, FloatArray] = {}
    fractions: dict[str, FloatArray] = {}
    for kind in SINGULAR_KINDS:
        values = get_array(workspace_map, kind)
        if values is None:
            continue
        usable = np.isfinite(values)
        counts = usable.sum(axis=1)
        near = (usable & (values < float(tolerances[kind]))).sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            fractions[kind] = np.where(counts > 0, near / counts, np.nan)
        median = np.full(values.shape[0], np.nan)
        some = counts > 0
        median[some] = np.nanmedian(values[some], axis=1)
        medians[kind] = median
    return medians, fractions


def _summary(
    workspace_map: WorkspaceMap, fields: dict[str, FloatArray]
) -> dict[str, Any]:
    """The key numbers of the map (JSON-ready)."""
    attrs, grid = workspace_map.attrs, workspace_map.grid
    reach = np.nan_to_num(fields["reachability"])
    best = fields["dexterity_best"]
    positions = np.asarray(grid.positions, dtype=np.float64)
    resolution = float(grid.resolution)
    voxel_volume = resolution**3
    reached = reach > 0.0
    full = reach >= 1.0
    orientations = len(grid.orientations)
    covering = attrs.get("orientation_set", {}).get("covering_radius")
    near = fields.get("near_singular_fraction")
    reached_best = best[reached & np.isfinite(best)]
    distance = np.linalg.norm(positions[reached], axis=1)
    return {
        "robot": attrs.get("robot"),
        "family": attrs.get("family"),
        "sampled": bool(attrs.get("sampled", False)),
        "samples": attrs.get("samples"),
        "redundancy": attrs.get("redundancy"),
        "voxels": int(positions.shape[0]),
        "orientations": orientations,
        "poses": int(positions.shape[0]) * orientations,
        "resolution": resolution,
        "grid_shape": [int(n) for n in grid.shape],
        "orientation_construction": attrs.get("orientation_set", {}).get(
            "construction"
        ),
        "covering_radius_deg": None
        if covering is None
        else float(np.degrees(covering)),
        "reachable_voxels": int(reached.sum()),
        "reachable_volume_m3": float(reached.sum() * voxel_volume),
        "dexterous_voxels": int(full.sum()),
        "dexterous_volume_m3": float(full.sum() * voxel_volume),
        "dexterous_fraction": float(full.sum() / reached.sum())
        if reached.any()
        else 0.0,
        "reached_pose_fraction": float(reach.mean()) if reach.size else 0.0,
        "dexterity_best_max": float(reached_best.max()) if reached_best.size else None,
        "dexterity_best_median": (
            float(np.median(reached_best)) if reached_best.size else None
        ),
        "near_singular_fraction_mean": (
            None
            if near is None or not np.isfinite(near).any()
            else float(np.nanmean(near))
        ),
        "max_reach_m": float(distance.max()) if distance.size else None,
        "z_range_m": (
            [float(positions[reached, 2].min()), float(positions[reached, 2].max())]
            if reached.any()
            else None
        ),
    }


def _field(
    name: str, label: str, values: FloatArray, vmax: float, cmap: str
) -> VoxelField:
    return VoxelField(name, label, values, 0.0, vmax if vmax > 0.0 else 1.0, cmap)


def build_workspace_report(
    workspace_map: WorkspaceMap, *, heights: list[float] | None = None
) -> WorkspaceReport:
    """Compute the figures and key numbers of a map and render the HTML.

    Args:
        workspace_map: A :class:`~workbench.workspace.WorkspaceMap`
            (``open_map(path)``).
        heights: z of the horizontal slices [m], each drawn at its nearest
            voxel layer (the summary's ``slice_heights_m``); default
            :data:`SLICE_COUNT` heights spread over the reached layers
            (:func:`choose_heights`).

    Raises:
        InputError: If the map lacks ``reachability`` or ``dexterity_best``, or
            a height lies outside the map's voxel layers.
    """
    from workbench.plots import workspace as plots
    from workbench.reports._singularity_figures import png_bytes
    from workbench.reports._workspace_html import render

    fields: dict[str, FloatArray] = {}
    for name in (*VOXEL_ARRAYS, "dexterity_median", "near_singular_fraction"):
        values = get_array(workspace_map, name)
        if values is None and name in VOXEL_ARRAYS:
            raise InputError(f"the workspace map has no {name!r} array to report")
        if values is not None:
            fields[name] = values
    grid = workspace_map.grid
    summary = _summary(workspace_map, fields)
    reach = np.where(fields["reachability"] > 0.0, fields["reachability"], np.nan)
    top = summary["dexterity_best_max"] or 1.0
    reachability = _field(
        "reachability", "reachability [fraction of orientations]", reach, 1.0, "viridis"
    )
    dexterity = _field(
        "best dexterity",
        "best dexterity √det(J Jᵀ) [m³]",
        fields["dexterity_best"],
        top,
        "viridis",
    )
    if heights:
        z = get_layer_coordinates(grid, 2)
        low, high = z[0] - 0.5 * grid.resolution, z[-1] + 0.5 * grid.resolution
        for h in heights:
            if not low <= h <= high:
                raise InputError(
                    f"slice height {h:g} m is outside the map's z range "
                    f"[{low:.3f}, {high:.3f}] m"
                )
        heights = [float(z[get_nearest_layer(grid, 2, h)]) for h in heights]
    else:
        heights = choose_heights(grid, fields["reachability"])
    figures = {
        "reachability_slices": plots.plot_horizontal_slices(
            grid, reachability, heights
        ),
        "dexterity_slices": plots.plot_horizontal_slices(grid, dexterity, heights),
        "sections": plots.plot_vertical_sections(grid, [reachability, dexterity]),
    }
    histogram_fields = [reachability, dexterity]
    singular: list[VoxelField] = []
    if "near_singular_fraction" in fields:
        near = _field(
            "near-singular",
            "near-singular fraction [1]",
            fields["near_singular_fraction"],
            1.0,
            "magma_r",
        )
        histogram_fields.append(near)
        singular.append(near)
    tolerances = workspace_map.attrs.get("tolerances") or {
        "shoulder": SHOULDER_TOL,
        "elbow": ELBOW_TOL,
        "wrist": WRIST_TOL,
    }
    medians, fractions = compute_singular_distances(workspace_map, tolerances)
    for kind, values in medians.items():
        finite = values[np.isfinite(values)]
        top = (
            float(np.quantile(finite, DISTANCE_SCALE_QUANTILE)) if finite.size else 1.0
        )
        singular.append(
            _field(
                f"median {_SYMBOLS[kind]}",
                f"median {kind} distance {_SYMBOLS[kind]} [{_UNITS[kind]}]",
                values,
                top,
                "magma",
            )
        )
    figures["histograms"] = plots.plot_histograms(histogram_fields)
    if singular:
        figures["singular_regions"] = plots.plot_vertical_sections(grid, singular)
        figures["singular_slices"] = plots.plot_horizontal_slices(
            grid, singular[0], heights
        )
    summary["near_singular_by_kind"] = {
        kind: float(np.nanmean(v)) if np.isfinite(v).any() else None
        for kind, v in fractions.items()
    }
    summary["slice_heights_m"] = [round(z, HEIGHT_DECIMALS) for z in heights]
    png = {name: png_bytes(fig) for name, fig in figures.items()}
    summary["figures"] = list(png)
    page = render(workspace_map.attrs, summary, png)
    return WorkspaceReport(page, summary, png)


def write_workspace_report(
    workspace_map: WorkspaceMap, path: str | Path, **options: Any
) -> WorkspaceReport:
    """Build the report (see :func:`build_workspace_report`) and write it whole.

    Raises:
        InputError: If the map cannot be reported or the file cannot be written.
    """
    report = build_workspace_report(workspace_map, **options)
    write_text_atomic(path, report.html)
    return report


__all__ = [
    "DISTANCE_SCALE_QUANTILE",
    "HEIGHT_DECIMALS",
    "SLICE_COUNT",
    "WorkspaceReport",
    "build_workspace_report",
    "choose_heights",
    "compute_singular_distances",
    "write_workspace_report",
]
