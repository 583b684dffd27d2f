"""Rigid transforms and rotations: checks and conversions from matrices.

A rotation ``R`` (3, 3) maps child-frame to parent-frame coordinates, as in
``pin.SE3``; positions are in metres.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import DimensionError, InputError, NonFiniteError
from workbench.validation import as_finite_array, as_vector

FloatArray = npt.NDArray[np.float64]

RIGIDITY_TOL = 1e-6
"""Tolerance on ``max |R^T R - I|`` and on the bottom row [0, 0, 0, 1].

Computed transforms meet it by ~1e-15; typed matrices need 7 decimals.
"""

UNIT_NORM_TOL = 1e-9
"""Tolerance on ``| |x| - 1 |`` for quaternions and rotation axes."""


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


def compute_rigidity_errors(poses: FloatArray) -> tuple[FloatArray, FloatArray]:
    """How far N finite homogeneous matrices are from rigid, vectorised.

    The quantities :func:`check_rigid_rows` tests, for many poses at once.

    Args:
        poses: Shape (N, 4, 4), finite (not checked).

    Returns:
        ``(error, det)``, each (N,): ``max |R^T R - I|`` together with the
        bottom row's distance from ``[0, 0, 0, 1]`` (a pose is rigid when
        ``error <= RIGIDITY_TOL`` and ``det > 0``), and ``det R``.
    """
    tt = poses.reshape(len(poses), 16).T  # row 4 i + j: entry (i, j) of each pose
    c0, c1, c2 = tt[0:12:4], tt[1:12:4], tt[2:12:4]  # columns of R, (3, n)
    error = np.abs(tt[15] - 1.0)
    for k in (12, 13, 14):
        np.maximum(error, np.abs(tt[k]), out=error)
    for u, v, unit in (
        (c0, c0, 1.0), (c1, c1, 1.0), (c2, c2, 1.0), (c0, c1, 0.0), (c0, c2, 0.0),
        (c1, c2, 0.0),
    ):  # fmt: skip
        np.maximum(
            error, np.abs(u[0] * v[0] + u[1] * v[1] + u[2] * v[2] - unit), out=error
        )
    det = (
        c2[0] * (c0[1] * c1[2] - c0[2] * c1[1])
        + c2[1] * (c0[2] * c1[0] - c0[0] * c1[2])
        + c2[2] * (c0[0] * c1[1] - c0[1] * c1[0])
    )
    return error, det
