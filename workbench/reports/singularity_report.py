"""The singularity report: one self-contained HTML file with embedded figures.

matplotlib is imported lazily (Agg canvas, no pyplot), only when a report is
built. For a PUMA-type robot the report holds the det J map over (θ2, θ3) with
the shoulder and elbow loci, the σmin map, the arm in each singular
configuration, the analytic factorisation checked against Pinocchio, the
degenerate directions and, given a trajectory, its closest approaches. Any
other OPW or UR-type arm gets the maps, its factors of det J checked against
Pinocchio, the classes of random configurations, the arm at each singularity
and the degenerate directions; other robots (a 7-axis arm, any arm without that
structure) the numeric maps only: σmin, manipulability and condition number, and
det J when the Jacobian is square. A seven-axis arm also gets σmin over random
configurations and, for an SRS arm (KUKA LBR iiwa), its analytic conditions
checked against σmin of Pinocchio's Jacobian
(:mod:`workbench.reports._redundant_singularities`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.atomic_files import write_text_atomic
from workbench.model.robot import Robot
from workbench.progress import StageProgress
from workbench.reports.html_report import HtmlReport
from workbench.singularities.along_path import find_closest_approaches
from workbench.singularities.conditions import (
    PumaFactorisation,
    classify_configuration,
    compute_conditions,
    find_factorisation,
    find_puma_factorisation,
)
from workbench.singularities.directions import compute_degenerate_direction
from workbench.singularities.loci import (
    compute_example_configurations,
    get_elbow_singular_theta3,
)
from workbench.singularities.measures import (
    compute_joint_grid,
    compute_measures,
    cross_check_det_j,
)

FloatArray = npt.NDArray[np.float64]
#: ``progress(stage, done, total)``.
ReportProgress = StageProgress

#: Grid side for robots without the analytic determinant (one Pinocchio call
#: per point), whatever ``grid_size`` asks.
NUMERIC_GRID_MAX = 120
#: Sub-grid stride for the check of the analytic det J map against Pinocchio.
SUBGRID_STRIDE = 50
#: Half width of the (θ2, θ3) maps around the middle of the joint limits [rad].
MAP_HALF_WIDTH = np.radians(200.0)
#: Maps drawn from the σmin grid for robots without an analytic factorisation.
NUMERIC_MAPS = ("manipulability", "condition_number")


@dataclass(frozen=True, slots=True)
class SingularityReport(HtmlReport):
    """A built singularity report (``html``, ``summary``, ``figures``)."""


def build_singularity_report(
    robot: Robot,
    *,
    grid_size: int = 1000,
    svd_grid_size: int = 200,
    samples: int = 2000,
    trajectory: tuple[npt.ArrayLike, npt.ArrayLike] | None = None,
    progress: ReportProgress | None = None,
    seed: int = 0,
) -> SingularityReport:
    """Compute everything and render the HTML.

    Args:
        robot: Any robot; PUMA-type ones get the analytic sections, other OPW
            and UR-type arms their factors, classes and degenerate directions,
            the others the numeric maps (no det J map when nv ≠ 6).
        grid_size: Points per axis of the det J map.
        svd_grid_size: Points per axis of the σmin map.
        samples: Random configurations (within limits) of the det J check.
        trajectory: Optional ``(t, q)``, shapes (K,) [s] and (K, nq) [rad].
        progress: Called as ``progress(stage, done, total)`` during the grids.
        seed: Seed of the random configurations.

    Raises:
        InputError: If the trajectory is malformed.
    """
    from workbench.reports import _singularity_figures as figs
    from workbench.reports._singularity_html import render

    fac: PumaFactorisation | None = find_puma_factorisation(robot)
    if fac is None:
        grid_size = min(grid_size, NUMERIC_GRID_MAX)
        svd_grid_size = min(svd_grid_size, NUMERIC_GRID_MAX)
    axes = [np.linspace(*_window(robot, j), grid_size) for j in (1, 2)]
    svd_axes = [np.linspace(*_window(robot, j), svd_grid_size) for j in (1, 2)]
    q_fixed = _fixed_joints(robot, fac, seed)

    def stage(name: str) -> Callable[[int, int], None] | None:
        return None if progress is None else (lambda d, n: progress(name, d, n))

    det_grid = None
    if robot.nv == 6:  # det J needs a square Jacobian
        det_grid = compute_joint_grid(
            robot, *axes, q_fixed=q_fixed, progress=stage("det J map")
        )
    svd_grid = compute_joint_grid(
        robot, *svd_axes, q_fixed=q_fixed, quantity="svd", progress=stage("σmin map")
    )
    data: dict[str, Any] = {"robot": robot, "fac": fac, "det_grid": det_grid}
    data |= {"svd_grid": svd_grid, "examples": {}}
    summary: dict[str, Any] = {
        "robot": robot.name,
        "puma_type": fac is not None,
        "elbow_theta3_deg": None,
        "det_j_map": None if det_grid is None else _grid_summary(det_grid),
        "sigma_min_map": _grid_summary(svd_grid),
        "map_ranges": _map_ranges(svd_grid),
    }
    overlay: dict[str, Any] = {"shoulder": None, "elbow_theta3": None, "examples": {}}
    data["family_fac"] = None
    if fac is None:  # another OPW or UR-type arm: factors, check and classes
        data["family_fac"] = _family_data(robot, samples, seed, summary)
        if data["family_fac"] is not None:
            data |= _direction_data(robot, summary)
    if fac is not None and det_grid is not None:  # a PUMA has six joints
        data |= _analytic_data(robot, fac, det_grid, samples, seed, summary)
        sub = det_grid.configurations()[::2, ::2]
        shoulder = compute_conditions(robot, sub).shoulder
        overlay = {
            "shoulder": (det_grid.x[::2], det_grid.y[::2], shoulder),
            "elbow_theta3": data["elbow"],
            "examples": data["examples"],
        }
    figures: dict[str, bytes] = {}
    if det_grid is not None:
        det_map = figs.plot_det_map(robot, det_grid, **overlay)
        figures["det_j_map"] = figs.png_bytes(det_map)
    sigma_map = figs.plot_sigma_map(robot, svd_grid, **overlay)
    figures["sigma_min_map"] = figs.png_bytes(sigma_map)
    if fac is None and data["family_fac"] is None:
        for measure in NUMERIC_MAPS:
            measure_map = figs.plot_measure_map(robot, svd_grid, measure)
            figures[f"{measure}_map"] = figs.png_bytes(measure_map)
    if robot.nv > 6:  # seven axes: SRS analytic conditions, σmin sampled
        from workbench.reports import _redundant_singularities as seven

        data["redundant"] = seven.compute_redundant_data(robot, samples, seed, summary)
        sampled = seven.plot_sigma_samples(robot, data["redundant"]["sigma_samples"])
        figures["sigma_min_samples"] = figs.png_bytes(sampled)
        if data["redundant"]["srs"] is not None:
            sweeps = seven.plot_locus_sweeps(robot, data["redundant"]["srs"]["sweeps"])
            figures["srs_sweeps"] = figs.png_bytes(sweeps)
    if data.get("directions"):
        arms = figs.plot_singular_arms(robot, data["examples"], data["directions"])
        figures["arms"] = figs.png_bytes(arms, tight=False)
    if trajectory is not None:
        t, q = (np.asarray(v, dtype=np.float64) for v in trajectory)
        approaches = find_closest_approaches(robot, t, q)
        signals = compute_conditions(robot, q).as_dict() if fac is not None else {}
        signals["sigma_min"] = np.atleast_1d(compute_measures(robot, q).sigma_min)
        along = figs.plot_distances_along_path(t, signals, approaches)
        figures["trajectory"] = figs.png_bytes(along)
        data["approaches"] = approaches
        summary["closest_approach"] = {
            kind: {"t": a.t, "distance": a.distance, "unit": a.unit}
            | {"crossings": list(a.crossings)}
            for kind, a in approaches.items()
        }
    summary["figures"] = list(figures)
    return SingularityReport(render(data, summary, figures), summary, figures)


def write_singularity_report(
    robot: Robot, path: str | Path, **options: Any
) -> SingularityReport:
    """Build the report (see :func:`build_singularity_report`) and write it.

    The file is written whole or not at all (``atomic_files.write_text_atomic``).
    """
    report = build_singularity_report(robot, **options)
    write_text_atomic(path, report.html)
    return report


def _family_data(
    robot: Robot, samples: int, seed: int, summary: dict[str, Any]
) -> PumaFactorisation | None:
    """Factors of det J, their check and the classes of random configurations.

    For an OPW or UR-type arm without a PUMA DH table (``ur5``, the KUKA and
    ABB models); None for an arm of neither family.
    """
    if robot.nv != 6:  # a seven-axis family has no 6R factorisation of det J
        return None
    fac = find_factorisation(robot)
    if fac is None:
        return None
    rng = np.random.default_rng(seed)
    q = rng.uniform(robot.lower, robot.upper, (samples, 6))
    check = cross_check_det_j(robot, q)
    classes = [classify_configuration(robot, qi) for qi in q]
    described = fac.describe()
    elbow = get_elbow_singular_theta3(robot)
    summary |= {
        "elbow_theta3_deg": [round(float(v), 6) for v in np.degrees(elbow)],
        "family": fac.family,
        "det_j_constant": fac.constant,
        "factors": {k: described[k] for k in ("shoulder", "elbow", "wrist")},
        "cross_check": {
            "samples": samples,
            "max_relative_error": check.max_relative_error,
        },
        "classes": {
            kind: sum(kind in c for c in classes)
            for kind in ("shoulder", "elbow", "wrist")
        }
        | {"none": sum(not c for c in classes)},
    }
    return fac


def _analytic_data(
    robot: Robot,
    fac: PumaFactorisation,
    det_grid: Any,
    samples: int,
    seed: int,
    summary: dict[str, Any],
) -> dict[str, Any]:
    """Cross-checks, elbow angles and degenerate directions of a PUMA."""
    rng = np.random.default_rng(seed)
    start = time.perf_counter()
    check = cross_check_det_j(
        robot, rng.uniform(robot.lower, robot.upper, (samples, 6))
    )
    seconds = time.perf_counter() - start
    sub_q = det_grid.configurations()[::SUBGRID_STRIDE, ::SUBGRID_STRIDE]
    sub = cross_check_det_j(robot, sub_q.reshape(-1, 6))
    sub_err = float(np.max(np.abs(sub.analytic - sub.pinocchio)))
    elbow = get_elbow_singular_theta3(robot)
    inside = [bool(robot.lower[2] <= v <= robot.upper[2]) for v in elbow]
    described = fac.describe()
    summary |= {
        "elbow_theta3_deg": [round(float(v), 6) for v in np.degrees(elbow)],
        "elbow_theta3_within_limits": inside,
        "det_j_constant": fac.constant,
        "factors": {k: described[k] for k in ("shoulder", "elbow", "wrist")},
        "cross_check": {
            "samples": samples,
            "max_relative_error": check.max_relative_error,
            "seconds": round(seconds, 3),
            "subgrid_points": int(sub.q.shape[0]),
            "subgrid_max_abs_error": sub_err,
        },
    }
    return {
        "check": check,
        "check_seconds": seconds,
        "subgrid": (sub, sub_err),
        "elbow": elbow,
        "elbow_inside": inside,
    } | _direction_data(robot, summary)


def _direction_data(robot: Robot, summary: dict[str, Any]) -> dict[str, Any]:
    """One configuration on each locus and its degenerate directions (any arm)."""
    examples = compute_example_configurations(robot)
    directions = {
        name: compute_degenerate_direction(robot, q, name.split(",")[0])
        for name, q in examples.items()
    }
    summary["degenerate_directions"] = [
        {
            "name": name,
            "q_deg": np.degrees(d.q).round(6).tolist(),
            "sigma_min": d.sigma_min,
            "reference": d.reference,
            "reference_point": d.reference_point.tolist(),
            "direction": d.direction.tolist(),
            "residual": d.residual,
            "tool_direction": d.tool_direction.tolist(),
            "tool_residual": d.tool_residual,
            "paper_axis": d.paper_axis,
            "angle_to_paper_deg": d.angle_to_paper_deg,
            "self_motion": d.self_motion.tolist(),
        }
        for name, d in directions.items()
    ]
    return {"examples": examples, "directions": directions}


def _fixed_joints(robot: Robot, fac: PumaFactorisation | None, seed: int) -> FloatArray:
    """Joints held fixed on the maps.

    For a PUMA: 0, and θ5 = 90° so that the wrist factor is 1. Otherwise the
    most manipulable of a few random configurations within the limits.
    """
    if fac is not None:
        q = np.clip(np.zeros(robot.nq), robot.lower, robot.upper)
        q[4] = np.pi / 2 - fac.theta_offset[4]
        return q
    lower = np.maximum(robot.lower, -np.pi)
    upper = np.minimum(robot.upper, np.pi)
    candidates = np.random.default_rng(seed).uniform(lower, upper, (64, robot.nq))
    return candidates[np.argmax(compute_measures(robot, candidates).manipulability)]


def _window(robot: Robot, joint: int) -> tuple[float, float]:
    """A bit more than one turn, centred on the middle of the limits [rad].

    The maps are 2π-periodic; the margin keeps loci near ±π off the edges.
    """
    lo, hi = robot.lower[joint], robot.upper[joint]
    mid = 0.5 * (lo + hi) if np.isfinite(lo + hi) else 0.0
    return mid - MAP_HALF_WIDTH, mid + MAP_HALF_WIDTH


def _grid_summary(grid: Any) -> dict[str, Any]:
    return {
        "shape": [grid.y.size, grid.x.size],
        "method": grid.method,
        "seconds": round(grid.seconds, 4),
    }


def _map_ranges(grid: Any) -> dict[str, list[float | None]]:
    """``[min, max]`` of each SVD measure over the grid; None stands for inf."""
    return {
        name: [
            float(v) if np.isfinite(v) else None
            for v in (np.min(values), np.max(values))
        ]
        for name, values in grid.values.items()
        if name != "det_j"
    }
