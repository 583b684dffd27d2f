r"""The seven-axis sections of the singularity report: SRS analytic, others sampled.

An SRS arm (KUKA LBR iiwa) gets its analytic conditions
(:mod:`workbench.singularities.redundant`: det(J Jᵀ) factorised, the elbow,
shoulder, wrist and shoulder-wrist loci) checked against Pinocchio's 6 × 7
Jacobian three ways:

* det(J Jᵀ) of the factorisation against the product of the squared singular
  values of Pinocchio's J over random configurations within the limits
  (largest relative error);
* one configuration on each locus (a random one with the locus' angles set):
  σ_min of Pinocchio's J there, and the residual ‖uᵀ J_W‖ of the analytic lost
  direction u (J moved to the wrist centre W);
* a sweep of the locus' angle(s) through it: σ_min of Pinocchio's J and the
  analytic distance along it, both zero at the locus only.

Every seven-axis arm, SRS or not (the Franka Panda has no analytic conditions
here), gets σ_min of Pinocchio's J over random configurations within the
limits: a sampled picture, said as such.
"""

from __future__ import annotations

import html
from typing import Any

import numpy as np
import numpy.typing as npt
from matplotlib.figure import Figure

from workbench.model.robot import Robot
from workbench.singularities.measures import compute_measures
from workbench.singularities.redundant import (
    SRS_CONDITION_UNITS,
    SRS_SINGULARITY_KINDS,
    compute_srs_conditions,
    compute_srs_degenerate_direction,
    compute_srs_det_jjt,
    find_srs_factorisation,
)

FloatArray = npt.NDArray[np.float64]

#: Random configurations of the σ_min histogram.
SIGMA_SAMPLES = 20_000
#: Half width of each locus sweep [rad] and its points.
SWEEP_HALF_WIDTH = 0.5
SWEEP_POINTS = 201
#: The four loci where J loses rank, and the DH angles (index, value [rad])
#: that put a configuration on each; the sweep moves the angles with a
#: ``+ t`` (the crossing ones).
LOCUS_ANGLES: dict[str, tuple[tuple[int, float, bool], ...]] = {
    "elbow": ((3, 0.0, True),),
    "shoulder": ((1, 0.0, True), (2, np.pi / 2, False)),
    "wrist": ((5, 0.0, True), (4, np.pi / 2, False)),
    "shoulder_wrist": ((1, 0.0, True), (5, 0.0, True)),
}


