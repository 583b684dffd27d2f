"""``--scene`` / ``--no-collision`` and the collision keys of the JSON output."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from workbench.collision import CollisionChecker, PathClearance, Scene, read_scene
from workbench.model.robot import Robot


def add_collision_arguments(parser: argparse.ArgumentParser, default: str) -> None:
    """``--scene FILE`` and ``--no-collision``."""
    parser.add_argument(
        "--scene",
        type=Path,
        metavar="FILE",
        help=f"obstacles, JSON in the robot base frame (default: {default})",
    )
    parser.add_argument(
        "--no-collision",
        action="store_true",
        help="skip the self- and scene-collision check",
    )


def load_scene(
    args: argparse.Namespace, default: Callable[[], Scene | None]
) -> Scene | None:
    """The scene of ``--scene`` or ``default()``; None with ``--no-collision``.

    Raises:
        SceneFileError: If the file is missing or invalid.
    """
    if args.no_collision:
        return None
    return read_scene(args.scene) if args.scene is not None else default()


def build_checker(
    robot: Robot, scene: Scene | None, *, explicit: bool = False
) -> CollisionChecker | None:
    """A checker of ``robot`` in ``scene``; None when the check is skipped.

    A robot without collision geometry skips the default check (nothing to
    check); with a scene the user gave (``explicit``) it is an error.

    Raises:
        InputError: If ``explicit`` and the robot has no collision geometry.
    """
    if scene is None:
        return None
    if robot.collision_model.ngeoms == 0 and not explicit:
        return None
    return CollisionChecker(robot, scene)


def get_collision_keys(
    scene: Scene | None, report: PathClearance | None
) -> dict[str, Any]:
    """JSON keys: ``scene``, ``min_clearance``, ``collisions`` and details."""
    if report is None:
        return {"scene": None, "min_clearance": None, "collisions": []}
    return {"scene": scene.name if scene else None, **report.as_dict()}


def print_collision_summary(report: PathClearance | None) -> None:
    """Human-readable lines of the collision check (stdout)."""
    if report is None:
        print("collision check skipped (--no-collision)")
        return
    print(
        f"min clearance {report.min_clearance:.4g} m ({report.body_a} - "
        f"{report.body_b} at t = {report.t:.4g} s); proven lower bound over the "
        f"path {report.lower_bound:.4g} m"
    )
    for c in report.contacts:
        print(
            f"  contact {c.body_a} - {c.body_b}: t = {c.t_start:.4g} .. "
            f"{c.t_end:.4g} s, deepest {c.distance:.4g} m at t = {c.t:.4g} s"
        )


def report_collision_error(report: PathClearance | None) -> bool:
    """Print the one-line error of the first contact; True if there was one."""
    if report is None or not report.contacts:
        return False
    first = report.contacts[0]
    more = len(report.contacts) - 1
    extra = f" (and {more} more contact(s))" if more else ""
    print(
        f"workbench: error: collision of {first.body_a} with {first.body_b} "
        f"from t = {first.t_start:.6g} s, distance {first.distance:.6g} m at "
        f"t = {first.t:.6g} s{extra}",
        file=sys.stderr,
    )
    return True
