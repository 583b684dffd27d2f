r"""Compiled closed form of UR-type arms (axes 2, 3, 4 parallel): all eight branches.

The arm is the fitted chain base · DH(θ) · tool of
:mod:`workbench.ik.structure` with α1, α4, α5 = ±90°, α2 = α3 = 0, a5 = 0 and
an empty last row, so the target of the DH chain is
:math:`M = B^{-1} T E^{-1}` and the wrist point (axes 5 and 6 meet there) is
its origin p. With σ_i the sign of α_i and :math:`D = d_2 + d_3 + d_4`:

* θ1: z1 = σ1 (s1, −c1, 0) and z1 · p = D (every link but the first moves
  in planes ⊥ z1), two solutions, none inside the cylinder r < |D|;
* θ5: z1 · z5 = −σ4 σ5 c5, two solutions ±θ5;
* θ6: z1 in the tool frame is (σ4 s5 c6, −σ4 s5 s6, ·); free when s5 = 0
  (wrist singular);
* θ2 + θ3 + θ4 and the planar two-link arm (a2, a3) to the origin of frame 3,
  two elbows.

Labels follow the PUMA's (``closed_form`` module docs): shoulder right / left
(σ1 D x > 0, x the wrist point along x1), elbow up / down (the elbow above /
below the line from the shoulder to the origin of frame 3, heights along z0),
wrist up / down (σ5 sin θ5 > 0 / < 0: z5 along +x4 / −x4). Branch ``b`` =
4·left + 2·down + wrist-down.

Like ``_puma_kernel``, every angle is an atan2 of arguments computed first, so
that a batch makes all atan2 calls in one vectorised loop, and the batch's
first stage (:func:`batch_arguments`) is :func:`angle_arguments` rewritten for
LLVM's loop vectoriser, bitwise equal (poses with a singular wrist or the
wrist point on the base axis go to :func:`angle_arguments`). Status codes,
flag slots and the helpers both closed forms use are those of
:mod:`workbench.ik._kernel_common`.
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
from workbench.ik._puma import (
    ELBOW_SINGULAR_TOL,
    LIMIT_TOL,
    MODEL_ERROR_SLACK,
    WRIST_SINGULAR_TOL,
)
from workbench.ik.structure import KinematicStructure

FloatArray = npt.NDArray[np.float64]

GEOMETRY_DTYPE = np.dtype(
    [
        ("sigma1", "f8"),
        ("sigma4", "f8"),
        ("sigma5", "f8"),
        ("offset", "f8"),  # D = d2 + d3 + d4
        ("d1", "f8"),
        ("a1", "f8"),
        ("a2", "f8"),
        ("a3", "f8"),
        ("a4", "f8"),
        ("d5", "f8"),
        ("based", "f8"),  # 1.0 when base_inv is not the identity
        ("reach_low", "f8"),
        ("reach_high", "f8"),
        ("cylinder2", "f8"),
        ("turn_tol", "f8"),  # NEAR_SINGULAR_TOL, plus the model's error
        ("theta_offset", "f8", 6),
        ("joint_sign", "f8", 6),
        ("plain", "f8", 6),
        ("lower", "f8", 6),
        ("upper", "f8", 6),
        ("base_inv", "f8", (4, 4)),
        ("tool_inv", "f8", (4, 4)),
    ],
    align=True,
)

#: Angle slots: θ1 per shoulder; θ5 of wrist-up per shoulder; θ6, θ3 of
#: elbow-up and θ234 = θ2 + θ3 + θ4 per (shoulder, wrist) pair; θ2 per branch
#: (θ4 is θ234 − θ2 − θ3: four atan2 per pose fewer than one per branch).
U1, U5, U6, U3, U2, U234 = 0, 2, 4, 8, 12, 20
N_ANGLES = 24
#: Bit ``DEAD + 2·shoulder + wrist`` of the mask: that pair cannot reach.
DEAD = 28
#: Bit ``SINGULAR + shoulder`` of the mask: the wrist is singular (s5 = 0).
SINGULAR = 32
#: Bit of the mask: shoulder singular (as ``_puma_kernel.SHOULDER``).
SHOULDER = 34
SHOULDER_SINGULAR_TOL = 1e-10
#: Bit ``ELBOW + 2·shoulder + wrist`` of the mask: that pair's elbow is
#: singular (|sin θ3| <= ELBOW_SINGULAR_TOL), its elbow-up and -down meet.
ELBOW = 35
#: Orientation error [rad] a turn of θ6 may cost (about |s5| times the turn)
#: to bring frame 3 within reach near a wrist singularity. There θ6 comes
#: from a vector of length |s5| known to ~1e-16, so it is known to ~1e-16 /
#: |s5| only, and frame 3 (√(d5² + a4²) from the wrist point) moves with it:
#: a pose at the stretched or folded elbow may land outside the reach by far
#: more than its rounding, and is turned back into it, not refused. A model
#: that is UR-type only up to an error (``turn_tol`` of the record) gets
#: MODEL_ERROR_SLACK times it more: its branches are refined on the model.
NEAR_SINGULAR_TOL = 1e-13
#: A turned frame 3 lands this fraction of a2 + a3 inside the arm's reach.
REACH_MARGIN = 1e-12
#: The bits of the mask that flag a singular wrist, per (shoulder, elbow) pair
#: of branches 2·pair, 2·pair + 1, and a (shoulder, wrist) pair that cannot
#: reach, per branch.
_WRIST_BITS = (SINGULAR, SINGULAR, SINGULAR + 1, SINGULAR + 1)
_DEAD_BITS = tuple(DEAD + 2 * (b >> 2) + (b & 1) for b in range(8))
#: The mask layout of :func:`solve_pose` (``_kernel_common.solve_one``).
_ELBOW_BITS = tuple(ELBOW + 2 * (b >> 2) + (b & 1) for b in range(8))
_LAYOUT = (N_ANGLES, _WRIST_BITS, SHOULDER, _ELBOW_BITS, _DEAD_BITS)


def pack_geometry(structure: KinematicStructure, lower, upper) -> np.ndarray:
    """The constants of a UR-type arm as a read-only (1,) record array.

    Args:
        structure: Its fitted structure (family ``"ur"``).
        lower: Lower joint limits, (6,) [rad].
        upper: Upper joint limits, (6,) [rad].
    """
    j = structure.table.joints
    g = np.zeros(1, dtype=GEOMETRY_DTYPE)
    g["sigma1"] = math.copysign(1.0, j[0].alpha)
    g["sigma4"] = math.copysign(1.0, j[3].alpha)
    g["sigma5"] = math.copysign(1.0, j[4].alpha)
    g["offset"] = j[1].d + j[2].d + j[3].d
    g["d1"], g["a1"], g["a2"], g["a3"] = j[0].d, j[0].a, j[1].a, j[2].a
    g["a4"], g["d5"] = j[3].a, j[4].d
    low, high = abs(abs(j[1].a) - abs(j[2].a)), abs(j[1].a) + abs(j[2].a)
    # frame 3 comes from θ6, which a near-singular wrist knows to ~1e-16 / |s5|:
    # a pose at the folded or stretched elbow may land ~1e-11 m outside, and
    # clamping it costs at most the slack in position; a model that differs
    # from the idealised chain reaches that much farther (MODEL_ERROR_SLACK)
    model_slack = MODEL_ERROR_SLACK * structure.residual
    slack = 1e-10 * high + model_slack
    g["reach_low"], g["reach_high"] = low - slack, high + slack
    radius = max(abs(j[1].d + j[2].d + j[3].d) - model_slack, 0.0)
    g["cylinder2"] = radius**2 * (1.0 - 1e-12)
    # a model that differs from the idealised chain moves θ6 by its error / s5
    g["turn_tol"] = NEAR_SINGULAR_TOL + model_slack
    common.pack_joint_fields(g, structure, lower, upper, LIMIT_TOL)
    g.setflags(write=False)
    return g


@common.inline
def _frame_pose(geo, pose: FloatArray, out: FloatArray) -> None:
    """Rows 0..2 of ``base_inv · pose · tool_inv`` into ``out``."""
    tool, base = common.frames(geo)
    common.write_framed(pose, out, tool, base, geo.based != 0.0)


@common.inline
def _planar(geo, c1, s1, c5, c6, s6, s5, rot, big_px, big_py):
    """x4 = (c234, s234) and the origin of frame 3 (X, Y) in the arm plane.

    For one (θ1, θ5, θ6): x4 = R14 e_x, and frame 3's origin = wrist point −
    d5 z4 − a4 x4, z4 = σ5 (s6 n + c6 o), seen from the shoulder in frame 1.
    ``rot``: the target's rotation (nx, ox, ax, ny, oy, ay, nz, oz, az).
    """
    s1g, s5g = geo.sigma1, geo.sigma5
    nx, ox, ax, ny, oy, ay, nz, oz, az = rot
    wx = c6 * c5 * nx - s6 * c5 * ox + s5g * s5 * ax
    wy = c6 * c5 * ny - s6 * c5 * oy + s5g * s5 * ay
    wz = c6 * c5 * nz - s6 * c5 * oz + s5g * s5 * az
    c234, s234 = c1 * wx + s1 * wy, s1g * wz
    zx = s5g * (s6 * nx + c6 * ox)
    zy = s5g * (s6 * ny + c6 * oy)
    zz = s5g * (s6 * nz + c6 * oz)
    big_x = big_px - geo.d5 * (c1 * zx + s1 * zy) - geo.a4 * c234
    big_y = big_py - geo.d5 * s1g * zz - geo.a4 * s234
    return c234, s234, big_x, big_y


@common.inline
def _turn_may_reach(geo, s5: float, dist: float) -> bool:
    """Whether a turn of θ6 within ``turn_tol`` may bring frame 3 in reach.

    ``dist``: frame 3's distance from the shoulder [m]. A turn δ moves it by at
    most √(d5² + a4²) |δ| and costs about |s5| |δ| of orientation; a pair
    outside the reach by ``miss`` needs δ >= miss / √(d5² + a4²). The reach
    is the arm's own, |a2| ± |a3|, not the tests' (a pair within their slack
    but outside it would be clamped, at the cost of its miss in position).
    Selects only (the vectorised batch evaluates it too).
    """
    a2, a3 = abs(geo.a2), abs(geo.a3)
    miss = max(abs(a2 - a3) - dist, dist - (a2 + a3))
    arm = math.sqrt(geo.d5 * geo.d5 + geo.a4 * geo.a4)
    return (miss > 0.0) & (abs(s5) * miss <= geo.turn_tol * arm)


@common.inline
def _reach_turn(geo, c1, s1, m, big_px, big_py, big_x, big_y, dist):
    """Turn of θ6 [rad] at a wrist singularity that brings frame 3 within reach.

    With z5 ∥ z1, turning θ6 turns the offset v = wrist point − frame 3 origin
    rigidly in the arm plane (at the rate −(n_P × o_P) = ±1); the turn is the
    smallest one to the nearest reachable distance (0 if none is reachable).
    """
    vx, vy = big_px - big_x, big_py - big_y
    pn, rm = math.sqrt(big_px * big_px + big_py * big_py), math.sqrt(vx * vx + vy * vy)
    if pn * rm == 0.0:
        return 0.0
    # the arm's own reach, strictly inside by REACH_MARGIN (the reach tests'
    # slack is wider: rounding never takes the turned frame 3 out of them) ...
    a2, a3 = abs(geo.a2), abs(geo.a3)
    margin = REACH_MARGIN * (a2 + a3)
    low = max(abs(a2 - a3) + margin, abs(pn - rm))
    high = min(a2 + a3 - margin, pn + rm)
    if low > high:  # ... or, if the circle does not get there, within the slack
        low = max(geo.reach_low, abs(pn - rm))
        high = min(geo.reach_high, pn + rm)
        if low > high:
            return 0.0
    t = min(max(dist, low), high)
    cos_angle = (pn * pn + rm * rm - t * t) / (2.0 * pn * rm)
    angle = math.acos(min(max(cos_angle, -1.0), 1.0))
    a_p, a_v = math.atan2(big_py, big_px), math.atan2(vy, vx)
    turn_a = common.remainder(a_p + angle - a_v)
    turn_b = common.remainder(a_p - angle - a_v)
    turn = turn_a if abs(turn_a) <= abs(turn_b) else turn_b
    npx, npy = c1 * m[0, 0] + s1 * m[1, 0], geo.sigma1 * m[2, 0]
    opx, opy = c1 * m[0, 1] + s1 * m[1, 1], geo.sigma1 * m[2, 1]
    rate = -(npx * opy - npy * opx)
    return turn / rate


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

    Args:
        geo: The arm's record (:data:`GEOMETRY_DTYPE`).
        target: (4, 4) pose of the tool frame, checked rigid and finite.
        prev: (6,) previous configuration [rad], or (0,) for none.
        y: (N_ANGLES,) output, first arguments of the atan2.
        x: (N_ANGLES,) output, second arguments.
        scratch: (4, 4) work space.

    Returns:
        ``(status, mask)``: :data:`OK`, :data:`OUT_OF_REACH` or
        :data:`IN_CYLINDER`; bit ``slot`` of the mask: the slot holds its angle
        in ``y`` (θ1 on the base axis, θ6 at a wrist singularity); bit
        ``SINGULAR + shoulder`` flags a singular wrist; bit
        ``DEAD + pair``: the (shoulder, wrist) pair cannot reach, its in-plane
        distance [m] in ``x[U3 + pair]``.
    """
    has_prev = prev.shape[0] != 0
    _frame_pose(geo, target, scratch)
    m = scratch
    nx, ny = m[0, 0], m[1, 0]
    ox, oy = m[0, 1], m[1, 1]
    ax, ay = m[0, 2], m[1, 2]
    px, py, pz = m[0, 3], m[1, 3], m[2, 3]
    rot = (nx, ox, ax, ny, oy, ay, m[2, 0], m[2, 1], m[2, 2])
    r2 = px * px + py * py
    if r2 < geo.cylinder2:
        x[U3] = math.sqrt(r2)
        return IN_CYLINDER, 0
    s1g, s4g, s5g = geo.sigma1, geo.sigma4, geo.sigma5
    sd = s1g * geo.offset
    right = 1.0 if sd >= 0.0 else -1.0
    rho = common.clamped_root(r2 - geo.offset * geo.offset)
    a2, a3 = geo.a2, geo.a3
    mask = np.int64(0)
    if rho <= SHOULDER_SINGULAR_TOL:
        mask |= np.int64(1) << SHOULDER
    for arm in range(2):
        x1 = right * rho if arm == 0 else -right * rho
        if r2 > 0.0:
            c1, s1 = (px * x1 - py * sd) / r2, (py * x1 + px * sd) / r2
            y[U1 + arm], x[U1 + arm] = s1, c1
        else:  # wrist point on the base axis (D = 0): theta1 free
            t1 = geo.theta_offset[0]
            if has_prev:
                t1 += geo.joint_sign[0] * prev[0]
            c1, s1 = math.cos(t1), math.sin(t1)
            y[U1 + arm] = t1
            mask |= 1 << (U1 + arm)
        c5 = -s4g * s5g * s1g * (s1 * ax - c1 * ay)
        # z1 in the tool frame: (sigma4 s5 c6, -sigma4 s5 s6, .); |s5| from it
        vx, vy = s1g * (s1 * nx - c1 * ny), s1g * (s1 * ox - c1 * oy)
        s5 = s5g * math.sqrt(vx * vx + vy * vy)  # wrist-up: sigma5 s5 >= 0
        y[U5 + arm], x[U5 + arm] = s5, c5
        singular = abs(s5) <= WRIST_SINGULAR_TOL
        if singular:  # theta6 free: its offset, or the previous value
            t6 = geo.theta_offset[5]
            if has_prev:
                t6 += geo.joint_sign[5] * prev[5]
            c6, s6 = math.cos(t6), math.sin(t6)
            mask |= 1 << (SINGULAR + arm)
        else:
            inv = s4g / s5  # |(c6, s6)| = |v| / |s5| = 1
            c6, s6 = vx * inv, -vy * inv
        # wrist point from the shoulder, in the arm plane (frame 1)
        big_px, big_py = c1 * px + s1 * py - geo.a1, s1g * (pz - geo.d1)
        c234_up = s234_up = big_x_up = big_y_up = 0.0
        for wrist in range(2):
            pair = 2 * arm + wrist
            sw = 1.0 if wrist == 0 else -1.0  # the other wrist: -s5, theta6 + pi
            cs6, ss6, ss5 = sw * c6, sw * s6, sw * s5
            if wrist == 0 or singular:
                c234, s234, big_x, big_y = _planar(
                    geo, c1, s1, c5, cs6, ss6, ss5, rot, big_px, big_py
                )
            else:  # x4 and z4 turn over: frame 3 mirrored about the wrist point
                c234, s234 = -c234_up, -s234_up
                big_x, big_y = 2.0 * big_px - big_x_up, 2.0 * big_py - big_y_up
            dist2 = big_x * big_x + big_y * big_y
            dist = math.sqrt(dist2)
            if singular:
                t6p = (
                    t6
                    if wrist == 0
                    else (t6 - common.PI if t6 > 0.0 else t6 + common.PI)
                )
                if not (geo.reach_low <= dist <= geo.reach_high):
                    # turn theta6 (and with it frame 4 about the wrist point)
                    # until frame 3 is within reach, if it can be
                    t6p += _reach_turn(
                        geo, c1, s1, m, big_px, big_py, big_x, big_y, dist
                    )
                    cs6, ss6 = math.cos(t6p), math.sin(t6p)
                    c234, s234, big_x, big_y = _planar(
                        geo, c1, s1, c5, cs6, ss6, ss5, rot, big_px, big_py
                    )
                    dist2 = big_x * big_x + big_y * big_y
                    dist = math.sqrt(dist2)
                y[U6 + pair] = t6p
                mask |= 1 << (U6 + pair)
            else:
                y[U6 + pair], x[U6 + pair] = ss6, cs6
                c234_up, s234_up, big_x_up, big_y_up = c234, s234, big_x, big_y
                if _turn_may_reach(geo, ss5, dist):  # θ6 ill-conditioned
                    turn = _reach_turn(
                        geo, c1, s1, m, big_px, big_py, big_x, big_y, dist
                    )
                    if abs(ss5 * turn) <= geo.turn_tol:
                        t6p = math.atan2(ss6, cs6) + turn
                        c234, s234, big_x, big_y = _planar(
                            geo, c1, s1, c5, math.cos(t6p), math.sin(t6p), ss5,
                            rot, big_px, big_py,
                        )  # fmt: skip
                        dist2 = big_x * big_x + big_y * big_y
                        dist = math.sqrt(dist2)
                        y[U6 + pair] = t6p
                        mask |= 1 << (U6 + pair)
            y[U234 + pair], x[U234 + pair] = s234, c234
            if not (geo.reach_low <= dist <= geo.reach_high):
                mask |= 1 << (DEAD + pair)
                y[U3 + pair], x[U3 + pair] = 0.0, dist
                for elbow in range(2):
                    b = 4 * arm + 2 * elbow + wrist
                    y[U2 + b], x[U2 + b] = 0.0, 1.0
                continue
            c3 = (dist2 - a2 * a2 - a3 * a3) / (2.0 * a2 * a3)
            c3 = common.clip_unit(c3)
            up = -1.0 if s1g * a2 * a3 * big_x > 0.0 else 1.0
            s3_up = up * common.clamped_root(1.0 - c3 * c3)
            if abs(s3_up) <= ELBOW_SINGULAR_TOL:
                mask |= np.int64(1) << (ELBOW + pair)
            y[U3 + pair], x[U3 + pair] = s3_up, c3
            for elbow in range(2):
                b = 4 * arm + 2 * elbow + wrist
                s3 = s3_up if elbow == 0 else -s3_up
                k1, k2 = a2 + a3 * c3, a3 * s3
                c2, s2 = big_x * k1 + big_y * k2, big_y * k1 - big_x * k2
                # (0, 0), frame 3 on axis 2 (theta2 free): atan2 gives 0
                y[U2 + b], x[U2 + b] = s2, c2
    if mask >> DEAD & 15 == 15:
        return OUT_OF_REACH, int(mask)
    return OK, int(mask)


