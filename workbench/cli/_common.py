"""Argument helpers shared by the commands."""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError, NonFiniteError
from workbench.json_numbers import to_json_ready
from workbench.model.loading import load_robot
from workbench.model.robot import Robot
from workbench.validation import parse_float, parse_int

#: Exit code of a request the robot cannot meet (an unreachable pose, a
#: limit violation), printed as one line on stderr.
EXIT_INFEASIBLE = 3


def add_robot_argument(
    parser: argparse.ArgumentParser,
    default: str | None = None,
    *,
    help_text: str | None = None,
) -> None:
    """The robot's options: ``--robot``, ``--package-dir``, ``--xacro-arg``, ``--srdf``.

    ``--robot NAME|PATH`` is required unless defaulted. Load the robot they
    name with :func:`load_robot_from_args`.
    """
    parser.add_argument(
        "--robot",
        required=default is None and help_text is None,
        default=default,
        help=help_text
        or "robot name (puma560, puma560-kang, ur5, panda, ...) or path to a .urdf "
        "or .xacro file"
        + (f" (default: {default})" if default else ""),
    )
    parser.add_argument(
        "--package-dir",
        action="append",
        default=[],
        metavar="DIR|NAME=DIR",
        help="folder holding ROS packages (found by the name in their package.xml "
        "or by folder name) or one package's folder, or NAME=DIR for one package; "
        "for package:// mesh URIs and $(find NAME) (repeatable; searched before "
        "ROS_PACKAGE_PATH and the description's folders)",
    )
    parser.add_argument(
        "--xacro-arg",
        action="append",
        default=[],
        type=xacro_argument,
        metavar="NAME:=VALUE",
        help="the value of a xacro file's <xacro:arg> (repeatable)",
    )
    parser.add_argument(
        "--srdf",
        type=Path,
        metavar="FILE",
        help="the robot's SRDF: its <disable_collisions> pairs are left out of the "
        "self-collision check (default: ROBOT.srdf beside a --robot file, if any; "
        "else the pairs the workbench computes)",
    )


