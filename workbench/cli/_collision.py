"""``--scene`` / ``--no-collision`` and the collision keys of the JSON output."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from workbench.collision import (
    CollisionChecker,
    PathClearance,
    Scene,
    get_pick_and_place_scene,
    read_scene,
)
from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.tasks import compute_fish_cutting_clearance, get_fish_cutting_scene
from workbench.tasks.fish_cutting import FishCuttingResult
from workbench.trajectory.pick_and_place import JointTrajectory


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
        InputError: If both ``--scene`` and ``--no-collision`` are given.
        SceneFileError: If the file is missing or invalid.
    """
    if args.no_collision and args.scene is not None:
        raise InputError("--scene and --no-collision contradict each other")
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


def check_pick_and_place_path(
    robot: Robot, traj: JointTrajectory, args: argparse.Namespace, rate: float
) -> tuple[Scene | None, PathClearance | None]:
    """The collision check of a pick-and-place (``plan``, ``export --pick-place``).

    Args:
        robot: The arm.
        traj: The trajectory.
        args: With ``scene`` and ``no_collision``.
        rate: Samples per second [Hz] of the check (proven between samples).

    Returns:
        The scene (``--scene``, else
        :func:`workbench.collision.get_pick_and_place_scene`; None with
        ``--no-collision``) and the clearance (None when skipped).
    """
    scene = load_scene(args, lambda: get_pick_and_place_scene(robot))
    checker = build_checker(robot, scene, explicit=args.scene is not None)
    return scene, None if checker is None else traj.check_collisions(checker, rate)


def check_fish_cutting_path(
    robot: Robot,
    result: FishCuttingResult,
    given: Scene | None,
    args: argparse.Namespace,
) -> tuple[Scene | None, CollisionChecker | None, PathClearance | None]:
    """The collision check of a fish-cutting run (``fishcut``, ``export --fishcut``).

    Args:
        robot: The arm.
        result: The run.
        given: The scene of ``--scene`` (read before the run), or None.
        args: With ``scene`` and ``no_collision``.

    The scene is ``given``, else Kang's cell scaled to the arm; the check is
    :func:`workbench.tasks.compute_fish_cutting_clearance`.

    Returns:
        The scene (None with ``--no-collision``), the checker and the clearance
        (both None when the check is skipped).
    """
    if args.no_collision:
        return None, None, None
    scene = given or get_fish_cutting_scene(robot, result.fish, result.setup)
    checker = build_checker(robot, scene, explicit=args.scene is not None)
    if checker is None:
        return scene, None, None
    clearance = compute_fish_cutting_clearance(robot, result, checker=checker)
    return scene, checker, clearance


#: Why a collision check did not run (``collision_skipped`` of the JSON output).
SKIPPED_BY_FLAG = "--no-collision"
SKIPPED_NO_GEOMETRY = "no collision geometry in the URDF"


def get_skip_reason(robot: Robot, args: argparse.Namespace) -> str | None:
    """Why the collision check of this run is skipped, or None if it runs."""
    if args.no_collision:
        return SKIPPED_BY_FLAG
    if robot.collision_model.ngeoms == 0:
        return SKIPPED_NO_GEOMETRY
    return None


def get_collision_keys(
    scene: Scene | None, report: PathClearance | None, skipped: str | None
) -> dict[str, Any]:
    """JSON keys: ``scene``, ``min_clearance``, ``collisions``, ``collision_skipped``.

    ``collision_skipped`` is :func:`get_skip_reason`'s reason, None when the
    check ran.
    """
    if report is None:
        return {
            "scene": None,
            "min_clearance": None,
            "collisions": [],
            "collision_skipped": skipped,
        }
    return {
        "scene": scene.name if scene else None,
        **report.as_dict(),
        "collision_skipped": None,
    }


def print_collision_summary(report: PathClearance | None, skipped: str | None) -> None:
    """Human-readable lines of the collision check (stdout).

    Args:
        report: The clearance, None when the check was skipped.
        skipped: Why it was skipped (:func:`get_skip_reason`).
    """
    if report is None:
        if skipped == SKIPPED_NO_GEOMETRY:
            print("no collision geometry in the URDF: collision check not possible")
        else:
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
    message = get_collision_error(report)
    if message is None:
        return False
    print(f"workbench: error: {message}", file=sys.stderr)
    return True


def get_collision_error(report: PathClearance | None) -> str | None:
    """The one-line message of the first contact, or None without contact."""
    return None if report is None else report.describe_first_contact()
