r"""Pose representations and exact conversions between them.

A rotation ``R`` (3, 3) maps child-frame to parent-frame coordinates, as in
``pin.SE3``; positions are in metres. The 7-number pose of Angeles et al. (1988)
is ``angeles7 = [e sin(phi), cos(phi), p]``, phi in [0, pi], with
:math:`\mathrm{vect}(Q) = e\sin\phi = \tfrac12[R_{32}-R_{23}, R_{13}-R_{31},
R_{21}-R_{12}]`, :math:`\mathrm{tr}(Q) = 1 + 2\cos\phi`; its first four
numbers are ``angeles4``. Near phi = pi the skew part of R is tiny and its
direction is lost to rounding, so the axis is read from :math:`R + R^T`. At
phi = pi exactly the seven numbers do not fix the axis: converting them back
raises :class:`~workbench.errors.InputError`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import cast

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import DimensionError, InputError, NonFiniteError
from workbench.validation import as_finite_array, as_vector

FloatArray = npt.NDArray[np.float64]

ANGELES7_TOL = 1e-9
"""Default tolerance on ``| |v|^2 + c^2 - 1 |`` for exact (computed) data."""

ANGELES7_PRINTED_TOL = 0.05
r"""Tolerance on ``| |v|^2 + c^2 - 1 |`` for numbers printed to 2 decimals.

Rounding each of the four unit-vector components :math:`x_i` by
:math:`|\delta_i| \le 0.005` changes the squared norm by
:math:`\sum_i (2 x_i \delta_i + \delta_i^2) \le 0.01 \sum_i |x_i| + 10^{-4}
\le 0.0201` (:math:`\sum_i |x_i| \le 2` on the unit 4-sphere); 0.05 adds margin
yet rejects a dropped digit. Angeles' Table II pick has norm² 1.009.
"""

RIGIDITY_TOL = 1e-6
"""Tolerance on ``max |R^T R - I|`` and on the bottom row [0, 0, 0, 1].

