"""Vectorised closed-form IK: all eight branches of N poses at once (numpy).

Same formulas, branch order and wrapping as :func:`workbench.ik.analytic`
(without ``q_previous``). A chunk of poses is solved with the pose as the
last, contiguous axis, the four (arm, elbow) pairs as (arm, elbow, pose), and
the joint values are written straight into the result, stored (arm, elbow,
flip, joint, pose): ``q`` is the (N, 8, 6) view of that array, so no
transposing copy is made (``np.ascontiguousarray(q)`` gives the pose-major
layout if a consumer needs it).

Written for throughput: few numpy calls per chunk (what can be stacked is:
the rows of A, the entries of M, the two arguments of θ6), preallocated
buffers for the large arrays, the ±1 signs of the DH table applied through
the order of subtractions, and the symmetries of the branches used instead of
recomputing (θ2 of the left arm from the right arm's, θ4, θ6 flipped by ±π).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from workbench.ik._puma import (
    WRIST_SINGULAR_TOL,
    PumaGeometry,
    _wrap_plan,
    get_geometry,
    wrap_array_to_limits,
)
from workbench.ik._targets import as_targets, check_chunk
from workbench.robot import Robot

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

#: Poses per chunk: the ~110 numpy calls of a chunk are spread over enough
#: poses that their overhead is small, the arrays of a chunk stay in the CPU
#: caches (measured best between 3072 and 8192 on a 2 MB L2).
_CHUNK = 4096

#: Rows of the elbow arrays (sign of sin γ) per (arm, elbow): the left arm's
#: elbow-up has the right arm's elbow-down sign and vice versa.
_ELBOW_ROWS = np.array([[0, 1], [1, 0]])


class _Buffers:
    """Arrays written once per chunk, allocated once per call."""

    def __init__(self, n: int) -> None:
        self.m = np.empty((2, 3, 2, n))  # m00, m01, m02 per (arm, ., elbow)
        self.m_tmp = np.empty((2, 3, 2, n))
        self.yx = np.empty((2, 2, 2, n))  # arguments of theta6
        self.yx_tmp = np.empty((2, 2, 2, n))


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
        ``(robot.lower <= q) & (q <= robot.upper)`` for that. ``q`` is a view
        with the pose axis fastest in memory (not C-contiguous).

    Raises:
        UnsupportedRobotError: If the robot has no PUMA-type DH table.
        DimensionError: If ``targets`` is not (N, 4, 4).
        NonFiniteError: If an entry is NaN or infinite.
        InputError: If a pose is not rigid (``poses.RIGIDITY_TOL``).
    """
    geo = get_geometry(robot)
    t = as_targets(targets)
    count = t.shape[0]
    out = np.empty((2, 2, 2, 6, count))  # (arm, elbow, flip, joint, pose)
    reachable = np.empty(count, dtype=bool)
    buffers = _Buffers(min(count, _CHUNK))
    for start in range(0, count, _CHUNK):
        stop = min(start + _CHUNK, count)
        n = stop - start
        tt = np.ascontiguousarray(t[start:stop].reshape(n, 16).T)
        check_chunk(tt, start)
        res = out[..., start:stop]
        ok = _solve_chunk(geo, tt, buffers, res)
        if not ok.all():
            res[..., ~ok] = np.nan
        reachable[start:stop] = ok
    # the 8 flags of a pose are 8 bytes: written as one uint64 each
    valid = np.empty((count, 8), dtype=bool)
    np.multiply(
        reachable.view(np.uint8),
        np.uint64(0x0101010101010101),
        out=valid.view(np.uint64).reshape(count),
    )
    return out.reshape(48, count).T.reshape(count, 8, 6), valid


