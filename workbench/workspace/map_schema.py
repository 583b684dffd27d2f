"""The schema of a map's group attributes: types, ranges and their consistency.

:func:`check_attributes` reads the attributes ``docs/workspace.md`` lists
(written by :func:`workbench.workspace._partial.map_attributes`) and refuses,
with one line naming the attribute, any value of the wrong type, out of its
range or inconsistent with the others: a resolution of 0 or NaN, a 2-number
origin, a string covering radius, a negative grid shape, tolerances on a
seven-axis map. It runs on every open (it reads only the attributes);
:func:`workbench.workspace.verify.verify_map` also re-derives the grid and
the orientation set from them.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from workbench.errors import InputError
from workbench.ik.families import FAMILIES

#: A SHA-256 digest written as hex.
_SHA256 = re.compile(r"[0-9a-f]{64}")
#: The orientation-set constructions of :mod:`workbench.workspace.orientations`.
CONSTRUCTIONS = ("super-fibonacci", "super-fibonacci-cone")
#: Largest grid of a map [voxels] (:func:`~workbench.workspace.make_pose_grid`).
MAX_VOXELS = 2**31


class _Damaged(Exception):
    """One attribute is wrong: its dotted name and what is wrong with it."""

    def __init__(self, name: str, what: str):
        super().__init__(name, what)
        self.name, self.what = name, what


def _get(attrs: Mapping[str, Any], name: str) -> Any:
    value: Any = attrs
    for part in name.split("."):
        if not isinstance(value, Mapping) or part not in value:
            raise _Damaged(name, "missing")
        value = value[part]
    return value


def _number(value: Any, name: str, *, low: float | None = None, strict=False) -> float:
    """A finite JSON number (not a bool), ``> low`` (strict) or ``>= low``."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise _Damaged(name, f"must be a number, got {value!r}")
    if not math.isfinite(value):
        raise _Damaged(name, f"must be finite, got {value!r}")
    if low is not None and (value <= low if strict else value < low):
        raise _Damaged(
            name, f"must be {'>' if strict else '>='} {low:g}, got {value!r}"
        )
    return float(value)


