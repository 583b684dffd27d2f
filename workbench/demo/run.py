"""The papers' examples end to end, as used by ``workbench demo``.

Angeles et al. (1988): Table III through the forward kinematics of the
``puma560`` model, compared with their Table II; then Section V end to end
(:mod:`workbench.demo.pick_and_place`): IK of Table II, the normal-spline
trajectory, limits, minimum duration, Cartesian histories, singularities and
the figures; a coarse workspace map of the arm and the base placement of the
cell (:mod:`workbench.demo.base_placement`); Table III's path in the cell with
an obstacle on it, planned around (:mod:`workbench.demo.avoid`). Kang's fish
cutting runs in a second process meanwhile.
"""

from __future__ import annotations

import ctypes
import functools
import json
import logging
import multiprocessing
import os
import signal
import sys
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.connection import Connection
from pathlib import Path
from types import FrameType, TracebackType
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench import paper_data
from workbench.atomic_files import remove_temporaries_of_process, write_text_atomic
from workbench.collision import CollisionChecker, check_path, get_angeles_scene
from workbench.demo.avoid import run_avoid_demo
from workbench.demo.base_placement import run_base_placement_demo
from workbench.demo.pick_and_place import run_pick_and_place_demo
from workbench.errors import InputError
from workbench.json_numbers import to_json_ready
from workbench.model.loading import load_robot
from workbench.model.robot import Robot
from workbench.planning.online_planner import load_kernels
from workbench.poses import angeles7_from_se3
from workbench.tasks.fish_cutting import run_fish_cutting, summarize_fish_cutting
from workbench.tasks.fish_scene import get_fish_cutting_scene
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
PRINTED_DECIMALS = 2  # Angeles' Table II prints two decimals (mm for positions)
SUMMARY_DIGITS = 9  # significant digits of the floats in summary.json


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
        return np.round(self.computed, PRINTED_DECIMALS)

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
        # Back to the printed decimals: 0.09407 m * 1e3 is -94.07000000000001 mm.
        printed_units = np.round(printed * _PRINTED_SCALE, PRINTED_DECIMALS)
        rows.append(Table2Comparison(pose, q_deg, printed_units, computed))
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
    from workbench.reports.singularity_report import build_singularity_report
    from workbench.viz import write_trajectory_html

    samples = read_trajectory_csv(out_dir / "pick_and_place.csv", robot.nq)
    preview = write_trajectory_html(
        robot,
        samples,
        out_dir / "preview.html",
        title=f"Angeles et al. (1988) Sec. V: pick and place, {robot.name}",
        checker=CollisionChecker(robot, get_angeles_scene(robot)),
    )
    report = out_dir / "singularities.html"
    built = build_singularity_report(robot, trajectory=(samples.t, samples.q))
    write_text_atomic(report, built.html)
    return {"preview": str(preview), "singularity_report": str(report)}


def _run_fish_cutting(out_dir: Path, *, pages: bool) -> dict[str, Any]:
    """Kang's Fig. 7 program on the simulated fish: CSV, summary, 3D preview."""
    # First the planner's kernels that do not call the closed form: in a
    # second process (run_demo), the first may be compiling that one now.
    load_kernels()
    kang = load_robot("puma560-kang")
    result = run_fish_cutting(kang)
    write_trajectory_csv(
        out_dir / "fishcut.csv", result.servo, joint_names=kang.joint_names
    )
    summary = summarize_fish_cutting(result, kang.name)
    checker = CollisionChecker(
        kang, get_fish_cutting_scene(kang, result.fish, result.setup)
    )
    stride = max(1, round(result.setup.servo_rate / result.setup.planning_rate))
    clearance = check_path(checker, result.servo.t, result.servo.q, stride=stride)
    summary["collision"] = {"scene": checker.scene.name, **clearance.as_dict()}
    if pages:
        from workbench.viz import write_trajectory_html

        write_trajectory_html(
            kang,
            result.servo,
            out_dir / "fishcut.html",
            title=f"Kang (2007) Fig. 7: fish cutting, {kang.name}",
            checker=checker,
        )
    return summary


