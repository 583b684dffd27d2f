"""Exception hierarchy of the workbench.

Every error the workbench raises on purpose derives from :class:`WorkbenchError`.
Two families tell the command line which exit code to use:

* :class:`InputError` (exit code 2): the request itself is malformed — wrong
  joint count, NaN, unknown robot name, unreadable file.
* :class:`InfeasibleError` (exit code 3): the request is well formed but cannot
  be met — unreachable pose, limit violation.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable


class WorkbenchError(Exception):
    """Base class of every error raised by the workbench."""


class InputError(WorkbenchError, ValueError):
    """The input is malformed (CLI exit code 2)."""


class InfeasibleError(WorkbenchError):
    """The input is well formed but the request cannot be met (CLI exit code 3)."""


class DimensionError(InputError):
    """An array has the wrong shape.

    Attributes:
        name: What the array is (e.g. ``"q"``).
        expected: Expected shape.
        received: Received shape.
    """

    def __init__(self, name: str, expected: tuple[int, ...], received: tuple[int, ...]):
        self.name = name
        self.expected = expected
        self.received = received
        super().__init__(
            f"{name} must have shape {expected}, got shape {received}"
            + _count_hint(expected, received)
        )


def _count_hint(expected: tuple[int, ...], received: tuple[int, ...]) -> str:
    if len(expected) == 1 and len(received) == 1:
        return f" ({expected[0]} values expected, {received[0]} given)"
    return ""


class NonFiniteError(InputError):
    """An input contains NaN or infinity."""


class RobotNotFoundError(InputError):
    """A robot name is neither a known robot nor a path to a URDF file."""

    def __init__(self, name: str, valid: Iterable[str]):
        self.name = name
        self.valid = sorted(valid)
        close = [v for v in self.valid if name and v.startswith(name)]
        close += [
            v for v in difflib.get_close_matches(name, self.valid) if v not in close
        ]
        hint = f" did you mean {', '.join(close[:3])}?" if close and name else ""
        super().__init__(
            f"unknown robot {name!r};{hint} valid names: {', '.join(self.valid)}"
            " (or a path to a .urdf file)"
        )


class FrameNotFoundError(InputError):
    """A frame name is not in the model."""

    def __init__(self, name: str, valid: Iterable[str]):
        self.name = name
        self.valid = list(valid)
        super().__init__(
            f"frame {name!r} not in the model; valid frames: {', '.join(self.valid)}"
        )


class JointNotFoundError(InputError):
    """A joint name is not in the model."""

    def __init__(self, name: str, valid: Iterable[str]):
        self.name = name
        self.valid = list(valid)
        super().__init__(
            f"joint {name!r} not in the model; valid joints: {', '.join(self.valid)}"
        )


class URDFLoadError(InputError):
    """A URDF file is missing, unreadable or malformed."""


class DHTableError(InputError):
    """A Denavit–Hartenberg table is missing, unreadable or malformed."""


class JointLimitError(InfeasibleError):
    """A joint leaves its position, speed or acceleration limit.

    Attributes:
        joint: Joint name.
        value: Offending value [rad, rad/s or rad/s²].
        lower: Lower limit, same unit.
        upper: Upper limit, same unit.
        t: Time of the violation [s], or None for a single configuration.
    """

    def __init__(
        self,
        joint: str,
        value: float,
        lower: float,
        upper: float,
        t: float | None = None,
        kind: str = "position",
    ):
        self.joint = joint
        self.value = value
        self.lower = lower
        self.upper = upper
        self.t = t
        self.kind = kind
        when = "" if t is None else f" at t = {t:.6g} s"
        super().__init__(
            f"joint {joint} {kind} {value:.6g}{when} outside [{lower:.6g}, {upper:.6g}]"
        )


class SceneFileError(InputError):
    """A scene file is missing, unreadable or invalid (the message says where)."""


class UnsupportedRobotError(InputError):
    """The robot has no closed-form IK (not a 6R or 7R arm of a supported family)."""


class UnreachableError(InfeasibleError):
    """The wrist centre of the target lies where the arm cannot put it.

    Attributes:
        distance: Distance [m] of the wrist centre from the shoulder (``kind``
            ``"reach"``) or from the base axis (``kind`` ``"cylinder"``).
        bounds: Reachable interval of that distance, ``(low, high)`` [m].
        kind: ``"reach"`` (too far or too close to the shoulder),
            ``"cylinder"`` (inside the cylinder of radius |d2 + d3| around the
            base axis that the shoulder offset keeps the wrist out of) or
            ``"model"`` (at the edge of the reach, where the model and its
            idealised structure differ: no branch refines onto the pose,
            distance and bounds then 0; or, on a calibrated arm, the
            idealised arm misses the pose by less than the model's deviation,
            so that the model may reach it: solutions unlisted, distance and
            bounds those of the idealised arm).

    A seven-axis arm's solver words its own ``message`` (the redundancy
    parameter's value and the values that reach).
    """

    def __init__(
        self,
        distance: float,
        bounds: tuple[float, float],
        kind: str,
        message: str | None = None,
    ):
        self.distance = distance
        self.bounds = bounds
        self.kind = kind
        if message is not None:
            pass
        elif kind == "model":
            message = (
                "out of reach: the pose is at the edge of the reach of the "
                "idealised arm, and no branch reaches it on the robot's own model"
            )
        elif kind == "cylinder":
            message = (
                f"out of reach: wrist centre at {distance:.6g} m from the base axis, "
                f"inside the unreachable cylinder of radius {bounds[0]:.6g} m "
                "(the shoulder offset d2 + d3) around it"
            )
        else:
            message = (
                f"out of reach: wrist centre at distance {distance:.6g} m from the "
                f"shoulder, reach is [{bounds[0]:.6g}, {bounds[1]:.6g}] m"
            )
        super().__init__(message)


class DifferentialIKError(InfeasibleError):
    """The QP of :func:`workbench.ik.qp_step` has no solution the solver could find."""
