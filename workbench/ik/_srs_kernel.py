r"""Compiled closed form of SRS seven-axis arms (KUKA LBR iiwa): eight branches per ψ.

The arm is the fitted chain base · DH(θ) · tool of :mod:`workbench.ik.structure`
(family ``"srs"``): a = 0 in every row, α1..α6 = σ_k π/2 (σ_k = ±1), α7 = 0,
d2 = d4 = d6 = 0. The shoulder S = (0, 0, d1) (frame 0) is where axes 1, 2, 3
meet, the elbow E = S + d3 z2 where axes 3, 4, 5 meet, the wrist centre
W = E + d5 z4 where axes 5, 6, 7 meet, and the flange is W + d7 z7. With
:math:`M = B^{-1} T E^{-1}` (R, p) the target of the DH chain:

* W = p − d7 R e_z; L = |SW|; u = SW / L;
* θ4 from L by the law of cosines: L² = d3² + d5² − 2 σ3 σ4 d3 d5 cos θ4
  (z2 · z4 = −σ3 σ4 cos θ4), two elbows ±θ4;
* the reference shoulder R03° (Shimizu et al., IEEE T-RO 24(5), 2008): the
  arm with θ3 = 0 and θ4 = +|θ4| reaching W, with θ1° = atan2(SW_y, SW_x)
  (0 when W is on axis 1, the algorithmic singularity) and θ2° solving
  ``[ρ, σ1 SW_z] = [[v_x, σ2 v_z], [−σ2 v_z, v_x]] [c2, s2]``, where
  v = (σ4 s4 d5, 0, d3 − σ3 σ4 c4 d5) is SW in frame 2 and ρ = |SW_xy|;
* the arm angle ψ turns the shoulder about u: R03 = R_u(ψ) R03° (elbow-pos)
  and R03 = R_u(ψ) R03° D (elbow-neg), D = diag(−1, 1, −1): the elbow-neg
  arm with the same elbow point has θ3 + π and −θ4, and R23(θ3 + π) =
  R23(θ3) D. So R03 = A_s sin ψ + B_s cos ψ + C_s with A_s = [u]× R03°,
  B_s = −[u]×² R03°, C_s = u uᵀ R03° (times D for elbow-neg), and every
  branch with the same ψ has the same elbow point;
* θ2 = ±atan2(|z2_xy|, −σ1 σ2 σ3 R03[2, 1]) (shoulder sign), θ1 from
  z2 = σ3 R03[:, 1] = σ2 (c1 s2, s1 s2, −σ1 c2), θ3 from R02ᵀ R03[:, 0] =
  (c3, s3, 0);
* R47 = R04ᵀ R: z7 = R47 e_z = σ6 (c5 s6, s5 s6, −σ5 c6) gives θ6 (wrist
  sign) and θ5, and row 2 of R57 = R45ᵀ R47, σ6 (s7, c7, 0), gives θ7.

ψ is therefore the angle, right-handed about u, from the reference half-plane
(bounded by the line SW, containing the reference elbow E0 = S + d3 z2°) to the
half-plane of the arm's elbow E: one elbow point per ψ, shared by all eight
branches (Shimizu's own reference uses θ4 of the branch, which puts the
elbow-neg branches' ψ at π from ours: ``docs/seven-axis.md``, errata). At the
stretched elbow (E on SW) the rotation R_u(ψ) of the shoulder still defines ψ.

Branch ``b = 4·(θ2 < 0) + 2·(θ4 < 0) + (θ6 < 0)``, DH angles of the fitted
chain; labels :data:`BRANCHES`. Status codes and flag bits are those of
:mod:`workbench.ik._redundant_common`; the joint values and their limits those
of :mod:`workbench.ik._kernel_common` (``joint_value``), limits widened by
``LIMIT_TOL``. The feasible arm angles are
:mod:`workbench.ik._srs_intervals` (``compute_feasible_intervals``), which
calls these kernels.
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
    PARAMETER_SINGULAR,
    REACHED,
    SHOULDER_SINGULAR,
    WITHIN_LIMITS,
    WRIST_SINGULAR,
)
from workbench.ik.structure import KinematicStructure

FloatArray = npt.NDArray[np.float64]

#: Branch labels, index ``4·(θ2 < 0) + 2·(θ4 < 0) + (θ6 < 0)`` (DH angles of the
#: fitted chain; "pos" includes 0).
BRANCHES: tuple[str, ...] = tuple(
    f"shoulder-{s}/elbow-{e}/wrist-{w}"
    for s in ("pos", "neg")
    for e in ("pos", "neg")
    for w in ("pos", "neg")
)
#: The redundancy parameter, as messages name it.
PARAMETER = "arm angle"
#: |sin θ2|, |sin θ6| at or below which a branch is flagged shoulder, wrist
#: singular; |SW_xy| / |SW| at or below which the arm angle is flagged
#: PARAMETER_SINGULAR (W on axis 1).
SINGULAR_TOL = 1e-10
#: |sin θ4| at or below which a branch is flagged elbow singular: the law of
#: cosines gives cos θ4 to a few ulps, so |sin θ4| only to about 3e-8 at the
#: stretched elbow (a pose computed at θ4 = 0 may give |sin θ4| = 1.5e-8).
ELBOW_SINGULAR_TOL = 1e-7
#: |sin θ2| (|sin θ6|) at or below which a given ``q_previous`` fixes θ1 (θ5):
#: there the pose leaves θ1 − ±θ3 (θ5 − ±θ7) to rounding (an error of about
#: 1e-16 / |sin|, above 1e-3 rad), and keeping θ1 costs at most this times π
#: times the arm's lengths of position (orientation) error.
SPLIT_TOL = 1e-13
#: Slack of the law of cosines: |cos θ4| up to 1 + this is clipped to 1 (a pose
#: at the stretched elbow rounded outward), beyond it the pose is out of reach.
REACH_TOL = 1e-12

GEOMETRY_DTYPE = np.dtype(
    [
        ("sigma", "f8", 6),  # sign of alpha_1..6
        ("d1", "f8"),
        ("d3", "f8"),
        ("d5", "f8"),
        ("d7", "f8"),
        ("reach_tol", "f8"),  # REACH_TOL plus the model's error, on cos θ4
        ("based", "f8"),  # 1.0 when base_inv is not the identity
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
    """The constants of an SRS arm as a read-only (1,) record array.

    Args:
        structure: Its fitted structure (family ``"srs"``, seven DH rows).
        lower: Lower joint limits, (7,) [rad].
        upper: Upper joint limits, (7,) [rad].
    """
    j = structure.table.joints
    g = np.zeros(1, dtype=GEOMETRY_DTYPE)
    g["sigma"] = [math.copysign(1.0, x.alpha) for x in j[:6]]
    g["d1"], g["d3"], g["d5"], g["d7"] = j[0].d, j[2].d, j[4].d, j[6].d
    model_slack = MODEL_ERROR_SLACK * structure.residual
    g["reach_tol"] = REACH_TOL + model_slack * (abs(j[2].d) + abs(j[4].d)) / abs(
        j[2].d * j[4].d
    )
    common.pack_joint_fields(g, structure, lower, upper, LIMIT_TOL)
    g.setflags(write=False)
    return g


def parameter_range(geometry: np.ndarray) -> tuple[float, float]:
    """The range of the arm angle [rad]: (−π, π] (every value is reached)."""
    return -math.pi, math.pi


@common.inline
def _framed_target(geo, pose: FloatArray, tool, base, based: bool):
    """Rotation (9,) row-major and SW [m] of ``base_inv · pose · tool_inv``."""
    r0, r1, r2 = common.frame_rows(
        common.matrix_row(pose, 0),
        common.matrix_row(pose, 1),
        common.matrix_row(pose, 2),
        tool,
        base,
        based,
    )
    return _wrist_point(geo, r0, r1, r2)


@common.inline
def _wrist_point(geo, r0, r1, r2):
    """Rotation (9,) row-major, SW (3,) [m] and L = |SW| of the framed rows."""
    d7 = geo.d7
    rot = (r0[0], r0[1], r0[2], r1[0], r1[1], r1[2], r2[0], r2[1], r2[2])
    swx = r0[3] - d7 * r0[2]
    swy = r1[3] - d7 * r1[2]
    swz = r2[3] - d7 * r2[2] - geo.d1
    return rot, (swx, swy, swz)


@common.inline
def _elbow_cosine(geo, length2: float) -> float:
    """The cosine of θ4 by the law of cosines for L² = |SW|² (unclipped)."""
    d3, d5 = geo.d3, geo.d5
    return geo.sigma[2] * geo.sigma[3] * (d3 * d3 + d5 * d5 - length2) / (2.0 * d3 * d5)


@common.inline
def _reference(geo, sw, c4: float, s4: float):
    """Columns of R03° (θ3 = 0, θ4 = atan2(s4 ≥ 0, c4)) and ρ = |SW_xy|.

    θ1° = atan2(SW_y, SW_x); within the algorithmic singularity (ρ at most
    SINGULAR_TOL |SW|) θ1° = 0, and the reference arm, built for SW turned
    into the plane y = 0, is turned back onto SW by the least rotation (an
    angle below SINGULAR_TOL), so that it reaches W exactly. Returns
    ``(col0, col1, col2, rho)``; the columns as 3-tuples in frame 0.
    """
    s1g, s2g, s3g, s4g = geo.sigma[0], geo.sigma[1], geo.sigma[2], geo.sigma[3]
    swx, swy, swz = sw
    vx = s4g * s4 * geo.d5
    vz = geo.d3 - s3g * s4g * c4 * geo.d5
    rho = math.sqrt(swx * swx + swy * swy)
    length = math.sqrt(rho * rho + swz * swz)
    on_axis = rho <= SINGULAR_TOL * length
    c1 = 1.0 if on_axis else swx / rho
    s1 = 0.0 if on_axis else swy / rho
    c2 = vx * rho - s2g * vz * s1g * swz
    s2 = s2g * vz * rho + vx * s1g * swz
    h = math.sqrt(c2 * c2 + s2 * s2)
    c2, s2 = (c2 / h, s2 / h) if h > 0.0 else (1.0, 0.0)
    # R02 columns; R03° = R02 R23(0): col0 = R02 col0, col1 = σ3 R02 col2,
    # col2 = −σ3 R02 col1
    a0 = (c1 * c2, s1 * c2, s1g * s2)
    a1 = (s1g * s2g * s1, -s1g * s2g * c1, 0.0)
    a2 = (s2g * c1 * s2, s2g * s1 * s2, -s1g * s2g * c2)
    col1 = (s3g * a2[0], s3g * a2[1], s3g * a2[2])
    col2 = (-s3g * a1[0], -s3g * a1[1], -s3g * a1[2])
    if on_axis and rho > 0.0:  # turn (ρ, 0, SW_z) onto SW
        inv = 1.0 / (length * length)
        v = (-swz * swy * inv, swz * (swx - rho) * inv, rho * swy * inv)
        k = 1.0 / (1.0 + (rho * swx + swz * swz) * inv)
        a0, col1, col2 = (
            _least_turn(v, k, a0),
            _least_turn(v, k, col1),
            _least_turn(v, k, col2),
        )
    return a0, col1, col2, rho


@common.inline
def _least_turn(v, k: float, x):
    """The rotation taking a to b applied to x, v = a × b, k = 1 / (1 + a · b).

    x + v × x + k v × (v × x) (Rodrigues' formula of the least rotation).
    """
    w = (
        v[1] * x[2] - v[2] * x[1],
        v[2] * x[0] - v[0] * x[2],
        v[0] * x[1] - v[1] * x[0],
    )
    ww = (
        v[1] * w[2] - v[2] * w[1],
        v[2] * w[0] - v[0] * w[2],
        v[0] * w[1] - v[1] * w[0],
    )
    return (x[0] + w[0] + k * ww[0], x[1] + w[1] + k * ww[1], x[2] + w[2] + k * ww[2])


@common.inline
def _turn(u, x, c: float, s: float):
    """R_u(ψ) x (Rodrigues), c = cos ψ, s = sin ψ."""
    ux, uy, uz = u
    k = (1.0 - c) * (ux * x[0] + uy * x[1] + uz * x[2])
    return (
        c * x[0] + s * (uy * x[2] - uz * x[1]) + k * ux,
        c * x[1] + s * (uz * x[0] - ux * x[2]) + k * uy,
        c * x[2] + s * (ux * x[1] - uy * x[0]) + k * uz,
    )


@common.inline
def _dh_angle(geo, j: int, prev: FloatArray) -> float:
    """The DH angle of joint ``j`` of the configuration ``prev`` [rad]."""
    return geo.joint_sign[j] * prev[j] + geo.theta_offset[j]


@common.inline
def _shoulder(geo, c0, c1, gc2: float, prev: FloatArray, has_prev: bool):
    """(θ1, θ2, θ3, |s2|) of one shoulder sign ``gc2`` (±1) from R03 columns."""
    s1g, s2g, s3g = geo.sigma[0], geo.sigma[1], geo.sigma[2]
    zx, zy = s2g * s3g * c1[0], s2g * s3g * c1[1]  # = s2 (c1, s1)
    h = math.sqrt(zx * zx + zy * zy)
    c2 = -s1g * s2g * s3g * c1[2]
    s2 = gc2 * h
    if has_prev and h <= SPLIT_TOL:  # axes 1 and 3 aligned: θ1 kept
        t1 = _dh_angle(geo, 0, prev)
        cos1, sin1 = math.cos(t1), math.sin(t1)
    elif h > 0.0:
        cos1, sin1 = gc2 * zx / h, gc2 * zy / h
        t1 = math.atan2(sin1, cos1)
    else:
        cos1, sin1, t1 = 1.0, 0.0, 0.0
    t2 = math.atan2(s2, c2)
    # (c3, s3) = (R02 col0, R02 col1) · R03 col0
    c3 = cos1 * c2 * c0[0] + sin1 * c2 * c0[1] + s1g * s2 * c0[2]
    s3 = s1g * s2g * (sin1 * c0[0] - cos1 * c0[1])
    return t1, t2, math.atan2(s3, c3), h


@common.inline
def _wrist(geo, r47, gc6: float, prev: FloatArray, has_prev: bool):
    """(θ5, θ6, θ7, |s6|) of one wrist sign ``gc6`` (±1); r47 row-major (9,)."""
    s5g, s6g = geo.sigma[4], geo.sigma[5]
    zx, zy = s6g * r47[2], s6g * r47[5]  # = s6 (c5, s5)
    h = math.sqrt(zx * zx + zy * zy)
    c6 = -s5g * s6g * r47[8]
    if has_prev and h <= SPLIT_TOL:  # axes 5 and 7 aligned: θ5 kept
        t5 = _dh_angle(geo, 4, prev)
        cos5, sin5 = math.cos(t5), math.sin(t5)
    elif h > 0.0:
        cos5, sin5 = gc6 * zx / h, gc6 * zy / h
        t5 = math.atan2(sin5, cos5)
    else:
        cos5, sin5, t5 = 1.0, 0.0, 0.0
    # row 2 of R57 = σ5 (s5 row0 − c5 row1) of R47 = σ6 (s7, c7, 0)
    v0 = s5g * (sin5 * r47[0] - cos5 * r47[3])
    v1 = s5g * (sin5 * r47[1] - cos5 * r47[4])
    return t5, math.atan2(gc6 * h, c6), math.atan2(s6g * v0, s6g * v1), h


@common.inline
def _twin(angles):
    """The twin of a spherical joint's (a, b, c, |sin b|): (a + π, −b, c + π, ·)."""
    return (
        common.remainder(angles[0] + common.PI),
        -angles[1],
        common.remainder(angles[2] + common.PI),
        angles[3],
    )


@common.inline
def _elbow_frames(geo, rot, r03, e: float, c4: float, s4: float):
    """Column 0 of R03 and R47 = R04ᵀ R (row-major (9,)) of one elbow.

    ``r03``: the columns of R_u(ψ) R03° (elbow-pos); ``e`` = ±1 the elbow
    sign (elbow-neg: R03 D, D = diag(−1, 1, −1)); ``s4`` = |sin θ4|.
    """
    b0, b1, b2 = r03
    s4g = geo.sigma[3]
    c0 = (e * b0[0], e * b0[1], e * b0[2])
    c2 = (e * b2[0], e * b2[1], e * b2[2])
    # R04 = R03 R34(e θ4): columns c4 c0 + e s4 c1, σ4 c2, σ4 (e s4 c0 − c4 c1)
    es4 = e * s4
    x4 = (c4 * c0[0] + es4 * b1[0], c4 * c0[1] + es4 * b1[1], c4 * c0[2] + es4 * b1[2])
    y4 = (s4g * c2[0], s4g * c2[1], s4g * c2[2])
    z4 = (
        s4g * (es4 * c0[0] - c4 * b1[0]),
        s4g * (es4 * c0[1] - c4 * b1[1]),
        s4g * (es4 * c0[2] - c4 * b1[2]),
    )
    r47 = (
        x4[0] * rot[0] + x4[1] * rot[3] + x4[2] * rot[6],
        x4[0] * rot[1] + x4[1] * rot[4] + x4[2] * rot[7],
        x4[0] * rot[2] + x4[1] * rot[5] + x4[2] * rot[8],
        y4[0] * rot[0] + y4[1] * rot[3] + y4[2] * rot[6],
        y4[0] * rot[1] + y4[1] * rot[4] + y4[2] * rot[7],
        y4[0] * rot[2] + y4[1] * rot[5] + y4[2] * rot[8],
        z4[0] * rot[0] + z4[1] * rot[3] + z4[2] * rot[6],
        z4[0] * rot[1] + z4[1] * rot[4] + z4[2] * rot[7],
        z4[0] * rot[2] + z4[1] * rot[5] + z4[2] * rot[8],
    )
    return c0, r47


@common.inline
def _branches(geo, rot, sw, value, prev, has_prev, q, flags, with_flags):
    """All eight branches of one framed target; returns the status.

    ``rot`` (9,) row-major rotation and ``sw`` the wrist point from S, both in
    frame 0; ``q`` (8, 7) out (robot joint values); ``flags`` (8,) uint8 out,
    written if ``with_flags``.
    """
    swx, swy, swz = sw
    length2 = swx * swx + swy * swy + swz * swz
    c4 = _elbow_cosine(geo, length2)
    if not (abs(c4) <= 1.0 + geo.reach_tol):
        return OUT_OF_REACH
    c4 = common.clip_unit(c4)
    s4 = common.clamped_root((1.0 - c4) * (1.0 + c4))
    t4 = math.atan2(s4, c4)
    col0, col1, col2, rho = _reference(geo, sw, c4, s4)
    length = math.sqrt(length2)
    # (W at S, only when d3 = ±d5 and folded: any axis will do)
    u = (swx / length, swy / length, swz / length) if length > 0.0 else (0.0, 0.0, 1.0)
    cp, sp = math.cos(value), math.sin(value)
    b0, b1, b2 = _turn(u, col0, cp, sp), _turn(u, col1, cp, sp), _turn(u, col2, cp, sp)
    param = rho <= SINGULAR_TOL * length
    for elbow in range(2):
        e = 1.0 if elbow == 0 else -1.0
        c0, r47 = _elbow_frames(geo, rot, (b0, b1, b2), e, c4, s4)
        q4 = common.joint_value(geo, 3, e * t4, prev, has_prev)
        shoulder = _shoulder(geo, c0, b1, 1.0, prev, has_prev)
        h2 = shoulder[3]
        wrist = _wrist(geo, r47, 1.0, prev, has_prev)
        h6 = wrist[3]
        for side in range(2):
            if side == 1:  # the twins: (θ1 + π, −θ2, θ3 + π), (θ5 + π, −θ6, θ7 + π)
                shoulder = _twin(shoulder)
                wrist = _twin(wrist)
                if has_prev and h2 <= SPLIT_TOL:
                    shoulder = _shoulder(geo, c0, b1, -1.0, prev, has_prev)
                if has_prev and h6 <= SPLIT_TOL:
                    wrist = _wrist(geo, r47, -1.0, prev, has_prev)
            q1 = common.joint_value(geo, 0, shoulder[0], prev, has_prev)
            q2 = common.joint_value(geo, 1, shoulder[1], prev, has_prev)
            q3 = common.joint_value(geo, 2, shoulder[2], prev, has_prev)
            q5 = common.joint_value(geo, 4, wrist[0], prev, has_prev)
            q6 = common.joint_value(geo, 5, wrist[1], prev, has_prev)
            q7 = common.joint_value(geo, 6, wrist[2], prev, has_prev)
            for other in range(2):
                b = 4 * side + 2 * elbow + other  # shoulder `side`
                q[b, 0], q[b, 1], q[b, 2], q[b, 3] = q1, q2, q3, q4
                b = 4 * other + 2 * elbow + side  # wrist `side`
                q[b, 4], q[b, 5], q[b, 6] = q5, q6, q7
        if with_flags:
            for k in range(4):
                b = 4 * (k >> 1) + 2 * elbow + (k & 1)
                ok = common.row_within_limits(geo, q, b)
                bits = REACHED | (WITHIN_LIMITS if ok else 0)
                bits |= SHOULDER_SINGULAR if h2 <= SINGULAR_TOL else 0
                bits |= ELBOW_SINGULAR if s4 <= ELBOW_SINGULAR_TOL else 0
                bits |= WRIST_SINGULAR if h6 <= SINGULAR_TOL else 0
                bits |= PARAMETER_SINGULAR if param else 0
                flags[b] = bits
    return OK


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
    """All eight branches of one pose for one arm angle.

    Args:
        geometry: The arm's (1,) record (:func:`pack_geometry`).
        pose: (4, 4) pose of the tool frame in the robot's base frame [m].
        value: Arm angle ψ [rad].
        q_previous: (7,) configuration [rad] each angle is taken nearest to
            (and θ1 or θ5 from, within SPLIT_TOL of a shoulder or wrist
            singularity), or (0,).
        q: (8, 7) output, robot joint values [rad], branch order
            :data:`BRANCHES`; NaN rows when the pose is out of reach.
        flags: (8,) uint8 output, bits of ``_flags``.
        check: Test first that the pose is finite and rigid.

    Returns:
        OK, NOT_RIGID or OUT_OF_REACH (then ``q`` is NaN, ``flags`` 0).
    """
    geo = geometry[0]
    if check and not common.is_rigid(pose):
        q[:] = np.nan
        flags[:] = 0
        return NOT_RIGID
    tool, base = common.frames(geo)
    rot, sw = _framed_target(geo, pose, tool, base, geo.based != 0.0)
    previous = np.empty(q_previous.shape[0])
    for j in range(q_previous.shape[0]):
        previous[j] = q_previous[j]
    status = _branches(
        geo, rot, sw, value, previous, previous.shape[0] != 0, q, flags, True
    )
    if status != OK:
        q[:] = np.nan
        flags[:] = 0
    return status


@entry_point(outputs=("q", "valid"), contiguous=("poses", "values"))
def solve_batch(
    geometry: np.ndarray,
    poses: FloatArray,
    values: FloatArray,
    q: FloatArray,
    valid: npt.NDArray[np.bool_],
) -> None:
    """All eight branches of N poses, each for its own arm angle (no limits).

    Args:
        geometry: The arm's (1,) record.
        poses: (N, 4, 4) C-contiguous poses of the tool frame [m].
        values: (N,) arm angles [rad].
        q: (N, 8, 7) output [rad], each angle in (−π, π] or its
            representative within the limits; NaN where not reached.
        valid: (N, 8) output: the branch reaches the pose.
    """
    geo = geometry[0]
    tool, base = common.frames(geo)
    based = geo.based != 0.0
    none = np.empty(0)
    no_flags = np.empty(0, dtype=np.uint8)
    for i in range(poses.shape[0]):
        pose = poses[i]
        rot, sw = _framed_target(geo, pose, tool, base, based)
        status = _branches(geo, rot, sw, values[i], none, False, q[i], no_flags, False)
        reached = status == OK
        for b in range(8):
            valid[i, b] = reached
        if not reached:
            q[i] = np.nan


@common.inline
def _dh_rotation(geo, j: int, theta: float):
    """Columns of Rz(θ) Rx(α_j), α_j = σ_j π/2 (j < 6), as 3-tuples."""
    c, s = math.cos(theta), math.sin(theta)
    sg = geo.sigma[j]
    return (c, s, 0.0), (0.0, 0.0, sg), (sg * s, -sg * c, 0.0)


@common.inline
def _times(a, b):
    """Product of two rotations given as column 3-tuples."""
    return _apply(a, b[0]), _apply(a, b[1]), _apply(a, b[2])


@common.inline
def _apply(a, x):
    """A rotation (column 3-tuples) times a vector."""
    a0, a1, a2 = a
    return (
        a0[0] * x[0] + a1[0] * x[1] + a2[0] * x[2],
        a0[1] * x[0] + a1[1] * x[1] + a2[1] * x[2],
        a0[2] * x[0] + a1[2] * x[1] + a2[2] * x[2],
    )


@common.inline
def _arm_angle(geo, theta: FloatArray) -> float:
    """ψ [rad] of DH angles ``theta`` (7,) (module docstring)."""
    r01 = _dh_rotation(geo, 0, theta[0])
    r02 = _times(r01, _dh_rotation(geo, 1, theta[1]))
    r03 = _times(r02, _dh_rotation(geo, 2, theta[2]))
    c4, s4 = math.cos(theta[3]), math.sin(theta[3])
    # SW = d3 z2 + d5 z4, z4 = R03 (σ4 s4, −σ4 c4, 0)
    s4g, d3, d5 = geo.sigma[3], geo.d3, geo.d5
    sw = (
        d3 * r02[2][0] + d5 * s4g * (s4 * r03[0][0] - c4 * r03[1][0]),
        d3 * r02[2][1] + d5 * s4g * (s4 * r03[0][1] - c4 * r03[1][1]),
        d3 * r02[2][2] + d5 * s4g * (s4 * r03[0][2] - c4 * r03[1][2]),
    )
    e = math.copysign(1.0, s4)  # (−0.0: the kernel's stretched elbow-neg)
    col0, col1, col2, _ = _reference(geo, sw, c4, abs(s4))
    a0, a1, a2 = r03
    a0 = (e * a0[0], e * a0[1], e * a0[2])
    a2 = (e * a2[0], e * a2[1], e * a2[2])
    # R_u(ψ) = R03 D R03°ᵀ: sin ψ u = vee(R − Rᵀ) / 2, cos ψ = (tr R − 1) / 2
    # (entries r_ik = a0_i col0_k + a1_i col1_k + a2_i col2_k as scalars: no array)
    r00 = a0[0] * col0[0] + a1[0] * col1[0] + a2[0] * col2[0]
    r01 = a0[0] * col0[1] + a1[0] * col1[1] + a2[0] * col2[1]
    r02 = a0[0] * col0[2] + a1[0] * col1[2] + a2[0] * col2[2]
    r10 = a0[1] * col0[0] + a1[1] * col1[0] + a2[1] * col2[0]
    r11 = a0[1] * col0[1] + a1[1] * col1[1] + a2[1] * col2[1]
    r12 = a0[1] * col0[2] + a1[1] * col1[2] + a2[1] * col2[2]
    r20 = a0[2] * col0[0] + a1[2] * col1[0] + a2[2] * col2[0]
    r21 = a0[2] * col0[1] + a1[2] * col1[1] + a2[2] * col2[1]
    r22 = a0[2] * col0[2] + a1[2] * col1[2] + a2[2] * col2[2]
    length = math.sqrt(sw[0] * sw[0] + sw[1] * sw[1] + sw[2] * sw[2])
    sin_psi = (sw[0] * (r21 - r12) + sw[1] * (r02 - r20) + sw[2] * (r10 - r01)) / (
        2.0 * length
    )
    cos_psi = 0.5 * (r00 + r11 + r22 - 1.0)
    return math.atan2(sin_psi, cos_psi)


@entry_point(outputs=("out",))
def parameter_of(geometry: np.ndarray, q: FloatArray, out: FloatArray) -> None:
    """The arm angle ψ [rad] of N configurations.

    Args:
        geometry: The arm's (1,) record.
        q: (N, 7) robot joint values [rad].
        out: (N,) output, ψ in [−π, π]; with W on axis 1 the reference takes
            θ1° = 0 (always finite).
    """
    geo = geometry[0]
    theta = np.empty(7)
    for i in range(q.shape[0]):
        for j in range(7):
            theta[j] = geo.joint_sign[j] * q[i, j] + geo.theta_offset[j]
        out[i] = _arm_angle(geo, theta)


@entry_point()
def diagnose(
    geometry: np.ndarray, pose: FloatArray, value: float
) -> tuple[int, float, float, float]:
    """Why no branch reaches a pose (the arm angle does not matter for SRS arms).

    Returns:
        ``(status, distance, low, high)``: OUT_OF_REACH with |SW| [m], the
        distance of the wrist centre from the shoulder, and the reach
        [||d3| − |d5||, |d3| + |d5|] [m]; NOT_RIGID (zeros); else (OK, |SW|,
        low, high).
    """
    geo = geometry[0]
    if not common.is_rigid(pose):
        return NOT_RIGID, 0.0, 0.0, 0.0
    tool, base = common.frames(geo)
    _, sw = _framed_target(geo, pose, tool, base, geo.based != 0.0)
    length2 = sw[0] * sw[0] + sw[1] * sw[1] + sw[2] * sw[2]
    d3, d5 = abs(geo.d3), abs(geo.d5)
    reached = abs(_elbow_cosine(geo, length2)) <= 1.0 + geo.reach_tol
    return (OK if reached else OUT_OF_REACH), math.sqrt(length2), abs(d3 - d5), d3 + d5


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

    Solves with ``q_predicted`` as ``q_previous``; keeps ``branch`` if its
    squared joint step is at most ``max_step2`` [rad²], else takes the nearest
    of all eight (the first on a tie).

    Returns:
        ``(status, index, within_limits)``; ``q_out`` (7,) the configuration
        [rad] (undefined unless OK; index −1 then).
    """
    q = np.empty((8, 7))
    flags = np.empty(8, dtype=np.uint8)
    status = solve_pose(geometry, pose, value, q_predicted, q, flags, True)
    if status != OK:
        return status, -1, False
    index = common.nearest_or_kept(q, q_predicted, branch, max_step2)
    for j in range(7):
        q_out[j] = q[index, j]
    return status, index, (flags[index] & WITHIN_LIMITS) != 0


__all__ = [
    "BRANCHES",
    "ELBOW_SINGULAR_TOL",
    "PARAMETER",
    "SINGULAR_TOL",
    "diagnose",
    "pack_geometry",
    "parameter_of",
    "parameter_range",
    "solve_batch",
    "solve_pose",
    "track",
]
