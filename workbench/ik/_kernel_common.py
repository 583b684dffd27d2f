r"""What the compiled closed forms share: status codes, flag bits, pose rows, angles.

The kernels of both families (:mod:`workbench.ik._puma_kernel`,
:mod:`workbench.ik._ur_kernel`) call these helpers; the cache of every kernel
is keyed on the source of the modules it imports (``workbench._compiled``),
so an edit here recompiles them.

Conventions: a pose is a (4, 4) homogeneous matrix [m] or, in a batch, 16
consecutive entries of a flat (N · 16,) array; a row is a 4-tuple of floats.
The helpers called per pose or per angle in the batch loops are written for
LLVM's loop vectoriser: selects rather than branches, no library calls but
``sqrt``, unsigned flat indices (:func:`flat_index`).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point, helper
from workbench.ik._flags import (
    ELBOW_SINGULAR,
    REACHED,
    SHOULDER_SINGULAR,
    WITHIN_LIMITS,
    WRIST_SINGULAR,
)
from workbench.poses import RIGIDITY_TOL

FloatArray = npt.NDArray[np.float64]
Row = tuple[float, float, float, float]

#: Status codes of the kernels' ``solve_pose``, ``batch_arguments`` and
#: ``diagnose``: solved; the pose is not a finite rigid transform (within
#: RIGIDITY_TOL, the test of ``workbench.poses``); the wrist is out of the arm's
#: reach; it is inside the cylinder the shoulder offset keeps it out of.
OK, NOT_RIGID, OUT_OF_REACH, IN_CYLINDER = 0, 1, 2, 3

PI = math.pi
TAU = 2.0 * math.pi

#: For the helpers called per angle or per pose inside the batch loops:
#: inlined into their callers by LLVM (``forceinline``, LLVM's alwaysinline),
#: not by Numba (``inline="always"``, several times slower to compile).
inline = helper(forceinline=True)

#: For the bodies of the families' entry points (called once each): inlined by
#: Numba into the entry point, without a compile and an LLVM pass of their own.
body = helper(inline_source=True)


@inline
def remainder(x: float) -> float:
    """IEEE remainder of ``x`` by 2π, in [−π, π] (exact; ties may keep ±π)."""
    if -PI <= x <= PI:
        return x
    if -3.0 * PI <= x <= 3.0 * PI:  # one turn off: x ∓ 2π is exact
        return x - TAU if x > 0.0 else x + TAU
    r = np.fmod(x, TAU)  # exact, then at most one exact turn
    if r > PI:
        return r - TAU
    if r < -PI:
        return r + TAU
    return r


@inline
def joint_value(geo, j: int, theta: float, prev: FloatArray, has_prev: bool) -> float:
    """Joint value [rad] of DH angle ``theta`` of joint ``j``.

    Near ``prev[j]`` if ``has_prev``; else the representative (mod 2π) in
    (−π, π] if within the limits, else the first of ±2π, ±4π from it that is
    (else the one in (−π, π]). ``geo``: a record with the fields
    ``joint_sign``, ``theta_offset``, ``plain``, ``lower``, ``upper``.
    """
    sign = geo.joint_sign[j]
    if has_prev:
        return prev[j] + remainder(sign * (theta - geo.theta_offset[j]) - prev[j])
    if geo.plain[j] != 0.0:  # theta in [-pi, pi] is its own value, but -pi is pi
        return theta if theta > -PI else PI
    y = remainder(sign * (theta - geo.theta_offset[j]))
    if y <= -PI:
        y += TAU
    lo, hi = geo.lower[j], geo.upper[j]
    if lo <= y <= hi:
        return y
    for turns in (1.0, -1.0, 2.0, -2.0):
        z = y + turns * TAU
        if lo <= z <= hi:
            return z
    return y


@inline
def within_limits(geo, q: FloatArray, b: int) -> bool:
    """Whether branch ``b`` of ``q`` (8, 6) is within ``geo``'s widened limits."""
    ok = True
    for j in range(6):
        ok &= geo.lower[j] <= q[b, j] <= geo.upper[j]
    return ok


