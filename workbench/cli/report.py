"""``workbench report``: self-contained HTML reports (``report singularities``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from workbench.atomic_files import check_outputs, write_text_atomic
from workbench.cli._common import (
    add_json_flag,
    add_robot_argument,
    bounded_int,
    get_input_paths,
    load_robot_from_args,
    print_json,
)
from workbench.trajectory.csv_io import read_trajectory_csv

#: Largest ``--grid`` (points per axis of the det J map).
MAX_GRID = 4000
#: Largest ``--svd-grid`` (points per axis of the σmin map: one SVD each).
MAX_SVD_GRID = 1000


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``report`` command group."""
    parser = commands.add_parser(
        "report",
        help="self-contained HTML reports with plots",
        description="Write an HTML report (figures embedded, no other files).",
    )
    kinds = parser.add_subparsers(dest="report", metavar="REPORT", required=True)
    sing = kinds.add_parser(
        "singularities",
        help="singularity maps, loci, arm drawings, cross-checks",
        description=(
            "det J over (θ2, θ3) with the shoulder and elbow loci, σmin map, the "
            "arm in each singular configuration, analytic vs Pinocchio check, "
            "degenerate directions; for other OPW or UR-type arms the factors, "
            "their check and the classes of random configurations; for SRS "
            "seven-axis arms (KUKA iiwa) the analytic conditions of the 6 × 7 "
            "Jacobian checked against its σmin; numeric maps only for other "
            "robots (σmin over a joint grid, and over random configurations for "
            "seven-axis arms such as the Panda)."
        ),
    )
    add_robot_argument(sing)
    sing.add_argument("--out", required=True, type=Path, help="HTML file to write")
    sing.add_argument(
        "--grid",
        type=bounded_int(2, MAX_GRID),
        default=1000,
        help=f"points per axis of the det J map (default: 1000; 2..{MAX_GRID})",
    )
    sing.add_argument(
        "--svd-grid",
        type=bounded_int(2, MAX_SVD_GRID),
        default=200,
        help=f"points per axis of the σmin map (default: 200; 2..{MAX_SVD_GRID})",
    )
    sing.add_argument(
        "--trajectory",
        type=Path,
        help="joint trajectory CSV (t,q1..qn,qd..,qdd..): closest approaches",
    )
    sing.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress lines on stderr (nor with -q or WORKBENCH_PROGRESS=0)",
    )
    add_json_flag(sing)
    sing.set_defaults(
        run=run_singularities,
        progress_message="report: computing the singularity report…",
    )


def run_singularities(args: argparse.Namespace) -> int:
    """Build and write the singularity report; returns the exit code."""
    from workbench.reports.singularity_report import build_singularity_report

    out = args.out
    check_outputs([out], get_input_paths(args))
    if args.no_progress:
        args.progress.finish()  # no line at all
    robot = load_robot_from_args(args)
    trajectory = None
    if args.trajectory is not None:
        samples = read_trajectory_csv(args.trajectory, robot.nq)
        trajectory = (samples.t, samples.q)
    report = build_singularity_report(
        robot,
        grid_size=args.grid,
        svd_grid_size=args.svd_grid,
        trajectory=trajectory,
        progress=None
        if args.no_progress
        else args.progress.stages("report singularities", unit="points"),
    )
    write_text_atomic(out, report.html)
    summary = {"out": str(out), **report.summary}
    if args.json:
        print_json(summary)
        return 0
    print(f"wrote {out} ({out.stat().st_size / 1e6:.2f} MB)")
    if summary["elbow_theta3_deg"] is not None:
        elbow = ", ".join(f"{v:+.3f}" for v in summary["elbow_theta3_deg"])
        print(f"elbow-singular θ3 [deg]: {elbow}")
        print(f"det J constant K [m²]: {summary['det_j_constant']:+.6f}")
        check = summary["cross_check"]
        error = check["max_relative_error"]
        print(
            f"analytic vs Pinocchio: max relative error {error:.2e}"
            f" over {check['samples']} configurations"
        )
    if (srs := summary.get("srs")) is not None:
        check = srs["cross_check"]
        print(
            f"SRS det(J Jᵀ) analytic vs Pinocchio: max relative error "
            f"{check['max_relative_error']:.2e} over {check['samples']} configurations"
        )
        for locus in srs["loci"]:
            print(
                f"on the {locus['kind']} locus: σmin {locus['sigma_min']:.1e}, "
                f"|uᵀJ| {locus['residual']:.1e}"
            )
    if (sampled := summary.get("sigma_min_samples")) is not None:
        print(
            f"σmin over {sampled['samples']} random configurations: min "
            f"{sampled['min']:.3g}, median {sampled['median']:.3g}"
            + ("" if srs is not None else " (numeric only: no analytic conditions)")
        )
    records = summary.get("degenerate_directions", [])
    if records:
        worst = max(r["residual"] for r in records)
        print(
            f"degenerate directions: {len(records)} configurations, "
            f"max |u^T J| {worst:.1e}"
        )
    for name, key in (("det J", "det_j_map"), ("σmin", "sigma_min_map")):
        if (grid := summary[key]) is not None:  # no det J map when nv ≠ 6
            shape, seconds = grid["shape"], grid["seconds"]
            print(f"{name} map {shape[0]}×{shape[1]}: {seconds:.3f} s")
    return 0
