"""What a URDF says of its joints that Pinocchio's parser does not check or honour.

Pinocchio accepts a joint axis of zero length (the model then fails at the
first non-zero angle) and a lower limit above the upper one; both are refused
here, naming the joint and the values. ``<mimic>`` tags are read here and
applied with :func:`pinocchio.transformJointIntoMimic`: the mimicking joint
then has no coordinate of its own and follows its leader,
``q_follower = multiplier * q_leader + offset``, in FK and Jacobians.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import pinocchio as pin

from workbench.errors import URDFLoadError

_MOVING = ("revolute", "continuous", "prismatic")
_LIMITED = ("revolute", "prismatic")


@dataclass(frozen=True, slots=True)
class MimicJoint:
    """A joint that follows another: ``q = multiplier * q_leader + offset``.

    Attributes:
        joint: Name of the mimicking (following) joint.
        leader: Name of the joint it follows.
        multiplier: Gain, dimensionless (URDF default 1).
        offset: Offset [rad or m] (URDF default 0).
    """

    joint: str
    leader: str
    multiplier: float
    offset: float

    def __str__(self) -> str:
        """``"JOINT follows LEADER"``, for messages."""
        return f"{self.joint} follows {self.leader}"


def parse_urdf_joints(text: str, path: Path) -> list[MimicJoint]:
    """Check every moving joint of a URDF; return its mimic joints.

    Args:
        text: The URDF's XML, already read by Pinocchio's parser (urdfdom),
            which checked the form of its numbers.
        path: Its file, for the messages.

    Returns:
        The ``<mimic>`` tags of the moving joints, in file order.

    Raises:
        URDFLoadError: If a joint's axis has zero length, a revolute or
            prismatic joint's lower limit exceeds its upper limit.
    """
    try:
        root = ET.fromstring(text)
    except ET.ParseError as err:
        raise URDFLoadError(f"{path}: malformed URDF: {err}") from err
    mimics = []
    for joint in root.iter("joint"):
        kind, name = joint.get("type"), joint.get("name", "?")
        if kind not in _MOVING:
            continue
        _check_axis(joint, name, path)
        if kind in _LIMITED:
            _check_limits(joint, name, path)
        tag = joint.find("mimic")
        if tag is not None:
            mimics.append(
                MimicJoint(
                    name,
                    tag.get("joint", ""),
                    _number(tag, "multiplier", 1.0),
                    _number(tag, "offset", 0.0),
                )
            )
    return mimics


def _number(element: ET.Element, key: str, default: float) -> float:
    """A number attribute (urdfdom, which read the file first, checked its form)."""
    text = element.get(key)
    return default if text is None else float(text)


def _check_axis(joint: ET.Element, name: str, path: Path) -> None:
    axis = joint.find("axis")
    if axis is None:
        return  # URDF default (1, 0, 0)
    text = axis.get("xyz", "1 0 0")
    if math.hypot(*(float(x) for x in text.split())) == 0.0:
        raise URDFLoadError(
            f"{path}: joint {name!r} has a zero-length axis (xyz={text!r}); "
            "give a unit vector"
        )


def _check_limits(joint: ET.Element, name: str, path: Path) -> None:
    limit = joint.find("limit")
    if limit is None:
        return
    lower = _number(limit, "lower", 0.0)
    upper = _number(limit, "upper", 0.0)
    if lower > upper:
        raise URDFLoadError(
            f"{path}: joint {name!r} has lower limit {lower:g} above its upper "
            f"limit {upper:g}"
        )


def apply_mimic_joints(
    model: pin.Model, mimics: list[MimicJoint], path: Path
) -> pin.Model:
    """Make each mimicking joint of ``model`` follow its leader.

    A mimic tag whose joint is not a moving joint of ``model`` (fixed, or
    locked by the catalog) is skipped.

    Raises:
        URDFLoadError: If a leader is not a moving joint of the model, is
            itself a mimicking joint, is not revolute or prismatic (nor its
            follower), or comes after its follower in Pinocchio's joint order
            (which Pinocchio cannot represent).
    """
    followers = {m.joint for m in mimics}
    for mimic in mimics:
        if not model.existJointName(mimic.joint):
            continue
        if not model.existJointName(mimic.leader):
            raise URDFLoadError(
                f"{path}: joint {mimic.joint!r} mimics {mimic.leader!r}, which is "
                "not a moving joint of the URDF"
            )
        if mimic.leader in followers:
            raise URDFLoadError(
                f"{path}: joint {mimic.joint!r} mimics {mimic.leader!r}, which "
                "mimics another joint itself (chains of mimic joints are not "
                "supported)"
            )
        leader = model.getJointId(mimic.leader)
        follower = model.getJointId(mimic.joint)
        if any(
            model.joints[j].nq != 1 or model.joints[j].nv != 1
            for j in (leader, follower)
        ):
            raise URDFLoadError(
                f"{path}: joint {mimic.joint!r} mimics {mimic.leader!r}: mimic "
                "joints must be revolute or prismatic (one coordinate each), "
                "leader and follower"
            )
        if leader > follower:
            raise URDFLoadError(
                f"{path}: joint {mimic.joint!r} mimics {mimic.leader!r}, which "
                "Pinocchio cannot represent: the leader must come before its "
                "follower in the kinematic tree (depth first, sibling joints by "
                "name)"
            )
        model = pin.transformJointIntoMimic(
            model, leader, follower, mimic.multiplier, mimic.offset
        )
    return model


__all__ = ["MimicJoint", "apply_mimic_joints", "parse_urdf_joints"]