def _integer(value: Any, name: str, *, low: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise _Damaged(name, f"must be an integer, got {value!r}")
    if value < low:
        raise _Damaged(name, f"must be >= {low}, got {value!r}")
    return value


def _numbers(value: Any, name: str, size: int | None) -> list[float]:
    if not isinstance(value, list) or (size is not None and len(value) != size):
        count = "a list" if size is None else f"a list of {size} numbers"
        raise _Damaged(name, f"must be {count}, got {value!r}")
    return [_number(v, f"{name}[{i}]") for i, v in enumerate(value)]


def _text(value: Any, name: str) -> str:
    if not isinstance(value, str) or not value:
        raise _Damaged(name, f"must be a non-empty string, got {value!r}")
    return value


def check_attributes(path: str | Path, attrs: Mapping[str, Any]) -> None:
    """Raise unless ``attrs`` are the attributes of a workspace map.

    ``format`` and ``format_version`` are checked by the caller.

    Args:
        path: The map (for the message).
        attrs: Its group attributes.

    Raises:
        InputError: One line: ``PATH is a damaged workspace map (attribute
            NAME: WHAT)``.
    """
    try:
        _check(attrs)
    except _Damaged as err:
        raise InputError(
            f"{path} is a damaged workspace map (attribute {err.name}: {err.what})"
        ) from None


def _check(attrs: Mapping[str, Any]) -> None:
    _text(_get(attrs, "robot"), "robot")
    _text(_get(attrs, "tool_frame"), "tool_frame")
    digest = _get(attrs, "urdf_sha256")
    if not isinstance(digest, str) or not _SHA256.fullmatch(digest):
        raise _Damaged("urdf_sha256", f"must be 64 hex digits, got {digest!r}")
    srdf = attrs.get("srdf_sha256")  # (maps written before SRDFs have none)
    if srdf is not None and not (isinstance(srdf, str) and _SHA256.fullmatch(srdf)):
        raise _Damaged("srdf_sha256", f"must be null or 64 hex digits, got {srdf!r}")
    family = _get(attrs, "family")
    known = FAMILIES.get(family) if isinstance(family, str) else None
    if family is not None and known is None:
        names = ", ".join(FAMILIES)
        raise _Damaged("family", f"must be null or one of {names}, got {family!r}")
    _check_limits(attrs)
    _check_sampling(attrs, family)
    _check_grid(attrs)
    _check_orientations(attrs)
    _integer(_get(attrs, "block_voxels"), "block_voxels")
    seven_axis = known is not None and known.redundant
    _check_redundancy(attrs, seven_axis and not attrs["sampled"])
    scene = _get(attrs, "scene")
    if scene is not None and (attrs["sampled"] or seven_axis):
        raise _Damaged("scene", "a sampled or seven-axis map has no scene")
    if scene is not None and not isinstance(scene.get("objects", None), list):
        raise _Damaged("scene", "must be null or a scene with a list of objects")
    versions = _get(attrs, "versions")
    if not isinstance(versions, Mapping) or not all(
        isinstance(v, str) for v in versions.values()
    ):
        raise _Damaged(
            "versions", f"must map package names to versions, got {versions!r}"
        )


def _check_limits(attrs: Mapping[str, Any]) -> None:
    lower = _numbers(_get(attrs, "joint_limits.lower"), "joint_limits.lower", None)
    upper = _numbers(_get(attrs, "joint_limits.upper"), "joint_limits.upper", None)
    if not lower or len(lower) != len(upper):
        raise _Damaged("joint_limits", "lower and upper must have one value per joint")
    bad = [i for i, (lo, hi) in enumerate(zip(lower, upper, strict=True)) if lo > hi]
    if bad:
        raise _Damaged("joint_limits", f"lower > upper at joint index {bad[0]}")


def _check_sampling(attrs: Mapping[str, Any], family: str | None) -> None:
    sampled = _get(attrs, "sampled")
    if not isinstance(sampled, bool):
        raise _Damaged("sampled", f"must be true or false, got {sampled!r}")
    samples, sampling = _get(attrs, "samples"), _get(attrs, "sampling")
    if not sampled:
        if family is None:
            raise _Damaged("sampled", "an exact map needs a family")
        if samples is not None or sampling is not None:
            raise _Damaged("samples", "an exact map has no samples (null)")
        return
    _integer(samples, "samples")
    _integer(_get(attrs, "sampling.samples_per_block"), "sampling.samples_per_block")
    _integer(_get(attrs, "sampling.seed"), "sampling.seed", low=0)


def _check_grid(attrs: Mapping[str, Any]) -> None:
    _numbers(_get(attrs, "grid.origin"), "grid.origin", 3)
    _number(_get(attrs, "grid.resolution"), "grid.resolution", low=0.0, strict=True)
    shape = _get(attrs, "grid.shape")
    if not isinstance(shape, list) or len(shape) != 3:
        raise _Damaged("grid.shape", f"must be 3 integers, got {shape!r}")
    sizes = [_integer(n, f"grid.shape[{i}]") for i, n in enumerate(shape)]
    if math.prod(sizes) > MAX_VOXELS:
        raise _Damaged("grid.shape", f"{sizes} is more than {MAX_VOXELS} voxels")
    bounds = _get(attrs, "grid.bounds")
    if not isinstance(bounds, list) or len(bounds) != 2:
        raise _Damaged("grid.bounds", f"must be 2 rows of 3 numbers, got {bounds!r}")
    low = _numbers(bounds[0], "grid.bounds[0]", 3)
    high = _numbers(bounds[1], "grid.bounds[1]", 3)
    if any(a > b for a, b in zip(low, high, strict=True)):
        raise _Damaged("grid.bounds", "a minimum is above its maximum")


def _check_orientations(attrs: Mapping[str, Any]) -> None:
    construction = _get(attrs, "orientation_set.construction")
    if construction not in CONSTRUCTIONS:
        raise _Damaged(
            "orientation_set.construction",
            f"must be one of {', '.join(CONSTRUCTIONS)}, got {construction!r}",
        )
    _integer(_get(attrs, "orientation_set.count"), "orientation_set.count")
    radius = _get(attrs, "orientation_set.covering_radius")
    _number(radius, "orientation_set.covering_radius", low=0.0, strict=True)
    if radius > math.pi:
        raise _Damaged("orientation_set.covering_radius", f"must be <= π, got {radius}")
    if construction == "super-fibonacci-cone":
        axis = _numbers(_get(attrs, "orientation_set.axis"), "orientation_set.axis", 3)
        if abs(math.hypot(*axis) - 1.0) > 1e-12:
            raise _Damaged("orientation_set.axis", "must be a unit vector")
        half = _get(attrs, "orientation_set.half_angle")
        _number(half, "orientation_set.half_angle", low=0.0, strict=True)
        if half > math.pi:
            raise _Damaged("orientation_set.half_angle", f"must be <= π, got {half}")


def _check_redundancy(attrs: Mapping[str, Any], seven_axis: bool) -> None:
    tolerances, redundancy = _get(attrs, "tolerances"), _get(attrs, "redundancy")
    if not seven_axis:
        if redundancy is not None:
            raise _Damaged("redundancy", "only a seven-axis exact map has one")
        if not attrs["sampled"]:
            if not isinstance(tolerances, Mapping):
                raise _Damaged("tolerances", f"must be an object, got {tolerances!r}")
            for key in ("shoulder", "elbow", "wrist"):
                name = f"tolerances.{key}"
                _number(_get(attrs, name), name, low=0.0, strict=True)
        return
    if tolerances is not None:
        raise _Damaged("tolerances", "a seven-axis map has none (null)")
    _text(_get(attrs, "redundancy.parameter"), "redundancy.parameter")
    low, high = _numbers(_get(attrs, "redundancy.range"), "redundancy.range", 2)
    if not low < high:
        raise _Damaged("redundancy.range", f"must be increasing, got {[low, high]}")
    count = _integer(_get(attrs, "redundancy.samples"), "redundancy.samples")
    values = _numbers(_get(attrs, "redundancy.values"), "redundancy.values", count)
    if any(not low <= v <= high for v in values):
        raise _Damaged("redundancy.values", "a value lies outside redundancy.range")
