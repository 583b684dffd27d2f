"""Which link pairs of a robot are checked against each other (an SRDF's job).

MoveIt's setup assistant writes ``<disable_collisions>`` entries into a robot's
SRDF for link pairs that need no check. We compute the same two reasons from
the collision geometry itself:

* ``Adjacent``: the links hang on consecutive joints of the kinematic tree
  (a joint and its parent joint in Pinocchio, fixed joints merged), and
  ``Rigid``: they hang on the same joint (they never move relative to each
  other);
* ``Default``: their geometry is in contact (distance <= :data:`CONTACT_TOL`)
  at the zero pose (``pinocchio.neutral``), as joint housings that overlap by
  construction are.

Every other pair of links with geometry is checked. :meth:`SelfCollisionFilter.to_srdf`
writes the list in the SRDF form a user can read and compare.
"""

from __future__ import annotations

from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

import pinocchio as pin

from workbench.model.robot import Robot

#: Distance [m] at or below which two geometries count as in contact.
CONTACT_TOL = 1e-9


@dataclass(frozen=True, slots=True)
class DisabledPair:
    """A link pair that is not checked, and why.

    Attributes:
        link_a, link_b: Link names (sorted).
        reason: ``"Rigid"``, ``"Adjacent"`` or ``"Default"``.
    """

    link_a: str
    link_b: str
    reason: str

    def as_dict(self) -> dict[str, str]:
        """JSON form: ``{link_a, link_b, reason}`` (``workbench urdf srdf --json``)."""
        return {"link_a": self.link_a, "link_b": self.link_b, "reason": self.reason}


@dataclass(frozen=True, slots=True)
class SelfCollisionFilter:
    """The link pairs excluded from self-collision checks.

    Attributes:
        robot: Robot name.
        links: Links with collision geometry, in model order.
        disabled: The excluded pairs, sorted.
        srdf: The SRDF the pairs were read from, or None (computed).
    """

    robot: str
    links: tuple[str, ...]
    disabled: tuple[DisabledPair, ...]
    srdf: str | None = None

    def is_disabled(self, link_a: str, link_b: str) -> bool:
        """Whether the pair (either order) is excluded."""
        key = tuple(sorted((link_a, link_b)))
        return any((d.link_a, d.link_b) == key for d in self.disabled)

    def get_checked_pairs(self) -> list[tuple[str, str]]:
        """Link pairs that are checked, sorted."""
        off = {(d.link_a, d.link_b) for d in self.disabled}
        pairs = {
            (min(a, b), max(a, b))
            for i, a in enumerate(self.links)
            for b in self.links[i + 1 :]
            if a != b
        }
        return sorted(p for p in pairs if p not in off)

    def to_srdf(self) -> str:
        """SRDF text with one ``<disable_collisions>`` line per excluded pair."""
        how = (
            "computed by workbench.collision: links on the same or consecutive "
            "joints, and links in contact at the zero pose"
            if self.srdf is None
            else "read from the robot's SRDF (its pairs between links of the "
            "model), and links on the same joint"
        )
        lines = [
            '<?xml version="1.0"?>',
            f"<!-- Self-collision filter {how}. -->",
            f"<robot name={quoteattr(self.robot)}>",
        ]
        lines += [
            f"  <disable_collisions link1={quoteattr(d.link_a)} "
            f"link2={quoteattr(d.link_b)} reason={quoteattr(d.reason)}/>"
            for d in self.disabled
        ]
        lines.append("</robot>")
        return "\n".join(lines) + "\n"


def get_link_name(model: pin.Model, geometry: pin.GeometryObject) -> str:
    """Name of the link (body frame) a geometry object is attached to."""
    return str(model.frames[geometry.parentFrame].name)


def compute_self_collision_filter(
    robot: Robot, geometry_model: pin.GeometryModel | None = None
) -> SelfCollisionFilter:
    """Compute the excluded link pairs from the robot's collision geometry.

    A robot loaded with an SRDF (:attr:`~workbench.model.Robot.srdf_path`)
    leaves out its ``<disable_collisions>`` pairs (between links of the
    model; the others are ignored) and the ``Rigid`` ones, as MoveIt does;
    nothing is computed from contacts then.

    Args:
        robot: The robot.
        geometry_model: Collision geometry; default ``robot.collision_model``.

    Returns:
        The filter; the same robot always gives the same filter.
    """
    model = robot.model
    geometry = pin.GeometryModel(geometry_model or robot.collision_model)
    objects = list(geometry.geometryObjects)
    links = [get_link_name(model, g) for g in objects]
    joints = [int(g.parentJoint) for g in objects]
    reasons: dict[tuple[str, str], str] = {}
    candidates = []
    for i in range(len(objects)):
        for j in range(i + 1, len(objects)):
            if links[i] == links[j]:
                continue
            key = (min(links[i], links[j]), max(links[i], links[j]))
            a, b = joints[i], joints[j]
            if a == b:
                reasons[key] = "Rigid"
            elif model.parents[a] == b or model.parents[b] == a:
                reasons.setdefault(key, "Adjacent")
            else:
                candidates.append((i, j, key))
    if robot.srdf_path is not None:  # the SRDF's pairs, not the computed ones
        present = set(links)
        reasons = {key: r for key, r in reasons.items() if r == "Rigid"}
        for link_a, link_b, reason in robot.disabled_collisions:
            if link_a in present and link_b in present:
                reasons.setdefault((link_a, link_b), reason)
        candidates.clear()
    for i, j, _ in candidates:
        geometry.addCollisionPair(pin.CollisionPair(i, j))
    data = pin.GeometryData(geometry)
    if candidates:
        pin.computeDistances(
            model, model.createData(), geometry, data, pin.neutral(model)
        )
    for k, (_, _, key) in enumerate(candidates):
        if data.distanceResults[k].min_distance <= CONTACT_TOL:
            reasons.setdefault(key, "Default")
    disabled = tuple(DisabledPair(a, b, r) for (a, b), r in sorted(reasons.items()))
    unique_links = tuple(dict.fromkeys(links))
    srdf = None if robot.srdf_path is None else str(robot.srdf_path)
    return SelfCollisionFilter(robot.name, unique_links, disabled, srdf)


__all__ = [
    "CONTACT_TOL",
    "DisabledPair",
    "SelfCollisionFilter",
    "compute_self_collision_filter",
    "get_link_name",
]
