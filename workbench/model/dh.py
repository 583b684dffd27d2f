r"""Standard Denavit–Hartenberg tables: data, validation, and an independent FK.

A table row holds the constant parameters of one revolute joint. Frame ``i`` is
placed relative to frame ``i-1`` by

.. math::
    {}^{i-1}T_i = R_z(\theta_i + \theta_{0,i})\, T_z(d_i)\, T_x(a_i)\, R_x(\alpha_i).

The products here use numpy only, so that tests can check Pinocchio against a
computation that shares no code with it.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt

from workbench.errors import DHTableError
from workbench.validation import as_vector, read_json_file

#: Tool-frame names (a URDF link name): letters, digits, ``_`` and ``.``, single
#: ``-`` between them.
NAME_PATTERN = re.compile(r"[A-Za-z0-9_.]+(-[A-Za-z0-9_.]+)*")
#: Robot names may also hold spaces and other printable characters, but no
#: ``--`` and no ``-`` at the end (the name goes into an XML comment).
ROBOT_NAME_PATTERN = re.compile(r"(?!.*--)(?!.*-$)[^\x00-\x1f\x7f]+")

FloatArray = npt.NDArray[np.float64]

#: Largest |a| and |d| of a row [m]: a thousand times any industrial arm's
#: links, and far below where the reach (a sum of lengths) and the IK's squares
#: of lengths lose their digits or overflow.
MAX_DH_LENGTH = 1000.0

#: Joint speed limit used when a table row gives none [rad/s]. An assumption,
#: stated in urdf/README.md; override it per row with ``"velocity"``.
DEFAULT_VELOCITY_LIMIT = 1.0


@dataclass(frozen=True, slots=True)
class DHJoint:
    """One row of a standard DH table (SI units).

    Attributes:
        alpha: Twist about x_i [rad].
        a: Link length along x_i [m].
        d: Offset along z_{i-1} [m].
        theta_offset: Constant added to the joint variable [rad].
        lower: Lower position limit of the joint variable [rad].
        upper: Upper position limit of the joint variable [rad].
        velocity: Speed limit [rad/s].
    """

    alpha: float
    a: float
    d: float
    theta_offset: float = 0.0
    lower: float = -math.pi
    upper: float = math.pi
    velocity: float = DEFAULT_VELOCITY_LIMIT


@dataclass(frozen=True, slots=True)
class DHTable:
    """A serial arm of revolute joints described by a standard DH table.

    Attributes:
        name: Robot name (used as the URDF robot name).
        joints: One row per joint, base to tip.
        tool_frame: Name of the frame placed at the last DH frame.
        source: Free text saying where the numbers come from.
    """

    name: str
    joints: tuple[DHJoint, ...]
    tool_frame: str = "tool"
    source: str = ""
    convention: ClassVar[str] = "standard"
    _keys: ClassVar[tuple[str, ...]] = (
        "name",
        "convention",
        "joints",
        "tool_frame",
        "source",
    )
    _fields: ClassVar[tuple[str, ...]] = tuple(DHJoint.__dataclass_fields__)
    _required: ClassVar[tuple[str, ...]] = ("alpha", "a", "d")

    @property
    def nq(self) -> int:
        """Number of joints."""
        return len(self.joints)

    @classmethod
    def from_dict(cls, raw: Any, source: str = "DH table") -> DHTable:
        """Build a table from its JSON form (see docs/interface.md).

        Args:
            raw: Parsed JSON object.
            source: Where it came from, for error messages.

        Raises:
            DHTableError: If a key is missing, unknown or not a finite number,
                or a length exceeds :data:`MAX_DH_LENGTH`.
        """
        if not isinstance(raw, dict):
            raise DHTableError(f"{source}: top level must be a JSON object")
        unknown = sorted(set(raw) - set(cls._keys))
        if unknown:
            raise DHTableError(
                f"{source}: unknown key(s) {', '.join(unknown)}; "
                f"valid keys: {', '.join(cls._keys)}"
            )
        convention = raw.get("convention", "standard")
        if convention != "standard":
            raise DHTableError(
                f"{source}: convention {convention!r} not supported (only 'standard')"
            )
        name = _check_name(raw.get("name"), "name", source, ROBOT_NAME_PATTERN)
        rows = raw.get("joints")
        if not isinstance(rows, list) or not rows:
            raise DHTableError(f"{source}: 'joints' must be a non-empty list")
        joints = tuple(cls._parse_row(row, i, source) for i, row in enumerate(rows, 1))
        tool_frame = _check_name(
            raw.get("tool_frame", "tool"), "tool_frame", source, NAME_PATTERN
        )
        generated = {f"frame{i}" for i in range(len(joints) + 1)}
        generated |= {f"link{i}" for i in range(1, len(joints) + 1)}
        if tool_frame in generated:
            raise DHTableError(
                f"{source}: 'tool_frame' {tool_frame!r} is the name of a generated "
                f"link (frame0..frame{len(joints)}, link1..link{len(joints)})"
            )
        text = raw.get("source", "")
        if not isinstance(text, str):
            raise DHTableError(f"{source}: 'source' must be a string")
        return cls(name=name, joints=joints, tool_frame=tool_frame, source=text)

    @classmethod
    def _parse_row(cls, row: Any, index: int, source: str) -> DHJoint:
        where = f"{source}: joint {index}"
        if not isinstance(row, dict):
            raise DHTableError(f"{where} must be a JSON object")
        unknown = sorted(set(row) - set(cls._fields))
        if unknown:
            raise DHTableError(
                f"{where}: unknown key(s) {', '.join(unknown)}; "
                f"valid keys: {', '.join(cls._fields)}"
            )
        missing = [k for k in cls._required if k not in row]
        if missing:
            raise DHTableError(f"{where}: missing key(s) {', '.join(missing)}")
        values = {}
        for key, value in row.items():
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise DHTableError(f"{where}: {key!r} must be a number, got {value!r}")
            if not math.isfinite(value):
                raise DHTableError(f"{where}: {key!r} must be finite, got {value!r}")
            values[key] = float(value)
        joint = DHJoint(**values)
        for key in ("a", "d"):
            if abs(values[key]) > MAX_DH_LENGTH:
                raise DHTableError(
                    f"{where}: {key!r} must be at most {MAX_DH_LENGTH:g} m in "
                    f"magnitude, got {values[key]!r}"
                )
        if joint.lower > joint.upper:
            raise DHTableError(
                f"{where}: lower limit {joint.lower} > upper limit {joint.upper}"
            )
        if joint.velocity <= 0.0:
            raise DHTableError(
                f"{where}: velocity limit must be > 0, got {joint.velocity}"
            )
        return joint

    @classmethod
    def from_json(cls, path: str | Path) -> DHTable:
        """Read a table from a JSON file.

        Raises:
            DHTableError: If the file is missing, not JSON, or malformed.
        """
        raw = read_json_file(path, DHTableError, "DH table")
        return cls.from_dict(raw, source=str(path))

    def link_transforms(self, q: npt.ArrayLike) -> FloatArray:
        r"""Transforms ``{}^{i-1}T_i`` of every joint at configuration ``q``.

        Args:
            q: Joint variables, shape (nq,) [rad].

        Returns:
            Shape (nq, 4, 4), homogeneous transforms [m].
        """
        q = as_vector(q, self.nq, "q")
        theta = q + np.array([j.theta_offset for j in self.joints])
        alpha = np.array([j.alpha for j in self.joints])
        a = np.array([j.a for j in self.joints])
        d = np.array([j.d for j in self.joints])
        ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
        out = np.zeros((self.nq, 4, 4))
        out[:, 0, 0], out[:, 0, 1], out[:, 0, 2], out[:, 0, 3] = (
            ct,
            -st * ca,
            st * sa,
            a * ct,
        )
        out[:, 1, 0], out[:, 1, 1], out[:, 1, 2], out[:, 1, 3] = (
            st,
            ct * ca,
            -ct * sa,
            a * st,
        )
        out[:, 2, 1], out[:, 2, 2], out[:, 2, 3] = sa, ca, d
        out[:, 3, 3] = 1.0
        return out

    def frame_transforms(self, q: npt.ArrayLike) -> FloatArray:
        """Poses of DH frames 0..nq in the base frame at ``q``.

        Returns:
            Shape (nq + 1, 4, 4); entry 0 is the identity (base frame).
        """
        frames = np.empty((self.nq + 1, 4, 4))
        frames[0] = np.eye(4)
        for i, link in enumerate(self.link_transforms(q)):
            frames[i + 1] = frames[i] @ link
        return frames

    def forward_kinematics(self, q: npt.ArrayLike) -> FloatArray:
        """Pose of the last DH frame (the tool frame) in the base frame, (4, 4)."""
        return self.frame_transforms(q)[-1]

    def geometric_jacobian(self, q: npt.ArrayLike) -> FloatArray:
        r"""Geometric Jacobian of the tool frame, base axes, from the DH frames.

        Column i is :math:`[z_{i-1} \times (p - o_{i-1});\ z_{i-1}]`, i.e. the
        LOCAL_WORLD_ALIGNED Jacobian of Pinocchio.

        Returns:
            Shape (6, nq), rows [linear (m/s); angular (rad/s)] per rad/s.
        """
        frames = self.frame_transforms(q)
        z = frames[:-1, :3, 2]
        o = frames[:-1, :3, 3]
        p = frames[-1, :3, 3]
        return np.vstack([np.cross(z, p - o).T, z.T])


def _check_name(value: Any, key: str, source: str, pattern: re.Pattern[str]) -> str:
    """A table's ``name`` or ``tool_frame``, checked against ``pattern``."""
    if not isinstance(value, str) or not value:
        raise DHTableError(f"{source}: {key!r} must be a non-empty string")
    if not pattern.fullmatch(value):
        rule = (
            "letters, digits, '_', '.' and single '-' between them"
            if pattern is NAME_PATTERN
            else "printable, without '--' or a final '-'"
        )
        raise DHTableError(f"{source}: {key!r} must be {rule}, got {value!r}")
    return value
