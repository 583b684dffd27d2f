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

The status codes and flag slots are those of
:mod:`workbench.ik._kernel_common`, which holds the helpers both closed forms
share. A pose is checked rigid here, with the test and tolerance of
``workbench.poses``: :data:`NOT_RIGID` means it is not, and the Python side
only words the error; :func:`diagnose` gives what the message of an
unreachable pose needs, from the packed record alone.

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

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point
from workbench.ik import _kernel_common as common
from workbench.ik._kernel_common import IN_CYLINDER as IN_CYLINDER
from workbench.ik._kernel_common import NOT_RIGID as NOT_RIGID
from workbench.ik._kernel_common import OK as OK
from workbench.ik._kernel_common import OUT_OF_REACH as OUT_OF_REACH
from workbench.ik._puma import ELBOW_SINGULAR_TOL, WRIST_SINGULAR_TOL, PumaGeometry

FloatArray = npt.NDArray[np.float64]

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
        ("reach_low", "f8"),  # slack folded in (PumaGeometry.reach_test)
        ("reach_high", "f8"),
        ("cylinder2", "f8"),  # squared radius of the unreachable cylinder
        ("reach", "f8", 2),  # PumaGeometry.reach, the bounds an error states
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


@common.inline
def frame_pose(geo, pose: FloatArray, out: FloatArray) -> None:
    """Rows 0..2 of ``base_inv · pose · tool_inv``: the target of the DH chain.

    Args:
        geo: The arm's record.
        pose: (4, 4) pose of the tool frame in the base frame.
        out: (4, 4) scratch; rows 0..2 are written.
    """
    tool, base = common.frames(geo)
    common.write_framed(pose, out, tool, base, geo.framed != 0.0)


@entry_point()
def wrist_centre(geo, pose: FloatArray) -> tuple[float, float, float]:
    """Wrist centre (x, y, z − d1) [m] in DH frame 0, z relative to the shoulder."""
    framed = np.empty((4, 4))
    frame_pose(geo, pose, framed)
    return _centre(geo, framed)


@entry_point()
def diagnose(geometry: np.ndarray, pose: FloatArray) -> tuple[int, float, float, float]:
    """Why a pose is unreachable, from the packed record alone.

    Args:
        geometry: (1,) record array of :data:`GEOMETRY_DTYPE`.
        pose: (4, 4) target pose of the tool frame, finite and rigid.

    Returns:
        ``(status, distance, low, high)``: :data:`OUT_OF_REACH` with the wrist
        centre's distance [m] from the shoulder (with a shoulder offset a1, of
        the arm nearer its reach) and the arm's reach ``[low, high]`` [m];
        :data:`IN_CYLINDER` with its distance from the base axis and the
        cylinder's radius |d2 + d3| twice; else ``(OK, 0, 0, 0)``.
    """
    geo = geometry[0]
    px, py, pz = wrist_centre(geo, pose)
    r2 = px * px + py * py
    low, high = geo.reach_low, geo.reach_high  # the tests' bounds (slack in)
    distance = math.sqrt(r2 + pz * pz)
    if geo.a1 == 0.0 and not (low <= distance <= high):
        return OUT_OF_REACH, distance, geo.reach[0], geo.reach[1]
    if r2 < geo.cylinder2:
        radius = abs(geo.offset)
        return IN_CYLINDER, math.sqrt(r2), radius, radius
    if geo.a1 != 0.0:  # the arm whose in-plane distance is nearer the reach
        rho = common.clamped_root(r2 - geo.offset * geo.offset)
        right, left = math.hypot(rho - geo.a1, pz), math.hypot(-rho - geo.a1, pz)
        if max(low - left, left - high) < max(low - right, right - high):
            distance = left
        else:
            distance = right
        if not (low <= distance <= high):
            return OUT_OF_REACH, distance, geo.reach[0], geo.reach[1]
    return OK, 0.0, 0.0, 0.0


