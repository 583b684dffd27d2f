"""Angeles et al. (1988) Section V end to end, as used by ``workbench demo``.

Table II poses → closed-form IK (all branches; the one nearest Table III is
kept) → normal-spline joint trajectory with T = 10 s → exact limit check,
minimum duration and time-optimal comparison → forward kinematics as the
paper's seven numbers (Figs. 4–6) with the tool velocity and acceleration →
closest approach to each singularity → clearance to the assumed work cell
(pedestal and pick table, :func:`workbench.collision.get_angeles_scene`) and
between the links, reported (not fatal: the paper checked collisions on a
graphic display) → PNG plots (Figs. 1–6) and a CSV.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from workbench import paper_data
from workbench.collision import CollisionChecker, get_angeles_scene
from workbench.errors import WorkbenchError
from workbench.ik import analytic, nearest
from workbench.model.robot import Robot
from workbench.poses import ANGELES7_PRINTED_TOL, se3_from_angeles7
from workbench.trajectory import (
    compare_time_optimal,
    compute_cartesian_trajectory,
    compute_literal_spline,
    minimum_duration,
    pick_and_place,
)
from workbench.trajectory.csv_io import write_trajectory_csv

_log = logging.getLogger(__name__)

#: Samples of the Cartesian histories and of the singularity check.
CARTESIAN_SAMPLES = 1001
#: Sample rate of the written joint CSV [Hz].
CSV_RATE_HZ = 100.0
#: Figure files written by :func:`run_pick_and_place_demo`.
FIGURES = {
    "fig1": "fig1_normal_spline.png",
    "fig2": "fig2_joints_1-3.png",
    "fig3": "fig3_joints_4-6.png",
    "fig4": "fig4_vect.png",
    "fig5": "fig5_cos.png",
    "fig6": "fig6_position.png",
    "tool_velocity": "tool_velocity_acceleration.png",
}


def _ik_table(robot: Robot) -> dict[str, Any]:
    """Every closed-form branch of both Table II poses, in degrees."""
    table = {}
    for pose, printed in (
        ("pick", paper_data.ANGELES_PICK_ANGELES7),
        ("place", paper_data.ANGELES_PLACE_ANGELES7),
    ):
        target = se3_from_angeles7(printed, tol=ANGELES7_PRINTED_TOL)
        table[pose] = [
            {
                "branch": s.branch,
                "q_deg": np.rad2deg(s.q),
                "within_limits": bool(s.within_limits),
            }
            for s in analytic(robot, target)
        ]
    return table


def _nearest_table3(robot: Robot, printed: np.ndarray, q3: np.ndarray) -> Any:
    """The closed-form branch of a Table II pose nearest its Table III row.

    The paper's configuration is reproduced, within the limits or not (its
    pick sits on joint 2's limit, the rounded Table II a hair beyond), so
    this is ``ik.nearest`` on every branch, not the selection rule
    (``ik.select``) that chooses within the limits.
    """
    target = se3_from_angeles7(printed, tol=ANGELES7_PRINTED_TOL)
    return nearest(analytic(robot, target, q_previous=q3), q3)


def _singularities(robot: Robot, t: np.ndarray, q: np.ndarray) -> dict[str, Any]:
    try:
        from workbench.singularities.along_path import find_closest_approaches
    except ImportError:  # the singularity analysis is another module's job
        return {}
    approaches = find_closest_approaches(robot, t, q)
    return {
        kind: {
            "t": a.t,
            "distance": a.distance,
            "unit": a.unit,
            "crossings": list(a.crossings),
        }
        for kind, a in approaches.items()
    }


def check_collisions(robot: Robot, traj) -> dict[str, Any]:
    """Clearance of a pick-and-place trajectory in Angeles' (assumed) scene.

    The spline is checked with its exact peak joint speeds and accelerations
    as the bound between the samples (every ``1 / CSV_RATE_HZ`` s), so no
    contact is missed.

    Returns:
        ``{"scene", "min_clearance", "collisions", ...}`` (JSON-ready).
    """
    checker = CollisionChecker(robot, get_angeles_scene(robot))
    report = traj.check_collisions(checker, CSV_RATE_HZ)
    return {"scene": checker.scene.name, **report.as_dict()}


def run_pick_and_place_demo(
    robot: Robot, out_dir: Path, *, plots: bool = True
) -> dict[str, Any]:
    """Section V of Angeles et al. on ``robot`` (the ``puma560`` model).

    Args:
        robot: Angeles' PUMA (Table I).
        out_dir: Folder for the CSV and the PNG figures (created).
        plots: Write the PNG figures (matplotlib, imported only then).

    Returns:
        A JSON-ready summary.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    duration = paper_data.ANGELES_DURATION
    q3_pick = np.deg2rad(paper_data.ANGELES_PICK_Q_DEG)
    q3_place = np.deg2rad(paper_data.ANGELES_PLACE_Q_DEG)
    pick = _nearest_table3(robot, paper_data.ANGELES_PICK_ANGELES7, q3_pick)
    place = _nearest_table3(robot, paper_data.ANGELES_PLACE_ANGELES7, q3_place)
    traj = pick_and_place(robot, pick.q, place.q, duration)
    paper_traj = pick_and_place(robot, q3_pick, q3_place, duration)
    t = np.linspace(0.0, duration, CARTESIAN_SAMPLES)
    cart = compute_cartesian_trajectory(traj, t)
    ends = np.abs(np.concatenate([cart.velocity[[0, -1]], cart.acceleration[[0, -1]]]))
    comparison = compare_time_optimal(robot, q3_pick, q3_place, use_toppra=False)
    write_trajectory_csv(
        out_dir / "pick_and_place.csv",
        traj.sample_uniform(CSV_RATE_HZ),
        joint_names=robot.joint_names,
    )
    try:
        singular = _singularities(robot, t, traj.sample(t)[0])
    except WorkbenchError as err:
        _log.warning("singularity check skipped: %s", err)
        singular = {}
    figures = _write_figures(traj, cart, out_dir) if plots else {}
    return {
        "duration": duration,
        "n_points": traj.spline.n_points,
        "amplitude": traj.spline.amplitude,
        "ik_branches": _ik_table(robot),
        "pick": {
            "branch": pick.branch,
            "q_deg": np.rad2deg(pick.q),
            "minus_table3_deg": np.rad2deg(pick.q) - paper_data.ANGELES_PICK_Q_DEG,
            "within_limits": pick.within_limits,
        },
        "place": {
            "branch": place.branch,
            "q_deg": np.rad2deg(place.q),
            "minus_table3_deg": np.rad2deg(place.q) - paper_data.ANGELES_PLACE_Q_DEG,
            "within_limits": place.within_limits,
        },
        "violations": [v.as_dict() for v in traj.check_limits()],
        "table3_violations": [v.as_dict() for v in paper_traj.check_limits()],
        "min_duration": minimum_duration(robot, traj.q_pick, traj.q_place),
        "table3_min_duration": comparison.spline_duration,
        "time_optimal_duration": comparison.optimal_duration,
        "time_optimal_ratio": comparison.ratio,
        "tool_end_rates_max": float(ends.max()),
        "singularities": singular,
        "table3_collision": check_collisions(robot, paper_traj),
        "csv": str(out_dir / "pick_and_place.csv"),
        "figures": figures,
    }


