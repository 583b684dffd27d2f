"""Motion requests in MoveIt's format: a start state and a joint-space goal.

:func:`read_request` reads a ``moveit_msgs/MotionPlanRequest`` written as
YAML (the requests of MotionBenchMaker): ``start_state.joint_state`` (names
and positions) and one ``goal_constraints`` entry of ``joint_constraints``
(``joint_name``, ``position``), and returns them as configurations of the
robot. Joints the request names but the model lacks (a gripper's fingers in
an arm-only model) are ignored; every joint of the model must be given, in
the start and in the goal. Values are joint values [rad, m for prismatic
joints], as MoveIt writes them; a continuous joint's angle becomes its
(cos, sin) pair of ``q``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt

from workbench.collision.moveit_scene import read_yaml_file
from workbench.errors import InputError, SceneFileError
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]


class MotionRequest(NamedTuple):
    """A start and a goal configuration, each (nq,) [rad, m]."""

    start: FloatArray
    goal: FloatArray


def read_request(path: str | Path, robot: Robot) -> MotionRequest:
    """The start and goal configurations of ``robot`` a MoveIt request asks for.

    Args:
        path: A ``moveit_msgs/MotionPlanRequest`` as YAML (module docstring).
        robot: The robot; the request's joints are matched to its
            :attr:`~workbench.model.Robot.joint_names`.

    Returns:
        ``(start, goal)``, (nq,) each.

    Raises:
        InputError: If the file is no request (unreadable, not YAML, no
            start state or no joint goal, several goal constraints), a joint
            of the model is missing from the start or the goal, or a value
            is not a finite number; the message names the key and the joint.
    """
    path = Path(path)
    try:
        raw = read_yaml_file(path, "motion request")
    except SceneFileError as err:
        raise InputError(str(err)) from None
    return parse_request(raw, robot, source=path)


def parse_request(raw: Any, robot: Robot, *, source: str | Path) -> MotionRequest:
    """:func:`read_request` of a request already read from its YAML.

    Args:
        raw: The request as YAML loads it (a mapping).
        robot: The robot whose joints the request's are matched to.
        source: Where the request came from, for the messages.

    Raises:
        InputError: As :func:`read_request`.
    """
    path = source
    if not isinstance(raw, Mapping):
        raise InputError(f"{path}: not a MoveIt motion request (no mapping)")
    state = raw.get("start_state")
    joint_state = state.get("joint_state") if isinstance(state, Mapping) else None
    if not isinstance(joint_state, Mapping):
        raise InputError(f"{path}: no start_state.joint_state")
    names, positions = joint_state.get("name"), joint_state.get("position")
    if (
        not isinstance(names, list)
        or not isinstance(positions, list)
        or len(names) != len(positions)
    ):
        raise InputError(
            f"{path}: start_state.joint_state must have as many names as positions"
        )
    start = _configuration(
        robot, dict(zip(map(str, names), positions, strict=True)), path, "start_state"
    )
    goals = raw.get("goal_constraints")
    if not isinstance(goals, list) or not goals:
        raise InputError(f"{path}: no goal_constraints")
    if len(goals) > 1:
        raise InputError(
            f"{path}: {len(goals)} goal constraints; give one (a joint-space goal)"
        )
    constraints = (
        goals[0].get("joint_constraints") if isinstance(goals[0], Mapping) else None
    )
    if not isinstance(constraints, list) or not constraints:
        raise InputError(f"{path}: the goal has no joint_constraints")
    targets: dict[str, Any] = {}
    for item in constraints:
        if not isinstance(item, Mapping) or "joint_name" not in item:
            raise InputError(
                f"{path}: a joint constraint needs joint_name and position"
            )
        targets[str(item["joint_name"])] = item.get("position")
    goal = _configuration(robot, targets, path, "goal_constraints")
    return MotionRequest(start, goal)


def _configuration(
    robot: Robot, values: Mapping[str, Any], path: str | Path, where: str
) -> FloatArray:
    """``q`` of ``robot`` from joint values by name (others ignored)."""
    out = np.empty(robot.n_joints)
    for i, name in enumerate(robot.joint_names):
        if name not in values:
            raise InputError(f"{path}: {where} gives no value for joint {name!r}")
        value = values[name]
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not math.isfinite(value)
        ):
            raise InputError(
                f"{path}: {where}: joint {name!r} must be a finite number, got "
                f"{value!r}"
            )
        out[i] = float(value)
    return robot.as_configuration(out)
