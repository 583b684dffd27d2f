"""HTML of the singularity report (no matplotlib here; figures come as PNG bytes)."""

from __future__ import annotations

import base64
import html
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.singularities.conditions import CONDITION_UNITS, SINGULARITY_KINDS

FloatArray = npt.NDArray[np.float64]

_CSS = """
body{font:15px/1.55 system-ui,sans-serif;max-width:1080px;margin:2em auto;padding:0 1em;
color:#222}h1{margin-bottom:.2em}h2{margin-top:1.8em;border-bottom:1px solid #ddd}
table{border-collapse:collapse;margin:.5em 0 1em;font-size:13px}
td,th{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}
th{background:#f2f2f2}td.n{text-align:right;font-variant-numeric:tabular-nums}
img{max-width:100%;display:block;margin:1em auto .2em}.cap{color:#555;font-size:13px}
code{background:#f4f4f4;padding:0 3px}.box{background:#f7f9fc;border:1px solid #cdd8e6;
padding:.6em 1.2em;border-radius:6px}
"""


def render(data: dict[str, Any], summary: dict[str, Any], figures: dict) -> str:
    """The whole document."""
    robot, fac = data["robot"], data["fac"]
    uri = {
        name: "data:image/png;base64," + base64.b64encode(png).decode("ascii")
        for name, png in figures.items()
    }
    parts = [_head(robot, fac, data), _key_numbers(data, summary)]
    if fac is not None:
        parts.append(_conditions(fac))
    parts.append(_maps(data, uri))
    if "redundant" in data:
        from workbench.reports._redundant_singularities import render_sections

        parts.append(render_sections(robot, data["redundant"], uri))
    if fac is not None:
        parts += [_arms_and_directions(data, uri), _cross_check(data), _kang(data)]
    elif data.get("directions"):
        parts.append(_arms_and_directions(data, uri))
    if "approaches" in data:
        parts.append(_trajectory(data["approaches"], uri["trajectory"]))
    return "\n".join([*parts, "</body></html>"])


def _head(robot: Any, fac: Any, data: dict[str, Any]) -> str:
    name = html.escape(robot.name)
    family = data.get("family_fac")
    if fac is not None:
        kind = "PUMA-type DH table: analytic conditions and numeric measures."
    elif family is not None:
        kind = (
            f"{family.family.upper()} family, recognised from the joint axes: "
            "det J factorised into shoulder, elbow and wrist conditions; maps "
            "and numeric measures."
        )
    elif robot.nv == 6:
        kind = "No OPW or UR structure: numeric measures only (Pinocchio's Jacobian)."
    elif data.get("redundant", {}).get("srs") is not None:
        kind = (
            f"SRS seven-axis arm: J is 6 × {robot.nv}, so it has no determinant; "
            "det(J Jᵀ) factorised into the elbow, shoulder and wrist conditions, "
            "checked against σmin of Pinocchio's Jacobian; numeric maps."
        )
    else:
        kind = (
            f"{robot.nv} joints: J is 6 × {robot.nv}, so it has no determinant, "
            "and this arm has no analytic singularity conditions here: numeric "
            "measures only (σmin, manipulability, condition number of Pinocchio's "
            "Jacobian over a joint grid and over random configurations)."
        )
    return f"""<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">
<title>Singularities of {name}</title><style>{_CSS}</style></head><body>
<h1>Singularities of {name}</h1>
<p>{kind} Jacobian J of the tool frame <code>{html.escape(robot.tool_frame)}</code>,
LOCAL_WORLD_ALIGNED: rows [m/s; rad/s] in base axes per rad/s of joint speed.
Angles in degrees, lengths in metres.</p>"""


