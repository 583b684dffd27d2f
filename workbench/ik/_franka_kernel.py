r"""Compiled closed form of Franka-type seven-axis arms, q7 given: all eight branches.

The arm is the fitted chain base · DH(θ) · tool of :mod:`workbench.ik.structure`
(standard DH, θ_k = s_k q_k + θ0_k) with the Franka pattern: α1..α6 = ±90°
(σ_k = sin α_k), a1 = a2 = d2 = 0 (axes 1, 2, 3 meet in the shoulder point
S = (0, 0, d1)), a3 ≠ 0 and a4 ≠ 0 (the elbow offsets; E, the foot on axis 4
of the common normal of axes 3 and 4, is the elbow point), a5 = 0 (axes 5 and
6 meet in the wrist point W), a6 ≠ 0 (axis 7 off axis 6); d3, d4 (the Panda's
0), d5, d6 and row 7 are free.
Derivation (after He & Liu 2021, written for any lengths of the pattern; the
section "Franka arms" of docs/seven-axis.md has the details):

* q7 fixes frame 6: the target of the DH chain is M = B⁻¹ T E⁻¹ (frame 7) and
  frame 6 is M · A7(θ7)⁻¹; W = o6 − a6 x6 − d6 σ6 y6 (axis 6 is z5 = σ6 y6).
* θ4 (elbow): in frame 3, E − S = u = (a3, σ3 d3, 0) and
  W − E = (R(θ4) (a4, −σ4 d5), d4), so
  |W − S|² = L24² + L46² + d4² + 2 L24 L46 cos(θ4 + φ), φ the angle from u to
  (a4, −σ4 d5): two elbows θ4 = ±δ4 − φ.
* θ5 (wrist): in frame 4, W − S is (X, Y, D) = (−σ4 κ, σ4 d4, D) with
  κ = −σ4 (a4 + a3 c4 + σ3 d3 s4) and D = σ4 (a3 s4 − σ3 d3 c4) + d5 (known
  from θ4), and axis 6 (z5) makes σ5 (s5 X − c5 Y) = (W − S) · z5 (known
  from the pose): two wrists per elbow, (W − S) · x5 = ±√(X² + Y² − (w · z5)²).
* θ6 turns W − S, seen from frame 6, onto its image in frame 5; then
  R03 = R06 (R34 R45 R56)ᵀ, θ1, θ2 from axis 3 (z2 = σ3 y3), two shoulders
  (θ1 + π, −θ2, θ3 + π), and θ3 from x3 in frame 2.

Every step is an exact identity of the chain, so the eight rows are every real
solution for the given q7 (He & Liu and ``frankik`` keep the elbow θ4 = −δ4 − φ
only: the Panda's other elbow is mostly, not always, outside its q4 limits).

Branches: bit 2 elbow, bit 1 wrist, bit 0 shoulder, each set when a triple
product of the joint axes a_k (their positive directions) is positive:
shoulder (a1 × a3) · a2 (the Panda: sign of sin q2); elbow
((E − S) × (W − E)) · a4 (the turn of the arm at the elbow about axis 4; the
Panda's q4 limits hold the "neg" elbow, He & Liu's); wrist (W − S) · (a5 × a6)
(the Panda, within its q4 limits: sign of −cos q5).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point
from workbench.ik import _kernel_common as common
from workbench.ik._puma import LIMIT_TOL, MODEL_ERROR_SLACK
from workbench.ik._redundant_common import (
    ELBOW_SINGULAR,
    NOT_RIGID,
    OK,
    OUT_OF_REACH,
    REACHED,
    SHOULDER_SINGULAR,
    WITHIN_LIMITS,
    WRIST_SINGULAR,
)
from workbench.ik.structure import KinematicStructure

FloatArray = npt.NDArray[np.float64]

#: Branch labels, index 4·elbow + 2·wrist + shoulder (bit set: "pos", the
#: triple product of the module docstring positive).
BRANCHES: tuple[str, ...] = tuple(
    f"elbow-{elbow}/wrist-{wrist}/shoulder-{shoulder}"
    for elbow in ("neg", "pos")
    for wrist in ("neg", "pos")
    for shoulder in ("neg", "pos")
)
PARAMETER = "q7"
#: A branch is flagged singular where it meets its twin: |sin θ2| (shoulder:
#: axes 1 and 3 aligned), |sin(θ4 + φ)| (elbow: S, E, W aligned), the
#: cosine |(W − S) · x5| / √(X² + Y²) of the wrist equation (module
#: docstring; d4 = 0: |cos θ5|, axis 6 in the plane of S, E, W) at most
#: this. The elbow's and the wrist's are roots of differences, (1 − k)(1 + k) and
#: (X² + Y² − (w · z5)²) / (X² + Y²), so at the singularity they come out as
#: √(rounding) ≈ 1e-8, or more where |κ| is small (axis 5 near S).
SINGULAR_TOL = 1e-6
#: Rounding tolerated beyond the reach before a branch is refused:
#: |cos(θ4 + φ)| ≤ 1 + REACH_SLACK; |w · z5| ≤ √(κ² + d4²) + REACH_SLACK (L24 + L46);
#: each widened by ``MODEL_ERROR_SLACK`` times the model's residual (a model
#: off its idealised structure: the branch is clamped and refined on it).
REACH_SLACK = 1e-12
#: Below this |sin θ2|, θ1 is not computed from axis 3 but taken from
#: q_previous (or θ1 = θ0_1): axes 1 and 3 aligned, only θ1 ± θ3 matter.
#: Axis 3 comes out of R06 (R34 R45 R56)ᵀ with an error of up to ~1e-13.
_SHOULDER_FREE = 1e-12
B = 8

GEOMETRY_DTYPE = np.dtype(
    [
        ("sigma", "f8", 6),  # sin α1..α6, each ±1
        ("d1", "f8"),
        ("d3", "f8"),
        ("d4", "f8"),
        ("a3", "f8"),
        ("a4", "f8"),
        ("d5", "f8"),
        ("a6", "f8"),
        ("d6", "f8"),
        ("a7", "f8"),
        ("d7", "f8"),
        ("ca7", "f8"),
        ("sa7", "f8"),
        ("l24s", "f8"),  # L24²
        ("l46s", "f8"),  # L46²
        ("inv_2l", "f8"),  # 1 / (2 L24 L46)
        ("reach_tol", "f8"),  # REACH_SLACK (L24 + L46) + model slack [m]
        ("cos_tol", "f8"),  # REACH_SLACK + model slack, on cos(θ4 + φ)
        ("cphi", "f8"),
        ("sphi", "f8"),
        ("label", "f8", 3),  # ±1: the sign of shoulder, wrist, elbow bit 0
        ("based", "f8"),
        ("q7_low", "f8"),
        ("q7_high", "f8"),
        ("theta_offset", "f8", 7),
        ("joint_sign", "f8", 7),
        ("plain", "f8", 7),
        ("lower", "f8", 7),
        ("upper", "f8", 7),
        ("base_inv", "f8", (4, 4)),
        ("tool_inv", "f8", (4, 4)),
    ],
    align=True,
)


def pack_geometry(structure: KinematicStructure, lower, upper) -> np.ndarray:
    """The constants of a Franka-type arm as a read-only (1,) record array.

    Args:
        structure: Its fitted structure (family ``"franka"``, 7 DH rows).
        lower: Lower joint limits, (7,) [rad].
        upper: Upper joint limits, (7,) [rad].
    """
    j = structure.table.joints
    g = np.zeros(1, dtype=GEOMETRY_DTYPE)
    sigma = [math.copysign(1.0, x.alpha) for x in j[:6]]
    g["sigma"] = sigma
    g["d1"], g["d3"], g["a3"], g["a4"] = j[0].d, j[2].d, j[2].a, j[3].a
    g["d4"] = j[3].d
    g["d5"], g["a6"], g["d6"] = j[4].d, j[5].a, j[5].d
    g["a7"], g["d7"] = j[6].a, j[6].d
    g["ca7"], g["sa7"] = math.cos(j[6].alpha), math.sin(j[6].alpha)
    ux, uy = j[2].a, sigma[2] * j[2].d
    vx, vy = j[3].a, -sigma[3] * j[4].d
    l24, l46 = math.hypot(ux, uy), math.hypot(vx, vy)
    g["l24s"], g["l46s"] = l24 * l24, l46 * l46
    g["inv_2l"] = 1.0 / (2.0 * l24 * l46)
    # (a model off its idealised structure reaches up to this much further:
    # the branches are clamped onto the wrist's edge and refined on the model)
    model_slack = MODEL_ERROR_SLACK * structure.residual
    g["reach_tol"] = REACH_SLACK * (l24 + l46) + model_slack
    g["cos_tol"] = REACH_SLACK + model_slack * (l24 + l46) / (l24 * l46)
    g["cphi"] = (ux * vx + uy * vy) / (l24 * l46)
    g["sphi"] = (ux * vy - uy * vx) / (l24 * l46)
    s = structure.joint_sign
    # physical sign (module docstring) of the kernel's roots sin theta2 >= 0,
    # cos theta5 >= 0 and epsilon = +1 of theta4 = epsilon delta4 - phi
    shoulder = -sigma[0] * sigma[1] * s[0] * s[1] * s[2]
    wrist = s[4] * s[5] * sigma[4]
    elbow = s[3]
    g["label"] = [shoulder, wrist, elbow]
    common.pack_joint_fields(g, structure, lower, upper, LIMIT_TOL)
    g["q7_low"], g["q7_high"] = lower[6], upper[6]
    g.setflags(write=False)
    return g


def parameter_range(geometry: np.ndarray) -> tuple[float, float]:
    """The limits of q7 [rad]: the range of the redundancy parameter."""
    return float(geometry["q7_low"][0]), float(geometry["q7_high"][0])


@common.inline
def _flip(t: float) -> float:
    """The angle ``t`` [rad] plus π, in [−π, π]."""
    return t - common.PI if t > 0.0 else t + common.PI


@common.inline
def _wrist_point(geo, f0, f1, f2, t7: float):
    """Axes x6, y6, z6 of frame 6 and W − S in frame 0 from the DH-framed pose."""
    (r00, r01, r02, px), (r10, r11, r12, py), (r20, r21, r22, pz) = f0, f1, f2
    ca, sa = geo.ca7, geo.sa7
    c7, s7 = math.cos(t7), math.sin(t7)
    # Q = R Rx(-alpha7): frame 6 = Q Rz(-theta7), o6 = p - a7 Qx - d7 Qz
    qx = (r00, r10, r20)
    qy = (ca * r01 - sa * r02, ca * r11 - sa * r12, ca * r21 - sa * r22)
    qz = (sa * r01 + ca * r02, sa * r11 + ca * r12, sa * r21 + ca * r22)
    x6 = (c7 * qx[0] - s7 * qy[0], c7 * qx[1] - s7 * qy[1], c7 * qx[2] - s7 * qy[2])
    y6 = (s7 * qx[0] + c7 * qy[0], s7 * qx[1] + c7 * qy[1], s7 * qx[2] + c7 * qy[2])
    a7, d7, a6, d6s = geo.a7, geo.d7, geo.a6, geo.d6 * geo.sigma[5]
    w = (
        px - a7 * qx[0] - d7 * qz[0] - a6 * x6[0] - d6s * y6[0],
        py - a7 * qx[1] - d7 * qz[1] - a6 * x6[1] - d6s * y6[1],
        pz - a7 * qx[2] - d7 * qz[2] - a6 * x6[2] - d6s * y6[2] - geo.d1,
    )
    return x6, y6, qz, w


@common.inline
def _dot(a, b) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@common.inline
def _arm(geo, f0, f1, f2, value: float):
    """What the elbow and the wrist need from a DH-framed pose and q7 = ``value``.

    Returns:
        ``(x6, y6, z6, w, r2, k, wz5)``: the axes of frame 6, w = W − S [m]
        (frame 0), r2 = |w|², k = cos(θ4 + φ) (unclipped) and w · z5 [m]
        (z5 = σ6 y6: axis 6).
    """
    t7 = geo.joint_sign[6] * value + geo.theta_offset[6]
    x6, y6, z6, w = _wrist_point(geo, f0, f1, f2, t7)
    r2 = _dot(w, w)
    k = (r2 - geo.l24s - geo.l46s - geo.d4 * geo.d4) * geo.inv_2l
    return x6, y6, z6, w, r2, k, geo.sigma[5] * _dot(w, y6)


@common.inline
def _times_t(r, c: float, s: float, sigma: float):
    """Row ``r`` times (Rz(θ) Rx(α))ᵀ, α = ±90° (σ = sin α), θ of cos c, sin s."""
    return (r[0] * c + r[2] * sigma * s, r[0] * s - r[2] * sigma * c, r[1] * sigma)


@common.inline
def _free_angle(geo, j: int, prev, has_prev: bool) -> float:
    """The DH angle of joint ``j`` where it is free: q_previous's, else θ0."""
    t = geo.theta_offset[j]
    if has_prev:
        t += geo.joint_sign[j] * prev[j]
    return t


