"""Values derived from a robot, cached per robot object and held weakly.

Several layers derive costly values from a :class:`~workbench.model.robot.Robot`:
its kinematic structure, the closed-form solver, the compiled chain. Each is
computed once per robot object with :func:`per_robot` and forgotten with the
robot: the cache holds no strong reference to it (an entry leaves when the
robot is garbage-collected), and an entry is rebuilt when the robot's model,
limits or tool frame have been replaced since (its *stamp*) by objects that are
not equal to them (an equal copy of the model describes the same arm). A
lookup first compares the robot's ``_revision`` (renewed by every attribute
assignment): the stamp is built and compared only after an assignment.
"""

from __future__ import annotations

import functools
import weakref
from collections.abc import Callable
from typing import Any, TypeVar

from workbench.model.robot import Robot

T = TypeVar("T")


def _stamp(robot: Robot) -> tuple[Any, ...]:
    """What a derived value depends on: the objects, compared by identity."""
    return (
        robot.model,
        robot.lower,
        robot.upper,
        robot.velocity_limit,
        robot.acceleration_limit,
        robot.tool_frame_id,
        robot.dh_table,
    )


def _same(a: tuple[Any, ...], b: tuple[Any, ...]) -> bool:
    """Whether two stamps hold the same objects (or equal ones).

    Tuple comparison tests identity first, so the usual case (nothing
    replaced) compares no array; two different arrays of more than one entry
    make ``==`` ambiguous, which means "replaced".
    """
    try:
        return a == b
    except ValueError:
        return False


def per_robot(build: Callable[[Robot], T]) -> Callable[[Robot], T]:
    """Cache ``build(robot)`` per robot object, weakly (module docstring).

    The decorated function takes the robot only. A lookup costs a dict access
    and the comparison of two ints; ``cache_clear()`` empties it.
    """
    # entries: [robot (weakly), revision, stamp, value]
    entries: dict[int, list[Any]] = {}

    @functools.wraps(build)
    def cached(robot: Robot) -> T:
        key = id(robot)
        entry = entries.get(key)
        if entry is not None and entry[0]() is robot:
            if entry[1] == robot._revision:  # nothing assigned since
                return entry[3]
            revision, stamp = robot._revision, _stamp(robot)
            if _same(entry[2], stamp):
                entry[1] = revision
                return entry[3]
        else:
            revision, stamp = robot._revision, _stamp(robot)
        value = build(robot)
        if entry is None or entry[0]() is not robot:
            weakref.finalize(robot, entries.pop, key, None)
        entries[key] = [weakref.ref(robot), revision, stamp, value]
        return value

    cached.cache_clear = entries.clear  # type: ignore[attr-defined]
    return cached


__all__ = ["per_robot"]