def _key_numbers(data: dict[str, Any], summary: dict[str, Any]) -> str:
    det, svd = data["det_grid"], data["svd_grid"]
    rows = []
    if data["fac"] is not None:
        fac, check = data["fac"], summary["cross_check"]
        angles = ", ".join(
            f"{math.degrees(v):+.3f}° ({'within' if ok else 'outside'} the limits)"
            for v, ok in zip(data["elbow"], data["elbow_inside"], strict=True)
        )
        rows += [
            ("det J", f"K · shoulder · elbow · wrist, K = {fac.constant:+.6f} m²"),
            ("elbow-singular θ3", angles),
            (
                "analytic vs Pinocchio",
                f"max relative error {check['max_relative_error']:.2e} over "
                f"{check['samples']} random configurations",
            ),
        ]
    family = data.get("family_fac")
    if family is not None:
        described = family.describe()
        check, classes = summary["cross_check"], summary["classes"]
        rows += [
            ("det J", f"K · shoulder · elbow · wrist, K = {family.constant:+.6f} m²"),
            *((kind, html.escape(described[kind])) for kind in SINGULARITY_KINDS),
            (
                "elbow-singular θ3",
                ", ".join(f"{v:+.3f}°" for v in summary["elbow_theta3_deg"]),
            ),
            (
                "analytic vs Pinocchio",
                f"max relative error {check['max_relative_error']:.2e} over "
                f"{check['samples']} random configurations",
            ),
            (
                "classes of those",
                ", ".join(f"{k}: {v}" for k, v in classes.items()),
            ),
        ]
    if det is not None:
        rows.append(
            (
                "det J map",
                f"{det.x.size} × {det.y.size} in {det.seconds:.3f} s ({det.method})",
            )
        )
    rows.append(
        (
            "σmin map",
            f"{svd.x.size} × {svd.y.size} in {svd.seconds:.3f} s ({svd.method})",
        )
    )
    rows += [
        (f"{_MEASURE_NAMES[name]} over the map", f"{_number(lo)} … {_number(hi)}")
        for name, (lo, hi) in summary["map_ranges"].items()
    ]
    body = "".join(f"<tr><th>{k}</th><td>{v}</td></tr>" for k, v in rows)
    return f'<div class="box"><h3>Key numbers</h3><table>{body}</table></div>'


def _conditions(fac: Any) -> str:
    d = fac.describe()
    meaning = {
        "shoulder": "x1 coordinate of the wrist centre: its signed distance from the "
        "vertical plane through the base axis z0 parallel to the shoulder axis z1",
        "elbow": "sine of the angle between the upper arm (x2) and the elbow → wrist "
        "centre line seen along z2; 0 at the largest and smallest reach",
        "wrist": "sin θ5; 0 when the axes of joints 4 and 6 (z3, z5) are collinear",
    }
    rows = "".join(
        f"<tr><td>{k}</td><td><code>{html.escape(d[k])}</code></td>"
        f"<td>{CONDITION_UNITS[k]}</td><td>{meaning[k]}</td></tr>"
        for k in SINGULARITY_KINDS
    )
    return f"""<h2>The three conditions and the factorisation of det J</h2>
<p>Derived from this robot's own DH table (σ1 = sin α1 = {fac.sigma1:+.0f},
σ3 = sin α3 = {fac.sigma3:+.0f}, sin α4 sin α5 = {fac.wrist_sign:+.0f}; c23 =
cos(θ2 + θ3)): <b>det J [m³] = K · shoulder · elbow · wrist</b> with
<code>{html.escape(d["constant"])}</code>. Each condition is a signed distance;
the configuration is singular where one of them is 0.</p>
<table><tr><th>condition</th><th>formula</th><th>unit</th><th>meaning</th></tr>
{rows}</table>"""


def _number(value: float | None) -> str:
    return "∞" if value is None else f"{value:.3g}"