@inline
def row_within_limits(geo, q: FloatArray, b: int) -> bool:
    """Whether row ``b`` of ``q`` (B, n) is within ``geo``'s widened limits (any n)."""
    ok = True
    for j in range(q.shape[1]):
        ok &= geo.lower[j] <= q[b, j] <= geo.upper[j]
    return ok


@inline
def nearest_or_kept(
    q: FloatArray, reference: FloatArray, kept: int, max_step2: float
) -> int:
    """The row of ``q`` (B, n) continuing a motion at ``reference`` (n,).

    Row ``kept`` if its squared distance to ``reference`` is at most
    ``max_step2`` [rad²], else the nearest row (the first on a tie); NaN rows
    (branches not reached) are skipped; −1 if every row is NaN.
    """
    best, best_d2 = -1, math.inf
    for b in range(q.shape[0]):
        d2 = 0.0
        for j in range(q.shape[1]):
            d = q[b, j] - reference[j]
            d2 += d * d
        if b == kept and d2 <= max_step2:
            return b
        if d2 < best_d2:
            best, best_d2 = b, d2
    return best


@inline
def clip_unit(k: float) -> float:
    """``k`` clipped to [−1, 1] (selects, which the batch loop vectorises)."""
    k = k if k > -1.0 else -1.0
    return k if k < 1.0 else 1.0


@inline
def clamped_root(v: float) -> float:
    """√max(v, 0): the root of a quantity ≥ 0 up to rounding.

    ``abs`` of the clamped value (the same value) tells LLVM the root's
    argument is not negative, so that it uses the sqrt instruction (which a
    vectorised loop can) rather than libm's ``sqrt``, which may set errno.
    """
    return math.sqrt(abs(v if v > 0.0 else 0.0))


@inline
def flat_index(i: int, width: int, slot: int) -> np.uint64:
    """Flat index ``i * width + slot``, unsigned: no negative-index test."""
    return np.uint64(i) * np.uint64(width) + np.uint64(slot)


@inline
def matrix_row(m: FloatArray, i: int) -> Row:
    """Row ``i`` of a (4, 4) matrix."""
    return m[i, 0], m[i, 1], m[i, 2], m[i, 3]


@inline
def pose_row(poses: FloatArray, i: int, row: int) -> Row:
    """Row ``row`` of pose ``i`` of the flat (N · 16,) array of N poses."""
    k = 4 * row
    return (
        poses[flat_index(i, 16, k)],
        poses[flat_index(i, 16, k + 1)],
        poses[flat_index(i, 16, k + 2)],
        poses[flat_index(i, 16, k + 3)],
    )


@inline
def frames(geo):
    """Rows 0..2 of ``geo.tool_inv`` and of ``geo.base_inv``, for frame_rows."""
    e, b = geo.tool_inv, geo.base_inv
    tool = (matrix_row(e, 0), matrix_row(e, 1), matrix_row(e, 2))
    return tool, (matrix_row(b, 0), matrix_row(b, 1), matrix_row(b, 2))


@inline
def frame_rows(r0: Row, r1: Row, r2: Row, tool, base, based: bool):
    """Rows 0..2 of ``base_inv · pose · tool_inv`` from rows 0..2 of the pose.

    ``tool``, ``base``: rows 0..2 of ``tool_inv`` and ``base_inv``
    (:func:`frames`; their row 3 is 0 0 0 1); ``base_inv`` is left out unless
    ``based``. Rows as 4-tuples, so that the batch's vectorised loops and the
    one-pose kernels share the arithmetic.
    """
    t0, t1, t2 = _times_tool(r0, tool), _times_tool(r1, tool), _times_tool(r2, tool)
    return (
        _base_row(base[0], t0, t1, t2) if based else t0,
        _base_row(base[1], t0, t1, t2) if based else t1,
        _base_row(base[2], t0, t1, t2) if based else t2,
    )


