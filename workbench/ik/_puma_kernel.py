r"""Compiled closed form of PUMA-type arms: one pose, all eight branches.

The one implementation of the formulas that :func:`~workbench.ik.analytic`,
:func:`~workbench.ik.analytic_batch` and the online planner share, compiled
with Numba (``cache=True``: compiled once per machine, then loaded). The
derivation is in ``docs/errata-kang-ik.md``; the constants of an arm come from
:class:`~workbench.ik._puma.PumaGeometry`, packed by :func:`pack_geometry` into
one record (:data:`GEOMETRY_DTYPE`).

Conventions of every function here:

* a pose is a (4, 4) homogeneous matrix of the tool frame in the base frame
  [m];
* ``q`` is (8, 6) [rad], branch ``b`` = 4·left + 2·down + flip (the order of
  ``closed_form.BRANCHES``), joint values (DH angle minus theta offset);
* without a previous configuration each joint value is the representative
  (mod 2π) in (−π, π] if it is within the limits, else the first of ±2π,
  ±4π that is (else the one in (−π, π]); with one, the representative
  nearest it.

The status codes tell the Python side which error to raise; it then runs the
slow, exact checks that word the message.

A batch (:func:`batch_arguments`, ``_atan2_kernel.atan2_into``,
:func:`batch_assemble`) makes the atan2 calls in one vectorised loop, several
times faster than libm's; :func:`solve_pose` does all of it for one pose.
:func:`batch_arguments` is :func:`angle_arguments` rewritten for LLVM's loop
vectoriser (four poses at a time with AVX2, three times as fast): the same
arithmetic in the same order, with selects for its branches, so the same
values bitwise (``tests/test_ik_any_arm.py`` compares them on random,
singular and unreachable poses of every model); the rare poses it leaves
(wrist centre on the base axis, a singular wrist) go to
:func:`angle_arguments`.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point, helper
from workbench.ik._puma import WRIST_SINGULAR_TOL, PumaGeometry, get_geometry
from workbench.model.robot import Robot
from workbench.poses import RIGIDITY_TOL

FloatArray = npt.NDArray[np.float64]

#: Status codes of :func:`solve_pose`.
OK, NOT_RIGID, OUT_OF_REACH, IN_CYLINDER = 0, 1, 2, 3

#: The record of arm constants the kernels read (see ``PumaGeometry``).
GEOMETRY_DTYPE = np.dtype(
    [
        ("sigma1", "f8"),
        ("sigma3", "f8"),
        ("sigma4", "f8"),
        ("sigma5", "f8"),
        ("d1", "f8"),
        ("offset", "f8"),
        ("a1", "f8"),
        ("a2", "f8"),
        ("forearm", "f8"),
        ("cos_beta", "f8"),
        ("sin_beta", "f8"),
        ("up_sign", "f8"),
        ("d6", "f8"),
        ("cos_alpha6", "f8"),
        ("sin_alpha6", "f8"),
        ("reach_low", "f8"),  # slack folded in, as check_reach
        ("reach_high", "f8"),
        ("cylinder2", "f8"),  # squared radius of the unreachable cylinder
        ("theta_offset", "f8", 6),
        ("plain", "f8", 6),  # see PumaGeometry.plain (1.0 or 0.0)
        ("lower", "f8", 6),  # limits widened by LIMIT_TOL
        ("upper", "f8", 6),
        ("joint_sign", "f8", 6),
        ("framed", "f8"),  # 1.0 when base_inv or tool_inv is not the identity
        ("base_inv", "f8", (4, 4)),
        ("tool_inv", "f8", (4, 4)),
    ],
    align=True,
)

#: Fast acceptance of a pose: columns x, y of R orthonormal and z = x × y, and
#: the bottom row, each to within RIGIDITY_TOL / 5, as one sum of squares (then
#: every entry of RᵀR − I is well within RIGIDITY_TOL and det R > 0). A pose
#: that fails it takes the exact checks of ``_targets``.
_FAST_TOL2 = (RIGIDITY_TOL / 5.0) ** 2

_PI = math.pi
_TAU = 2.0 * math.pi


@lru_cache(maxsize=16)
def packed_geometry(robot: Robot) -> np.ndarray:
    """The constants of a robot's closed form, a read-only (1,) record array.

    Cached per robot object, like :func:`~workbench.ik._puma.get_geometry`.

    Raises:
        UnsupportedRobotError: If the robot has no PUMA-type DH table.
    """
    return pack_geometry(get_geometry(robot))


def pack_geometry(geo: PumaGeometry) -> np.ndarray:
    """The constants of ``geo`` as a read-only (1,) :data:`GEOMETRY_DTYPE` array."""
    packed = np.zeros(1, dtype=GEOMETRY_DTYPE)
    for name in GEOMETRY_DTYPE.names or ():
        if name in PumaGeometry.__slots__:
            packed[name] = getattr(geo, name)
    packed["reach_low"], packed["reach_high"], packed["cylinder2"] = geo.reach_test
    packed["lower"], packed["upper"] = geo.bounds
    identity = np.eye(4)
    packed["framed"] = not (
        np.array_equal(geo.base_inv, identity)
        and np.array_equal(geo.tool_inv, identity)
    )
    packed.setflags(write=False)
    return packed


#: For the helpers called per angle or per pose inside the batch loops: inlined
#: into their callers by LLVM (measured: the batch's joint-value stage 3x faster
#: than calls). ``forceinline`` (LLVM's alwaysinline) rather than Numba's
#: ``inline="always"`` (inlining in Numba's IR, before type inference): same
#: machine code speed, a third of the compile time on the first run.
_inline = helper(forceinline=True)


@_inline
def _remainder(x: float) -> float:
    """IEEE remainder of ``x`` by 2π, in [−π, π] (exact; ties may keep ±π)."""
    if -_PI <= x <= _PI:
        return x
    if -3.0 * _PI <= x <= 3.0 * _PI:  # one turn off: x ∓ 2π is exact
        return x - _TAU if x > 0.0 else x + _TAU
    r = np.fmod(x, _TAU)  # exact, then at most one exact turn
    if r > _PI:
        return r - _TAU
    if r < -_PI:
        return r + _TAU
    return r


@_inline
def _joint_value(geo, j: int, theta: float, prev: FloatArray, has_prev: bool) -> float:
    """Joint value of DH angle ``theta``: near ``prev[j]`` if given, else wrapped."""
    sign = geo.joint_sign[j]
    if has_prev:
        return prev[j] + _remainder(sign * (theta - geo.theta_offset[j]) - prev[j])
    if geo.plain[j] != 0.0:  # theta in [-pi, pi] is its own value, but -pi is pi
        return theta if theta > -_PI else _PI
    y = _remainder(sign * (theta - geo.theta_offset[j]))
    if y <= -_PI:
        y += _TAU
    lo, hi = geo.lower[j], geo.upper[j]
    if lo <= y <= hi:
        return y
    for turns in (1.0, -1.0, 2.0, -2.0):
        z = y + turns * _TAU
        if lo <= z <= hi:
            return z
    return y


@_inline
def _clip_unit(k: float) -> float:
    """``k`` clipped to [−1, 1] (selects, which the batch loop vectorises)."""
    k = k if k > -1.0 else -1.0
    return k if k < 1.0 else 1.0


@_inline
def _clamped_root(v: float) -> float:
    """√max(v, 0): the root of a quantity ≥ 0 up to rounding.

    ``abs`` of the clamped value (the same value) tells LLVM the root's
    argument is not negative, so that it uses the sqrt instruction (which a
    vectorised loop can) rather than libm's ``sqrt``, which may set errno.
    """
    return math.sqrt(abs(v if v > 0.0 else 0.0))


@_inline
def _matrix_row(m: FloatArray, i: int) -> tuple[float, float, float, float]:
    """Row ``i`` of a (4, 4) matrix."""
    return m[i, 0], m[i, 1], m[i, 2], m[i, 3]


@_inline
def _pose_row(poses: FloatArray, i: int, row: int) -> tuple[float, float, float, float]:
    """Row ``row`` of pose ``i`` of the flat (N · 16,) array of N poses."""
    k = 4 * row
    return (
        poses[_at(i, 16, k)],
        poses[_at(i, 16, k + 1)],
        poses[_at(i, 16, k + 2)],
        poses[_at(i, 16, k + 3)],
    )


@_inline
def _at(i: int, width: int, slot: int) -> np.uint64:
    """Flat index ``i * width + slot``, unsigned: no negative-index test."""
    return np.uint64(i) * np.uint64(width) + np.uint64(slot)


@_inline
def _frame_rows(r0, r1, r2, tool, base):
    """Rows 0..2 of ``base_inv · pose · tool_inv`` from rows 0..2 of the pose.

    ``tool``, ``base``: rows 0..2 of ``tool_inv`` and ``base_inv`` (their row
    3 is 0 0 0 1). Rows as 4-tuples, so that the batch's vectorised loop and
    :func:`frame_pose` share the arithmetic.
    """
    t0, t1, t2 = _times_tool(r0, tool), _times_tool(r1, tool), _times_tool(r2, tool)
    return (
        _base_row(base[0], t0, t1, t2),
        _base_row(base[1], t0, t1, t2),
        _base_row(base[2], t0, t1, t2),
    )


@_inline
def _times_tool(r, tool) -> tuple[float, float, float, float]:
    """A pose row times ``tool_inv`` (rows ``tool``)."""
    (p0, p1, p2, p3), (e0, e1, e2) = r, tool
    return (
        p0 * e0[0] + p1 * e1[0] + p2 * e2[0],
        p0 * e0[1] + p1 * e1[1] + p2 * e2[1],
        p0 * e0[2] + p1 * e1[2] + p2 * e2[2],
        p0 * e0[3] + p1 * e1[3] + p2 * e2[3] + p3,
    )


@_inline
def _base_row(b, t0, t1, t2) -> tuple[float, float, float, float]:
    """Row ``b`` of ``base_inv`` times the rows t0, t1, t2 (and 0 0 0 1)."""
    return (
        b[0] * t0[0] + b[1] * t1[0] + b[2] * t2[0],
        b[0] * t0[1] + b[1] * t1[1] + b[2] * t2[1],
        b[0] * t0[2] + b[1] * t1[2] + b[2] * t2[2],
        b[0] * t0[3] + b[1] * t1[3] + b[2] * t2[3] + b[3],
    )


@_inline
def _frames(geo):
    """Rows 0..2 of ``tool_inv`` and of ``base_inv``, for :func:`_frame_rows`."""
    e, b = geo.tool_inv, geo.base_inv
    tool = (_matrix_row(e, 0), _matrix_row(e, 1), _matrix_row(e, 2))
    return tool, (_matrix_row(b, 0), _matrix_row(b, 1), _matrix_row(b, 2))


@_inline
def frame_pose(geo, pose: FloatArray, out: FloatArray) -> None:
    """Rows 0..2 of ``base_inv · pose · tool_inv``: the target of the DH chain.

    Args:
        geo: The arm's record.
        pose: (4, 4) pose of the tool frame in the base frame.
        out: (4, 4) scratch; rows 0..2 are written.
    """
    r0, r1, r2 = _matrix_row(pose, 0), _matrix_row(pose, 1), _matrix_row(pose, 2)
    if geo.framed != 0.0:
        tool, base = _frames(geo)
        r0, r1, r2 = _frame_rows(r0, r1, r2, tool, base)
    out[0, 0], out[0, 1], out[0, 2], out[0, 3] = r0
    out[1, 0], out[1, 1], out[1, 2], out[1, 3] = r1
    out[2, 0], out[2, 1], out[2, 2], out[2, 3] = r2


@entry_point()
def wrist_centre(geo, pose: FloatArray) -> tuple[float, float, float]:
    """Wrist centre (x, y, z − d1) [m] in DH frame 0, z relative to the shoulder."""
    framed = np.empty((4, 4))
    frame_pose(geo, pose, framed)
    return _centre(geo, framed)


@_inline
def _centre(geo, pose: FloatArray) -> tuple[float, float, float]:
    """Wrist centre of a pose of the last DH frame, as :func:`wrist_centre`."""
    ax, ay, az = pose[0, 2], pose[1, 2], pose[2, 2]
    if geo.sin_alpha6 != 0.0:  # z column of R Rx(-alpha6), that is z5
        ca, sa = geo.cos_alpha6, geo.sin_alpha6
        ax = sa * pose[0, 1] + ca * ax
        ay = sa * pose[1, 1] + ca * ay
        az = sa * pose[2, 1] + ca * az
    return (
        pose[0, 3] - geo.d6 * ax,
        pose[1, 3] - geo.d6 * ay,
        pose[2, 3] - geo.d6 * az - geo.d1,
    )


@_inline
def _roughly_rigid(pose: FloatArray) -> bool:
    """The fast acceptance test (finite, rigid to RIGIDITY_TOL / 5)."""
    return _rigid_rows(
        _matrix_row(pose, 0),
        _matrix_row(pose, 1),
        _matrix_row(pose, 2),
        _matrix_row(pose, 3),
    )


@_inline
def _rigid_rows(row0, row1, row2, row3) -> bool:
    """:func:`_roughly_rigid` of the four rows of a pose."""
    (r00, r01, r02, r03), (r10, r11, r12, r13) = row0, row1
    (r20, r21, r22, r23), (b0, b1, b2, b3) = row2, row3
    e0 = r00 * r00 + r10 * r10 + r20 * r20 - 1.0
    e1 = r01 * r01 + r11 * r11 + r21 * r21 - 1.0
    e2 = r00 * r01 + r10 * r11 + r20 * r21
    ex = r10 * r21 - r20 * r11 - r02  # x × y - z
    ey = r20 * r01 - r00 * r21 - r12
    ez = r00 * r11 - r10 * r01 - r22
    b3 = b3 - 1.0
    err2 = e0 * e0 + e1 * e1 + e2 * e2 + ex * ex + ey * ey + ez * ez
    err2 += b0 * b0 + b1 * b1 + b2 * b2 + b3 * b3
    # a NaN fails the comparison; an infinite translation makes the sum NaN
    return (err2 <= _FAST_TOL2) & ((r03 + r13 + r23) * 0.0 == 0.0)


#: Slots of the 22 angles of one pose that come from an atan2: θ1 per arm;
#: θ3, θ2, θ4, θ5 (of the no-flip twin) and θ6 per (arm, elbow) pair =
#: 2·left + down.
T1, T3, T2, T4, T5, T6 = 0, 2, 6, 10, 14, 18
N_ANGLES = 22
#: Bit ``DEAD + arm`` of the mask of :func:`angle_arguments`: that arm cannot
#: reach the wrist centre (only with a shoulder offset a1 != 0).
DEAD = 22
#: Bit of the mask set when the shoulder is singular: the wrist centre is
#: within SHOULDER_SINGULAR_TOL of the cylinder |D| (of the base axis when
#: D = 0), where the right and left arms meet.
SHOULDER = 24
#: Distance [m] of the wrist centre's projection from the shoulder-singular
#: surface below which the shoulder counts as singular.
SHOULDER_SINGULAR_TOL = 1e-10


@_inline
def angle_arguments(
    geo,
    target: FloatArray,
    prev: FloatArray,
    y: FloatArray,
    x: FloatArray,
    scratch: FloatArray,
) -> tuple[int, int]:
    """The arguments (y, x) of the atan2 of each angle slot of one pose.

    Everything of the closed form but the atan2 calls, so that a batch can make
    those in one vectorised call. A slot whose angle is known without atan2
    (θ1 with the wrist centre on the base axis, θ4 at a wrist singularity) has
    its bit set in the returned mask and holds the angle itself in ``y``.

    Args:
        geo: The arm's record (:data:`GEOMETRY_DTYPE`).
        target: (4, 4) target pose, already checked rigid and finite.
        prev: (6,) previous configuration [rad], or (0,) for none.
        y: (N_ANGLES,) output, first arguments of the atan2.
        x: (N_ANGLES,) output, second arguments.
        scratch: (4, 4) work space.

    Returns:
        ``(status, exact)``: :data:`OK`, :data:`OUT_OF_REACH` or
        :data:`IN_CYLINDER` (``y``, ``x`` then undefined), and the bit mask of the
        slots that hold their angle; bit ``T4 + pair`` also marks a singular
        wrist, bit ``DEAD + arm`` an arm that cannot reach (its slots hold 0).
    """
    has_prev = prev.shape[0] != 0
    if geo.framed != 0.0:
        frame_pose(geo, target, scratch)
        pose = scratch
    else:  # the DH chain's own frames: no copy
        pose = target
    nx, ny, nz = pose[0, 0], pose[1, 0], pose[2, 0]
    ox, oy, oz = pose[0, 1], pose[1, 1], pose[2, 1]
    ax, ay, az = pose[0, 2], pose[1, 2], pose[2, 2]
    if geo.sin_alpha6 != 0.0:  # R' = R Rx(-alpha6): its z column is z5
        ca, sa = geo.cos_alpha6, geo.sin_alpha6
        ox, ax = ca * ox - sa * ax, sa * ox + ca * ax
        oy, ay = ca * oy - sa * ay, sa * oy + ca * ay
        oz, az = ca * oz - sa * az, sa * oz + ca * az
    px, py, pz = _centre(geo, pose)
    r2 = px * px + py * py
    if geo.a1 == 0.0 and not (
        geo.reach_low <= math.sqrt(r2 + pz * pz) <= geo.reach_high
    ):
        return OUT_OF_REACH, 0
    if r2 < geo.cylinder2:
        return IN_CYLINDER, 0

    s1g, s3g, a2, ell = geo.sigma1, geo.sigma3, geo.a2, geo.forearm
    g, sigma5 = geo.sigma4 * geo.sigma5, geo.sigma5
    sd = s1g * geo.offset
    right = 1.0 if sd >= 0.0 else -1.0  # sign of x1 on the right arm
    # planar arm in the plane of z1: wrist centre at (x1, y1) = (+-rho, s1 pz)
    rho, y1 = _clamped_root(r2 - geo.offset * geo.offset), s1g * pz
    distance = math.sqrt(r2 + pz * pz)  # from the shoulder when a1 = 0
    exact = (1 << SHOULDER) if rho <= SHOULDER_SINGULAR_TOL else 0
    k = big_a = root = 0.0
    # rows of A = Rx(alpha1)^T Rz(-theta1) R' that do not depend on theta1
    a10, a11, a12 = s1g * nz, s1g * oz, s1g * az
    s13 = s3g * s1g
    for arm in range(2):  # right, left
        x1 = right * rho if arm == 0 else -right * rho
        xp = x1 - geo.a1  # wrist centre from the shoulder, along x1
        if geo.a1 != 0.0:
            distance = math.sqrt(xp * xp + pz * pz)
        if not (geo.reach_low <= distance <= geo.reach_high):
            exact |= 1 << (DEAD + arm)
            for slot in (T1 + arm, T3, T2, T4, T5, T6):
                for pair in range(2 * arm, 2 * arm + 2):
                    y[slot if slot == T1 + arm else slot + pair] = 0.0
                    x[slot if slot == T1 + arm else slot + pair] = 1.0
            continue
        if arm == 0 or geo.a1 != 0.0:  # a1 = 0: both arms alike, up to sides
            k = (xp * xp + pz * pz - a2 * a2 - ell * ell) / (2.0 * a2 * ell)
            k = _clip_unit(k)  # cos(gamma), gamma = theta3 + beta
            big_a = a2 + ell * k
            root = _clamped_root(1.0 - k * k)
        # elbow-up: sin(gamma) of the sign of up_sign times that of xp
        if xp != 0.0:
            side = 1.0 if xp > 0.0 else -1.0
        else:
            side = right if arm == 0 else -right
        sg = geo.up_sign * side * root
        if r2 > 0.0:
            c1, s1 = (px * x1 - py * sd) / r2, (py * x1 + px * sd) / r2
            y[T1 + arm], x[T1 + arm] = s1, c1
        else:  # wrist centre on the base axis (D = 0): theta1 is free
            t1 = geo.theta_offset[0]
            if has_prev:
                t1 += geo.joint_sign[0] * prev[0]
            c1, s1 = math.cos(t1), math.sin(t1)
            y[T1 + arm] = t1
            exact |= 1 << (T1 + arm)
        a00, a01, a02 = c1 * nx + s1 * ny, c1 * ox + s1 * oy, c1 * ax + s1 * ay
        m10 = s13 * (s1 * nx - c1 * ny)
        m11 = s13 * (s1 * ox - c1 * oy)
        m12 = s13 * (s1 * ax - c1 * ay)
        for elbow in range(2):  # up, down
            pair = 2 * arm + elbow
            sgb = sg if elbow == 0 else -sg
            c3 = k * geo.cos_beta + sgb * geo.sin_beta
            s3 = sgb * geo.cos_beta - k * geo.sin_beta
            y[T3 + pair], x[T3 + pair] = s3, c3
            big_b = ell * sgb
            c2, s2 = xp * big_a + y1 * big_b, y1 * big_a - xp * big_b
            y[T2 + pair], x[T2 + pair] = s2, c2
            norm = math.sqrt(c2 * c2 + s2 * s2)
            if norm > 0.0:
                c2, s2 = c2 / norm, s2 / norm
            else:  # wrist centre on the shoulder axis: theta2 is free
                c2, s2 = 1.0, 0.0
            c23, s23 = c2 * c3 - s2 * s3, s2 * c3 + c2 * s3
            # M = R36 Rx(alpha6)^T = Rx(alpha3)^T Rz(-theta23) A
            m02 = c23 * a02 + s23 * a12
            m22 = s3g * (s23 * a02 - c23 * a12)
            m00, m01 = c23 * a00 + s23 * a10, c23 * a01 + s23 * a11
            h = math.sqrt(m02 * m02 + m12 * m12)
            if h > WRIST_SINGULAR_TOL:  # (c4, s4) = (m02, m12) / h, scale-free
                y[T4 + pair], x[T4 + pair] = m12, m02
                c4, s4 = m02, m12
            else:  # theta4 free: 0, or split by continuity with prev
                t4 = geo.theta_offset[3]
                if has_prev:
                    t4 += geo.joint_sign[3] * prev[3]
                c4, s4 = math.cos(t4), math.sin(t4)
                if has_prev:  # move theta4 and theta6 by the same amount
                    t6 = math.atan2(
                        g * (s4 * m00 - c4 * m10), g * (s4 * m01 - c4 * m11)
                    )
                    # z5 along +z3 (m22 > 0): theta4 + theta6 fixed, else the
                    # difference
                    kappa = -1.0 if m22 > 0.0 else 1.0
                    step6 = t6 - geo.theta_offset[5] - geo.joint_sign[5] * prev[5]
                    t4 -= kappa * _remainder(step6) / 2.0
                    c4, s4 = math.cos(t4), math.sin(t4)
                y[T4 + pair] = t4
                exact |= 1 << (T4 + pair)
                h = c4 * m02 + s4 * m12
            y[T5 + pair], x[T5 + pair] = sigma5 * h, -g * m22
            y[T6 + pair] = g * (s4 * m00 - c4 * m10)
            x[T6 + pair] = g * (s4 * m01 - c4 * m11)
    if exact >> DEAD & 3 == 3:
        return OUT_OF_REACH, 0
    return OK, exact


@_inline
def assemble(
    geo,
    angles: FloatArray,
    prev: FloatArray,
    q: FloatArray,
    within: npt.NDArray[np.bool_],
    exact: int,
) -> None:
    """Joint values of the eight branches from the 22 DH angles of a pose.

    Args:
        geo: The arm's record.
        angles: (N_ANGLES,) DH angles [rad] in the slots of
            :func:`angle_arguments`, each in [−π, π].
        prev: (6,) previous configuration [rad], or (0,) for none.
        q: (8, 6) output [rad].
        within: (8,) output, branch within the limits (± LIMIT_TOL); or (0,)
            to skip the tests.
        exact: Mask of :func:`angle_arguments`: the branches of an arm with
            bit ``DEAD + arm`` are NaN (and not within the limits).
    """
    has_prev = prev.shape[0] != 0
    for arm in range(2):
        if exact >> (DEAD + arm) & 1:
            for b in range(4 * arm, 4 * arm + 4):
                for j in range(6):
                    q[b, j] = np.nan
                if within.shape[0]:
                    within[b] = False
            continue
        q1 = _joint_value(geo, 0, angles[T1 + arm], prev, has_prev)
        for elbow in range(2):
            pair = 2 * arm + elbow
            q2 = _joint_value(geo, 1, angles[T2 + pair], prev, has_prev)
            q3 = _joint_value(geo, 2, angles[T3 + pair], prev, has_prev)
            t4, t5, t6 = angles[T4 + pair], angles[T5 + pair], angles[T6 + pair]
            # the flip twin: (theta4 + pi, -theta5, theta6 + pi)
            t4f = t4 - _PI if t4 > 0.0 else t4 + _PI
            t6f = t6 - _PI if t6 > 0.0 else t6 + _PI
            for flip in range(2):
                b = 2 * pair + flip
                q[b, 0], q[b, 1], q[b, 2] = q1, q2, q3
                q[b, 3] = _joint_value(geo, 3, t4f if flip else t4, prev, has_prev)
                q[b, 4] = _joint_value(geo, 4, -t5 if flip else t5, prev, has_prev)
                q[b, 5] = _joint_value(geo, 5, t6f if flip else t6, prev, has_prev)
                if within.shape[0]:
                    ok = True
                    for j in range(6):
                        ok &= geo.lower[j] <= q[b, j] <= geo.upper[j]
                    within[b] = ok


@entry_point(outputs=("q", "flags"))
def solve_pose(
    geometry: np.ndarray,
    pose: FloatArray,
    prev: FloatArray,
    q: FloatArray,
    flags: npt.NDArray[np.bool_],
    check: bool,
) -> int:
    """All eight branches of one pose.

    Args:
        geometry: (1,) record array of :data:`GEOMETRY_DTYPE`.
        pose: (4, 4) target pose.
        prev: (6,) previous configuration [rad]: each angle is then the
            representative nearest it, and a free θ4/θ6 split by continuity;
            or (0,) for none.
        q: (8, 6) output, joint values [rad].
        flags: (14,) output: per branch, within the limits (8), then per
            (arm, elbow) pair, wrist singular (4), then shoulder singular, then
            "an arm cannot reach" (its branches are NaN).
        check: Run the fast rigidity test first (False once the exact
            checks of ``_targets`` accepted the pose).

    Returns:
        :data:`OK`, or :data:`NOT_RIGID`, :data:`OUT_OF_REACH`,
        :data:`IN_CYLINDER` (outputs then undefined).
    """
    geo = geometry[0]
    if check and not _roughly_rigid(pose):
        return NOT_RIGID
    y, x = np.empty(N_ANGLES), np.empty(N_ANGLES)
    # prev as the batch passes it (writable, C): the helpers compile once
    previous = np.empty(prev.shape[0])
    for j in range(prev.shape[0]):  # (a slice assignment compiles an overload)
        previous[j] = prev[j]
    status, exact = angle_arguments(geo, pose, previous, y, x, np.empty((4, 4)))
    if status != OK:
        return status
    angles = np.empty(N_ANGLES)
    for slot in range(N_ANGLES):
        if exact >> slot & 1:
            angles[slot] = y[slot]
        else:
            angles[slot] = math.atan2(y[slot], x[slot])
    assemble(geo, angles, previous, q, flags[:8], exact)
    for pair in range(4):
        flags[8 + pair] = exact >> (T4 + pair) & 1
    flags[12] = exact >> SHOULDER & 1
    flags[13] = exact >> DEAD & 3 != 0
    return OK


@_inline
def _pair_arguments(y, x, i, pair, dead, sgb, k, xp, big_a, y1, a0, a1, m1, geo):
    """The slots of one (arm, elbow) pair of pose ``i``, as angle_arguments.

    ``a0``, ``a1``, ``m1``: (a00, a01, a02), (a10, a11, a12) and (m10, m11,
    m12) of angle_arguments. Returns whether the wrist is singular (the pose
    then needs angle_arguments). A dead arm's slots get (0, 1).
    """
    (a00, a01, a02), (a10, a11, a12), (m10, m11, m12) = a0, a1, m1
    ell, s3g, g = geo.forearm, geo.sigma3, geo.sigma4 * geo.sigma5
    c3 = k * geo.cos_beta + sgb * geo.sin_beta
    s3 = sgb * geo.cos_beta - k * geo.sin_beta
    big_b = ell * sgb
    c2, s2 = xp * big_a + y1 * big_b, y1 * big_a - xp * big_b
    y[_at(i, N_ANGLES, T3 + pair)] = 0.0 if dead else s3
    x[_at(i, N_ANGLES, T3 + pair)] = 1.0 if dead else c3
    y[_at(i, N_ANGLES, T2 + pair)] = 0.0 if dead else s2
    x[_at(i, N_ANGLES, T2 + pair)] = 1.0 if dead else c2
    norm = math.sqrt(c2 * c2 + s2 * s2)
    c2, s2 = (c2 / norm, s2 / norm) if norm > 0.0 else (1.0, 0.0)
    c23, s23 = c2 * c3 - s2 * s3, s2 * c3 + c2 * s3
    m02 = c23 * a02 + s23 * a12
    m22 = s3g * (s23 * a02 - c23 * a12)
    m00, m01 = c23 * a00 + s23 * a10, c23 * a01 + s23 * a11
    h = math.sqrt(m02 * m02 + m12 * m12)
    y[_at(i, N_ANGLES, T4 + pair)] = 0.0 if dead else m12
    x[_at(i, N_ANGLES, T4 + pair)] = 1.0 if dead else m02
    y[_at(i, N_ANGLES, T5 + pair)] = 0.0 if dead else geo.sigma5 * h
    x[_at(i, N_ANGLES, T5 + pair)] = 1.0 if dead else -g * m22
    y[_at(i, N_ANGLES, T6 + pair)] = 0.0 if dead else g * (m12 * m00 - m02 * m10)
    x[_at(i, N_ANGLES, T6 + pair)] = 1.0 if dead else g * (m12 * m01 - m02 * m11)
    return (not dead) & (h <= WRIST_SINGULAR_TOL)


@_inline
def _arm_arguments(y, x, i, arm, x1, xp, distance, pz, px, py, r2, pose, geo):
    """The slots of one arm of pose ``i``: (dead, singular) as angle_arguments.

    ``pose``: (nx, ny, ox, oy, ax, ay, a10, a11, a12, y1) of angle_arguments.
    """
    nx, ny, ox, oy, ax, ay, a10, a11, a12, y1 = pose
    a2, ell, sd = geo.a2, geo.forearm, geo.sigma1 * geo.offset
    dead = (distance < geo.reach_low) | (distance > geo.reach_high)
    k = (xp * xp + pz * pz - a2 * a2 - ell * ell) / (2.0 * a2 * ell)
    k = _clip_unit(k)
    big_a = a2 + ell * k
    root = _clamped_root(1.0 - k * k)
    right = 1.0 if sd >= 0.0 else -1.0
    side_x = 1.0 if xp > 0.0 else -1.0
    side = side_x if xp != 0.0 else (right if arm == 0 else -right)
    sg = geo.up_sign * side * root
    c1, s1 = (px * x1 - py * sd) / r2, (py * x1 + px * sd) / r2
    y[_at(i, N_ANGLES, T1 + arm)] = 0.0 if dead else s1
    x[_at(i, N_ANGLES, T1 + arm)] = 1.0 if dead else c1
    a0 = (c1 * nx + s1 * ny, c1 * ox + s1 * oy, c1 * ax + s1 * ay)
    s13 = geo.sigma3 * geo.sigma1
    m1 = (
        s13 * (s1 * nx - c1 * ny),
        s13 * (s1 * ox - c1 * oy),
        s13 * (s1 * ax - c1 * ay),
    )
    a1 = (a10, a11, a12)
    up = _pair_arguments(y, x, i, 2 * arm, dead, sg, k, xp, big_a, y1, a0, a1, m1, geo)
    down = _pair_arguments(
        y, x, i, 2 * arm + 1, dead, -sg, k, xp, big_a, y1, a0, a1, m1, geo
    )
    return dead, up | down


@entry_point(
    outputs=("y", "x", "status", "exact", "odd"),
    contiguous=("poses",),
    vectorize=True,
)
def batch_arguments(
    geometry: np.ndarray,
    poses: FloatArray,
    y: FloatArray,
    x: FloatArray,
    status: npt.NDArray[np.int8],
    exact: npt.NDArray[np.int64],
    odd: npt.NDArray[np.uint8],
    check: bool,
) -> int:
    """Stage 1 of a batch: :func:`angle_arguments` of N poses, checked.

    The loop over the poses is written for LLVM's loop vectoriser (four poses
    at a time with AVX2): the same arithmetic as :func:`angle_arguments`, in
    the same order (the results are bitwise equal, tested), with selects for
    branches. The poses it cannot handle that way (wrist centre on the base
    axis, a singular wrist) are marked ``odd``, for :func:`batch_fallback`.

    Args:
        geometry: (1,) record array of :data:`GEOMETRY_DTYPE`.
        poses: (N · 16,) target poses, the (N, 4, 4) array flattened.
        y: (N · N_ANGLES,) output, first arguments of the atan2, the
            (N, N_ANGLES) array flattened.
        x: (N · N_ANGLES,) output, second arguments, likewise.
        status: (N,) output status per pose.
        exact: (N,) output bit masks.
        odd: (N,) output: bit 0 the pose needs angle_arguments, bit 1 it
            failed the fast rigidity test.
        check: Run the fast rigidity test on each pose.

    Returns:
        The number of poses flagged in ``odd`` (0: nothing left to do).
    """
    geo = geometry[0]
    tool, base = _frames(geo)
    framed, rotated = geo.framed != 0.0, geo.sin_alpha6 != 0.0
    ca, sa, d6, a1g = geo.cos_alpha6, geo.sin_alpha6, geo.d6, geo.a1
    s1g, off = geo.sigma1, geo.offset
    right = 1.0 if s1g * off >= 0.0 else -1.0
    flagged = 0
    for i in range(status.shape[0]):
        row0, row1 = _pose_row(poses, i, 0), _pose_row(poses, i, 1)
        row2, row3 = _pose_row(poses, i, 2), _pose_row(poses, i, 3)
        rigid = _rigid_rows(row0, row1, row2, row3)
        f0, f1, f2 = _frame_rows(row0, row1, row2, tool, base)  # as frame_pose
        nx, ox, ax, qx = f0 if framed else row0
        ny, oy, ay, qy = f1 if framed else row1
        nz, oz, az, qz = f2 if framed else row2
        # R Rx(-alpha6), as selects
        ox, ax = (ca * ox - sa * ax, sa * ox + ca * ax) if rotated else (ox, ax)
        oy, ay = (ca * oy - sa * ay, sa * oy + ca * ay) if rotated else (oy, ay)
        oz, az = (ca * oz - sa * az, sa * oz + ca * az) if rotated else (oz, az)
        px, py, pz = qx - d6 * ax, qy - d6 * ay, qz - d6 * az - geo.d1
        r2 = px * px + py * py
        total = math.sqrt(r2 + pz * pz)
        rho, y1 = _clamped_root(r2 - off * off), s1g * pz
        pose = (nx, ny, ox, oy, ax, ay, s1g * nz, s1g * oz, s1g * az, y1)
        x1 = right * rho
        xp = x1 - a1g
        distance = total if a1g == 0.0 else math.sqrt(xp * xp + pz * pz)
        dead_r, odd_r = _arm_arguments(
            y, x, i, 0, x1, xp, distance, pz, px, py, r2, pose, geo
        )
        xp = -x1 - a1g
        distance = total if a1g == 0.0 else math.sqrt(xp * xp + pz * pz)
        dead_l, odd_l = _arm_arguments(
            y, x, i, 1, -x1, xp, distance, pz, px, py, r2, pose, geo
        )
        mask = (1 << SHOULDER) if rho <= SHOULDER_SINGULAR_TOL else 0
        mask |= (1 << DEAD) if dead_r else 0
        mask |= (1 << (DEAD + 1)) if dead_l else 0
        code = OK
        code = OUT_OF_REACH if dead_r & dead_l else code
        code = IN_CYLINDER if r2 < geo.cylinder2 else code
        unreachable = (total < geo.reach_low) | (total > geo.reach_high)
        code = OUT_OF_REACH if (a1g == 0.0) & unreachable else code
        status[i] = code
        exact[i] = mask if code == OK else 0
        special = (code == OK) & ((r2 <= 0.0) | odd_r | odd_l)
        flag = (1 if special else 0) | (2 if check & (not rigid) else 0)
        odd[i] = flag
        flagged += flag != 0
    return flagged


@entry_point(outputs=("y", "x", "status", "exact"), contiguous=("odd",))
def batch_fallback(
    geometry: np.ndarray,
    poses: FloatArray,
    y: FloatArray,
    x: FloatArray,
    status: npt.NDArray[np.int8],
    exact: npt.NDArray[np.int64],
    odd: npt.NDArray[np.uint8],
) -> int:
    """Stage 1 of a batch, the poses :func:`batch_arguments` flagged ``odd``.

    Arguments as :func:`batch_arguments`'s, with ``poses`` (N, 4, 4), ``y`` and
    ``x`` (N, N_ANGLES).

    Its own kernel, compiled without the vectoriser options of
    :func:`batch_arguments` (which would have LLVM warn about each loop here
    it cannot vectorise).

    Returns:
        −1, or the index of the first pose that failed the fast rigidity test
        (the outputs of it and later poses then undefined).
    """
    geo = geometry[0]
    none, scratch = np.empty(0), np.empty((4, 4))
    for i in range(poses.shape[0]):
        if odd[i]:
            if odd[i] & 2:
                return i
            status[i], exact[i] = angle_arguments(
                geo, poses[i], none, y[i], x[i], scratch
            )
    return -1


@entry_point(outputs=("angles", "q", "valid"), contiguous=("y", "status", "exact"))
def batch_assemble(
    geometry: np.ndarray,
    angles: FloatArray,
    y: FloatArray,
    status: npt.NDArray[np.int8],
    exact: npt.NDArray[np.int32],
    q: FloatArray,
    valid: npt.NDArray[np.bool_],
) -> None:
    """Stage 3 of a batch: joint values from ``angles = arctan2(y, x)``.

    Args:
        geometry: (1,) record array of :data:`GEOMETRY_DTYPE`.
        angles: (N, N_ANGLES) ``arctan2(y, x)`` (slots in ``exact`` ignored).
        y: (N, N_ANGLES), from :func:`batch_arguments`.
        status: (N,), from :func:`batch_arguments`.
        exact: (N,), from :func:`batch_arguments`.
        q: (N, 8, 6) output [rad]; NaN for a pose whose status is not OK.
        valid: (N, 8) output, True where the status is OK.
    """
    geo = geometry[0]
    none, no_within = np.empty(0), np.empty(0, dtype=np.bool_)
    for i in range(angles.shape[0]):
        if status[i] != OK:
            q[i] = np.nan
            valid[i] = False
            continue
        mask = exact[i]
        if mask:
            for slot in range(N_ANGLES):
                if mask >> slot & 1:
                    angles[i, slot] = y[i, slot]
        assemble(geo, angles[i], none, q[i], no_within, mask)
        for arm in range(2):
            alive = not (mask >> (DEAD + arm) & 1)
            for b in range(4 * arm, 4 * arm + 4):
                valid[i, b] = alive


@helper()
def _distance2(a: FloatArray, b: FloatArray) -> float:
    d2 = 0.0
    for j in range(a.shape[0]):
        d = a[j] - b[j]
        d2 += d * d
    return d2


@entry_point()
def continuing_branch(
    q: FloatArray, q_reference: FloatArray, pair: int, max_step2: float
) -> int:
    """The branch continuing a motion at ``q_reference`` (Kang's θ4 rule).

    The nearer of the two wrist twins of ``pair`` (branches ``2 pair`` and
    ``2 pair + 1``, the previous cycle's) if its squared distance is at most
    ``max_step2``; else, after a shoulder or elbow singularity, the nearest of
    all eight (the first on a tie). Distances are plain Euclidean: ``q`` holds
    the representatives nearest ``q_reference`` (``solve_pose`` with it as
    ``prev``), so they equal those of ``closed_form.nearest``.
    """
    twin = 2 * pair
    d_a, d_b = _distance2(q[twin], q_reference), _distance2(q[twin + 1], q_reference)
    if d_a <= d_b:
        if d_a <= max_step2:
            return twin
    elif d_b <= max_step2:
        return twin + 1
    best, best_d2 = 0, math.inf
    for b in range(8):
        d2 = _distance2(q[b], q_reference)
        if d2 < best_d2:
            best, best_d2 = b, d2
    return best