def _maps(data: dict[str, Any], uri: dict[str, str]) -> str:
    det, svd, fac = data["det_grid"], data["svd_grid"], data["fac"]
    held = " ".join(f"{v:.0f}" for v in np.degrees(svd.q_fixed) + 0.0)
    j2, j3 = (j + 1 for j in svd.joints)
    markers = "; ".join(
        f"{k + 1}. {html.escape(n)}"
        for k, n in enumerate(data["examples"])
        if n != "wrist"
    )
    loci = (
        f" Green: shoulder locus; orange dashes: elbow loci; dotted box: joint "
        f"limits; markers: {markers}. θ5 = 90° makes the wrist factor 1, so the "
        "map is K · shoulder · elbow."
        if fac is not None
        else ""
    )
    det_section = ""
    if det is not None:
        det_section = f"""<h2>det J over (θ{j2}, θ{j3})</h2>
<img alt="det J map" src="{uri["det_j_map"]}">
<p class="cap">Other joints held at [{held}] deg. {det.x.size} × {det.y.size}
points ({det.method}, {det.seconds:.3f} s); slightly more than one turn is shown
(the map is 360°-periodic).{loci}</p>"""
    measures = "".join(
        f"""<h2>{_MEASURE_NAMES[name]} over (θ{j2}, θ{j3})</h2>
<img alt="{name} map" src="{uri[f"{name}_map"]}">
<p class="cap">{_MEASURE_CAPTIONS[name]} Same grid as the σmin map.</p>"""
        for name in ("manipulability", "condition_number")
        if f"{name}_map" in uri
    )
    return f"""{det_section}
<h2>σmin over (θ{j2}, θ{j3})</h2>
<img alt="sigma_min map" src="{uri["sigma_min_map"]}">
<p class="cap">Smallest singular value of the numeric Jacobian, {svd.x.size} ×
{svd.y.size} points ({svd.method}, {svd.seconds:.3f} s), other joints held at
[{held}] deg; slightly more than one turn is shown. Its dark troughs are
where J loses rank{"; they lie on the analytic loci (thin lines)" if fac else ""}.
Its values depend on units (m vs rad); its zeros do not.</p>{measures}"""


_MEASURE_NAMES = {
    "sigma_min": "σmin",
    "manipulability": "Manipulability",
    "condition_number": "Condition number",
}
_MEASURE_CAPTIONS = {
    "manipulability": "Yoshikawa's manipulability √det(J Jᵀ), the product of the "
    "singular values: 0 where J loses rank, larger where the tool moves more "
    "freely in every direction.",
    "condition_number": "σmax / σmin of J on a log scale (clipped at 10⁶): 1 is "
    "isotropic, ∞ singular, so the dark regions are near-singular.",
}


def _vec(v: FloatArray) -> str:
    return "[" + " ".join(f"{x + 0.0:+.3f}" for x in v) + "]"


def _deg(q: FloatArray) -> str:
    return " ".join(f"{v + 0.0:.2f}" for v in np.degrees(q))


def _arms_and_directions(data: dict[str, Any], uri: dict[str, str]) -> str:
    puma = data["fac"] is not None
    rows = []
    for k, (name, d) in enumerate(data["directions"].items()):
        angle = "—" if d.angle_to_paper_deg is None else f"{d.angle_to_paper_deg:.2f}°"
        kang = f"<td>{d.paper_axis or '—'}</td><td class=n>{angle}</td>" if puma else ""
        rows.append(
            f"<tr><td>{k + 1}. {html.escape(name)}</td><td>{_deg(d.q)}</td>"
            f"<td class=n>{d.sigma_min:.1e}</td><td>{_vec(d.direction)}</td>"
            f"<td class=n>{d.residual:.1e}</td><td class=n>{d.tool_residual:.1e}</td>"
            f"{kang}<td>{_vec(d.self_motion)}</td></tr>"
        )
    first = next(iter(data["directions"].values()))
    reference = html.escape(first.reference)
    head = "<th>Kang</th><th>angle</th>" if puma else ""
    image = ""
    if "arms" in uri:
        image = f'<img alt="arm in each singular configuration" src="{uri["arms"]}">'
    if puma:
        title = "The arm at each singularity (cf. Kang, Figs. 2 and 3)"
        caption = """Stick figure through the DH frame origins; red: degenerate
direction u at the wrist centre (★); dashed: the axis Kang names. Shoulder: the
wrist centre lies in the plane x1 = 0 and cannot move along z1. Elbow: the wrist
centre is at its largest (3) or smallest (4) distance from the shoulder and
cannot move along the shoulder → wrist line. The retracted elbow singularity (4)
lies outside the joint limits."""
        paper = " The angle compares u's linear part with Kang's axis."
    else:
        title = "The arm at each singularity"
        caption = f"""Stick figure through the joint origins; red: the linear part
of the degenerate direction u at the {reference}. Shoulder: that point lies in the
plane through axis 1 parallel to axis 2 and cannot move along axis 2. Elbow: the
arm is stretched (extended) or folded (retracted); for an OPW arm u is a force
along the dotted line, which meets axes 1, 2 and 3; for a UR arm it has a moment
part too."""
        paper = ""
    return f"""<h2>{title}</h2>
{image}
<p class="cap">{caption}</p>
<h2>Degenerate directions</h2>
<p>u: unit left null vector of J with its linear rows at the {reference},
[linear; angular] in base axes — the tool motion the arm cannot make (‖uᵀJ‖ with
Pinocchio's J moved to that point; ‖uᵀJ‖ tool: the same u moved to the tool frame
origin, with Pinocchio's J as it is). v: unit joint velocity [rad/s] with
J v ≈ 0 — joint motion lost to self-motion.{paper}</p>
<table><tr><th>configuration</th><th>q [deg]</th><th>σmin</th><th>u</th>
<th>‖uᵀJ‖</th><th>‖uᵀJ‖ tool</th>{head}<th>self-motion v</th></tr>
{"".join(rows)}</table>"""