@inline
def _times_tool(r: Row, tool) -> Row:
    """A pose row times ``tool_inv`` (rows ``tool``)."""
    (p0, p1, p2, p3), (e0, e1, e2) = r, tool
    return (
        p0 * e0[0] + p1 * e1[0] + p2 * e2[0],
        p0 * e0[1] + p1 * e1[1] + p2 * e2[1],
        p0 * e0[2] + p1 * e1[2] + p2 * e2[2],
        p0 * e0[3] + p1 * e1[3] + p2 * e2[3] + p3,
    )


@inline
def _base_row(b: Row, t0: Row, t1: Row, t2: Row) -> Row:
    """Row ``b`` of ``base_inv`` times the rows t0, t1, t2 (and 0 0 0 1)."""
    return (
        b[0] * t0[0] + b[1] * t1[0] + b[2] * t2[0],
        b[0] * t0[1] + b[1] * t1[1] + b[2] * t2[1],
        b[0] * t0[2] + b[1] * t1[2] + b[2] * t2[2],
        b[0] * t0[3] + b[1] * t1[3] + b[2] * t2[3] + b[3],
    )


@inline
def write_framed(pose: FloatArray, out: FloatArray, tool, base, based: bool) -> None:
    """Rows 0..2 of ``base_inv · pose · tool_inv`` into rows 0..2 of ``out``.

    Args:
        pose: (4, 4) pose of the tool frame in the base frame.
        out: (4, 4) scratch; rows 0..2 are written.
        tool: Rows of ``tool_inv``, as :func:`frame_rows`.
        base: Rows of ``base_inv``.
        based: Apply ``base_inv``.
    """
    r0, r1, r2 = matrix_row(pose, 0), matrix_row(pose, 1), matrix_row(pose, 2)
    r0, r1, r2 = frame_rows(r0, r1, r2, tool, base, based)
    out[0, 0], out[0, 1], out[0, 2], out[0, 3] = r0
    out[1, 0], out[1, 1], out[1, 2], out[1, 3] = r1
    out[2, 0], out[2, 1], out[2, 2], out[2, 3] = r2


@inline
def rigid_rows(row0: Row, row1: Row, row2: Row, row3: Row) -> bool:
    """Whether the pose of these rows is finite and rigid, as ``workbench.poses``.

    The exact test of ``ik._targets.pose_rows`` (``poses.check_rigid_rows``):
    every entry of RᵀR − I and of the bottom row minus [0, 0, 0, 1] within
    RIGIDITY_TOL, det R > 0, the translation finite. Comparisons joined by
    ``&`` (no branches: the batch loop vectorises it); a NaN fails them.
    """
    (a, b, c, p0), (d, e, f, p1), (g, h, i, p2), (w0, w1, w2, w3) = (
        row0,
        row1,
        row2,
        row3,
    )
    tol = RIGIDITY_TOL
    ok = abs(a * a + d * d + g * g - 1.0) <= tol  # entries of R^T R - I
    ok &= abs(b * b + e * e + h * h - 1.0) <= tol
    ok &= abs(c * c + f * f + i * i - 1.0) <= tol
    ok &= abs(a * b + d * e + g * h) <= tol
    ok &= abs(a * c + d * f + g * i) <= tol
    ok &= abs(b * c + e * f + h * i) <= tol
    ok &= (abs(w0) <= tol) & (abs(w1) <= tol) & (abs(w2) <= tol)
    ok &= abs(w3 - 1.0) <= tol
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    # an infinite or NaN translation makes the sum NaN
    return ok & (det > 0.0) & ((p0 + p1 + p2) * 0.0 == 0.0)


@inline
def is_rigid(pose: FloatArray) -> bool:
    """:func:`rigid_rows` of a (4, 4) pose."""
    return rigid_rows(
        matrix_row(pose, 0),
        matrix_row(pose, 1),
        matrix_row(pose, 2),
        matrix_row(pose, 3),
    )