def xacro_argument(text: str) -> tuple[str, str]:
    """Argparse type: ``NAME:=VALUE`` (as on the xacro command line)."""
    name, sep, value = text.partition(":=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"expected NAME:=VALUE, got {text!r}")
    return name.strip(), value


#: Largest ``--time-limit`` [s] of a planner.
MAX_TIME_LIMIT = 3600.0


def add_search_arguments(
    parser: argparse.ArgumentParser,
    *,
    scope: str = "",
    defaults: bool = True,
    planner: bool = False,
) -> None:
    """``--seed N``, ``--time-limit S`` (and ``--planner NAME``) of a motion planner.

    Args:
        parser: The subcommand's parser.
        scope: Words before each help text (e.g. ``"with --avoid: "``).
        defaults: Whether the parsed values default to 0 and 1 s; without,
            they stay None so that the command can tell whether they were
            given.
        planner: Whether to add ``--planner`` (default ``rrtconnect``).
    """
    parser.add_argument(
        "--seed",
        type=bounded_int(0, 2**63 - 1),
        default=0 if defaults else None,
        metavar="N",
        help=f"{scope}the planner's random seed (default: 0)",
    )
    parser.add_argument(
        "--time-limit",
        type=bounded_float(MAX_TIME_LIMIT, "s"),
        default=1.0 if defaults else None,
        metavar="S",
        help=f"{scope}the planning budget [s] (default: 1)",
    )
    if planner:
        parser.add_argument(
            "--planner",
            type=_planner_name,
            default="rrtconnect",
            metavar="NAME",
            help="rrtconnect (compiled, the default) or ompl:NAME, one of OMPL's "
            "planners (ompl:RRTstar, ompl:BITstar, …; the [ompl] extra) with the "
            "same checker",
        )


def _planner_name(text: str) -> str:
    """``rrtconnect`` or ``ompl:NAME`` with NAME one of OMPL's planners offered."""
    from workbench.motion import PLANNERS

    if text not in PLANNERS:
        raise argparse.ArgumentTypeError(
            f"unknown planner {text!r}; one of {', '.join(PLANNERS)}"
        )
    return text


def add_limit_arguments(
    parser: argparse.ArgumentParser, *, acceleration: bool = True
) -> None:
    """``--velocity-limit`` (and ``--acceleration-limit``): one value or one per joint.

    Args:
        parser: The command's parser.
        acceleration: Whether the command uses acceleration limits too.
    """
    parser.add_argument(
        "--velocity-limit",
        nargs="+",
        type=positive_float,
        metavar="V",
        help="joint speed limits [rad/s], > 0: one for every joint or one per "
        "joint (default: the URDF's; velocity=0 there means none)",
    )
    if not acceleration:
        return
    parser.add_argument(
        "--acceleration-limit",
        nargs="+",
        type=positive_float,
        metavar="A",
        help="joint acceleration limits [rad/s²], > 0: one for every joint or one "
        "per joint (default: none)",
    )


def load_robot_from_args(
    args: argparse.Namespace, name: str | None = None, *, tool_frame: str | None = None
) -> Robot:
    """The robot of ``--robot`` (or ``name``), with ``--package-dir`` and limits.

    Raises:
        InputError: If a limit option has neither 1 nor nv values.
    """
    robot = load_robot(
        args.robot if name is None else name,
        tool_frame=tool_frame,
        package_dirs=getattr(args, "package_dir", ()),
        xacro_args=dict(getattr(args, "xacro_arg", ())) or None,
        srdf=getattr(args, "srdf", None),
    )
    limits = {
        key: _per_joint(robot, getattr(args, key, None), option)
        for key, option in (
            ("velocity_limit", "--velocity-limit"),
            ("acceleration_limit", "--acceleration-limit"),
        )
    }
    if any(value is not None for value in limits.values()):
        robot = robot.with_limits(**limits)
    return robot


def _per_joint(
    robot: Robot, values: list[float] | None, option: str
) -> npt.NDArray[np.float64] | None:
    if values is None:
        return None
    if len(values) not in (1, robot.nv):
        raise InputError(
            f"{option} takes 1 value (every joint) or {robot.nv} (one per joint of "
            f"{robot.name}: {', '.join(robot.joint_names)}), got {len(values)}"
        )
    return np.broadcast_to(np.asarray(values, dtype=np.float64), (robot.nv,))


def add_json_flag(parser: argparse.ArgumentParser) -> None:
    """``--json``: print exactly one JSON object on stdout."""
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def add_angle_arguments(parser: argparse.ArgumentParser, name: str = "q") -> None:
    """``(--deg | --rad) Q...``: joint values and their unit."""
    unit = parser.add_mutually_exclusive_group(required=True)
    unit.add_argument("--deg", action="store_true", help="joint values in degrees")
    unit.add_argument("--rad", action="store_true", help="joint values in radians")
    parser.add_argument(
        name, nargs="+", type=finite_float, metavar="Q", help="joint values"
    )


def finite_float(text: str) -> float:
    """Argparse type: a finite float."""
    try:
        value = parse_float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"not a finite number: {text!r}")
    return value


