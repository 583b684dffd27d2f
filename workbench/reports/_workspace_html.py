"""HTML of the workspace report (no matplotlib here; figures come as PNG bytes)."""

from __future__ import annotations

import base64
import html
import math
from collections.abc import Mapping
from typing import Any

from workbench.reports._singularity_html import _CSS


def _uri(png: bytes) -> str:
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def _number(value: float | None, digits: int = 3) -> str:
    return "—" if value is None else f"{value:.{digits}g}"


def _vector(values: Any) -> str:
    return "[" + ", ".join(f"{float(v):+.3f}" for v in values) + "]"


def _table(rows: list[tuple[str, str]]) -> str:
    body = "".join(f"<tr><th>{k}</th><td>{v}</td></tr>" for k, v in rows)
    return f"<table>{body}</table>"


def render(
    attrs: Mapping[str, Any], summary: Mapping[str, Any], figures: Mapping[str, bytes]
) -> str:
    """The whole document: metadata, key numbers, figures with captions."""
    uri = {name: _uri(png) for name, png in figures.items()}
    robot = html.escape(str(summary["robot"]))
    parts = [
        f"""<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">
<title>Workspace of {robot}</title><style>{_CSS}</style></head><body>
<h1>Workspace of {robot}</h1>
<p>{_kind(summary)} Positions in the robot's base frame (z up along the first
joint axis for the arms here), lengths in metres, dexterity in m³
(Yoshikawa's manipulability √det(J Jᵀ) of the best branch — of a sampled map, of
the best sample binned to the pose — |det J| for six joints).</p>""",
        _key_numbers(summary),
        _metadata(attrs, summary),
        _slices(summary, uri),
        _histograms(uri),
        _singular(attrs, summary, uri),
        "</body></html>",
    ]
    return "\n".join(parts)


def _kind(summary: Mapping[str, Any]) -> str:
    if summary["sampled"]:
        return (
            f"A <b>sampled</b> map: {summary['samples']} random configurations "
            "within the joint limits, each binned to its nearest grid pose, so "
            "a pose counts as reached only if a sample fell near it "
            "(reachability is a lower bound)."
        )
    family = summary.get("family")
    named = f" ({html.escape(str(family).upper())} family)" if family else ""
    redundancy = summary.get("redundancy")
    if redundancy:
        parameter = html.escape(str(redundancy["parameter"]))
        lo, hi = redundancy["range"]
        return (
            f"An <b>exact</b> map at {redundancy['samples']} values of the "
            f"{parameter}: every grid pose solved in closed form{named} at the "
            f"centres of {redundancy['samples']} equal cells of [{lo:.4f}, "
            f"{hi:.4f}] rad; a pose is reached when a branch within the joint "
            "limits reaches it at one of those values. Exact at those values: a "
            "pose reached only between them counts as unreached (reachability "
            "is a lower bound of the arm's, which more values raise)."
        )
    return (
        f"An <b>exact</b> map: every grid pose solved in closed form{named}; a "
        "pose is reached when a branch within the joint limits reaches it."
    )


def _key_numbers(summary: Mapping[str, Any]) -> str:
    rows = [
        (
            "reachable volume",
            f"{summary['reachable_volume_m3']:.4g} m³ ({summary['reachable_voxels']} "
            f"of {summary['voxels']} voxels reached in at least one orientation)",
        ),
        (
            "fully dexterous volume",
            f"{summary['dexterous_volume_m3']:.4g} m³ ({summary['dexterous_voxels']} "
            "voxels reached in every orientation: "
            f"{100 * summary['dexterous_fraction']:.1f}% of the reachable ones)",
        ),
        (
            "poses reached",
            f"{100 * summary['reached_pose_fraction']:.2f}% of {summary['poses']}",
        ),
        (
            "best dexterity",
            f"max {_number(summary['dexterity_best_max'])} m³, median over the "
            f"reachable voxels {_number(summary['dexterity_best_median'])} m³",
        ),
        (
            "near-singular",
            "mean over the reachable voxels of the fraction of reached "
            f"orientations with singularity margin &lt; 1: "
            f"{_number(summary['near_singular_fraction_mean'])}",
        ),
        ("reach", f"farthest reached voxel centre {_number(summary['max_reach_m'])} m"),
    ]
    if summary["z_range_m"] is not None:
        lo, hi = summary["z_range_m"]
        rows.append(("heights reached", f"z from {lo:+.3f} m to {hi:+.3f} m"))
    return f'<div class="box"><h3>Key numbers</h3>{_table(rows)}</div>'