def pack_joint_fields(
    record: np.ndarray, structure, lower, upper, limit_tol: float
) -> None:
    """Fill the joint and frame fields of a kernel's (1,) geometry record.

    Sets ``theta_offset``, ``joint_sign``, ``plain`` (θ in [−π, π] is the
    joint's own value: no offset, sign +1, limits within or around ±π, as
    :func:`joint_value` reads it), ``lower`` and ``upper`` widened by
    ``limit_tol`` [rad], ``base_inv``, ``based`` (1.0 unless ``base_inv`` is
    the identity) and ``tool_inv``, from a fitted ``KinematicStructure``.

    Args:
        record: The (1,) record array, writable.
        structure: The arm's fitted structure (n joints).
        lower: Lower joint limits, (n,) [rad].
        upper: Upper joint limits, (n,) [rad].
        limit_tol: Widening of the limits [rad].
    """
    offsets = [x.theta_offset for x in structure.table.joints]
    record["theta_offset"], record["joint_sign"] = offsets, structure.joint_sign
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    record["plain"] = [
        o == 0.0 and s == 1.0 and ((-PI <= lo and hi <= PI) or lo <= -PI < PI <= hi)
        for o, s, lo, hi in zip(
            offsets, structure.joint_sign, lower, upper, strict=True
        )
    ]
    record["lower"], record["upper"] = lower - limit_tol, upper + limit_tol
    record["base_inv"] = np.linalg.inv(structure.base)
    record["based"] = not np.array_equal(record["base_inv"][0], np.eye(4))
    record["tool_inv"] = np.linalg.inv(structure.tool)


@body
def solve_one(
    geo,
    pose: FloatArray,
    prev: FloatArray,
    q: FloatArray,
    flags: npt.NDArray[np.uint8],
    check: bool,
    angle_arguments,
    assemble,
    layout,
) -> int:
    """All eight branches of one pose: the body of a family's ``solve_pose``.

    Args:
        geo: The arm's record.
        pose: (4, 4) target pose of the tool frame in the base frame [m].
        prev: (6,) previous configuration [rad], or (0,) for none.
        q: (8, 6) output [rad].
        flags: (8,) uint8 output, the bits of ``_flags`` per branch.
        check: Test first that the pose is finite and rigid.
        angle_arguments: The family's ``angle_arguments``.
        assemble: The family's ``assemble``.
        layout: The family's mask, ``(n_angles, wrist_bits, shoulder_bit,
            elbow_bits, dead_bits)``: the number of angle slots, the mask bit
            of a singular wrist per (arm, elbow) pair (4,), of a singular
            shoulder, of a singular elbow per branch (8,), and of a branch
            that cannot reach (8,).

    Returns:
        OK, NOT_RIGID, OUT_OF_REACH or IN_CYLINDER (outputs then undefined).
    """
    n_angles, wrist_bits, shoulder_bit, elbow_bits, dead_bits = layout
    if check and not is_rigid(pose):
        return NOT_RIGID
    y, x = np.empty(n_angles), np.empty(n_angles)
    # prev as the batch passes it (writable, C): the helpers compile once
    previous = np.empty(prev.shape[0])
    for j in range(prev.shape[0]):  # (a slice assignment compiles an overload)
        previous[j] = prev[j]
    status, mask = angle_arguments(geo, pose, previous, y, x, np.empty((4, 4)))
    if status != OK:
        return status
    angles = np.empty(n_angles)
    for slot in range(n_angles):  # atan2, or the angle itself in y
        exact = mask >> slot & 1
        angles[slot] = y[slot] if exact else math.atan2(y[slot], x[slot])
    within = np.empty(8, dtype=np.bool_)
    assemble(geo, angles, previous, q, within, mask)
    shoulder = SHOULDER_SINGULAR if mask >> shoulder_bit & 1 else 0
    for b in range(8):
        if mask >> dead_bits[b] & 1:
            flags[b] = 0
            continue
        bits = REACHED | shoulder
        bits |= WITHIN_LIMITS if within[b] else 0
        bits |= WRIST_SINGULAR if mask >> wrist_bits[b >> 1] & 1 else 0
        bits |= ELBOW_SINGULAR if mask >> elbow_bits[b] & 1 else 0
        flags[b] = bits
    return OK