@common.inline
def _elbow(geo, k: float, s_delta: float, elbow: int):
    """The elbow ``elbow`` (bit 2 of the branch) from k and |sin(θ4 + φ)|.

    Returns:
        ``(c4, s4, big_d, kappa)``: cos, sin θ4; D = (W − S) · z4 and
        κ = ((W − S) × z4) · z3 [m].
    """
    sg = geo.sigma
    e = -geo.label[2] if elbow == 0 else geo.label[2]
    c4 = k * geo.cphi + e * s_delta * geo.sphi
    s4 = e * s_delta * geo.cphi - k * geo.sphi
    # w in frame 3 is (rx, ry, d4), rx = a3 + a4 c4 + sigma4 d5 s4 and
    # ry = sigma3 d3 + a4 s4 - sigma4 d5 c4; in frame 4 it is
    # (-sigma4 kappa, sigma4 d4, D), kappa and D expanded (no cancellation)
    big_d = sg[3] * (geo.a3 * s4 - sg[2] * geo.d3 * c4) + geo.d5
    kappa = -sg[3] * (geo.a4 + geo.a3 * c4 + sg[2] * geo.d3 * s4)
    return c4, s4, big_d, kappa


@common.inline
def _solve(geo, f0, f1, f2, value, prev, has_prev, q, flags) -> int:
    """All eight branches of one DH-framed pose (rows f0, f1, f2) for q7 = value.

    Writes ``q`` (8, 7) (NaN rows: not reached) and ``flags`` (8,) uint8;
    returns OK or OUT_OF_REACH.
    """
    sg = geo.sigma
    x6, y6, z6, w, r2, k, wz5 = _arm(geo, f0, f1, f2, value)
    for b in range(8):
        flags[b] = 0
        for j in range(7):
            q[b, j] = np.nan
    if not (abs(k) <= 1.0 + geo.cos_tol) or r2 <= 0.0:
        return OUT_OF_REACH
    k = common.clip_unit(k)
    s_delta = common.clamped_root((1.0 - k) * (1.0 + k))
    elbow_flag = ELBOW_SINGULAR if s_delta <= SINGULAR_TOL else 0
    # w in frame 6 rotated by Rx(alpha6): (w.x6, -sigma6 w.z6, w.z5)
    vx, vy = _dot(w, x6), -sg[5] * _dot(w, z6)
    rows6 = ((x6[0], y6[0], z6[0]), (x6[1], y6[1], z6[1]), (x6[2], y6[2], z6[2]))
    reached = False
    for elbow in range(2):
        c4, s4, big_d, kappa = _elbow(geo, k, s_delta, elbow)
        t4 = math.atan2(s4, c4)
        # w in frame 4 is (X, Y, D) = (-sigma4 kappa, sigma4 d4, D); axis 6
        # needs sigma5 (s5 X - c5 Y) = w . z5: |w . z5| <= rho5 = |(X, Y)|
        big_x, big_y = -sg[3] * kappa, sg[3] * geo.d4
        rho5_2 = big_x * big_x + big_y * big_y
        rho5 = math.sqrt(rho5_2)
        gap = rho5 - abs(wz5)
        if not (gap >= -geo.reach_tol) or (rho5 == 0.0 and wz5 != 0.0):
            continue
        root = common.clamped_root(gap * (rho5 + abs(wz5)))  # |w . x5|
        g5 = sg[4] * wz5
        wrist_flag = WRIST_SINGULAR if root <= SINGULAR_TOL * rho5 else 0
        for wrist in range(2):
            # w . x5 = h: its sign, times label[1], is the wrist's bit
            h = root if (wrist == 1) == (geo.label[1] > 0.0) else -root
            if rho5 > 0.0:
                s5 = (big_y * h + big_x * g5) / rho5_2
                c5 = (big_x * h - big_y * g5) / rho5_2
            else:  # axis 5 through S: theta5 free (self-motion)
                t5 = _free_angle(geo, 4, prev, has_prev)
                s5, c5 = math.sin(t5), math.cos(t5)
            t5 = math.atan2(s5, c5)
            # theta6 turns v onto u = w in frame 5 rotated by Rx(-alpha5)
            ux, uy = c5 * big_x + s5 * big_y, sg[4] * big_d
            y6a, x6a = vx * uy - vy * ux, vx * ux + vy * uy
            n6 = math.sqrt(y6a * y6a + x6a * x6a)
            if n6 > 0.0:
                c6, s6 = x6a / n6, y6a / n6
                t6 = math.atan2(y6a, x6a)
            else:  # W - S along axis 6: theta6 free
                t6 = _free_angle(geo, 5, prev, has_prev)
                c6, s6 = math.cos(t6), math.sin(t6)
            # frame 3: R03 = R06 (R34 R45 R56)^T
            r03 = (
                _times_t(
                    _times_t(_times_t(rows6[0], c6, s6, sg[5]), c5, s5, sg[4]),
                    c4, s4, sg[3],
                ),
                _times_t(
                    _times_t(_times_t(rows6[1], c6, s6, sg[5]), c5, s5, sg[4]),
                    c4, s4, sg[3],
                ),
                _times_t(
                    _times_t(_times_t(rows6[2], c6, s6, sg[5]), c5, s5, sg[4]),
                    c4, s4, sg[3],
                ),
            )  # fmt: skip
            x3 = (r03[0][0], r03[1][0], r03[2][0])
            y3 = (r03[0][1], r03[1][1], r03[2][1])
            # shoulder: axis 3 is z2 = sigma3 y3 = (s2' c1, s2' s1, -s1s2 c2)
            z2x, z2y, z2z = sg[2] * y3[0], sg[2] * y3[1], sg[2] * y3[2]
            h2 = math.sqrt(z2x * z2x + z2y * z2y)
            c2 = -sg[0] * sg[1] * z2z
            if h2 > _SHOULDER_FREE:
                c1, s1 = sg[1] * z2x / h2, sg[1] * z2y / h2
            else:
                t1 = _free_angle(geo, 0, prev, has_prev)
                c1, s1 = math.cos(t1), math.sin(t1)
            t1 = math.atan2(s1, c1)
            t2 = math.atan2(h2, c2)
            c3 = c2 * (c1 * x3[0] + s1 * x3[1]) + sg[0] * h2 * x3[2]
            s3 = sg[0] * sg[1] * (s1 * x3[0] - c1 * x3[1])
            t3 = math.atan2(s3, c3)
            shoulder_flag = SHOULDER_SINGULAR if h2 <= SINGULAR_TOL else 0
            singular = elbow_flag | wrist_flag | shoulder_flag
            for shoulder in range(2):
                # the root sin theta2 >= 0 has the physical sign label[0]
                flip = (shoulder == 1) != (geo.label[0] > 0.0)
                b = 4 * elbow + 2 * wrist + shoulder
                q[b, 0] = common.joint_value(
                    geo, 0, _flip(t1) if flip else t1, prev, has_prev
                )
                q[b, 1] = common.joint_value(
                    geo, 1, -t2 if flip else t2, prev, has_prev
                )
                q[b, 2] = common.joint_value(
                    geo, 2, _flip(t3) if flip else t3, prev, has_prev
                )
                q[b, 3] = common.joint_value(geo, 3, t4, prev, has_prev)
                q[b, 4] = common.joint_value(geo, 4, t5, prev, has_prev)
                q[b, 5] = common.joint_value(geo, 5, t6, prev, has_prev)
                q[b, 6] = value
                within = WITHIN_LIMITS if common.row_within_limits(geo, q, b) else 0
                flags[b] = REACHED | singular | within
            reached = True
    return OK if reached else OUT_OF_REACH