Computed transforms meet it by ~1e-15; typed matrices need 7 decimals.
"""

UNIT_NORM_TOL = 1e-9
"""Tolerance on ``| |x| - 1 |`` for quaternions and rotation axes."""


def _skew(v: FloatArray) -> FloatArray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def as_rotation(
    rotation: npt.ArrayLike, name: str = "rotation", *, tol: float = RIGIDITY_TOL
) -> FloatArray:
    """``rotation`` as a (3, 3) float array, checked to be a rotation.

    Raises:
        DimensionError: If it is not (3, 3).
        NonFiniteError: If an entry is NaN or infinite.
        InputError: If it is not orthonormal within ``tol`` or det is not +1.
    """
    r = as_finite_array(rotation, (3, 3), name)
    check_rigid_rows(r.tolist(), [], tol, name)
    return r


def _as_unit(value: npt.ArrayLike, size: int, name: str, tol: float) -> FloatArray:
    """Check a vector has unit norm within ``tol``; return it normalised."""
    x = as_vector(value, size, name)
    norm = math.hypot(*x)
    if abs(norm - 1.0) > tol:
        raise InputError(f"{name} must have unit norm, got |{name}| = {norm:.6g}")
    return x / norm


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


def as_se3(target: pin.SE3 | npt.ArrayLike, *, tol: float = RIGIDITY_TOL) -> pin.SE3:
    """Validate a rigid transform given as ``pin.SE3`` or a homogeneous matrix.

    Args:
        target: ``pin.SE3`` or a (4, 4) homogeneous matrix ``[[R, p], [0, 1]]``,
            child frame in parent frame, p in metres.
        tol: Tolerance on ``max |R^T R - I|`` and on the bottom row.

    Returns:
        A new ``pin.SE3`` (a copy; R is kept as given, not re-orthonormalised).

    Raises:
        DimensionError: If a matrix is not (4, 4).
        NonFiniteError: If an entry is NaN or infinite.
        InputError: If the bottom row is not [0, 0, 0, 1], R is not orthonormal
            within ``tol``, or det R is not +1.
    """
    if isinstance(target, pin.SE3):
        rows = target.rotation.tolist()
        check_rigid_rows(rows, target.translation.tolist(), tol, "rotation of the SE3")
        return pin.SE3(target)
    return se3_from_matrix(target, tol=tol)


def se3_from_matrix(matrix: npt.ArrayLike, *, tol: float = RIGIDITY_TOL) -> pin.SE3:
    """Build a ``pin.SE3`` from a (4, 4) homogeneous matrix, checking rigidity.

    Same checks, tolerance and errors as :func:`as_se3`, for matrices only.
    """
    try:
        m = np.asarray(matrix, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise NonFiniteError(
            f"homogeneous matrix must be numbers, got {matrix!r}"
        ) from err
    if m.shape != (4, 4):
        raise DimensionError("homogeneous matrix", (4, 4), m.shape)
    rows = m.tolist()
    if not all(math.isfinite(x) for x in rows[3]):
        raise NonFiniteError(f"homogeneous matrix must be finite, got {rows[3]}")
    if (
        max(abs(x - y) for x, y in zip(rows[3], (0.0, 0.0, 0.0, 1.0), strict=True))
        > tol
    ):
        raise InputError(
            f"homogeneous matrix must have bottom row [0, 0, 0, 1], got {rows[3]}"
        )
    rotation = [row[:3] for row in rows[:3]]
    translation = [row[3] for row in rows[:3]]
    check_rigid_rows(
        rotation, translation, tol, "rotation part of the homogeneous matrix"
    )
    return pin.SE3(np.array(rotation), np.array(translation))


def check_rigid_rows(
    rotation: list[list[float]], translation: list[float], tol: float, name: str
) -> None:
    """Check a pose given as plain floats (fast: no numpy).

    Args:
        rotation: Rows of R, 3 lists of 3 floats.
        translation: p as floats [m] (may be empty: rotation only).
        tol: Tolerance on ``max |R^T R - I|``.
        name: What the pose is, for the messages.

    Raises:
        NonFiniteError: If an entry is NaN or infinite.
        InputError: If R is not orthonormal within ``tol`` or det R <= 0.
    """
    (a, b, c), (d, e, f), (g, h, i) = rotation
    if not all(math.isfinite(x) for x in (a, b, c, d, e, f, g, h, i, *translation)):
        raise NonFiniteError(
            f"{name}: pose must be finite, got R={rotation}, p={translation}"
        )
    err = max(  # entries of R^T R - I
        abs(a * a + d * d + g * g - 1.0),
        abs(b * b + e * e + h * h - 1.0),
        abs(c * c + f * f + i * i - 1.0),
        abs(a * b + d * e + g * h),
        abs(a * c + d * f + g * i),
        abs(b * c + e * f + h * i),
    )
    if err > tol:
        raise InputError(
            f"{name} is not orthonormal: max |R^T R - I| = {err:.3g} > tol = {tol:g}"
        )
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    if det <= 0.0:
        raise InputError(
            f"{name} has det = {det:.6g} (a reflection); a rotation needs det = +1"
        )


def angeles4_from_rotation(
    rotation: npt.ArrayLike, *, tol: float = RIGIDITY_TOL
) -> FloatArray:
    """Orientation part of Angeles' pose, ``[e sin(phi), cos(phi)]``.

    Args:
        rotation: Shape (3, 3), orthonormal with det +1.
        tol: Orthonormality tolerance.

    Returns:
        Shape (4,), unit norm. ``e`` comes from the whole rotation, so ``v``
        keeps its direction even for phi within 1e-12 of pi.

    Raises:
        InputError: ``DimensionError`` if not (3, 3), ``NonFiniteError`` on
            NaN/inf, else not orthonormal within ``tol`` or det not +1.
    """
    e, s, c = _axis_sin_cos(as_rotation(rotation, tol=tol))
    return np.append(s * e, c)


def angeles7_from_se3(
    transform: pin.SE3 | npt.ArrayLike, *, tol: float = RIGIDITY_TOL
) -> FloatArray:
    """Seven-number pose of Angeles et al. (1988) from a rigid transform.

    Args:
        transform: ``pin.SE3`` or (4, 4) homogeneous matrix, child in parent.
        tol: Rigidity tolerance, see :func:`as_se3`.

    Returns:
        Shape (7,), ``[e sin(phi), cos(phi), p]``, phi in [0, pi], p [m]; e is
        in the parent frame, as in :func:`angeles4_from_rotation`.

    Raises:
        InputError: As :func:`as_se3` (and its subclasses).
    """
    t = as_se3(transform, tol=tol)
    return np.concatenate([angeles4_from_rotation(t.rotation, tol=tol), t.translation])


def rotation_from_angeles4(
    angeles4: npt.ArrayLike, *, tol: float = ANGELES7_TOL
) -> FloatArray:
    r"""Rotation from ``[v, c] = [e sin(phi), cos(phi)]``.

    ``(v, c)`` is first normalised onto the unit 4-sphere, then
    :math:`R = cI + [v]_\times + v v^T / (1 + c)`, written as
    :math:`(1 - c)\,\hat v \hat v^T` when c < 0 so it stays exact near pi.

    Args:
        angeles4: Shape (4,).
        tol: Largest accepted ``| |v|^2 + c^2 - 1 |``: :data:`ANGELES7_TOL` for
            computed data, :data:`ANGELES7_PRINTED_TOL` for 2-decimal prints.

    Returns:
        Shape (3, 3), orthonormal with det +1 to rounding.

    Raises:
        InputError: ``DimensionError`` if not (4,), ``NonFiniteError`` on NaN/inf,
            else if the norm is off by more than ``tol`` or v = 0 with c < 0
            (phi = pi: the axis is not determined).
    """
    x = as_vector(angeles4, 4, "angeles4")
    norm2 = float(x @ x)
    if abs(norm2 - 1.0) > tol:
        raise InputError(
            f"orientation [e sin(phi), cos(phi)] must have unit norm: "
            f"|v|^2 + c^2 = {norm2:.6g}, off by {norm2 - 1.0:+.3g} > tol = {tol:g} "
            "(numbers printed to 2 decimals: pass tol=ANGELES7_PRINTED_TOL)"
        )
    x = x / np.sqrt(norm2)
    v, c = x[:3], float(x[3])
    s = math.hypot(*v)
    if c >= 0.0:
        outer = np.outer(v, v) / (1.0 + c)
    elif s > 0.0:
        u = _direction(v)
        outer = (1.0 - c) * np.outer(u, u)
    else:
        raise InputError(
            "angeles7 with e sin(phi) = 0 and cos(phi) = -1 is a half turn "
            "(phi = pi) whose axis the 7 numbers do not fix; pass a rotation "
            "matrix or a quaternion instead"
        )
    return c * np.eye(3) + _skew(v) + outer


def se3_from_angeles7(angeles7: npt.ArrayLike, *, tol: float = ANGELES7_TOL) -> pin.SE3:
    """Rigid transform from the seven-number pose of Angeles et al. (1988).

    Args:
        angeles7: Shape (7,), ``[e sin(phi), cos(phi), p]``, p in metres.
        tol: Norm tolerance, see :func:`rotation_from_angeles4`.

    Returns:
        ``pin.SE3`` with an exact rotation (projected onto the unit sphere).

    Raises:
        InputError: As :func:`rotation_from_angeles4`; ``DimensionError`` if
            not (7,).
    """
    x = as_vector(angeles7, 7, "angeles7")
    return pin.SE3(rotation_from_angeles4(x[:4], tol=tol), x[4:].copy())


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