def _cross_check(data: dict[str, Any]) -> str:
    check, (sub, sub_err) = data["check"], data["subgrid"]
    rows = "".join(
        f"<tr><td>{_deg(q)}</td><td class=n>{a:+.9e}</td><td class=n>{p:+.9e}</td>"
        f"<td class=n>{r:.1e}</td></tr>"
        for q, a, p, r in zip(
            check.q[:8],
            check.analytic,
            check.pinocchio,
            check.relative_error,
            strict=False,
        )
    )
    return f"""<h2>Cross-check: analytic vs Pinocchio</h2>
<p>{check.q.shape[0]} configurations drawn uniformly within the joint limits:
largest relative error of the factorised det J against
<code>np.linalg.det(robot.jacobian(q))</code> <b>{check.max_relative_error:.2e}</b>
({data["check_seconds"]:.2f} s). On a sub-grid of the det J map ({sub.q.shape[0]}
points) the largest absolute difference is <b>{sub_err:.2e} m³</b>. First rows:</p>
<table><tr><th>q [deg]</th><th>analytic [m³]</th><th>Pinocchio [m³]</th>
<th>relative error</th></tr>{rows}</table>"""


def _kang(data: dict[str, Any]) -> str:
    fac, d = data["fac"], data["directions"]
    elbow = d.get("elbow, extended")
    angle = f"{elbow.angle_to_paper_deg:.1f}°" if elbow else "—"
    bend = math.degrees(math.atan2(abs(fac.a3), abs(fac.d4)))
    gap = abs(fac.a2 - fac.forearm) * 1e3
    return f"""<h2>Compared with Kang (2007), Section 3</h2>
<ul><li>Kang's printed Jacobian and conditions (1)–(3) agree with Pinocchio
(see <code>tests/test_singularities.py</code>); the elbow angles follow from
θ3 = atan2(d4, a3) and that − 180°.</li>
<li>Shoulder: the degenerate direction is exactly z1, as stated.</li>
<li>Elbow: the degenerate direction is the line from the shoulder to the wrist
centre, not x1 in general ({angle} apart in configuration 3); it equals x1 only
with the upper arm horizontal and no shoulder offset d2 + d3.</li>
<li>"Extended (but not fully extended)": at the elbow singularity the wrist
centre is exactly at its largest distance from the shoulder; only the links look
bent, by atan(a3/d4) = {bend:.2f}°.</li>
<li>Retracted: since a2 ≈ √(a3² + d4²), the wrist centre is then at most
|a2 − √(a3² + d4²)| = {gap:.2f} mm from the plane x1 = 0, whatever θ2: the arm is
also almost shoulder-singular there.</li></ul>
<p class="cap">Details: <code>docs/errata-kang-singularities.md</code>.</p>"""


def _trajectory(approaches: dict[str, Any], image: str) -> str:
    rows = "".join(
        f"<tr><td>{k}</td><td class=n>{a.distance:+.6g}</td><td>{a.unit}</td>"
        f"<td class=n>{a.t:.4f}</td>"
        f"<td>{', '.join(f'{c:.4f}' for c in a.crossings) or 'none'}</td></tr>"
        for k, a in approaches.items()
    )
    return f"""<h2>Along the trajectory</h2>
<table><tr><th>singularity</th><th>closest signed distance</th><th>unit</th>
<th>at t [s]</th><th>crosses the locus at t [s]</th></tr>{rows}</table>
<img alt="signed distances along the trajectory" src="{image}">"""