@common.inline
def _framed_rows(geo, pose: FloatArray):
    """Rows 0..2 of base_inv · pose · tool_inv: the pose of DH frame 7."""
    tool, base = common.frames(geo)
    r0, r1, r2 = (
        common.matrix_row(pose, 0),
        common.matrix_row(pose, 1),
        common.matrix_row(pose, 2),
    )
    return common.frame_rows(r0, r1, r2, tool, base, geo.based != 0.0)


@entry_point(outputs=("q", "flags"))
def solve_pose(
    geometry: np.ndarray,
    pose: FloatArray,
    value: float,
    q_previous: FloatArray,
    q: FloatArray,
    flags: npt.NDArray[np.uint8],
    check: bool,
) -> int:
    """All eight branches of one pose for q7 = ``value``.

    Args:
        geometry: From :func:`pack_geometry`.
        pose: (4, 4) pose of the tool frame in the robot's base frame [m].
        value: q7 [rad], the robot's joint value (limits not applied).
        q_previous: (7,) configuration [rad] each angle is taken nearest, or
            (0,) for the representative within the limits (else in (−π, π]).
        q: (8, 7) output [rad], rows in :data:`BRANCHES` order; NaN rows for
            the branches that do not reach.
        flags: (8,) uint8 output, bits of ``_flags``.
        check: Test first that the pose is finite and rigid.

    Returns:
        OK, NOT_RIGID or OUT_OF_REACH (no branch reaches).
    """
    geo = geometry[0]
    if check and not common.is_rigid(pose):
        return NOT_RIGID
    f0, f1, f2 = _framed_rows(geo, pose)
    has_prev = q_previous.shape[0] != 0
    return _solve(geo, f0, f1, f2, value, q_previous, has_prev, q, flags)


