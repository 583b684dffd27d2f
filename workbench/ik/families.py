r"""The closed-form families: one :class:`Family` record each, in one registry.

An arm has a closed form when its joint axes fit one of four families
(:mod:`workbench.ik.structure` names the geometric tests):

* ``"opw"``: 6R, ortho-parallel shoulder (axes 2 ∥ 3), spherical wrist (axes
  4, 5, 6 meet): PUMA, KUKA KR, ABB IRB, Fanuc, Stäubli; kernel
  :mod:`workbench.ik._puma_kernel`;
* ``"ur"``: 6R, axes 2 ∥ 3 ∥ 4, axes 5 and 6 meet: Universal Robots and its
  clones; kernel :mod:`workbench.ik._ur_kernel`;
* ``"srs"``: 7R, spherical shoulder, elbow and wrist: KUKA LBR iiwa; the arm
  angle ψ is the redundancy parameter; kernel :mod:`workbench.ik._srs_kernel`;
* ``"franka"``: 7R, the Franka Panda/FR3 geometry; joint 7's value q7 is the
  redundancy parameter; kernel :mod:`workbench.ik._franka_kernel`.

:data:`FAMILIES` maps each name to its :class:`Family`, which says what the
family is (joint count, branch labels, redundancy parameter), how its kernel
is reached (the kernel module, the packing of an arm's constants, the
feasible intervals of the parameter) and the kinematic facts other packages
need (which axes are parallel, which meet at the shoulder and at the wrist,
the reach from shoulder to wrist point). Every package outside
:mod:`workbench.ik` asks the record (:func:`get_family`) and never compares
family names. Adding a family is one kernel module and one entry here
(``docs/closed-form-ik.md``, "Adding a family").

:func:`get_family` recognises a robot's family once and caches it per robot
object (:func:`~workbench.model.per_robot.per_robot`): from the robot's DH
table when it has one of PUMA type and the tool frame is the table's last
frame (the PUMA models), else from the DH chain fitted to its joint axes
(:func:`~workbench.ik.structure.get_structure`).
"""

from __future__ import annotations

import math
import types
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
import numpy.typing as npt

from workbench.errors import UnsupportedRobotError
from workbench.ik import (
    _franka_intervals,
    _franka_kernel,
    _srs_intervals,
    _srs_kernel,
    _ur_kernel,
)
from workbench.ik import _puma_kernel as _opw_kernel
from workbench.ik._puma import geometry_from_dh, get_geometry
from workbench.ik.structure import get_structure
from workbench.model.dh import DHTable
from workbench.model.per_robot import per_robot
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]
#: Feasible intervals of the redundancy parameter: ``(geometry, pose)`` ->
#: per branch, sorted disjoint ``(lo, hi)`` [rad].
IntervalFunction = Callable[[np.ndarray, FloatArray], list[list[tuple[float, float]]]]

#: Branch names of OPW arms; index = 4·left + 2·down + flip (``ik.solver``).
BRANCHES: tuple[str, ...] = tuple(
    f"{arm}/elbow-{elbow}/{wrist}"
    for arm in ("right", "left")
    for elbow in ("up", "down")
    for wrist in ("no-flip", "flip")
)

#: Branch names of UR-type arms; index = 4·left + 2·down + wrist-down.
UR_BRANCHES: tuple[str, ...] = tuple(
    f"shoulder-{arm}/elbow-{elbow}/wrist-{wrist}"
    for arm in ("right", "left")
    for elbow in ("up", "down")
    for wrist in ("up", "down")
)