@common.inline
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
#: Bit ``ELBOW + arm`` of the mask: that arm's elbow is singular (stretched or
#: folded, |sin γ| <= ELBOW_SINGULAR_TOL), its elbow-up and elbow-down meet.
ELBOW = 25
#: The bits of the mask that flag a singular wrist, per (arm, elbow) pair, and
#: an arm that cannot reach, per branch.
_WRIST_BITS = (T4, T4 + 1, T4 + 2, T4 + 3)
_DEAD_BITS = (DEAD, DEAD, DEAD, DEAD, DEAD + 1, DEAD + 1, DEAD + 1, DEAD + 1)
#: The mask layout of :func:`solve_pose` (``_kernel_common.solve_one``).
_ELBOW_BITS = (ELBOW, ELBOW, ELBOW, ELBOW, ELBOW + 1, ELBOW + 1, ELBOW + 1, ELBOW + 1)
_LAYOUT = (N_ANGLES, _WRIST_BITS, SHOULDER, _ELBOW_BITS, _DEAD_BITS)


@common.inline
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
    rho, y1 = common.clamped_root(r2 - geo.offset * geo.offset), s1g * pz
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
            k = common.clip_unit(k)  # cos(gamma), gamma = theta3 + beta
            big_a = a2 + ell * k
            root = common.clamped_root(1.0 - k * k)
        if root <= ELBOW_SINGULAR_TOL:
            exact |= 1 << (ELBOW + arm)
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
                    t4 -= kappa * common.remainder(step6) / 2.0
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


@common.inline
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
        q1 = common.joint_value(geo, 0, angles[T1 + arm], prev, has_prev)
        for elbow in range(2):
            pair = 2 * arm + elbow
            q2 = common.joint_value(geo, 1, angles[T2 + pair], prev, has_prev)
            q3 = common.joint_value(geo, 2, angles[T3 + pair], prev, has_prev)
            t4, t5, t6 = angles[T4 + pair], angles[T5 + pair], angles[T6 + pair]
            # the flip twin: (theta4 + pi, -theta5, theta6 + pi)
            t4f = t4 - common.PI if t4 > 0.0 else t4 + common.PI
            t6f = t6 - common.PI if t6 > 0.0 else t6 + common.PI
            for flip in range(2):
                b = 2 * pair + flip
                q[b, 0], q[b, 1], q[b, 2] = q1, q2, q3
                q[b, 3] = common.joint_value(
                    geo, 3, t4f if flip else t4, prev, has_prev
                )
                q[b, 4] = common.joint_value(
                    geo, 4, -t5 if flip else t5, prev, has_prev
                )
                q[b, 5] = common.joint_value(
                    geo, 5, t6f if flip else t6, prev, has_prev
                )
                if within.shape[0]:
                    within[b] = common.within_limits(geo, q, b)