@entry_point(outputs=("q", "valid"), contiguous=("poses",))
def solve_batch(
    geometry: np.ndarray,
    poses: FloatArray,
    values: FloatArray,
    q: FloatArray,
    valid: npt.NDArray[np.bool_],
) -> None:
    """All eight branches of N poses, each for its own q7.

    Args:
        geometry: From :func:`pack_geometry`.
        poses: (N, 4, 4) C-contiguous poses of the tool frame [m]; a pose
            that is not finite and rigid gets NaN rows (the framework checks
            its targets before).
        values: (N,) q7 [rad].
        q: (N, 8, 7) output [rad], as :func:`solve_pose` without q_previous.
        valid: (N, 8) output: the branch reaches (limits not applied).
    """
    geo = geometry[0]
    tool, base = common.frames(geo)
    based = geo.based != 0.0
    flags = np.empty(B, dtype=np.uint8)
    none = np.empty(0)
    for i in range(poses.shape[0]):
        pose = poses[i]
        qi = q[i]
        if common.is_rigid(pose):
            r0, r1, r2 = (
                common.matrix_row(pose, 0),
                common.matrix_row(pose, 1),
                common.matrix_row(pose, 2),
            )
            f0, f1, f2 = common.frame_rows(r0, r1, r2, tool, base, based)
            _solve(geo, f0, f1, f2, values[i], none, False, qi, flags)
        else:
            for b in range(B):
                for j in range(7):
                    qi[b, j] = np.nan
        for b in range(B):
            valid[i, b] = qi[b, 0] == qi[b, 0]