@dataclass(frozen=True, slots=True)
class Family:
    """One closed-form family: what it is, its kernel, its kinematic facts.

    Attributes:
        name: ``"opw"``, ``"ur"``, ``"srs"`` or ``"franka"``: for display and
            the JSON outputs; code asks the other fields, never the name.
        title: One line saying what the family is, e.g. ``"ortho-parallel
            shoulder, spherical wrist"``.
        joint_count: Revolute joints of its arms, 6 or 7.
        branches: Branch labels, in the kernel's index order.
        parameter: The redundancy parameter as messages name it (``"arm
            angle"``, ψ; ``"q7"``), None for a six-axis family.
        parameter_periodic: True if the parameter is an angle taken mod 2π
            (the arm angle); False for a joint value with limits (q7) and for
            six-axis families.
        kernel: The compiled kernel module.
        pack: ``pack(robot)`` -> the robot's constants as the kernel's (1,)
            record.
        feasible_intervals: ``(geometry, pose)`` -> per branch the intervals
            [rad] of the parameter that reach ``pose`` within the joint
            limits; None for a six-axis family.
        parallel_axes: Axes (1-based) that are parallel, e.g. (2, 3) (OPW);
            empty if none.
        shoulder_axes: Axes that meet in one point at the shoulder, e.g. (1,
            2, 3) (seven-axis arms); empty if none (an OPW arm's axes 1 and 2
            may be offset, a1).
        elbow_axes: Axes that meet in one point at the elbow, (3, 4, 5) (SRS);
            empty if none (a Franka arm's elbow offsets a3, a4).
        wrist_axes: Axes that meet in the wrist point, e.g. (4, 5, 6) (OPW,
            the wrist centre) or (5, 6) (UR).
        reach: ``reach(table)`` -> the largest distance [m] of the wrist point
            from the shoulder of an arm with the fitted DH table ``table`` (the
            makers' "reach to the wrist point"): from axis 2, in the plane
            normal to it (six axes), or from the shoulder point S (seven axes).
    """

    name: str
    title: str
    joint_count: int
    branches: tuple[str, ...]
    parameter: str | None
    parameter_periodic: bool
    kernel: types.ModuleType
    pack: Callable[[Robot], np.ndarray]
    feasible_intervals: IntervalFunction | None
    parallel_axes: tuple[int, ...]
    shoulder_axes: tuple[int, ...]
    elbow_axes: tuple[int, ...]
    wrist_axes: tuple[int, ...]
    reach: Callable[[DHTable], float]

    @property
    def redundant(self) -> bool:
        """True for a seven-axis family, whose closed form takes a parameter."""
        return self.parameter is not None

    @property
    def spherical_wrist(self) -> bool:
        """True if three wrist axes meet in one point (the wrist centre)."""
        return len(self.wrist_axes) == 3

    def __repr__(self) -> str:
        return f"Family({self.name!r})"


def _pack_opw(robot: Robot) -> np.ndarray:
    """The OPW kernel's record of ``robot`` (its PUMA geometry)."""
    return _opw_kernel.pack_geometry(get_geometry(robot))


def _packer(kernel: types.ModuleType) -> Callable[[Robot], np.ndarray]:
    """``pack(robot)`` of a kernel that packs the fitted structure and limits."""

    def pack(robot: Robot) -> np.ndarray:
        return kernel.pack_geometry(get_structure(robot), robot.lower, robot.upper)

    pack.__name__ = pack.__qualname__ = f"pack_{kernel.__name__.rsplit('.', 1)[-1]}"
    return pack


def _reach_opw(table: DHTable) -> float:
    """``|a2| + hypot(a3, d4)``: upper arm, then elbow to wrist centre [m]."""
    rows = table.joints
    return abs(rows[1].a) + math.hypot(rows[2].a, rows[3].d)


def _reach_ur(table: DHTable) -> float:
    """``|a2| + |a3| + |d5|``: upper arm, forearm, wrist 1 to wrist point [m]."""
    rows = table.joints
    return abs(rows[1].a) + abs(rows[2].a) + abs(rows[4].d)


def _reach_seven_axis(table: DHTable) -> float:
    """``hypot(a3, d3) + hypot(a4, d5)``: shoulder S to wrist point, joint 4 [m].

    Both segments are normal to axis 4, which stretches them into line.
    """
    rows = table.joints
    return math.hypot(rows[2].a, rows[2].d) + math.hypot(rows[3].a, rows[4].d)