def _run_second_part(out_dir: Path, *, plots: bool) -> dict[str, Any]:
    """What the second process runs: the fish cutting, then the base placement.

    The base placement comes last: it needs the closed form, which the first
    process compiles meanwhile (and this one then loads from the cache).
    """
    fish = _run_fish_cutting(out_dir, pages=plots)
    placement = run_base_placement_demo(load_robot("puma560"), out_dir, plots=plots)
    return {"fish_cutting": fish, "base_placement": placement}


class _InSecondProcess:
    """``function(*args, **kwargs)`` run in a second process; :meth:`result` here.

    The process is forked (Linux, with more than one core available): it starts
    at once, with this process's modules and loaded kernels. Elsewhere, and
    whenever the second process fails, :meth:`result` makes the call in this
    process instead, so that an error is raised here with its traceback,
    exactly as without a second process. Leaving the ``with`` block early (an
    error here, Ctrl-C) stops the second process. The second process ends with
    this one: it gets SIGTERM when this process dies, even by ``kill -9``
    (Linux ``PR_SET_PDEATHSIG``), ignores Ctrl-C (this process stops it), and
    on SIGTERM leaves its files as they were (no temporary file stays).
    """

    def __init__(
        self, folder: Path, function: Callable[..., Any], *args: Any, **kwargs: Any
    ):
        self._call = functools.partial(function, *args, **kwargs)
        self._process: multiprocessing.process.BaseProcess | None = None
        self._receiver: Connection | None = None
        if sys.platform == "linux" and len(os.sched_getaffinity(0)) > 1:
            context = multiprocessing.get_context("fork")
            receiver, sender = context.Pipe(duplex=False)
            process = context.Process(
                target=_send_result,
                args=(sender, self._call, os.getpid(), folder),
                daemon=True,
            )
            # Ctrl-C waits until the fork is done (in its hooks, it would be
            # printed and lost); the child unblocks it after ignoring it.
            blocked = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
            try:
                process.start()
            except (AssertionError, OSError):  # e.g. in a daemonic process
                receiver.close()
            else:
                self._process, self._receiver = process, receiver
            finally:
                sender.close()
                signal.pthread_sigmask(signal.SIG_SETMASK, blocked)

    def __enter__(self) -> _InSecondProcess:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if self._process is not None:  # result() was not reached
            self._process.terminate()
            self._stop()

    def result(self) -> Any:
        """The function's return value (or its exception, raised here)."""
        if self._receiver is not None:
            try:
                done, value = self._receiver.recv()
            except EOFError:  # the process died
                done, value = False, None
            finally:
                self._stop()
            if done:
                return value
            _log.debug("the second process failed: running %s here", self._call)
        return self._call()

    def _stop(self) -> None:
        if self._receiver is not None:
            self._receiver.close()
            self._receiver = None
        if self._process is not None:
            self._process.join()
            self._process = None


def _send_result(
    sender: Connection, call: Callable[[], Any], parent: int, folder: Path
) -> None:
    """In the second process: send ``(True, call())``, or ``(False, None)``."""
    _end_with_parent(parent, folder)
    try:
        result = (True, call())
    except SystemExit:  # the call asked to exit: nothing to send
        raise
    except BaseException:  # the parent makes the call again, to raise it
        result = (False, None)
    try:
        sender.send(result)
        sender.close()
    except OSError:  # the parent is gone
        pass


#: Linux prctl option: the signal a process gets when its parent dies.
_PR_SET_PDEATHSIG = 1