def _solve_chunk(
    geo: PumaGeometry, tt: FloatArray, buffers: _Buffers, res: FloatArray
) -> BoolArray:
    """Solve a chunk given as (16, n), row 4 i + j = entry (i, j) of each pose.

    Writes ``res`` (arm, elbow, flip, joint, n) and returns the reachable mask
    (n,); the values of unreachable poses are meaningless.
    """
    n = tt.shape[1]
    # rows (x, y, z) of the columns n, o, a of R, each (3, n), and p
    r0, r1, r2_ = tt[0:3], tt[4:7], tt[8:11]
    p = tt[3:12:4]
    if geo.sin_alpha6 != 0.0:  # R' = R Rx(-alpha6): its z column is z5
        ca, sa = geo.cos_alpha6, geo.sin_alpha6
        r0, r1, r2_ = r0.copy(), r1.copy(), r2_.copy()
        for row, src in ((r0, tt[0:3]), (r1, tt[4:7]), (r2_, tt[8:11])):
            row[1] = ca * src[1] - sa * src[2]
            row[2] = sa * src[1] + ca * src[2]
    if geo.d6 != 0.0:  # wrist centre
        p = p - geo.d6 * np.stack((r0[2], r1[2], r2_[2]))
    px, py = p[0], p[1]
    pz = p[2] - geo.d1
    s1g, s3g, a2, ell = geo.sigma1, geo.sigma3, geo.a2, geo.forearm
    g = geo.sigma4 * geo.sigma5
    d2 = geo.offset * geo.offset
    sd = s1g * geo.offset
    right = 1.0 if sd >= 0.0 else -1.0  # sign of x1 on the right arm

    r2 = px * px
    r2 += py * py
    pz2 = pz * pz
    dist2 = r2 + pz2  # squared distance of the wrist centre from the shoulder
    low, high = geo.reach
    ok = dist2 >= low * low - 1e-12 * high * high
    ok &= dist2 <= high * high * (1 + 1e-12)
    ok &= r2 >= d2 * (1.0 - 1e-12)
    rho2 = r2 - d2
    np.maximum(rho2, 0.0, out=rho2)
    rho = np.sqrt(rho2)
    w2 = rho2 + pz2  # |x1 + i y1|^2, and |c2 + i s2| below (unless k is clipped)
    k = w2 - (a2 * a2 + ell * ell)
    k *= 0.5 / (a2 * ell)
    np.minimum(k, 1.0, out=k)
    np.maximum(k, -1.0, out=k)
    sgm = k * k
    np.subtract(1.0, sgm, out=sgm)
    np.sqrt(sgm, out=sgm)

    # theta1, (arm, n): c1 + i s1 = (px + i py)(x1 + i sd) / r2, x1 = +-rho
    on_axis = None if r2.all() else r2 == 0.0
    inv_r2 = 1.0 / (r2 if on_axis is None else np.where(on_axis, 1.0, r2))
    x1r = rho * inv_r2
    if right < 0.0:
        np.negative(x1r, out=x1r)
    uw = x1r * p[:2]  # x1 (px, py) / r2 of the right arm
    vz = (sd * inv_r2) * p[1::-1]  # sd (py, px) / r2
    diff, total = uw - vz, uw + vz
    c1, s1 = np.empty((2, n)), np.empty((2, n))
    c1[0] = diff[0]
    np.negative(total[0], out=c1[1])
    s1[0] = total[1]
    np.negative(diff[1], out=s1[1])
    if on_axis is not None and on_axis.any():  # D = 0, wrist centre on z0
        c1[:, on_axis] = np.cos(geo.theta_offset[0])
        s1[:, on_axis] = np.sin(geo.theta_offset[0])
    t1 = np.arctan2(s1, c1)

    # rows of A = Rx(alpha1)^T Rz(-theta1) R', (arm, column, n): row 0
    # c1 x + s1 y, row 1 sigma1 z, and sigma1 sigma3 (s1 x - c1 y) (rows 1 of
    # M); the factor g = sigma4 sigma5 of columns n and o is applied to theta6
    c1b, s1b = c1[:, None], s1[:, None]
    a_0 = c1b * r0
    a_0 += s1b * r1
    a_1 = r2_ if s1g > 0.0 else -r2_
    m_1 = s1b * r0
    tmp = c1b * r1
    if s3g * s1g > 0.0:
        m_1 -= tmp
    else:
        np.subtract(tmp, m_1, out=m_1)
    m12 = m_1[:, 2, None]  # (arm, 1, n)

    # elbow, (sign, n): c3 + i s3 = (k + i sin gamma)(cos beta - i sin beta),
    # sin gamma = +base on the right arm elbow-up and the left arm elbow-down
    base = sgm if geo.up_sign * right > 0.0 else -sgm
    cb, sb = geo.cos_beta, geo.sin_beta
    kcb, ksb, bsb, bcb = k * cb, k * sb, base * sb, base * cb
    c3pm, s3pm = np.empty((2, n)), np.empty((2, n))
    np.add(kcb, bsb, out=c3pm[0])
    np.subtract(kcb, bsb, out=c3pm[1])
    np.subtract(bcb, ksb, out=s3pm[0])
    np.add(bcb, ksb, out=s3pm[1])
    np.negative(s3pm[1], out=s3pm[1])
    t3 = np.arctan2(s3pm, c3pm)  # right arm (up, down), left arm (down, up)
    c3, s3 = c3pm[_ELBOW_ROWS], s3pm[_ELBOW_ROWS]  # (arm, elbow, n)

    # theta2, (arm, elbow, n): c2 + i s2 = (x1 + i y1)(A - i B) / w2 with
    # A = a2 + L k, B = L sin gamma; the left arm has x1 and sin gamma negated,
    # so its (c2, s2) is the right arm's (-c2, s2)
    on_shoulder = None if w2.all() else w2 == 0.0
    inv_w2 = 1.0 / (w2 if on_shoulder is None else np.where(on_shoulder, 1.0, w2))
    rho *= inv_w2
    pz *= inv_w2
    big_a = k * ell
    big_a += a2
    xa, ya = rho * big_a, pz * big_a  # x1 A / w2, y1 A / w2 up to signs
    xb, yb = rho * base, pz * base  # x1 B / (L w2), y1 B / (L w2) up to signs
    xb *= right * ell
    yb *= s1g * ell
    if right < 0.0:
        np.negative(xa, out=xa)
    if s1g < 0.0:
        np.negative(ya, out=ya)
    c2, s2 = np.empty((2, 2, n)), np.empty((1, 2, n))
    np.add(xa, yb, out=c2[0, 0])
    np.subtract(xa, yb, out=c2[0, 1])
    np.negative(c2[0], out=c2[1])
    np.subtract(ya, xb, out=s2[0, 0])
    np.add(ya, xb, out=s2[0, 1])
    # atan2(s2, -c2) = copysign(pi, s2) - atan2(s2, c2) for the left arm
    t2 = res[:, :, 0, 1]
    np.arctan2(s2[0], c2[0], out=t2[0])
    np.copysign(np.pi, s2[0], out=t2[1])
    t2[1] -= t2[0]
    if on_shoulder is not None and on_shoulder.any():  # theta2 free: 0
        c2[:, :, on_shoulder] = 1.0
    c23 = c2 * c3
    tmp4 = s2 * s3
    c23 -= tmp4
    s23 = c2 * s3
    np.multiply(s2, c3, out=tmp4)
    s23 += tmp4

    # wrist, from M = R36 Rx(alpha6)^T (without g in rows 0 and 1 of columns
    # n and o): m0j = c23 a0j + s23 a1j, m22 = (-g sigma3)(s23 a02 - c23 a12)
    m = buffers.m[..., :n]
    m_tmp = buffers.m_tmp[..., :n]
    np.multiply(c23[:, None], a_0[:, :, None], out=m)
    np.multiply(s23[:, None], a_1[None, :, None], out=m_tmp)
    m += m_tmp
    m02 = m[:, 2]
    m22 = s23 * a_0[:, 2, None]
    np.multiply(c23, a_1[2], out=tmp4)
    if -g * s3g > 0.0:
        m22 -= tmp4
    else:
        np.subtract(tmp4, m22, out=m22)
    # theta6 = atan2(g (m12 m00 - m02 m10), g (m12 m01 - m02 m11)): scale-free,
    # so (c4, s4) = (m02, m12) / h enter unnormalised
    yx = buffers.yx[..., :n]
    yx_tmp = buffers.yx_tmp[..., :n]
    np.multiply(m12[:, None], m[:, 0:2], out=yx)
    np.multiply(m02[:, None], m_1[:, 0:2, None], out=yx_tmp)
    if g > 0.0:
        yx -= yx_tmp
    else:
        np.subtract(yx_tmp, yx, out=yx)
    t4 = np.arctan2(m12, m02, out=res[:, :, 0, 3])
    t6 = np.arctan2(yx[:, 0], yx[:, 1], out=res[:, :, 0, 5])
    h = m02 * m02
    h += m12 * m12
    np.sqrt(h, out=h)
    if h.min() <= WRIST_SINGULAR_TOL:
        _singular_wrist(geo, h, m, m_1, t4, t6, g)
    # sigma5 theta5 = atan2(h, m22): atan2 is odd in its first argument
    if geo.sigma5 > 0.0:
        np.arctan2(h, m22, out=res[:, :, 0, 4])
        np.negative(res[:, :, 0, 4], out=res[:, :, 1, 4])
    else:
        np.arctan2(h, m22, out=res[:, :, 1, 4])
        np.negative(res[:, :, 1, 4], out=res[:, :, 0, 4])
    # flip twins of theta4 and theta6 at once: t - pi if t > 0 else t + pi
    t46, flip46 = res[:, :, 0, 3::2], res[:, :, 1, 3::2]
    np.copysign(np.pi, t46, out=flip46)
    np.subtract(t46, flip46, out=flip46)
    if not t46.all():  # copysign made +0 flip to -pi
        flip46[t46 == 0.0] = np.pi

    # joint values: wrapped where not plain, shared ones broadcast
    _wrap(geo, 0, t1)
    _wrap(geo, 1, t2)
    _wrap(geo, 2, t3)
    res[:, :, :, 0] = t1[:, None, None]
    res[:, :, 1, 1] = t2
    res[0, :, :, 2] = t3[:, None]
    res[1, :, :, 2] = t3[::-1, None]
    for j in (3, 4, 5):
        _wrap(geo, j, res[:, :, :, j])
    return ok