#: Every closed-form family, by name (read-only).
FAMILIES: Mapping[str, Family] = MappingProxyType(
    {
        family.name: family
        for family in (
            Family(
                name="opw",
                title="ortho-parallel shoulder, spherical wrist",
                joint_count=6,
                branches=BRANCHES,
                parameter=None,
                parameter_periodic=False,
                kernel=_opw_kernel,
                pack=_pack_opw,
                feasible_intervals=None,
                parallel_axes=(2, 3),
                shoulder_axes=(),
                elbow_axes=(),
                wrist_axes=(4, 5, 6),
                reach=_reach_opw,
            ),
            Family(
                name="ur",
                title="three parallel axes (2, 3, 4), axes 5 and 6 meeting",
                joint_count=6,
                branches=UR_BRANCHES,
                parameter=None,
                parameter_periodic=False,
                kernel=_ur_kernel,
                pack=_packer(_ur_kernel),
                feasible_intervals=None,
                parallel_axes=(2, 3, 4),
                shoulder_axes=(),
                elbow_axes=(),
                wrist_axes=(5, 6),
                reach=_reach_ur,
            ),
            Family(
                name="srs",
                title="spherical shoulder, elbow and wrist",
                joint_count=7,
                branches=_srs_kernel.BRANCHES,
                parameter=_srs_kernel.PARAMETER,
                parameter_periodic=True,
                kernel=_srs_kernel,
                pack=_packer(_srs_kernel),
                feasible_intervals=_srs_intervals.compute_feasible_intervals,
                parallel_axes=(),
                shoulder_axes=(1, 2, 3),
                elbow_axes=(3, 4, 5),
                wrist_axes=(5, 6, 7),
                reach=_reach_seven_axis,
            ),
            Family(
                name="franka",
                title="spherical shoulder, offset elbow, axes 5 and 6 meeting",
                joint_count=7,
                branches=_franka_kernel.BRANCHES,
                parameter=_franka_kernel.PARAMETER,
                parameter_periodic=False,
                kernel=_franka_kernel,
                pack=_packer(_franka_kernel),
                feasible_intervals=_franka_intervals.compute_feasible_intervals,
                parallel_axes=(),
                shoulder_axes=(1, 2, 3),
                elbow_axes=(),
                wrist_axes=(5, 6),
                reach=_reach_seven_axis,
            ),
        )
    }
)


@per_robot
def _recognise(robot: Robot) -> tuple[Family | None, str]:
    """The family of ``robot`` and, for an arm of none, why (cached per robot)."""
    table = robot.dh_table
    if table is not None and robot.tool_frame == table.tool_frame:
        try:
            geometry_from_dh(table, robot.lower, robot.upper)
        except UnsupportedRobotError:
            pass  # the table is not PUMA-type: the axes decide
        else:
            return FAMILIES["opw"], ""
    try:
        structure = get_structure(robot)
    except UnsupportedRobotError as err:
        return None, str(err)
    return FAMILIES[structure.family], ""


def get_family(robot: Robot) -> Family | None:
    """The closed-form :class:`Family` of ``robot``, or None if it has none.

    Cached per robot object (weakly), so a lookup is a dict access.
    :func:`get_family_refusal` says why an arm has none.
    """
    return _recognise(robot)[0]


def get_family_refusal(robot: Robot) -> str | None:
    """Why ``robot`` has no closed form (which axes fail which test), else None."""
    family, reason = _recognise(robot)
    return None if family is not None else reason


def require_family(robot: Robot) -> Family:
    """The :class:`Family` of ``robot``, for callers that need one.

    Raises:
        UnsupportedRobotError: If the robot has no closed form (the message is
            :func:`get_family_refusal`'s).
    """
    family, reason = _recognise(robot)
    if family is None:
        raise UnsupportedRobotError(reason)
    return family


__all__ = [
    "BRANCHES",
    "FAMILIES",
    "UR_BRANCHES",
    "Family",
    "get_family",
    "get_family_refusal",
    "require_family",
]
