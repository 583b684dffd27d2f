"""Vectorised closed-form IK: all eight branches of N poses at once (numpy).

Same formulas, branch order and wrapping as :func:`workbench.ik.analytic`
(without ``q_previous``), written over arrays of shape (arm, elbow, pose).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from workbench.ik._puma import (
    WRIST_SINGULAR_TOL,
    PumaGeometry,
    get_geometry,
    wrap_array_to_limits,
)
from workbench.ik._targets import as_targets, check_chunk
from workbench.robot import Robot

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

#: Poses per chunk: the temporaries of one chunk stay in the CPU cache.
_CHUNK = 2048


def analytic_batch(
    robot: Robot, targets: npt.ArrayLike
) -> tuple[FloatArray, BoolArray]:
    """Every closed-form IK branch of N poses, vectorised.

    Args:
        robot: Robot with a PUMA-type DH table (``puma560``, ``puma560-kang``).
        targets: Shape (N, 4, 4), homogeneous poses of the tool frame in the
            base frame [m].

    Returns:
        ``q`` of shape (N, 8, 6) [rad], branch axis in the order of
        ``closed_form.BRANCHES``, wrapped as by :func:`~workbench.ik.analytic`
        (θ4 = 0 at a wrist singularity); and ``valid`` of shape (N, 8), True
        where the pose is reachable (then every branch reaches it). Rows of
        unreachable poses are NaN. Joint limits are not applied: test
        ``(robot.lower <= q) & (q <= robot.upper)`` for that.

    Raises:
        UnsupportedRobotError: If the robot has no PUMA-type DH table.
        DimensionError: If ``targets`` is not (N, 4, 4).
        NonFiniteError: If an entry is NaN or infinite.
        InputError: If a pose is not rigid (``poses.RIGIDITY_TOL``).
    """
    geo = get_geometry(robot)
    t = as_targets(targets)
    count = t.shape[0]
    q = np.empty((count, 8, 6))
    valid = np.empty((count, 8), dtype=bool)
    for start in range(0, count, _CHUNK):
        stop = min(start + _CHUNK, count)
        tt = np.ascontiguousarray(t[start:stop].reshape(stop - start, 16).T)
        check_chunk(tt, start)
        valid[start:stop] = _solve_chunk(geo, tt, q[start:stop])[:, None]
    return q, valid


def _solve_chunk(geo: PumaGeometry, tt: FloatArray, q: FloatArray) -> BoolArray:
    """Solve a chunk given as (16, n), row 4 i + j = entry (i, j) of each pose.

    Writes ``q`` (n, 8, 6) and returns the reachable mask (n,). Arrays are laid
    out (arm, elbow, pose) so that every loop is contiguous.
    """
    n = tt.shape[1]
    nx, ox, ax, px, ny, oy, ay, py, nz, oz, az, pz = tt[:12]
    if geo.sin_alpha6 != 0.0:
        ca, sa = geo.cos_alpha6, geo.sin_alpha6
        ox, ax = ca * ox - sa * ax, sa * ox + ca * ax
        oy, ay = ca * oy - sa * ay, sa * oy + ca * ay
        oz, az = ca * oz - sa * az, sa * oz + ca * az
    if geo.d6 != 0.0:
        px, py, pz = px - geo.d6 * ax, py - geo.d6 * ay, pz - geo.d6 * az
    pz = pz - geo.d1
    s1g, s3g, a2, ell = geo.sigma1, geo.sigma3, geo.a2, geo.forearm
    d2 = geo.offset * geo.offset
    sd = s1g * geo.offset
    r2 = px * px + py * py
    dist2 = r2 + pz * pz
    low, high = geo.reach
    ok = (dist2 >= low * low - 1e-12 * high * high) & (
        dist2 <= high * high * (1 + 1e-12)
    )
    ok &= r2 >= d2 * (1.0 - 1e-12)
    rho2 = np.maximum(r2 - d2, 0.0)
    rho = np.sqrt(rho2)
    k = (rho2 + pz * pz - (a2 * a2 + ell * ell)) * (0.5 / (a2 * ell))
    np.clip(k, -1.0, 1.0, out=k)
    sgm = np.sqrt(1.0 - k * k)
    right = 1.0 if sd >= 0.0 else -1.0

    # theta1: row 0 right arm (x1 = right rho), row 1 left arm
    on_axis = r2 == 0.0
    inv_r2 = 1.0 / np.where(on_axis, 1.0, r2)
    u, w = (right * inv_r2) * rho * px, (right * inv_r2) * rho * py
    v, z = (sd * inv_r2) * py, (sd * inv_r2) * px
    c1, s1 = np.empty((2, n)), np.empty((2, n))
    np.subtract(u, v, out=c1[0])
    np.add(u, v, out=c1[1])
    np.negative(c1[1], out=c1[1])
    np.add(w, z, out=s1[0])
    np.subtract(z, w, out=s1[1])
    if on_axis.any():  # D = 0 and the wrist centre on the base axis: theta1 free
        c1[:, on_axis] = np.cos(geo.theta_offset[0])
        s1[:, on_axis] = np.sin(geo.theta_offset[0])
    t1 = np.arctan2(s1, c1)

    # rows of A = Rx(alpha1)^T Rz(-theta1) R', shape (arm, 1, n) or (n,), with
    # the signs that M = R36 Rx(alpha6)^T needs folded in: g = sigma4 sigma5
    g = geo.sigma4 * geo.sigma5
    s13 = s3g * s1g
    a00 = (g * (c1 * nx + s1 * ny))[:, None]
    a01 = (g * (c1 * ox + s1 * oy))[:, None]
    a02 = (c1 * ax + s1 * ay)[:, None]
    a02m = (-g * s3g) * a02
    a10, a11 = (g * s1g) * nz, (g * s1g) * oz
    a12, a12m = s1g * az, (-g * s3g * s1g) * az
    m10 = ((g * s13) * (s1 * nx - c1 * ny))[:, None]
    m11 = ((g * s13) * (s1 * ox - c1 * oy))[:, None]
    m12 = np.empty((2, 2, n))
    np.multiply(s13, s1 * ax - c1 * ay, out=m12[:, 0])
    m12[:, 1] = m12[:, 0]

    # elbow, (arm, elbow, n): sin(gamma) = +base on (right, up), (left, down)
    base = (geo.up_sign * right) * sgm
    cb, sb = geo.cos_beta, geo.sin_beta
    c3, s3 = np.empty((2, 2, n)), np.empty((2, 2, n))
    c3[0, 0] = k * cb + base * sb
    c3[0, 1] = k * cb - base * sb
    s3[0, 0] = base * cb - k * sb
    s3[0, 1] = -base * cb - k * sb
    c3[1, 0], c3[1, 1], s3[1, 0], s3[1, 1] = c3[0, 1], c3[0, 0], s3[0, 1], s3[0, 0]
    t3 = np.arctan2(s3[0], c3[0])  # (+base, -base)
    big_a = a2 + ell * k
    w2 = rho2 + pz * pz  # |c2 + i s2| below, before scaling
    inv_w2 = 1.0 / np.where(w2 == 0.0, 1.0, w2)
    xa = (right * rho) * big_a  # x1 A, right arm
    yb = (s1g * ell) * pz * base  # y1 B, (right, up)
    ya = s1g * pz * big_a
    xb = (right * ell) * rho * base  # x1 B, (right, up)
    c2, s2 = np.empty((2, 2, n)), np.empty((2, 2, n))
    np.add(xa, yb, out=c2[0, 0])
    np.subtract(xa, yb, out=c2[0, 1])
    np.negative(c2[0], out=c2[1])
    np.subtract(ya, xb, out=s2[0, 0])
    np.add(ya, xb, out=s2[0, 1])
    s2[1] = s2[0]
    t2 = np.arctan2(s2, c2)
    c2 *= inv_w2
    s2 *= inv_w2
    if (w2 == 0.0).any():  # wrist centre on the shoulder axis: theta2 free
        c2[:, :, w2 == 0.0] = 1.0
    c23 = c2 * c3 - s2 * s3
    s23 = s2 * c3 + c2 * s3

    # wrist, from M = R36 Rx(alpha6)^T; t4 and t6 are scale-free, so the
    # no-flip (c4, s4) = (m02, m12) / h enter unnormalised
    m02 = c23 * a02 + s23 * a12
    m00 = c23 * a00 + s23 * a10  # times g
    m01 = c23 * a01 + s23 * a11  # times g
    m22 = s23 * a02m - c23 * a12m  # times -g
    t4 = np.arctan2(m12, m02)
    t6 = np.arctan2(m12 * m00 - m02 * m10, m12 * m01 - m02 * m11)
    h = np.sqrt(m02 * m02 + m12 * m12)
    if h.min() <= WRIST_SINGULAR_TOL:
        sing = h <= WRIST_SINGULAR_TOL
        t4[sing] = geo.theta_offset[3]
        c4, s4 = np.cos(geo.theta_offset[3]), np.sin(geo.theta_offset[3])
        t6[sing] = np.arctan2(s4 * m00 - c4 * m10, s4 * m01 - c4 * m11)[sing]
        h[sing] = (c4 * m02 + s4 * m12)[sing]
    if geo.sigma5 < 0.0:
        np.negative(h, out=h)
    t5 = np.arctan2(h, m22)

    # joint values as (joint, arm, elbow, flip, n), wrapped, then transposed
    res = np.empty((6, 2, 2, 2, n))
    t1, t2, t3 = (_wrap(geo, j, t) for j, t in ((0, t1), (1, t2), (2, t3)))
    res[0] = t1[:, None, None]
    res[1] = t2[:, :, None]
    res[2, 0, 0] = res[2, 1, 1] = t3[0]
    res[2, 0, 1] = res[2, 1, 0] = t3[1]
    res[3, :, :, 0] = _wrap(geo, 3, t4)
    res[3, :, :, 1] = _wrap(geo, 3, np.where(t4 > 0.0, t4 - np.pi, t4 + np.pi))
    res[4, :, :, 0] = _wrap(geo, 4, t5)
    res[4, :, :, 1] = _wrap(geo, 4, -t5)
    res[5, :, :, 0] = _wrap(geo, 5, t6)
    res[5, :, :, 1] = _wrap(geo, 5, np.where(t6 > 0.0, t6 - np.pi, t6 + np.pi))
    q[...] = res.reshape(6, 8, n).transpose(2, 1, 0)
    if not ok.all():
        q[~ok] = np.nan
    return ok


def _wrap(geo: PumaGeometry, j: int, theta: FloatArray) -> FloatArray:
    """Joint values of DH angles ``theta`` in [-pi, pi] of joint ``j``."""
    if geo.plain[j]:
        return theta
    offset = geo.theta_offset[j]
    return wrap_array_to_limits(
        theta - offset, geo.lower[j], geo.upper[j], reduced=offset == 0.0
    )