@entry_point(outputs=("out",))
def parameter_of(geometry: np.ndarray, q: FloatArray, out: FloatArray) -> None:
    """q7 of N configurations: ``q`` (N, 7) [rad] → ``out`` (N,) [rad]."""
    for i in range(q.shape[0]):
        out[i] = q[i, 6]


@entry_point()
def diagnose(
    geometry: np.ndarray, pose: FloatArray, value: float
) -> tuple[int, float, float, float]:
    """Why no branch reaches a pose for q7 = ``value``.

    Returns:
        ``(status, distance, low, high)``: the status of :func:`solve_pose`
        (checked), the distance |W − S| [m] of the wrist point from the
        shoulder for this q7 and the elbow's reach
        [√((L24 − L46)² + d4²), √((L24 + L46)² + d4²)] [m]. A distance
        within the reach with OUT_OF_REACH means that axis 6 cannot be
        normal to axis 5 there (|w · z5| > √(κ² + d4²), both elbows).
    """
    geo = geometry[0]
    if not common.is_rigid(pose):
        return NOT_RIGID, 0.0, 0.0, 0.0
    f0, f1, f2 = _framed_rows(geo, pose)
    w = _arm(geo, f0, f1, f2, value)[3]
    q = np.empty((B, 7))
    flags = np.empty(B, dtype=np.uint8)
    status = _solve(geo, f0, f1, f2, value, np.empty(0), False, q, flags)
    l24, l46, d4s = math.sqrt(geo.l24s), math.sqrt(geo.l46s), geo.d4 * geo.d4
    low, high = math.sqrt((l24 - l46) ** 2 + d4s), math.sqrt((l24 + l46) ** 2 + d4s)
    return status, math.sqrt(_dot(w, w)), low, high