def compute_redundant_data(
    robot: Robot, samples: int, seed: int, summary: dict[str, Any]
) -> dict[str, Any]:
    """The seven-axis sections' data; fills ``summary`` (the report's JSON).

    Args:
        robot: A robot with seven (or more) joints.
        samples: Random configurations of the det(J Jᵀ) check.
        seed: Seed of every random configuration.
        summary: The report's summary, completed in place with
            ``sigma_min_samples`` and, for an SRS arm, ``srs``.
    """
    rng = np.random.default_rng(seed)
    lower, upper = np.maximum(robot.lower, -np.pi), np.minimum(robot.upper, np.pi)
    q = rng.uniform(lower, upper, (SIGMA_SAMPLES, robot.nq))
    sigma = compute_measures(robot, q).sigma_min
    summary["sigma_min_samples"] = {
        "samples": SIGMA_SAMPLES,
        "min": float(sigma.min()),
        "median": float(np.median(sigma)),
        "max": float(sigma.max()),
    }
    data: dict[str, Any] = {"sigma_samples": sigma, "srs": None}
    fac = find_srs_factorisation(robot)
    if fac is None:
        return data
    check = q[:samples]
    measures = compute_measures(robot, check)
    pinocchio = np.prod(measures.singular_values**2, axis=-1)
    analytic = compute_srs_det_jjt(robot, check)
    relative = np.abs(analytic - pinocchio) / np.maximum(np.abs(pinocchio), 1e-300)
    loci = [_locus(robot, fac, kind, q[0]) for kind in LOCUS_ANGLES]
    sweeps = {kind: _sweep(robot, fac, kind, q[1]) for kind in LOCUS_ANGLES}
    summary["srs"] = {
        "det_jjt": "(d3 d5 sin θ4)² [sin²θ6 ΣA² + sin²θ2 ΣB²]",
        "d3": fac.d3,
        "d5": fac.d5,
        "cross_check": {
            "samples": len(check),
            "max_relative_error": float(relative.max()),
        },
        "loci": loci,
        "sweeps": {
            kind: {
                "half_width_deg": float(np.degrees(SWEEP_HALF_WIDTH)),
                "sigma_min_at_locus": float(s["sigma"][SWEEP_POINTS // 2]),
                "sigma_min_elsewhere": float(
                    np.delete(s["sigma"], SWEEP_POINTS // 2).min()
                ),
            }
            for kind, s in sweeps.items()
        },
    }
    data["srs"] = {
        "fac": fac,
        "loci": loci,
        "sweeps": sweeps,
        "check": (len(check), float(relative.max())),
    }
    return data


def _on_locus(fac: Any, kind: str, q: FloatArray, t: float = 0.0) -> FloatArray:
    """``q`` with the locus' DH angles set (crossing ones moved by ``t``) [rad]."""
    out = np.array(q, dtype=np.float64)
    for index, value, crossing in LOCUS_ANGLES[kind]:
        theta = value + (t if crossing else 0.0)
        out[index] = (theta - fac.theta_offset[index]) / fac.joint_sign[index]
    return out


def _jacobian_at(robot: Robot, q: FloatArray, point: FloatArray) -> FloatArray:
    """Pinocchio's tool Jacobian (base axes) with its linear rows at ``point``."""
    jacobian = robot.jacobian(q)
    r = point - robot.fk(q).translation
    skew = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    moved: FloatArray = jacobian.copy()
    moved[:3] = jacobian[:3] - skew @ jacobian[3:]  # v_W = v_tool + ω × r
    return moved


def _locus(robot: Robot, fac: Any, kind: str, q: FloatArray) -> dict[str, Any]:
    on = _on_locus(fac, kind, q)
    direction = compute_srs_degenerate_direction(robot, on, kind)
    jacobian = _jacobian_at(robot, on, direction.reference_point)
    return {
        "kind": kind,
        "q_deg": np.degrees(on).round(6).tolist(),
        "condition": float(direction.condition),
        "sigma_min": float(compute_measures(robot, on).sigma_min),
        "direction": direction.direction.tolist(),
        "reference_point": direction.reference_point.tolist(),
        "residual": float(np.linalg.norm(direction.direction @ jacobian)),
    }


def _sweep(robot: Robot, fac: Any, kind: str, q: FloatArray) -> dict[str, FloatArray]:
    t = np.linspace(-SWEEP_HALF_WIDTH, SWEEP_HALF_WIDTH, SWEEP_POINTS)
    path = np.array([_on_locus(fac, kind, q, float(x)) for x in t])
    condition = np.abs(getattr(compute_srs_conditions(robot, path), kind))
    return {
        "t": t,
        "sigma": compute_measures(robot, path).sigma_min,
        "condition": condition,
    }


def plot_sigma_samples(robot: Robot, sigma: FloatArray) -> Figure:
    """Histogram of σ_min over the random configurations (log scale)."""
    fig = Figure(figsize=(7.2, 3.6))
    ax = fig.add_subplot()
    floor = 1e-6
    shown = np.maximum(sigma, floor)
    bins = np.logspace(np.log10(shown.min()), np.log10(shown.max()), 60)
    ax.hist(shown, bins=bins.tolist(), color="#3b6ea8")
    ax.set_xscale("log")
    ax.set_xlabel("σmin of Pinocchio's J (mixed units: m/rad and 1)")
    ax.set_ylabel("configurations")
    ax.set_title(
        f"{robot.name}: σmin over {len(sigma)} random configurations within the limits"
    )
    return fig


def plot_locus_sweeps(robot: Robot, sweeps: dict[str, dict[str, FloatArray]]) -> Figure:
    """σ_min of Pinocchio's J and the analytic distance across each SRS locus."""
    fig = Figure(figsize=(9.0, 6.2))
    axes = fig.subplots(2, 2).ravel()
    for ax, (kind, sweep) in zip(axes, sweeps.items(), strict=True):
        degrees = np.degrees(sweep["t"])
        ax.plot(degrees, sweep["sigma"], color="#3b6ea8", label="σmin (Pinocchio)")
        ax.plot(
            degrees,
            sweep["condition"],
            color="#d9711c",
            linestyle="--",
            label=f"|{kind}| (analytic)",
        )
        ax.axvline(0.0, color="#999", linewidth=0.8)
        ax.set_title(f"across the {kind.replace('_', '-')} locus")
        ax.set_xlabel("crossing angle(s) − locus [deg]")
        ax.legend(fontsize=8)
    fig.suptitle(f"{robot.name}: σmin and the analytic distance, both 0 on the locus")
    fig.tight_layout()
    return fig


def render_sections(robot: Robot, data: dict[str, Any], uri: dict[str, str]) -> str:
    """HTML of the seven-axis sections."""
    sigma = data["sigma_samples"]
    srs = data["srs"]
    sampled = f"""<h2>σmin over random configurations</h2>
<img alt="sigma_min over random configurations" src="{uri["sigma_min_samples"]}">
<p class="cap">{len(sigma)} configurations drawn uniformly within the joint limits
(each angle within ±180°): σmin of Pinocchio's 6 × {robot.nv} Jacobian, smallest
{sigma.min():.3g}, median {np.median(sigma):.3g}. A sampled picture: random
configurations almost never lie on a singular locus, so this shows how far the
arm usually is from one, not where the loci are.</p>"""
    if srs is None:
        return sampled
    fac = srs["fac"]
    units = "".join(
        f"<tr><td>{kind}</td><td>{html.escape(SRS_CONDITION_UNITS[kind])}</td></tr>"
        for kind in SRS_SINGULARITY_KINDS
    )
    rows = "".join(
        f"<tr><td>{html.escape(r['kind'])}</td>"
        f"<td>{' '.join(f'{v:.2f}' for v in r['q_deg'])}</td>"
        f"<td class=n>{r['condition']:.1e}</td><td class=n>{r['sigma_min']:.1e}</td>"
        f"<td>[{' '.join(f'{v:+.3f}' for v in r['direction'])}]</td>"
        f"<td class=n>{r['residual']:.1e}</td></tr>"
        for r in srs["loci"]
    )
    return f"""<h2>SRS: analytic conditions of the 6 × 7 Jacobian</h2>
<p>Spherical shoulder S, elbow E and spherical wrist W (upper arm d3 =
{fac.d3:.4f} m, forearm d5 = {fac.d5:.4f} m): <b>det(J Jᵀ) = (d3 d5 sin θ4)²
[sin²θ6 ΣA² + sin²θ2 ΣB²]</b> [m⁶], with θ the DH angles of the fitted chain
(<code>workbench.singularities.redundant</code>). J loses rank exactly on four
loci; the fifth kind, the arm angle's algorithmic singularity (W on axis 1), loses
no twist.</p>
<table><tr><th>distance</th><th>unit and formula</th></tr>{units}</table>
<h2>Check against σmin of Pinocchio's Jacobian</h2>
<p>det(J Jᵀ) from the factorisation against Π σᵢ² of Pinocchio's J over
{srs["check"][0]} random configurations within the joint limits: largest relative
error <b>{srs["check"][1]:.2e}</b>. On each locus (a random configuration with
the locus' angles set): σmin of Pinocchio's J, and ‖uᵀ J‖ of the analytic lost
direction u = [f; m] (linear rows at W, base axes) with Pinocchio's J moved to
W.</p>
<table><tr><th>locus</th><th>q [deg]</th><th>distance</th><th>σmin</th>
<th>u</th><th>‖uᵀJ‖</th></tr>{rows}</table>
<img alt="sigma_min across each locus" src="{uri["srs_sweeps"]}">
<p class="cap">Each locus' angle(s) swept by ±{np.degrees(SWEEP_HALF_WIDTH):.0f}°
through it, the other joints held: σmin of Pinocchio's J (solid) and the analytic
distance (dashed) vanish together, at the locus only.</p>
{sampled}"""