def _metadata(attrs: Mapping[str, Any], summary: Mapping[str, Any]) -> str:
    grid = attrs.get("grid", {})
    shape = " × ".join(str(n) for n in summary["grid_shape"])
    origin = grid.get("origin")
    bounds = grid.get("bounds")
    orientation_set = attrs.get("orientation_set", {})
    covering = summary["covering_radius_deg"]
    described = f"{html.escape(str(orientation_set.get('construction')))}, " + (
        f"{summary['orientations']} orientations, covering radius "
        f"{_number(covering)}° (every rotation lies within it of one of the set)"
    )
    if "half_angle" in orientation_set:
        axis = _vector(orientation_set.get("axis", []))
        half = math.degrees(float(orientation_set["half_angle"]))
        described += f"; a cone of half angle {half:.1f}° about the axis {axis}"
    grid_text = f"{shape} voxels of {100 * summary['resolution']:g} cm"
    if origin is not None:
        grid_text += f", first centre {_vector(origin)} m"
    if bounds is not None:
        grid_text += f"; covers {_vector(bounds[0])} to {_vector(bounds[1])} m"
    kind = "exact (closed form)"
    if summary.get("redundancy"):
        redundancy = summary["redundancy"]
        kind = (
            f"exact (closed form) at {redundancy['samples']} values of the "
            f"{html.escape(str(redundancy['parameter']))}"
        )
    if summary["sampled"]:
        kind = f"sampled, {summary['samples']} random configurations"
    rows = [
        ("robot", f"<code>{html.escape(str(attrs.get('robot')))}</code>"),
        ("tool frame", f"<code>{html.escape(str(attrs.get('tool_frame')))}</code>"),
        ("URDF SHA-256", f"<code>{html.escape(str(attrs.get('urdf_sha256')))}</code>"),
        ("grid", grid_text),
        ("orientation set", described),
        (
            "poses",
            f"{summary['voxels']} voxels × {summary['orientations']} = "
            f"{summary['poses']}",
        ),
        ("map", kind),
    ]
    tolerances = attrs.get("tolerances")
    if tolerances:
        rows.append(
            (
                "singularity tolerances",
                f"|s| &lt; {tolerances['shoulder']:g} m, |e| &lt; "
                f"{tolerances['elbow']:.4g}, |w| &lt; {tolerances['wrist']:.4g}",
            )
        )
    versions = attrs.get("versions") or {}
    if versions:
        rows.append(
            (
                "versions",
                ", ".join(
                    f"{html.escape(str(k))} {html.escape(str(v))}"
                    for k, v in versions.items()
                ),
            )
        )
    return f"<h2>The map</h2>{_table(rows)}"


def _slices(summary: Mapping[str, Any], uri: Mapping[str, str]) -> str:
    heights = ", ".join(f"{z:+.3f}" for z in summary["slice_heights_m"])
    return f"""<h2>Reachability, slice by slice</h2>
<img alt="reachability slices" src="{uri["reachability_slices"]}">
<p class="cap">Horizontal slices at z = {heights} m (the voxel layers nearest
heights spread over the reached range), seen from above. Colour: fraction of the
map's orientations reached with a usable branch in that voxel; grey: reached in
none. Red cross: the base axis.</p>
<h2>Best dexterity, slice by slice</h2>
<img alt="dexterity slices" src="{uri["dexterity_slices"]}">
<p class="cap">Same slices; colour: the largest manipulability over the reached
orientations of each voxel [m³] (0 on a singularity).</p>
<h2>Section through the base axis</h2>
<img alt="vertical section" src="{uri["sections"]}">
<p class="cap">The x–z plane through the base axis (the voxel layer nearest y = 0):
reachability and best dexterity. Dotted red line: the base axis; triangle: the
base frame origin.</p>"""


def _histograms(uri: Mapping[str, str]) -> str:
    return f"""<h2>Distributions</h2>
<img alt="histograms" src="{uri["histograms"]}">
<p class="cap">Over the voxels reached in at least one orientation.</p>"""


def _singular(
    attrs: Mapping[str, Any], summary: Mapping[str, Any], uri: Mapping[str, str]
) -> str:
    if "singular_regions" not in uri:
        if summary.get("redundancy"):
            return """<h2>Singular regions</h2><p>This map holds no singularity
measures: the shoulder, elbow and wrist distances of a six-axis map are factors of
det J, which the 6 × 7 Jacobian of a seven-axis arm has not (its manipulability is
kept; the loci of an SRS arm are in <code>workbench report singularities</code>).</p>"""
        return """<h2>Singular regions</h2><p>This map holds no singularity
measures (a sampled map keeps the manipulability only).</p>"""
    by_kind = summary.get("near_singular_by_kind") or {}
    means = ", ".join(f"{k} {_number(v)}" for k, v in by_kind.items())
    kinds = (
        f""" The other panels show, per voxel, the median over the reached
orientations of the best branch's distance to each singularity, the analytic
factors of det J (<code>workbench.singularities.conditions</code>): shoulder |s|
[m], elbow |e| and wrist |w| [1]; dark is near-singular. The
fractions of reached orientations below each tolerance, averaged over the
reachable voxels, are {means}."""
        if by_kind
        else ""
    )
    return f"""<h2>Singular regions</h2>
<img alt="singular regions" src="{uri["singular_regions"]}">
<p class="cap">Section through the base axis. First panel: per voxel, the
fraction of the reached orientations whose best branch is near-singular
(singularity margin min(|s|/tol_s, |e|/tol_e, |w|/tol_w) &lt; 1).{kinds}</p>
<img alt="near-singular slices" src="{uri["singular_slices"]}">
<p class="cap">The near-singular fraction at the heights of the slices above.</p>"""