@entry_point(outputs=("q_out",))
def track(
    geometry: np.ndarray,
    pose: FloatArray,
    value: float,
    q_predicted: FloatArray,
    branch: int,
    max_step2: float,
    q_out: FloatArray,
) -> tuple[int, int, bool]:
    """The branch continuing a motion at ``q_predicted``.

    Args:
        geometry: From :func:`pack_geometry`.
        pose: (4, 4) target pose of the tool frame [m].
        value: q7 [rad].
        q_predicted: (7,) predicted configuration [rad]; every angle is the
            representative nearest it.
        branch: Index of the last branch.
        max_step2: Largest squared joint step [rad²] that keeps the branch.
        q_out: (7,) output configuration [rad] (undefined unless OK).

    Returns:
        ``(status, index, within)``: as :func:`solve_pose` (checked); the
        branch ``branch`` if it reaches within ``max_step2``, else the nearest
        reached one (the first on a tie); whether it is within the limits.
    """
    geo = geometry[0]
    q = np.empty((B, 7))
    flags = np.empty(B, dtype=np.uint8)
    if not common.is_rigid(pose):
        return NOT_RIGID, -1, False
    f0, f1, f2 = _framed_rows(geo, pose)
    status = _solve(geo, f0, f1, f2, value, q_predicted, True, q, flags)
    if status != OK:
        return status, -1, False
    best, best_d2 = -1, math.inf
    for b in range(B):
        d2 = 0.0
        for j in range(7):
            d = q[b, j] - q_predicted[j]
            d2 += d * d
        if d2 == d2 and (d2 < best_d2 or (b == branch and d2 <= max_step2)):
            best, best_d2 = b, d2
            if b == branch and d2 <= max_step2:
                break
    for j in range(7):
        q_out[j] = q[best, j]
    return status, best, flags[best] & WITHIN_LIMITS != 0


