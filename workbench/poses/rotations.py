r"""Rotations as axis–angle and as quaternions (``quat_wxyz``, ``quat_xyzw``).

Exact near phi = 0 and phi = pi: the axis is read from the skew part of R where
that is large, from :math:`R + R^T` near pi.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import cast

import numpy as np
import numpy.typing as npt

from workbench.poses.rigid import RIGIDITY_TOL, UNIT_NORM_TOL, _as_unit, as_rotation
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]


def _skew(v: FloatArray) -> FloatArray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _rotation_from_unit_quat(w: float, u: FloatArray) -> FloatArray:
    return (w * w - u @ u) * np.eye(3) + 2.0 * np.outer(u, u) + 2.0 * w * _skew(u)


def _direction(x: Sequence[float]) -> FloatArray:
    """Unit vector along a nonzero ``x``, exact even for subnormal entries.

    Plain floats (a few µs, where numpy calls on 3-vectors cost tens).
    """
    largest = max(map(abs, x))
    y = [float(v) / largest for v in x]
    norm = math.hypot(*y)
    return np.array([v / norm for v in y])


def _axis_sin_cos(rotation: FloatArray) -> tuple[FloatArray, float, float]:
    """Unit axis e, sin(phi) >= 0 and cos(phi) of a rotation, phi in [0, pi].

    Plain floats (a few µs, where numpy calls on 3-vectors cost tens).
    """
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = rows = rotation.tolist()
    w = (0.5 * (r21 - r12), 0.5 * (r02 - r20), 0.5 * (r10 - r01))  # vect(R)
    norm_w = math.hypot(*w)  # scaled internally: |w|^2 would underflow
    c = (r00 + r11 + r22 - 1.0) / 2.0
    h = math.hypot(norm_w, c)
    s, c = norm_w / h, c / h
    if c >= 0.0:  # phi <= pi/2: the skew part fixes the axis well
        return (_direction(w) if norm_w > 0.0 else np.array([1.0, 0.0, 0.0])), s, c
    # sym = (R + R^T) / 2 - c I = (1 - c) e e^T: its column of largest diagonal
    k = max(range(3), key=lambda j: rows[j][j])
    col = [0.5 * (rows[i][k] + rows[k][i]) - (c if i == k else 0.0) for i in range(3)]
    norm = math.hypot(*col)
    e = [x / norm for x in col]  # largest component of e positive
    if e[0] * w[0] + e[1] * w[1] + e[2] * w[2] < 0.0:
        e = [-x for x in e]
    return np.array(e), s, c


def axis_angle_from_rotation(
    rotation: npt.ArrayLike, *, tol: float = RIGIDITY_TOL, check: bool = True
) -> tuple[FloatArray, float]:
    """Unit axis and angle of a rotation, robust at 0 and at pi.

    Args:
        rotation: Shape (3, 3), orthonormal with det +1.
        tol: Orthonormality tolerance.
        check: Validate ``rotation``; False skips that for a float (3, 3)
            array known to be a rotation (e.g. computed from rotations).

    Returns:
        Axis e, shape (3,), unit, in the parent frame (= child frame), and angle
        phi [rad] in [0, pi]. At phi = 0 the axis is [1, 0, 0]; at phi = pi its
        largest component is positive.

    Raises:
        InputError: As :func:`angeles4_from_rotation`.
    """
    matrix = as_rotation(rotation, tol=tol) if check else cast(FloatArray, rotation)
    e, s, c = _axis_sin_cos(matrix)
    return e, math.atan2(s, c)


def rotation_from_axis_angle(
    axis: npt.ArrayLike, angle: float, *, tol: float = UNIT_NORM_TOL
) -> FloatArray:
    """Rotation by ``angle`` [rad] about a unit ``axis`` (Rodrigues).

    Args:
        axis: Shape (3,), unit norm within ``tol`` (then normalised).
        angle: Angle [rad], any finite value, right-hand sense about ``axis``.
        tol: Tolerance on ``| |axis| - 1 |``.

    Returns:
        Shape (3, 3) rotation.

    Raises:
        InputError: ``DimensionError`` if ``axis`` is not (3,) or ``angle`` not a
            scalar, ``NonFiniteError`` on NaN/inf, else ``axis`` not unit.
    """
    k = _skew(_as_unit(axis, 3, "axis", tol))
    phi = float(as_finite_array(angle, (), "angle"))
    return np.eye(3) + np.sin(phi) * k + 2.0 * np.sin(phi / 2.0) ** 2 * (k @ k)


def quat_wxyz_from_rotation(
    rotation: npt.ArrayLike, *, tol: float = RIGIDITY_TOL
) -> FloatArray:
    """Unit quaternion ``[w, x, y, z]`` (scalar first), shape (4,), of a rotation.

    ``rotation`` is (3, 3); ``tol`` and errors as :func:`angeles4_from_rotation`.
    Canonical ``w = cos(phi/2) >= 0``, vector part ``sin(phi/2) e`` with e from
    :func:`axis_angle_from_rotation`, so it is exact near phi = pi too.
    """
    e, phi = axis_angle_from_rotation(rotation, tol=tol)
    return np.append(np.cos(phi / 2.0), np.sin(phi / 2.0) * e)


def rotation_from_quat_wxyz(
    quat_wxyz: npt.ArrayLike, *, tol: float = UNIT_NORM_TOL
) -> FloatArray:
    """Rotation of a unit quaternion ``[w, x, y, z]`` (scalar first).

    Args:
        quat_wxyz: Shape (4,), unit norm within ``tol`` (then normalised).
        tol: Tolerance on ``| |q| - 1 |``.

    Returns:
        Shape (3, 3) rotation; ``q`` and ``-q`` give the same one.

    Raises:
        InputError: ``DimensionError`` if not (4,), ``NonFiniteError`` on
            NaN/inf, else if ``| |q| - 1 | > tol``.
    """
    q = _as_unit(quat_wxyz, 4, "quat_wxyz", tol)
    return _rotation_from_unit_quat(q[0], q[1:])


def quat_xyzw_from_rotation(
    rotation: npt.ArrayLike, *, tol: float = RIGIDITY_TOL
) -> FloatArray:
    """Unit quaternion ``[x, y, z, w]`` (Pinocchio's order) of a (3, 3) rotation.

    Same as :func:`quat_wxyz_from_rotation` (canonical ``w >= 0``, same
    ``tol`` and errors), reordered.
    """
    return np.roll(quat_wxyz_from_rotation(rotation, tol=tol), -1)


def rotation_from_quat_xyzw(
    quat_xyzw: npt.ArrayLike, *, tol: float = UNIT_NORM_TOL
) -> FloatArray:
    """Rotation (3, 3) of a unit quaternion ``[x, y, z, w]`` (Pinocchio's order).

    Same as :func:`rotation_from_quat_wxyz` (same ``tol`` and errors), with the
    scalar last; error messages name ``quat_xyzw``.
    """
    q = _as_unit(quat_xyzw, 4, "quat_xyzw", tol)
    return _rotation_from_unit_quat(q[3], q[:3])
