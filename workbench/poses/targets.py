"""Typed target poses: numbers as a person writes them, turned into one ``pin.SE3``.

One parser for every command that takes a tool pose (``workbench ik``,
``workbench plan pick-place``) and for Python callers who hold the same
numbers. A target is given in one of the :data:`TARGET_FORMS`:

* ``"angeles7"``: ``e_x sinφ, e_y sinφ, e_z sinφ, cosφ, p_x, p_y, p_z``
  (Angeles et al., 1988), norm² within :data:`~workbench.poses.ANGELES7_PRINTED_TOL`
  of 1 so that numbers printed to 2 decimals are accepted;
* ``"matrix"``: the 16 entries of the (4, 4) homogeneous matrix, row by
  row, rotation orthonormal within :data:`~workbench.poses.RIGIDITY_TOL`;
* ``"xyz_quat_wxyz"``: position x, y, z, then a unit quaternion w, x, y, z
  (scalar first), norm within :data:`QUAT_TYPED_TOL` of 1 (then normalised).

Positions are in metres times ``scale`` (``scale=1e-3`` for millimetres).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from workbench.errors import InputError, NonFiniteError
from workbench.poses.angeles7 import ANGELES7_PRINTED_TOL, se3_from_angeles7
from workbench.poses.rigid import as_se3
from workbench.poses.rotations import rotation_from_quat_wxyz

#: The forms of :func:`parse_target`, with their number of values.
TARGET_FORMS: dict[str, int] = {"angeles7": 7, "matrix": 16, "xyz_quat_wxyz": 7}
#: Largest accepted | |q| - 1 | of a typed quaternion (then normalised): four
#: decimals, as in "0.7071 0 0 0.7071", are enough.
QUAT_TYPED_TOL = 1e-3
#: Largest |coordinate| of a target position [m] (1000 km: far beyond any arm).
MAX_TARGET_COORDINATE = 1e6


def parse_target(values: Sequence[float], form: str, *, scale: float = 1.0) -> pin.SE3:
    """The tool pose written as numbers in one of :data:`TARGET_FORMS`.

    Args:
        values: The numbers, as many as ``TARGET_FORMS[form]``.
        form: ``"angeles7"``, ``"matrix"`` or ``"xyz_quat_wxyz"`` (module docs).
        scale: Metres per unit of the positions, > 0 (1e-3: millimetres).

    Returns:
        The pose of the tool frame in the base frame, positions in metres.
        A matrix keeps its rotation as given (not re-orthonormalised); a
        quaternion or angeles7 rotation is normalised.

    Raises:
        InputError: Unknown form, wrong count, a coordinate beyond
            :data:`MAX_TARGET_COORDINATE`, or numbers that make no rigid pose
            (``NonFiniteError`` on NaN or infinity).
    """
    if form not in TARGET_FORMS:
        raise InputError(
            f"target form must be one of {', '.join(TARGET_FORMS)}, got {form!r}"
        )
    count = TARGET_FORMS[form]
    if len(values) != count:
        raise InputError(f"a {form} target has {count} values, got {len(values)}")
    x = np.array(values, dtype=np.float64)
    if not np.isfinite(x).all():
        raise NonFiniteError(f"target values must be finite, got {list(values)}")
    if not (math.isfinite(scale) and scale > 0.0):
        raise InputError(f"scale must be a finite number > 0, got {scale!r}")
    if form == "matrix":
        m = x.reshape(4, 4)
        position = m[:3, 3]
    else:
        position = x[4:] if form == "angeles7" else x[:3]
    if max(abs(float(p)) * scale for p in position) > MAX_TARGET_COORDINATE:
        raise InputError(
            f"target position {position.tolist()} too far: each coordinate at most "
            f"{MAX_TARGET_COORDINATE:g} m"
        )
    if scale != 1.0:
        position *= scale  # a view into x (or m): the pose's position in metres
    if form == "angeles7":
        return se3_from_angeles7(x, tol=ANGELES7_PRINTED_TOL)
    if form == "matrix":
        return as_se3(m)
    return pin.SE3(rotation_from_quat_wxyz(x[3:], tol=QUAT_TYPED_TOL), x[:3])


__all__ = ["MAX_TARGET_COORDINATE", "QUAT_TYPED_TOL", "TARGET_FORMS", "parse_target"]
