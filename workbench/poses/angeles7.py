r"""The 7-number pose of Angeles et al. (1988) and its conversions.

The pose is ``angeles7 = [e sin(phi), cos(phi), p]``, phi in [0, pi], with
:math:`\mathrm{vect}(Q) = e\sin\phi = \tfrac12[R_{32}-R_{23}, R_{13}-R_{31},
R_{21}-R_{12}]`, :math:`\mathrm{tr}(Q) = 1 + 2\cos\phi`; its first four
numbers are ``angeles4``. Near phi = pi the skew part of R is tiny and its
direction is lost to rounding, so the axis is read from :math:`R + R^T`. At
phi = pi exactly the seven numbers do not fix the axis: converting them back
raises :class:`~workbench.errors.InputError`.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.poses.rigid import RIGIDITY_TOL, as_rotation, as_se3
from workbench.poses.rotations import _axis_sin_cos, _direction, _skew
from workbench.validation import as_vector

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