def _write_figures(traj, cart, out_dir: Path) -> dict[str, str]:
    from workbench.plots.trajectory import (
        plot_cartesian,
        plot_joint_trajectory,
        plot_normal_spline,
    )

    files = {key: out_dir / name for key, name in FIGURES.items()}
    plot_normal_spline(
        traj.spline,
        files["fig1"],
        literal=compute_literal_spline(traj.spline.n_points, 5.0),
        literal_amplitude=5.0,
    )
    title = "Angeles et al. Sec. V, T = 10 s: joints {} (Fig. {})"
    plot_joint_trajectory(
        traj, files["fig2"], joints=(0, 1, 2), title=title.format("1–3", 2)
    )
    plot_joint_trajectory(
        traj, files["fig3"], joints=(3, 4, 5), title=title.format("4–6", 3)
    )
    for key, which in (("fig4", "vect"), ("fig5", "cos"), ("fig6", "position")):
        plot_cartesian(cart, files[key], which=which)
    plot_cartesian(cart, files["tool_velocity"], which="velocity")
    return {key: str(path) for key, path in files.items()}


def format_pick_and_place(result: dict[str, Any]) -> str:
    """A short human summary of :func:`run_pick_and_place_demo`'s result."""
    lines = [
        f"Pick and place (Sec. V), T = {result['duration']:g} s, normal spline "
        f"N = {result['n_points']}, A = {result['amplitude']:.4f} (paper: A = 5, "
        "see docs/errata-angeles-spline.md)"
    ]
    for pose in ("pick", "place"):
        r = result[pose]
        lines.append(
            f"  IK of Table II {pose}: branch {r['branch']}, max |q - Table III| = "
            f"{np.max(np.abs(r['minus_table3_deg'])):.3f} deg"
            + ("" if r["within_limits"] else " (NOT within limits)")
        )
    lines.append(
        "  limits along the Table III trajectory: "
        + ("all respected" if not result["table3_violations"] else "VIOLATED")
    )
    lines.append("  limits along the IK(Table II) trajectory: " + _violations(result))
    lines.append(
        f"  minimum duration {result['table3_min_duration']:.4f} s; time-optimal on "
        f"the same path {result['time_optimal_duration']:.4f} s (ratio "
        f"{result['time_optimal_ratio']:.3f})"
    )
    lines.append(
        f"  tool velocity/acceleration at t = 0 and T: max "
        f"{result['tool_end_rates_max']:.1e}"
    )
    for kind, a in result["singularities"].items():
        if kind == "sigma_min":
            lines.append(
                f"  smallest singular value of J: {a['distance']:.3g} at "
                f"t = {a['t']:.2f} s (samples every "
                f"{result['duration'] / (CARTESIAN_SAMPLES - 1):g} s)"
            )
            continue
        crossed = (
            f", crossed at t = {', '.join(f'{c:.2f}' for c in a['crossings'])} s"
            if a["crossings"]
            else ""
        )
        lines.append(
            f"  {kind} singularity: closest {a['distance']:.3g} {a['unit']} at "
            f"t = {a['t']:.2f} s{crossed}"
        )
    lines += _format_collisions(result["table3_collision"])
    return "\n".join(lines)