@entry_point(outputs=("out",))
def reach_margins(
    geometry: np.ndarray, pose: FloatArray, values: FloatArray, out: FloatArray
) -> None:
    """How far one pose is within the reach, for N values of q7.

    Args:
        geometry: From :func:`pack_geometry`.
        pose: (4, 4) pose of the tool frame [m], finite and rigid.
        values: (N,) q7 [rad].
        out: (N, 3) output: 1 − k² (k = cos(θ4 + φ): the elbow reaches where
            ≥ 0), then (κ² + d4² − (w · z5)²) / |w|² for elbow 0 and 1 (the
            wrists of that elbow reach where ≥ 0; the elbow's margin where the
            elbow does not reach). Smooth in q7, unitless.
    """
    geo = geometry[0]
    f0, f1, f2 = _framed_rows(geo, pose)
    for i in range(values.shape[0]):
        arm = _arm(geo, f0, f1, f2, values[i])
        r2, k, wz5 = arm[4], arm[5], arm[6]
        elbow = (1.0 - k) * (1.0 + k)
        out[i, 0] = elbow
        s_delta = common.clamped_root(elbow)
        for e in range(2):
            kappa = _elbow(geo, common.clip_unit(k), s_delta, e)[3]
            margin = (kappa * kappa + geo.d4 * geo.d4 - wz5 * wz5) / r2
            out[i, 1 + e] = margin if elbow >= 0.0 else elbow
