"""The papers' examples end to end, as used by ``workbench demo``.

Angeles et al. (1988): Table III through the forward kinematics of the
``puma560`` model, compared with their Table II; then Section V end to end
(:mod:`workbench.demo.pick_and_place`): IK of Table II, the normal-spline
trajectory, limits, minimum duration, Cartesian histories, singularities and
the figures.
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench import paper_data
from workbench.demo.pick_and_place import run_pick_and_place_demo
from workbench.model.loading import load_robot
from workbench.model.robot import Robot
from workbench.poses import angeles7_from_se3
from workbench.tasks.fish_cutting import run_fish_cutting, summarize_fish_cutting
from workbench.trajectory.csv_io import read_trajectory_csv, write_trajectory_csv

_log = logging.getLogger(__name__)

#: Table II's row labels and the unit of each row as printed.
TABLE2_ROWS = (
    "e_x sinφ",
    "e_y sinφ",
    "e_z sinφ",
    "cosφ",
    "p_x [mm]",
    "p_y [mm]",
    "p_z [mm]",
)
_PRINTED_SCALE = np.array([1.0, 1.0, 1.0, 1.0, 1e3, 1e3, 1e3])


@dataclass(frozen=True, slots=True)
class Table2Comparison:
    """Table II as printed next to FK of Table III, in the paper's units.

    Attributes:
        pose: ``"pick"`` or ``"place"``.
        q_deg: Table III joint values, shape (6,) [deg].
        printed: Table II column, shape (7,) (orientation numbers, then mm).
        computed: FK of ``q_deg`` in the same units, shape (7,).
    """

    pose: str
    q_deg: npt.NDArray[np.float64]
    printed: npt.NDArray[np.float64]
    computed: npt.NDArray[np.float64]

    @property
    def rounded(self) -> npt.NDArray[np.float64]:
        """``computed`` rounded as the paper prints (two decimals)."""
        return np.round(self.computed, 2)

    @property
    def matches(self) -> bool:
        """True when every rounded value equals the printed one."""
        return bool(np.all(np.abs(self.rounded - self.printed) < 1e-9))


def compare_table2(robot: Robot) -> list[Table2Comparison]:
    """FK of Angeles' Table III (pick, place) against Table II.

    Args:
        robot: The ``puma560`` model (Angeles Table I).

    Returns:
        One comparison per pose, in the paper's units (mm for positions).
    """
    rows = []
    for pose, q_deg, printed in (
        ("pick", paper_data.ANGELES_PICK_Q_DEG, paper_data.ANGELES_PICK_ANGELES7),
        ("place", paper_data.ANGELES_PLACE_Q_DEG, paper_data.ANGELES_PLACE_ANGELES7),
    ):
        computed = angeles7_from_se3(robot.fk(np.deg2rad(q_deg))) * _PRINTED_SCALE
        rows.append(Table2Comparison(pose, q_deg, printed * _PRINTED_SCALE, computed))
    return rows


def format_table2(rows: list[Table2Comparison]) -> str:
    """Markdown table: printed vs computed for each pose."""
    header = (
        "| coordinate | "
        + " | ".join(f"{r.pose} printed | {r.pose} computed" for r in rows)
        + " |"
    )
    lines = [header, "|---" * (1 + 2 * len(rows)) + "|"]
    for i, label in enumerate(TABLE2_ROWS):
        cells = " | ".join(f"{r.printed[i]:.2f} | {r.computed[i]:.4f}" for r in rows)
        lines.append(f"| {label} | {cells} |")
    return "\n".join(lines)


def _write_pages(robot: Robot, out_dir: Path) -> dict[str, str]:
    """The 3D preview and the singularity report of the pick-and-place path."""
    from workbench.reports.singularity_report import write_singularity_report
    from workbench.viz import write_trajectory_html

    samples = read_trajectory_csv(out_dir / "pick_and_place.csv", robot.nq)
    preview = write_trajectory_html(
        robot, samples, out_dir / "preview.html", title="Angeles et al. Sec. V"
    )
    report = out_dir / "singularities.html"
    write_singularity_report(robot, report, trajectory=(samples.t, samples.q))
    return {"preview": str(preview), "singularity_report": str(report)}


def _run_fish_cutting(out_dir: Path, *, pages: bool) -> dict[str, object]:
    """Kang's Fig. 7 program on the simulated fish: CSV, summary, 3D preview."""
    kang = load_robot("puma560-kang")
    result = run_fish_cutting(kang)
    write_trajectory_csv(out_dir / "fishcut.csv", result.servo)
    summary = summarize_fish_cutting(result, kang.name)
    if pages:
        from workbench.viz import write_trajectory_html

        write_trajectory_html(
            kang, result.servo, out_dir / "fishcut.html", title="Kang Fig. 7 fish cut"
        )
    return summary


def format_fish_cutting(summary: dict[str, Any]) -> str:
    """Short human summary of the fish-cutting run."""
    kinds = [event["kind"] for event in summary["events"]]
    latency = summary["latency_us"]
    return (
        f"Fish cutting (Kang Fig. 7) on {summary['robot']}, simulated fish seed "
        f"{summary['seed']}: {summary['cycles']} planning cycles at "
        f"{summary['planning_rate_hz']:g} Hz ({summary['duration']:.2f} s), servo "
        f"{summary['servo_rate_hz']:g} Hz\n"
        f"  events: {kinds.count('flesh')} flesh, {kinds.count('bone')} bone; "
        f"max joint speed {summary['max_joint_speed']:.3f} rad/s; wrist flips "
        f"{summary['wrist_flips']}; wrist singularity crossings "
        f"{summary['wrist_singularity_crossings']}\n"
        f"  planning cycle: median {latency['median']:.1f} µs, "
        f"p99 {latency['p99']:.1f} µs"
    )


def run_demo(robot: Robot, out_dir: Path, *, plots: bool = True) -> dict[str, object]:
    """Run the papers' examples and write the results into ``out_dir``.

    Args:
        robot: The ``puma560`` model (Angeles Table I).
        out_dir: Output folder (created).
        plots: Also write the PNG figures, the 3D preview (``preview.html``)
            and the singularity report (``singularities.html``): the slow part.

    Returns:
        A JSON-ready summary (also written to ``out_dir/summary.json``).
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    rows = compare_table2(robot)
    table = format_table2(rows)
    (out_dir / "table2.md").write_text(
        "# Angeles et al. Table II reproduced from Table III\n\n" + table + "\n",
        encoding="utf-8",
    )
    summary = {
        "robot": robot.name,
        "out_dir": str(out_dir),
        "table2": {
            r.pose: {
                "q_deg": r.q_deg,
                "printed": r.printed,
                "computed": r.computed,
                "matches_printed_precision": r.matches,
            }
            for r in rows
        },
        "table2_matches": all(r.matches for r in rows),
        "table2_markdown": table,
        "pick_and_place": run_pick_and_place_demo(robot, out_dir, plots=plots),
    }
    summary["fish_cutting"] = _run_fish_cutting(out_dir, pages=plots)
    if plots:
        summary["pages"] = _write_pages(robot, out_dir)
    (out_dir / "summary.json").write_text(
        json.dumps(summary, indent=2, default=lambda a: np.asarray(a).tolist()) + "\n",
        encoding="utf-8",
    )
    _log.info("demo written to %s", out_dir)
    return summary