def _format_collisions(report: dict[str, Any]) -> list[str]:
    """Lines on the clearance of the Table III path (reported, not fatal)."""
    at = report["min_clearance_at"]
    lines = [
        f"  clearance along the Table III path (scene {report['scene']}, assumed, "
        f"see docs/collision.md): min {report['min_clearance']:.4f} m "
        f"({at['body_a']} - {at['body_b']} at t = {at['t']:.2f} s)"
    ]
    for c in report["collisions"]:
        lines.append(
            f"    CONTACT {c['body_a']} - {c['body_b']}: t = {c['t_start']:.2f} .. "
            f"{c['t_end']:.2f} s, deepest {-1e3 * c['distance']:.1f} mm at "
            f"t = {c['t']:.2f} s"
        )
    return lines


def _violations(result: dict[str, Any]) -> str:
    """The violations in degrees (the PUMA's joints are revolute)."""
    if not result["violations"]:
        return "all respected"
    unit = {"position": "deg", "velocity": "deg/s", "acceleration": "deg/s²"}
    return "; ".join(
        f"{v['joint']} {v['kind']} {np.rad2deg(v['value']):.4f} {unit[v['kind']]} at "
        f"t = {v['t']:.3g} s beyond its limit {np.rad2deg(v['limit']):.4g} "
        f"{unit[v['kind']]}"
        + (
            " (Table II is printed to 2 decimals; Table III puts joint 2 exactly "
            "on its 45 deg limit)"
            if v["kind"] == "position"
            else ""
        )
        for v in result["violations"]
    )