def name_text(text: str) -> str:
    """Argparse type: a name (a frame, a branch label, a topic), not empty."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"must be a name, not empty: {text!r}")
    return text


def positive_float(text: str) -> float:
    """Argparse type: a finite float > 0."""
    value = finite_float(text)
    if not value > 0.0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return value


def bounded_float(
    maximum: float, unit: str, *, minimum: float = 0.0
) -> Callable[[str], float]:
    """Argparse type: a float in ``(minimum, maximum]`` (``unit`` for messages)."""

    def parse(text: str) -> float:
        value = finite_float(text)
        if not minimum < value <= maximum:
            raise argparse.ArgumentTypeError(
                f"must be > {minimum:g} and at most {maximum:g} {unit}, got {text!r}"
            )
        return value

    return parse


def bounded_int(minimum: int, maximum: int) -> Callable[[str], int]:
    """Argparse type: an integer in ``[minimum, maximum]``."""

    def parse(text: str) -> int:
        try:
            value = parse_int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if not minimum <= value <= maximum:
            raise argparse.ArgumentTypeError(
                f"must be {minimum}..{maximum}, got {text!r}"
            )
        return value

    return parse


def get_input_paths(args: argparse.Namespace, *extra: Path | None) -> list[Path]:
    """The files a command reads; its outputs must be none of them.

    ``--robot`` when it is a URDF path, ``--srdf``, ``--scene``,
    ``--trajectory`` with its record (``trajectory.csv_io.record_path``) and
    ``extra`` (None entries and paths that are no file are left out).
    """
    from workbench.trajectory.csv_io import record_path

    paths = [Path(args.robot)] if getattr(args, "robot", None) else []
    for key in ("srdf", "scene", "trajectory"):
        if getattr(args, key, None) is not None:
            paths.append(getattr(args, key))
    if getattr(args, "trajectory", None) is not None:
        paths.append(record_path(args.trajectory))
    return [p for p in (*paths, *extra) if p is not None and p.is_file()]


def joint_values_rad(
    args: argparse.Namespace, values: list[float]
) -> npt.NDArray[np.float64]:
    """Joint values from the command line, converted to radians."""
    q = np.asarray(values, dtype=np.float64)
    if not np.all(np.isfinite(q)):
        raise NonFiniteError("joint values must be finite")
    return np.deg2rad(q) if args.deg else q


def configuration_from_args(
    robot: Robot, args: argparse.Namespace, values: list[float]
) -> npt.NDArray[np.float64]:
    """``q`` (nq,) from typed joint values: one angle per joint (``--deg``/``--rad``).

    With ``--rad``, Pinocchio's q (nq values, (cos, sin) per continuous joint)
    is accepted too (see :meth:`Robot.as_configuration`).

    Raises:
        DimensionError: If the count is wrong.
        InputError: If ``--deg`` is given nq values of a robot with continuous
            joints (degrees make no (cos, sin) pair).
    """
    angles = joint_values_rad(args, values)
    if args.deg and angles.size == robot.nq != robot.n_joints:
        raise InputError(
            f"--deg takes one angle per joint ({robot.n_joints} for {robot.name}); "
            f"the {robot.nq} values of Pinocchio's q, with (cos, sin) per "
            "continuous joint, go with --rad"
        )
    return robot.as_configuration(angles)


def q_from_degrees(robot: Robot, values: list[float]) -> npt.NDArray[np.float64]:
    """``q`` (nq,) from one angle per joint in degrees (``--pick-deg`` etc.)."""
    return robot.q_from_joint_values(np.deg2rad(np.asarray(values, dtype=np.float64)))


def print_json(payload: dict[str, Any]) -> None:
    """Print one JSON object (NumPy arrays become lists) on stdout.

    Full precision; in a list of floats, rounding noise of its largest entry
    prints as 0 (:func:`workbench.json_numbers.to_json_ready`).
    """
    ready = to_json_ready(payload)
    json.dump(ready, sys.stdout, default=_to_builtin, allow_nan=False)
    sys.stdout.write("\n")


def _to_builtin(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def format_time(seconds: float) -> str:
    """``48 µs``, ``1.3 ms``, ``0.52 s``; ``–`` for NaN."""
    if math.isnan(seconds):
        return "–"
    if seconds < 1e-3:
        return f"{1e6 * seconds:.0f} µs"
    if seconds < 1.0:
        return f"{1e3 * seconds:.3g} ms"
    return f"{seconds:.3g} s"


def format_vector(values: npt.ArrayLike, digits: int = 6) -> str:
    """Numbers on one line, fixed precision, sign-aligned."""
    return "  ".join(
        f"{x: .{digits}f}" for x in np.asarray(values, dtype=float).ravel()
    )