def _singular_wrist(
    geo: PumaGeometry,
    h: FloatArray,
    m: FloatArray,
    m_1: FloatArray,
    t4: FloatArray,
    t6: FloatArray,
    g: float,
) -> None:
    """θ4 = offset where |sin θ5| <= tol: θ6 from it, h = c4 m02 + s4 m12."""
    sing = h <= WRIST_SINGULAR_TOL
    c4, s4 = np.cos(geo.theta_offset[3]), np.sin(geo.theta_offset[3])
    m00, m01, m02 = (m[:, j][sing] for j in range(3))
    m10, m11, m12 = (np.broadcast_to(m_1[:, j, None], h.shape)[sing] for j in range(3))
    t4[sing] = geo.theta_offset[3]
    t6[sing] = np.arctan2(g * (s4 * m00 - c4 * m10), g * (s4 * m01 - c4 * m11))
    h[sing] = c4 * m02 + s4 * m12


def _wrap(geo: PumaGeometry, j: int, theta: FloatArray) -> None:
    """Joint values of DH angles ``theta`` in [-pi, pi] of joint ``j``, in place.

    :func:`wrap_array_to_limits`; with a zero offset its interval tests are
    made by arithmetic instead of masked adds (those are slow on strided
    arrays): ``floor((x - first) / s) + 1`` is exactly 1 if x >= first and 0
    otherwise while |x - first| < s, so x + shift * that is x + shift or x.
    """
    if geo.plain[j]:
        return
    offset = geo.theta_offset[j]
    plan = _wrap_plan(geo.lower[j], geo.upper[j]) if offset == 0.0 else None
    if (
        plan is None
        or not all(_SAFE_LOW <= abs(first if not below else last) <= np.pi
                   for _, first, last, below, both in plan if not both)
        or any(both for *_, both in plan)
        or max(abs(geo.lower[j]), abs(geo.upper[j])) > 6.0 * np.pi
        or theta.min() <= -np.pi
    ):  # fmt: skip
        if offset != 0.0:
            theta -= offset
        wrap_array_to_limits(theta, geo.lower[j], geo.upper[j], reduced=offset == 0.0)
        return
    step = np.empty_like(theta)
    for shift, first, last, from_below, _ in plan:
        if from_below:  # moves x <= last
            np.subtract(last, theta, out=step)
        else:  # moves x >= first
            np.subtract(theta, first, out=step)
        step *= _SCALE
        np.floor(step, out=step)
        step += 1.0
        step *= shift
        theta += step


#: x within [-6 pi, 6 pi] (in [-pi, pi] or moved into the limits) and the
#: thresholds in [-pi, pi]: |x - threshold| < 8 pi = 1 / _SCALE.
_SCALE = 1.0 / (8.0 * np.pi)
#: Thresholds at least this far from 0, so that (x - threshold) * _SCALE never
#: underflows to a zero of the wrong sign.
_SAFE_LOW = 1e-3