@entry_point(outputs=("q", "flags"))
def solve_pose(
    geometry: np.ndarray,
    pose: FloatArray,
    prev: FloatArray,
    q: FloatArray,
    flags: npt.NDArray[np.uint8],
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
        flags: (8,) uint8 output, the bits of ``_flags`` per branch (0 for
            a branch that does not reach: an arm that cannot, its rows NaN).
        check: Test first that the pose is finite and rigid (the test of
            ``workbench.poses``); False for a pose known to be.

    Returns:
        :data:`OK`, or :data:`NOT_RIGID`, :data:`OUT_OF_REACH`,
        :data:`IN_CYLINDER` (outputs then undefined).
    """
    geo = geometry[0]
    return common.solve_one(
        geo, pose, prev, q, flags, check, angle_arguments, assemble, _LAYOUT
    )


@entry_point(outputs=("q_out",))
def track(
    geometry: np.ndarray,
    pose: FloatArray,
    q_predicted: FloatArray,
    pair: int,
    max_step2: float,
    q_out: FloatArray,
) -> tuple[int, int, bool]:
    """The branch continuing a motion (``_kernel_common.track_one``)."""
    return common.track_one(
        geometry[0], pose, q_predicted, pair, max_step2, q_out,
        angle_arguments, assemble, _LAYOUT,
    )  # fmt: skip


@common.inline
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
    y[common.flat_index(i, N_ANGLES, T3 + pair)] = 0.0 if dead else s3
    x[common.flat_index(i, N_ANGLES, T3 + pair)] = 1.0 if dead else c3
    y[common.flat_index(i, N_ANGLES, T2 + pair)] = 0.0 if dead else s2
    x[common.flat_index(i, N_ANGLES, T2 + pair)] = 1.0 if dead else c2
    norm = math.sqrt(c2 * c2 + s2 * s2)
    c2, s2 = (c2 / norm, s2 / norm) if norm > 0.0 else (1.0, 0.0)
    c23, s23 = c2 * c3 - s2 * s3, s2 * c3 + c2 * s3
    m02 = c23 * a02 + s23 * a12
    m22 = s3g * (s23 * a02 - c23 * a12)
    m00, m01 = c23 * a00 + s23 * a10, c23 * a01 + s23 * a11
    h = math.sqrt(m02 * m02 + m12 * m12)
    y[common.flat_index(i, N_ANGLES, T4 + pair)] = 0.0 if dead else m12
    x[common.flat_index(i, N_ANGLES, T4 + pair)] = 1.0 if dead else m02
    y[common.flat_index(i, N_ANGLES, T5 + pair)] = 0.0 if dead else geo.sigma5 * h
    x[common.flat_index(i, N_ANGLES, T5 + pair)] = 1.0 if dead else -g * m22
    y[common.flat_index(i, N_ANGLES, T6 + pair)] = (
        0.0 if dead else g * (m12 * m00 - m02 * m10)
    )
    x[common.flat_index(i, N_ANGLES, T6 + pair)] = (
        1.0 if dead else g * (m12 * m01 - m02 * m11)
    )
    return (not dead) & (h <= WRIST_SINGULAR_TOL)


@common.inline
def _arm_arguments(y, x, i, arm, x1, xp, distance, pz, px, py, r2, pose, geo):
    """The slots of one arm of pose ``i``: (dead, singular) as angle_arguments.

    ``pose``: (nx, ny, ox, oy, ax, ay, a10, a11, a12, y1) of angle_arguments.
    """
    nx, ny, ox, oy, ax, ay, a10, a11, a12, y1 = pose
    a2, ell, sd = geo.a2, geo.forearm, geo.sigma1 * geo.offset
    dead = (distance < geo.reach_low) | (distance > geo.reach_high)
    k = (xp * xp + pz * pz - a2 * a2 - ell * ell) / (2.0 * a2 * ell)
    k = common.clip_unit(k)
    big_a = a2 + ell * k
    root = common.clamped_root(1.0 - k * k)
    right = 1.0 if sd >= 0.0 else -1.0
    side_x = 1.0 if xp > 0.0 else -1.0
    side = side_x if xp != 0.0 else (right if arm == 0 else -right)
    sg = geo.up_sign * side * root
    c1, s1 = (px * x1 - py * sd) / r2, (py * x1 + px * sd) / r2
    y[common.flat_index(i, N_ANGLES, T1 + arm)] = 0.0 if dead else s1
    x[common.flat_index(i, N_ANGLES, T1 + arm)] = 1.0 if dead else c1
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
            is not finite and rigid (the test of ``workbench.poses``).
        check: Test that each pose is finite and rigid.

    Returns:
        The number of poses flagged in ``odd`` (0: nothing left to do).
    """
    geo = geometry[0]
    tool, base = common.frames(geo)
    framed, rotated = geo.framed != 0.0, geo.sin_alpha6 != 0.0
    ca, sa, d6, a1g = geo.cos_alpha6, geo.sin_alpha6, geo.d6, geo.a1
    s1g, off = geo.sigma1, geo.offset
    right = 1.0 if s1g * off >= 0.0 else -1.0
    flagged = 0
    for i in range(status.shape[0]):
        row0, row1 = common.pose_row(poses, i, 0), common.pose_row(poses, i, 1)
        row2, row3 = common.pose_row(poses, i, 2), common.pose_row(poses, i, 3)
        rigid = common.rigid_rows(row0, row1, row2, row3)
        f0, f1, f2 = common.frame_rows(row0, row1, row2, tool, base, True)  # frame_pose
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
        rho, y1 = common.clamped_root(r2 - off * off), s1g * pz
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
        −1, or the index of the first pose that is not finite and rigid (the
        outputs of it and later poses then undefined).
    """
    return common.fallback_poses(
        geometry[0], poses, y, x, status, exact, odd, angle_arguments
    )


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
    common.assemble_poses(geo, angles, y, status, exact, q, valid, assemble, _DEAD_BITS)