@body
def fallback_poses(geo, poses, y, x, status, exact, odd, angle_arguments) -> int:
    """The body of a family's ``batch_fallback``: the poses flagged ``odd``.

    Each pose with bit 0 of ``odd`` gets ``angle_arguments`` (its ``status``,
    ``exact``, rows of ``y`` and ``x``); a pose with bit 1 (not finite and
    rigid) stops the loop. Returns −1, or the index of that pose.
    """
    none, scratch = np.empty(0), np.empty((4, 4))
    for i in range(poses.shape[0]):
        if odd[i]:
            if odd[i] & 2:
                return i
            status[i], exact[i] = angle_arguments(
                geo, poses[i], none, y[i], x[i], scratch
            )
    return -1


@body
def assemble_poses(geo, angles, y, status, exact, q, valid, assemble, dead_bits):
    """The body of a family's ``batch_assemble``.

    Joint values of N poses from ``angles = arctan2(y, x)`` (N, n_angles),
    with the slots marked in ``exact`` taken from ``y``; ``q`` (N, 8, 6) NaN
    and ``valid`` (N, 8) False for a pose whose ``status`` is not OK.
    ``dead_bits`` (8,): the mask bit per branch that says it cannot reach.
    """
    none, no_within = np.empty(0), np.empty(0, dtype=np.bool_)
    slot_bits = (1 << angles.shape[1]) - 1
    for i in range(angles.shape[0]):
        if status[i] != OK:
            q[i] = np.nan
            valid[i] = False
            continue
        mask = exact[i]
        if mask & slot_bits:  # (rare: an angle known without atan2)
            for slot in range(angles.shape[1]):
                if mask >> slot & 1:
                    angles[i, slot] = y[i, slot]
        assemble(geo, angles[i], none, q[i], no_within, mask)
        for b in range(8):
            valid[i, b] = not (mask >> dead_bits[b] & 1)


@inline
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


@body
def track_one(
    geo,
    pose: FloatArray,
    q_predicted: FloatArray,
    pair: int,
    max_step2: float,
    q_out: FloatArray,
    angle_arguments,
    assemble,
    layout,
) -> tuple[int, int, bool]:
    """The body of a family's ``track``: solve, then keep the continuing branch.

    Args:
        geo: The arm's record.
        pose: (4, 4) target pose of the tool frame in the base frame [m].
        q_predicted: (6,) predicted configuration [rad]: every angle is the
            representative nearest it (``solve_one``'s ``prev``).
        pair: (Arm, elbow) pair of the last branch, ``index >> 1``.
        max_step2: Largest squared joint step [rad²] that keeps the pair.
        q_out: (6,) output, the configuration [rad] (undefined unless OK).
        angle_arguments: As :func:`solve_one`.
        assemble: As :func:`solve_one`.
        layout: As :func:`solve_one`.

    Returns:
        ``(status, index, within)``: as :func:`solve_one`, then the branch
        (:func:`continuing_branch`) and whether it is within the limits.
    """
    q = np.empty((8, 6))
    flags = np.empty(8, dtype=np.uint8)
    status = solve_one(
        geo, pose, q_predicted, q, flags, True, angle_arguments, assemble, layout
    )
    if status != OK:
        return status, -1, False
    index = continuing_branch(q, q_predicted, pair, max_step2)
    for j in range(6):
        q_out[j] = q[index, j]
    return status, index, flags[index] & WITHIN_LIMITS != 0


__all__ = [
    "IN_CYLINDER",
    "NOT_RIGID",
    "OK",
    "OUT_OF_REACH",
    "PI",
    "TAU",
    "assemble_poses",
    "body",
    "clamped_root",
    "clip_unit",
    "continuing_branch",
    "fallback_poses",
    "flat_index",
    "frame_rows",
    "frames",
    "inline",
    "is_rigid",
    "joint_value",
    "matrix_row",
    "nearest_or_kept",
    "pack_joint_fields",
    "pose_row",
    "remainder",
    "rigid_rows",
    "row_within_limits",
    "solve_one",
    "track_one",
    "within_limits",
    "write_framed",
]