def _end_with_parent(parent: int, folder: Path) -> None:
    """In a forked child: stop on the parent's death, cleanly on SIGTERM.

    SIGTERM removes the child's temporary files in ``folder`` and exits at
    once; Ctrl-C is ignored, as the parent stops the child itself.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    signal.signal(signal.SIGTERM, functools.partial(_exit_on_sigterm, folder))
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    except (OSError, AttributeError):  # not Linux: the parent's exit stops it
        pass
    if os.getppid() != parent:  # the parent died before prctl
        os._exit(0)


def _exit_on_sigterm(folder: Path, signum: int, frame: FrameType | None) -> None:
    remove_temporaries_of_process(folder, os.getpid())
    os._exit(128 + signum)


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
        f"p99 {latency['p99']:.1f} µs\n"
        + _format_fish_clearance(summary.get("collision"))
    )


def _format_fish_clearance(report: dict[str, Any] | None) -> str:
    if report is None:
        return "  collision check skipped"
    at = report["min_clearance_at"]
    contacts = len(report["collisions"])
    return (
        f"  clearance (scene {report['scene']}; the knife links may touch the fish): "
        f"min {report['min_clearance']:.4f} m ({at['body_a']} - {at['body_b']} at "
        f"t = {at['t']:.2f} s), {contacts} contact(s)"
    )


def round_for_json(value: Any, digits: int = SUMMARY_DIGITS) -> Any:
    """``value`` with NumPy data as lists and floats cut to ``digits`` significant.

    Nine digits are far below the accuracy of anything the demo reports
    (the papers print 2-4 digits) and far above what a reader compares, and
    they keep ``-94.07`` from showing up as ``-94.07000000000001``. In a list
    of floats (a vector), entries within rounding of its largest one are 0
    (see :func:`workbench.json_numbers.to_json_ready`).

    Args:
        value: Nested dicts, lists, tuples, NumPy arrays and scalars.
        digits: Significant digits kept.

    Returns:
        The same structure with builtin types only.
    """
    return to_json_ready(value, digits=digits)


def check_output_folder(out_dir: Path) -> None:
    """Refuse an output folder that is a file or cannot be created or written.

    Raises:
        InputError: Naming the path and the reason.
    """
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"--out {out_dir}: a file, not a folder")
    existing = out_dir
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise InputError(f"--out {out_dir}: {existing} is a file, not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise InputError(f"--out {out_dir}: folder {existing} is not writable")


def run_demo(robot: Robot, out_dir: Path, *, plots: bool = True) -> dict[str, Any]:
    """Run the papers' examples and write the results into ``out_dir``.

    Args:
        robot: The ``puma560`` model (Angeles Table I).
        out_dir: Output folder (created).
        plots: Also write the PNG figures, the 3D previews (``preview.html``,
            ``avoid.html``) and the singularity report (``singularities.html``):
            the slow part.
            The self-collision filter of the model is always written
            (``<robot>.srdf``).

    Returns:
        A JSON-ready summary, also written to ``out_dir/summary.json`` with
        every float rounded to :data:`SUMMARY_DIGITS` significant digits (see
        :func:`round_for_json`); the CSV files keep full precision. Every file
        is written all at once (:mod:`workbench.atomic_files`).

    Raises:
        InputError: If ``out_dir`` is a file or cannot be created or written.
    """
    check_output_folder(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InputError(f"cannot create {out_dir}: {err.strerror or err}") from err
    # The fish cutting (its own robot, kernels and files) and the base
    # placement run in a second process meanwhile: on a first run most of the
    # time goes to compiling kernels, the planner's and the map's there and the
    # closed form here (which the planner then loads from the cache: see
    # workbench._compiled).
    with _InSecondProcess(out_dir, _run_second_part, out_dir, plots=plots) as second:
        rows = compare_table2(robot)
        table = format_table2(rows)
        write_text_atomic(
            out_dir / "table2.md",
            "# Angeles et al. Table II reproduced from Table III\n\n" + table + "\n",
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
            "avoid": run_avoid_demo(robot, out_dir, plots=plots),
        }
        checker = CollisionChecker(robot, get_angeles_scene(robot))
        write_text_atomic(out_dir / f"{robot.name}.srdf", checker.filter.to_srdf())
        pages = _write_pages(robot, out_dir) if plots else None
        summary.update(second.result())
    if pages is not None:
        summary["pages"] = pages
    write_text_atomic(
        out_dir / "summary.json", json.dumps(round_for_json(summary), indent=2) + "\n"
    )
    _log.info("demo written to %s", out_dir)
    return summary
