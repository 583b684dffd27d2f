"""``workbench fishcut``: Kang's fish-cutting program on a simulated fish, online."""

from __future__ import annotations

import argparse
import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from workbench.cli._common import add_json_flag, add_robot_argument, print_json
from workbench.errors import InputError
from workbench.model.loading import load_robot
from workbench.tasks import FishCuttingSetup, SimulatedFish, run_fish_cutting
from workbench.tasks.fish_cutting import summarize_fish_cutting
from workbench.trajectory.csv_io import write_trajectory_csv

DEFAULT_ROBOT = "puma560-kang"
_DEFAULTS = FishCuttingSetup()


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``fishcut`` command."""
    parser = commands.add_parser(
        "fishcut",
        help="Kang's fish-cutting program on a simulated fish, planned online",
        description=(
            "Run the fish-cutting program of Kang (2007, Fig. 7) on a simulated fish "
            "with the online planner: Cartesian command, closed-form IK with branch "
            "continuity and DLS joint rates each planning cycle, cubic Hermite "
            "interpolation at the servo rate. Touching the flesh slows the vertical "
            "cut, touching the bone stops it (or lifts the horizontal cut)."
        ),
    )
    add_robot_argument(parser, default=DEFAULT_ROBOT)
    parser.add_argument(
        "--csv", type=Path, metavar="FILE", help="write the servo-rate joint commands"
    )
    parser.add_argument(
        "--html", type=Path, metavar="FILE", help="write a 3D preview page (Meshcat)"
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="seed of the fish's flesh and bone (0)"
    )
    parser.add_argument(
        "--max-velocity",
        type=float,
        default=_DEFAULTS.max_velocity,
        metavar="M_S",
        help=f"tool speed limit [m/s] (default {_DEFAULTS.max_velocity:g})",
    )
    parser.add_argument(
        "--planning-rate",
        type=float,
        default=_DEFAULTS.planning_rate,
        metavar="HZ",
        help=f"planning cycles per second (default {_DEFAULTS.planning_rate:g})",
    )
    parser.add_argument(
        "--servo-rate",
        type=float,
        default=_DEFAULTS.servo_rate,
        metavar="HZ",
        help=f"servo samples per second, a multiple of the planning rate "
        f"(default {_DEFAULTS.servo_rate:g})",
    )
    add_json_flag(parser)
    parser.set_defaults(run=run)


def _check_writable(path: Path | None, option: str) -> None:
    if path is None:
        return
    if path.is_dir():
        raise InputError(f"{option} {path}: is a directory")
    if not path.parent.resolve().is_dir():
        raise InputError(f"{option} {path}: folder {path.parent} does not exist")


@contextlib.contextmanager
def _atomic_path(path: Path) -> Iterator[Path]:
    """A temporary path next to ``path``, renamed onto it only on success."""
    handle, name = tempfile.mkstemp(
        dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix
    )
    os.close(handle)
    tmp = Path(name)
    try:
        yield tmp
        mask = os.umask(0)  # mkstemp makes 0600 files: give the usual mode
        os.umask(mask)
        tmp.chmod(0o666 & ~mask)
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)


def run(args: argparse.Namespace) -> int:
    """Run the program; write the CSV and the page only if it completes."""
    _check_writable(args.csv, "--csv")
    _check_writable(args.html, "--html")
    robot = load_robot(args.robot)
    setup = FishCuttingSetup(
        max_velocity=args.max_velocity,
        planning_rate=args.planning_rate,
        servo_rate=args.servo_rate,
    )
    result = run_fish_cutting(robot, SimulatedFish(args.seed), setup)
    if args.html is not None:  # viewer imported lazily (optional extra)
        from workbench.viz import write_trajectory_html

        with _atomic_path(args.html) as tmp:
            write_trajectory_html(
                robot,
                result.servo,
                tmp,
                title=f"workbench fishcut: {robot.name}, fish seed {args.seed}",
            )
    if args.csv is not None:
        with _atomic_path(args.csv) as tmp:
            write_trajectory_csv(tmp, result.servo)
    summary = summarize_fish_cutting(result, robot.name)
    if args.json:
        print_json(summary)
        return 0
    print(
        f"robot {robot.name}: {summary['cycles']} planning cycles at "
        f"{setup.planning_rate:g} Hz, {summary['duration']:.2f} s, servo "
        f"{setup.servo_rate:g} Hz"
    )
    for event in summary["events"]:
        print(f"  t = {event['t']:6.2f} s  {event['kind']:5s}  ({event['primitive']})")
    lat = summary["latency_us"]
    print(f"planning cycle  median {lat['median']:.1f} µs  p99 {lat['p99']:.1f} µs")
    print(
        f"max joint speed {summary['max_joint_speed']:.3f} rad/s, wrist flips "
        f"{summary['wrist_flips']}, wrist singularity crossings "
        f"{summary['wrist_singularity_crossings']}, DLS cycles {summary['dls_cycles']}"
    )
    for option, path in (("csv", args.csv), ("html", args.html)):
        if path is not None:
            print(f"{option} written to {path}")
    return 0