@common.inline
def assemble(
    geo,
    angles: FloatArray,
    prev: FloatArray,
    q: FloatArray,
    within: npt.NDArray[np.bool_],
    mask: int,
) -> None:
    """Joint values of the eight branches from the DH angles of a pose.

    Args:
        geo: The arm's record.
        angles: (N_ANGLES,) DH angles [rad] of the slots, each in [−π, π].
        prev: (6,) previous configuration [rad], or (0,) for none.
        q: (8, 6) output [rad]; NaN rows for a pair that cannot reach.
        within: (8,) output, within the limits; or (0,) to skip the tests.
        mask: From :func:`angle_arguments`.
    """
    has_prev = prev.shape[0] != 0
    for arm in range(2):
        q1 = common.joint_value(geo, 0, angles[U1 + arm], prev, has_prev)
        t5 = angles[U5 + arm]
        for wrist in range(2):
            pair = 2 * arm + wrist
            dead = mask >> (DEAD + pair) & 1
            q5 = common.joint_value(geo, 4, -t5 if wrist else t5, prev, has_prev)
            q6 = common.joint_value(geo, 5, angles[U6 + pair], prev, has_prev)
            for elbow in range(2):
                b = 4 * arm + 2 * elbow + wrist
                if dead:
                    for j in range(6):
                        q[b, j] = np.nan
                    if within.shape[0]:
                        within[b] = False
                    continue
                t2, t3 = angles[U2 + b], angles[U3 + pair]
                t3 = -t3 if elbow else t3
                t4 = common.remainder(angles[U234 + pair] - t2 - t3)
                q[b, 0] = q1
                q[b, 1] = common.joint_value(geo, 1, t2, prev, has_prev)
                q[b, 2] = common.joint_value(geo, 2, t3, prev, has_prev)
                q[b, 3] = common.joint_value(geo, 3, t4, prev, has_prev)
                q[b, 4], q[b, 5] = q5, q6
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
    """All eight branches of one pose, as ``_puma_kernel.solve_pose``.

    ``q`` has NaN rows for the branches of a (shoulder, wrist) pair that
    cannot reach; the wrist of the (shoulder, elbow) pair ``p`` (branches
    2·p, 2·p + 1) is singular with shoulder ``p >> 1``.
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
    """The branch continuing a motion, as ``_puma_kernel.track``."""
    return common.track_one(
        geometry[0], pose, q_predicted, pair, max_step2, q_out,
        angle_arguments, assemble, _LAYOUT,
    )  # fmt: skip


@entry_point()
def diagnose(geometry: np.ndarray, pose: FloatArray) -> tuple[int, float, float, float]:
    """Why a pose is unreachable (arguments as ``_puma_kernel.diagnose``).

    Returns:
        ``(status, distance, low, high)``: :data:`OUT_OF_REACH` with the
        in-plane distance [m] of frame 3 from the shoulder nearest the reach
        and the reach ``[|a2| − |a3|, |a2| + |a3|]`` [m] (absolute);
        :data:`IN_CYLINDER` with the wrist point's distance from the base axis
        and the cylinder's radius |d2 + d3 + d4| twice; else ``(OK, 0, 0, 0)``.
    """
    geo = geometry[0]
    y, x = np.empty(N_ANGLES), np.empty(N_ANGLES)
    status, _ = angle_arguments(geo, pose, np.empty(0), y, x, np.empty((4, 4)))
    if status == OUT_OF_REACH:
        best, worst = 0.0, math.inf
        for pair in range(4):
            d = x[U3 + pair]
            miss = max(geo.reach_low - d, d - geo.reach_high)
            if miss < worst:
                best, worst = d, miss
        a2, a3 = abs(geo.a2), abs(geo.a3)
        return status, best, abs(a2 - a3), a2 + a3
    if status == IN_CYLINDER:
        radius = abs(geo.offset)
        return status, x[U3], radius, radius
    return OK, 0.0, 0.0, 0.0


@common.inline
def _pair_arguments(y, x, i, arm, wrist, planar, s5, geo) -> tuple[bool, bool]:
    """θ3 and θ2 slots of one (shoulder, wrist) pair of pose ``i``.

    ``planar``: (c234, s234, X, Y) of the pair; ``s5`` its sin θ5. As
    :func:`angle_arguments` for a pair whose wrist is not singular, unless it
    is out of reach and a turn of θ6 may bring it in (:func:`_turn_may_reach`,
    which angle_arguments then tries). Returns (dead, may turn).
    """
    c234, s234, big_x, big_y = planar
    pair = 2 * arm + wrist
    a2, a3 = geo.a2, geo.a3
    dist2 = big_x * big_x + big_y * big_y
    dist = math.sqrt(dist2)
    dead = (dist < geo.reach_low) | (dist > geo.reach_high)
    turn = _turn_may_reach(geo, s5, dist)
    y[common.flat_index(i, N_ANGLES, U234 + pair)] = s234
    x[common.flat_index(i, N_ANGLES, U234 + pair)] = c234
    c3 = common.clip_unit((dist2 - a2 * a2 - a3 * a3) / (2.0 * a2 * a3))
    up = -1.0 if geo.sigma1 * a2 * a3 * big_x > 0.0 else 1.0
    s3_up = up * common.clamped_root(1.0 - c3 * c3)
    y[common.flat_index(i, N_ANGLES, U3 + pair)] = 0.0 if dead else s3_up
    x[common.flat_index(i, N_ANGLES, U3 + pair)] = dist if dead else c3
    for elbow in range(2):
        b = 4 * arm + 2 * elbow + wrist
        s3 = s3_up if elbow == 0 else -s3_up
        k1, k2 = a2 + a3 * c3, a3 * s3
        c2, s2 = big_x * k1 + big_y * k2, big_y * k1 - big_x * k2
        y[common.flat_index(i, N_ANGLES, U2 + b)] = 0.0 if dead else s2
        x[common.flat_index(i, N_ANGLES, U2 + b)] = 1.0 if dead else c2
    return dead, turn


@common.inline
def _arm_arguments(y, x, i, arm, x1, point, rot, geo):
    """Slots of one shoulder of pose ``i``: (dead up, dead down, special).

    ``point``: the wrist point (px, py, pz, r2); ``rot`` as :func:`_planar`.
    As :func:`angle_arguments` for a shoulder whose wrist is not singular;
    ``special``: the wrist is singular or a pair may need a turn of θ6.
    """
    px, py, pz, r2 = point
    nx, ox, ax, ny, oy, ay = rot[0], rot[1], rot[2], rot[3], rot[4], rot[5]
    s1g, s4g, s5g = geo.sigma1, geo.sigma4, geo.sigma5
    sd = s1g * geo.offset
    c1, s1 = (px * x1 - py * sd) / r2, (py * x1 + px * sd) / r2
    y[common.flat_index(i, N_ANGLES, U1 + arm)] = s1
    x[common.flat_index(i, N_ANGLES, U1 + arm)] = c1
    c5 = -s4g * s5g * s1g * (s1 * ax - c1 * ay)
    vx, vy = s1g * (s1 * nx - c1 * ny), s1g * (s1 * ox - c1 * oy)
    s5 = s5g * math.sqrt(vx * vx + vy * vy)
    y[common.flat_index(i, N_ANGLES, U5 + arm)] = s5
    x[common.flat_index(i, N_ANGLES, U5 + arm)] = c5
    singular = abs(s5) <= WRIST_SINGULAR_TOL
    inv = s4g / s5
    c6, s6 = vx * inv, -vy * inv
    big_px, big_py = c1 * px + s1 * py - geo.a1, s1g * (pz - geo.d1)
    y[common.flat_index(i, N_ANGLES, U6 + 2 * arm)] = s6
    x[common.flat_index(i, N_ANGLES, U6 + 2 * arm)] = c6
    y[common.flat_index(i, N_ANGLES, U6 + 2 * arm + 1)] = -s6
    x[common.flat_index(i, N_ANGLES, U6 + 2 * arm + 1)] = -c6
    c234, s234, big_x, big_y = _planar(geo, c1, s1, c5, c6, s6, s5, rot, big_px, big_py)
    up, turn_up = _pair_arguments(y, x, i, arm, 0, (c234, s234, big_x, big_y), s5, geo)
    # the other wrist: frame 3 mirrored about the wrist point
    mirrored = (-c234, -s234, 2.0 * big_px - big_x, 2.0 * big_py - big_y)
    down, turn_down = _pair_arguments(y, x, i, arm, 1, mirrored, -s5, geo)
    return up, down, singular | turn_up | turn_down


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
    """Stage 1 of a batch, vectorised (as ``_puma_kernel.batch_arguments``).

    ``poses``, ``y`` and ``x`` flattened, as there.

    Poses with a singular wrist, the wrist point on the base axis or a pair
    that a turn of θ6 may bring within reach (:func:`_turn_may_reach`) are
    flagged in ``odd`` for :func:`batch_fallback`; the others get the values
    of :func:`angle_arguments`, bitwise. Returns the number of poses flagged.
    """
    geo = geometry[0]
    tool, base = common.frames(geo)
    based = geo.based != 0.0
    right = 1.0 if geo.sigma1 * geo.offset >= 0.0 else -1.0
    flagged = 0
    for i in range(status.shape[0]):
        row0, row1 = common.pose_row(poses, i, 0), common.pose_row(poses, i, 1)
        row2, row3 = common.pose_row(poses, i, 2), common.pose_row(poses, i, 3)
        rigid = common.rigid_rows(row0, row1, row2, row3)
        f0, f1, f2 = common.frame_rows(row0, row1, row2, tool, base, based)
        (nx, ox, ax, px), (ny, oy, ay, py), (nz, oz, az, pz) = f0, f1, f2
        r2 = px * px + py * py
        rho = common.clamped_root(r2 - geo.offset * geo.offset)
        rot = (nx, ox, ax, ny, oy, ay, nz, oz, az)
        point = (px, py, pz, r2)
        x1 = right * rho
        dead0, dead1, singular_r = _arm_arguments(y, x, i, 0, x1, point, rot, geo)
        dead2, dead3, singular_l = _arm_arguments(y, x, i, 1, -x1, point, rot, geo)
        mask = (1 << SHOULDER) if rho <= SHOULDER_SINGULAR_TOL else 0
        mask |= (1 << DEAD) if dead0 else 0
        mask |= (1 << (DEAD + 1)) if dead1 else 0
        mask |= (1 << (DEAD + 2)) if dead2 else 0
        mask |= (1 << (DEAD + 3)) if dead3 else 0
        code = OUT_OF_REACH if dead0 & dead1 & dead2 & dead3 else OK
        code = IN_CYLINDER if r2 < geo.cylinder2 else code
        status[i] = code
        exact[i] = mask if code == OK else 0
        # (a singular wrist's pairs may reach after all: angle_arguments says)
        special = (code != IN_CYLINDER) & ((r2 <= 0.0) | singular_r | singular_l)
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

    As ``_puma_kernel.batch_fallback`` (its own kernel, without the
    vectoriser's options); returns −1 or the first pose not finite and rigid.
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
    exact: npt.NDArray[np.int64],
    q: FloatArray,
    valid: npt.NDArray[np.bool_],
) -> None:
    """Stage 3 of a batch (as ``_puma_kernel.batch_assemble``)."""
    geo = geometry[0]
    common.assemble_poses(geo, angles, y, status, exact, q, valid, assemble, _DEAD_BITS)
