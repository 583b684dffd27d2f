"""SRDF files: the link pairs a robot's self-collision check leaves out.

MoveIt's setup assistant writes a robot's ``<disable_collisions link1=""
link2="" reason=""/>`` entries into its SRDF (``Adjacent``, ``Never``,
``Default``, ``User``, …). :func:`read_disabled_collisions` reads them;
:func:`find_srdf` finds the SRDF beside a URDF or xacro file
(``arm.urdf`` → ``arm.srdf``, ``arm.urdf.xacro`` → ``arm.srdf``). The other
elements of an SRDF (groups, end effectors, virtual joints) are not read.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from workbench.errors import URDFLoadError

#: Largest SRDF read [bytes].
MAX_SRDF_BYTES = 16 * 2**20
#: One excluded pair: the two link names (sorted) and the SRDF's reason.
DisabledCollision = tuple[str, str, str]


def find_srdf(description: str | Path) -> Path | None:
    """The SRDF beside a URDF or xacro file (same name, ``.srdf``), if any."""
    path = Path(description)
    name = path.name
    for suffix in (".xacro", ".urdf"):
        if name.lower().endswith(suffix):
            name = name[: -len(suffix)]
    candidate = path.with_name(f"{name}.srdf")
    return candidate if candidate.is_file() else None


def read_disabled_collisions(path: str | Path) -> tuple[DisabledCollision, ...]:
    """The ``<disable_collisions>`` entries of an SRDF, sorted.

    Args:
        path: The SRDF file.

    Returns:
        ``(link_a, link_b, reason)`` per entry, link names sorted within
        each pair, pairs sorted; a pair given twice once (its first reason).

    Raises:
        URDFLoadError: If the file cannot be read, is not XML, its root is
            not ``<robot>``, or an entry lacks a link name (one line).
    """
    path = Path(path)
    try:
        if path.stat().st_size > MAX_SRDF_BYTES:
            raise URDFLoadError(
                f"SRDF {path}: larger than {MAX_SRDF_BYTES // 2**20} MiB, not read"
            )
        root = ET.fromstring(path.read_bytes())
    except OSError as err:
        raise URDFLoadError(f"cannot read SRDF {path}: {err.strerror or err}") from err
    except ET.ParseError as err:
        raise URDFLoadError(f"SRDF {path}: not valid XML ({err})") from None
    if root.tag != "robot":
        raise URDFLoadError(
            f"SRDF {path}: the root element is <{root.tag}>, not <robot>"
        )
    pairs: dict[tuple[str, str], str] = {}
    for i, entry in enumerate(root.iter("disable_collisions")):
        a, b = entry.get("link1"), entry.get("link2")
        if not a or not b:
            raise URDFLoadError(
                f"SRDF {path}: <disable_collisions> entry {i} needs link1 and link2"
            )
        key = (min(a, b), max(a, b))
        pairs.setdefault(key, entry.get("reason") or "User")
    return tuple((a, b, reason) for (a, b), reason in sorted(pairs.items()))
