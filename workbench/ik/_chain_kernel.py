r"""Compiled serial-chain kinematics and the Levenberg–Marquardt loop of ``numeric``.

Everything here is compiled with Numba (``cache=True``: compiled once per
machine on first use, then loaded from the cache, whose key covers the source
of every module imported here: ``workbench._compiled``). Only :func:`run`,
:func:`solve_batch`, :func:`chain_kinematics` and :func:`chain_jacobians` are
entry points; a target is checked finite and rigid with the closed forms' test
(``_kernel_common.is_rigid``).

Compile time matters (the first ``numeric`` call with an empty cache): no
array slicing assignments or other library overloads (each compiles as a
function of its own), no literal arguments (each literal value compiles a
specialisation), and a shallow call tree (Numba re-optimises the code of every
callee in each caller).

The chain (built by ``workbench.ik._chain`` from the Pinocchio model) is one
float64 array of shape (n + 1, CHAIN_WIDTH). Row ``k < n`` describes the k-th
joint on the path from the base to the tool frame:

* ``[0:9]`` rotation, ``[9:12]`` translation of the joint placement in its
  parent joint's frame (Pinocchio's ``jointPlacements``), row-major;
* ``[12:15]`` unit axis in the joint frame; ``[15]`` ``REVOLUTE`` or
  ``PRISMATIC``;
* ``[16]``, ``[17]`` lower and upper limits [rad or m] (inf when unbounded);
* ``[18]`` ``WRAP_NONE``, ``WRAP_FULL_TURN`` (a bounded revolute joint whose
  range spans a full turn: it comes back in at the other end) or
  ``WRAP_UNBOUNDED`` (a continuous joint: never clipped);
* ``[19]`` for a revolute joint about a coordinate axis (x, y or z, either
  sign: most URDF joints) its index 0, 1 or 2, whose cheaper rotation the
  forward kinematics then uses; else -1.

Row ``n`` holds the tool frame placement in the last joint's frame in
``[0:12]``. Chain coordinates are one value per joint (an angle for a
continuous joint, whose Pinocchio ``q`` is (cos, sin)).

Poses are Pinocchio's: :math:`{}^oM_k = {}^oM_{k-1}\,M_k^{place}\,
\exp(\hat a_k q_k)` and :math:`{}^oM_f = {}^oM_n\,M_f^{place}`. The Jacobian
is Pinocchio's LOCAL frame Jacobian of the tool, rows [linear; angular].
The error of a configuration is :math:`e = \log_6(T^{-1}\,{}^oM_f)`, (6,).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point, helper
from workbench.ik._kernel_common import is_rigid

FloatArray = npt.NDArray[np.float64]

CHAIN_WIDTH = 20
REVOLUTE, PRISMATIC = 0.0, 1.0
WRAP_NONE, WRAP_FULL_TURN, WRAP_UNBOUNDED = 0.0, 1.0, 2.0

#: What :func:`run` aims at (``part``): the whole pose (the SE(3) log error,
#: weighted), the position only, the position and the tool's x, y or z axis.
PART_POSE, PART_POSITION, PART_FREE_X, PART_FREE_Y, PART_FREE_Z = 0, 1, 2, 3, 4

#: Status codes of :func:`run`.
CONVERGED, STALLED, EXHAUSTED, NOT_RIGID = 0, 1, 2, 3

#: Columns of the per-target statistics of :func:`run` / :func:`solve_batch`:
#: squared error, position error [m], rotation error [rad], steps, restarts.
ERR2, POSITION, ROTATION, STEPS, RESTARTS = 0, 1, 2, 3, 4
N_STATS = 5

DAMPING_GAIN = 3e-2
"""mu in lambda = mu |e|^2 + lambda_0 [1/m^2 ~ 1/rad^2 scale]."""

DAMPING_FLOOR = 1e-9
"""lambda_0: keeps J J^T + lambda I positive definite at singularities."""

STALL_STEPS = 4
"""A run ends when its error has not dropped by 10 % for this many steps."""

STALL_RATIO = 0.81
"""Squared-error ratio of one 10 % decrease."""

RUN_STEPS = 40
"""A run ends after this many steps, converging or not."""

NULL_GAIN = 0.1
"""Gain of the null-space pull to ``q_ref`` (redundant arms only) [1/step]."""

NULL_OFF_ERROR = 0.3
"""The null-space pull stops once |e| falls below this [m ~ rad]."""

MAX_STEP = 1.5
"""Newton steps (n = 6) are shortened to this norm [rad]."""

SINGULAR_STEP = 10.0
"""A Newton step longer than this [rad] means a (near-)singular Jacobian."""

ACTIVE_SET_ERROR = NULL_OFF_ERROR
"""Redundant arms re-solve a step that crosses a limit while |e| < this (the
null-space pull is off then)."""

UNBOUNDED_SPAN = math.pi
"""Restarts draw unbounded coordinates within +-this [rad]."""

_MAX_STEP2, _SINGULAR_STEP2 = MAX_STEP**2, SINGULAR_STEP**2
_NULL_OFF_ERROR2, _ACTIVE_SET_ERROR2 = NULL_OFF_ERROR**2, ACTIVE_SET_ERROR**2
_PI, _TAU = math.pi, 2.0 * math.pi
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)


@helper()
def _forward(chain: FloatArray, q: FloatArray, frames: FloatArray):
    """Poses of the joints (rows 0..n-1) and the tool (row n) in the base frame.

    ``frames`` (n + 1, 12) is filled: rotation (row-major) then position.
    """
    n = chain.shape[0] - 1
    # Sines and cosines first, into the rows they belong to (read back before
    # the row is filled): no library calls in the loop of matrix products.
    for k in range(n):
        if chain[k, 15] != PRISMATIC:
            frames[k, 0], frames[k, 1] = math.sin(q[k]), math.cos(q[k])
    _products(chain, q, frames)


@helper(forceinline=True)
def _products(chain: FloatArray, q: FloatArray, frames: FloatArray):
    """:func:`_forward` given the sines and cosines: ``frames[k, 0:2]`` = sin, cos q_k.

    (For callers that carry them from step to step instead of calling the
    library per joint: Newton's small steps, ``_refine_kernel``.) The running
    pose is held in scalars and each row stored once: LLVM cannot tell that
    ``frames`` and ``chain`` do not overlap, and would otherwise reload the
    placement after every store (most of the time of this loop).
    """
    n = chain.shape[0] - 1
    r0 = r1 = r2 = r3 = r4 = r5 = r6 = r7 = r8 = p0 = p1 = p2 = 0.0
    for k in range(n + 1):
        c, f = chain[k], frames[k]
        s, co = f[0], f[1]  # (a revolute joint's)
        c0, c1, c2, c3, c4, c5 = c[0], c[1], c[2], c[3], c[4], c[5]
        c6, c7, c8, c9, c10, c11 = c[6], c[7], c[8], c[9], c[10], c[11]
        if k == 0:  # the placement itself
            r0, r1, r2, r3, r4, r5, r6, r7, r8 = c0, c1, c2, c3, c4, c5, c6, c7, c8
            p0, p1, p2 = c9, c10, c11
        else:  # parent pose times the placement
            g0, g1, g2, g3, g4, g5 = r0, r1, r2, r3, r4, r5
            g6, g7, g8 = r6, r7, r8
            r0 = g0 * c0 + g1 * c3 + g2 * c6
            r1 = g0 * c1 + g1 * c4 + g2 * c7
            r2 = g0 * c2 + g1 * c5 + g2 * c8
            p0 = p0 + g0 * c9 + g1 * c10 + g2 * c11
            r3 = g3 * c0 + g4 * c3 + g5 * c6
            r4 = g3 * c1 + g4 * c4 + g5 * c7
            r5 = g3 * c2 + g4 * c5 + g5 * c8
            p1 = p1 + g3 * c9 + g4 * c10 + g5 * c11
            r6 = g6 * c0 + g7 * c3 + g8 * c6
            r7 = g6 * c1 + g7 * c4 + g8 * c7
            r8 = g6 * c2 + g7 * c5 + g8 * c8
            p2 = p2 + g6 * c9 + g7 * c10 + g8 * c11
        if k < n:
            x, y, z = c[12], c[13], c[14]
            m = int(c[19])
            if c[15] == PRISMATIC:  # translation q a along the joint axis
                p0 += q[k] * (r0 * x + r1 * y + r2 * z)
                p1 += q[k] * (r3 * x + r4 * y + r5 * z)
                p2 += q[k] * (r6 * x + r7 * y + r8 * z)
            elif m == 0:  # about coordinate axis m: a plane rotation of two columns
                s *= x  # the axis sign
                r1, r2 = r1 * co + r2 * s, r2 * co - r1 * s
                r4, r5 = r4 * co + r5 * s, r5 * co - r4 * s
                r7, r8 = r7 * co + r8 * s, r8 * co - r7 * s
            elif m == 1:
                s *= y
                r2, r0 = r2 * co + r0 * s, r0 * co - r2 * s
                r5, r3 = r5 * co + r3 * s, r3 * co - r5 * s
                r8, r6 = r8 * co + r6 * s, r6 * co - r8 * s
            elif m == 2:
                s *= z
                r0, r1 = r0 * co + r1 * s, r1 * co - r0 * s
                r3, r4 = r3 * co + r4 * s, r4 * co - r3 * s
                r6, r7 = r6 * co + r7 * s, r7 * co - r6 * s
            else:  # Rodrigues: exp(a^ q) = cos I + sin a^ + (1 - cos) a a^T.
                vers = 1.0 - co
                e00, e11, e22 = co + vers * x * x, co + vers * y * y, co + vers * z * z
                e01, e10 = vers * x * y - s * z, vers * x * y + s * z
                e02, e20 = vers * x * z + s * y, vers * x * z - s * y
                e12, e21 = vers * y * z - s * x, vers * y * z + s * x
                r0, r1, r2 = (
                    r0 * e00 + r1 * e10 + r2 * e20,
                    r0 * e01 + r1 * e11 + r2 * e21,
                    r0 * e02 + r1 * e12 + r2 * e22,
                )
                r3, r4, r5 = (
                    r3 * e00 + r4 * e10 + r5 * e20,
                    r3 * e01 + r4 * e11 + r5 * e21,
                    r3 * e02 + r4 * e12 + r5 * e22,
                )
                r6, r7, r8 = (
                    r6 * e00 + r7 * e10 + r8 * e20,
                    r6 * e01 + r7 * e11 + r8 * e21,
                    r6 * e02 + r7 * e12 + r8 * e22,
                )
        f[0], f[1], f[2], f[3], f[4], f[5] = r0, r1, r2, r3, r4, r5
        f[6], f[7], f[8], f[9], f[10], f[11] = r6, r7, r8, p0, p1, p2


@helper()
def _jacobian(chain: FloatArray, frames: FloatArray, jac: FloatArray):
    """LOCAL Jacobian of the tool into ``jac[:, :n]``, from :func:`_forward`."""
    n = chain.shape[0] - 1
    f = frames[n]
    for k in range(n):
        c, g = chain[k], frames[k]
        x, y, z = c[12], c[13], c[14]
        wx = g[0] * x + g[1] * y + g[2] * z  # joint axis in base axes
        wy = g[3] * x + g[4] * y + g[5] * z
        wz = g[6] * x + g[7] * y + g[8] * z
        if c[15] == REVOLUTE:  # linear w x (p_f - p_k), angular w
            dx, dy, dz = f[9] - g[9], f[10] - g[10], f[11] - g[11]
            lx, ly, lz = wy * dz - wz * dy, wz * dx - wx * dz, wx * dy - wy * dx
            turn = 1.0
        else:  # linear w, angular 0
            lx, ly, lz = wx, wy, wz
            turn = 0.0
        for i in range(3):  # into the tool's axes: R_f^T
            jac[i, k] = f[i] * lx + f[3 + i] * ly + f[6 + i] * lz
            jac[3 + i, k] = turn * (f[i] * wx + f[3 + i] * wy + f[6 + i] * wz)


@helper()
def _error(target: FloatArray, frames: FloatArray, e: FloatArray) -> float:
    r"""``e = log6(T^-1 oMf)`` (6,) of the tool (last row of ``frames``); |p_err|."""
    f, t = frames[frames.shape[0] - 1], target
    dx, dy, dz = f[9] - t[0, 3], f[10] - t[1, 3], f[11] - t[2, 3]
    # R = R_t^T R_f (row-major in e's scratch-free scalars), p = R_t^T (p_f - p_t).
    r00 = t[0, 0] * f[0] + t[1, 0] * f[3] + t[2, 0] * f[6]
    r01 = t[0, 0] * f[1] + t[1, 0] * f[4] + t[2, 0] * f[7]
    r02 = t[0, 0] * f[2] + t[1, 0] * f[5] + t[2, 0] * f[8]
    r10 = t[0, 1] * f[0] + t[1, 1] * f[3] + t[2, 1] * f[6]
    r11 = t[0, 1] * f[1] + t[1, 1] * f[4] + t[2, 1] * f[7]
    r12 = t[0, 1] * f[2] + t[1, 1] * f[5] + t[2, 1] * f[8]
    r20 = t[0, 2] * f[0] + t[1, 2] * f[3] + t[2, 2] * f[6]
    r21 = t[0, 2] * f[1] + t[1, 2] * f[4] + t[2, 2] * f[7]
    r22 = t[0, 2] * f[2] + t[1, 2] * f[5] + t[2, 2] * f[8]
    px = t[0, 0] * dx + t[1, 0] * dy + t[2, 0] * dz
    py = t[0, 1] * dx + t[1, 1] * dy + t[2, 1] * dz
    pz = t[0, 2] * dx + t[1, 2] * dy + t[2, 2] * dz
    # log3, robust at 0 and at pi: theta = atan2(|vee| / 2, (tr - 1) / 2).
    vx, vy, vz = r21 - r12, r02 - r20, r10 - r01
    co = 0.5 * (r00 + r11 + r22 - 1.0)
    si = 0.5 * math.sqrt(vx * vx + vy * vy + vz * vz)
    theta = math.atan2(si, co)
    if co > -0.9:  # w = theta / (2 sin theta) vee, Taylor near 0
        h = 0.5 + theta * theta / 12.0 if theta < 1e-4 else 0.5 * theta / si
        wx, wy, wz = h * vx, h * vy, h * vz
    else:  # near pi: the axis from the symmetric part cos I + (1 - cos) a a^T
        v = 1.0 - co
        if r00 >= r11 and r00 >= r22:
            ax = math.sqrt(max(r00 - co, 0.0) / v)
            ay, az = 0.5 * (r01 + r10) / (v * ax), 0.5 * (r02 + r20) / (v * ax)
        elif r11 >= r22:
            ay = math.sqrt(max(r11 - co, 0.0) / v)
            ax, az = 0.5 * (r01 + r10) / (v * ay), 0.5 * (r12 + r21) / (v * ay)
        else:
            az = math.sqrt(max(r22 - co, 0.0) / v)
            ax, ay = 0.5 * (r02 + r20) / (v * az), 0.5 * (r12 + r21) / (v * az)
        if ax * vx + ay * vy + az * vz < 0.0:  # vee = 2 sin(theta) a
            ax, ay, az = -ax, -ay, -az
        wx, wy, wz = theta * ax, theta * ay, theta * az
    # v = alpha p - w x p / 2 + beta (w . p) w  (the inverse of SE(3)'s V).
    t2 = theta * theta
    if theta < 1e-2:
        alpha, beta = 1.0 - t2 / 12.0 - t2 * t2 / 720.0, 1.0 / 12.0 + t2 / 720.0
    else:
        # theta / (2 tan(theta / 2)) by the half-angle formulas (no tan call),
        # each used where it is accurate; r = 1 for an exact rotation.
        r = math.sqrt(si * si + co * co)
        if co >= 0.0:
            alpha = 0.5 * theta * (r + co) / si
        else:
            alpha = 0.5 * theta * si / (r - co)
        beta = (1.0 - alpha) / t2
    wp = beta * (wx * px + wy * py + wz * pz)
    e[0] = alpha * px - 0.5 * (wy * pz - wz * py) + wp * wx
    e[1] = alpha * py - 0.5 * (wz * px - wx * pz) + wp * wy
    e[2] = alpha * pz - 0.5 * (wx * py - wy * px) + wp * wz
    e[3], e[4], e[5] = wx, wy, wz
    return math.sqrt(px * px + py * py + pz * pz)


@helper()
def _part_error(
    chain: FloatArray, frames: FloatArray, target: FloatArray, part: int,
    e: FloatArray, jac: FloatArray, with_jacobian: bool,
) -> tuple[float, float]:  # fmt: skip
    r"""Error and Jacobian of a partial target (``part``: :data:`PART_POSITION`, …).

    In the target's axes: ``e[:3] = R_t^T (p_f - p_t)``, the tool's offset, and
    for a free axis k ``e[3:] = R_t^T a - e_k``, ``a`` the tool's axis k (0 for
    the position only); ``jac`` (6, n) their exact derivatives (linear rows
    ``R_t^T v``, angular rows ``R_t^T (w x a)``, from the joints' world axes w).

    Returns:
        The tool's distance [m] and angle [rad] from the target.
    """
    n = chain.shape[0] - 1
    f, t = frames[n], target
    dx, dy, dz = f[9] - t[0, 3], f[10] - t[1, 3], f[11] - t[2, 3]
    for i in range(3):
        e[i] = t[0, i] * dx + t[1, i] * dy + t[2, i] * dz
    trace = 0.0
    for i in range(3):  # trace of R_t^T R_f
        trace += t[0, i] * f[i] + t[1, i] * f[3 + i] + t[2, i] * f[6 + i]
    rotation = math.acos(min(max(0.5 * (trace - 1.0), -1.0), 1.0))
    axis = part - PART_FREE_X  # -1 for the position only
    ax = ay = az = 0.0
    if axis >= 0:
        ax, ay, az = f[axis], f[3 + axis], f[6 + axis]  # the tool's axis, world
        for i in range(3):
            e[3 + i] = t[0, i] * ax + t[1, i] * ay + t[2, i] * az
        e[3 + axis] -= 1.0
    else:
        e[3] = e[4] = e[5] = 0.0
    position = math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
    if not with_jacobian:
        return position, rotation
    for k in range(n):
        c, g = chain[k], frames[k]
        x, y, z = c[12], c[13], c[14]
        wx = g[0] * x + g[1] * y + g[2] * z
        wy = g[3] * x + g[4] * y + g[5] * z
        wz = g[6] * x + g[7] * y + g[8] * z
        if c[15] == REVOLUTE:
            px, py, pz = f[9] - g[9], f[10] - g[10], f[11] - g[11]
            lx, ly, lz = wy * pz - wz * py, wz * px - wx * pz, wx * py - wy * px
            bx, by, bz = wy * az - wz * ay, wz * ax - wx * az, wx * ay - wy * ax
        else:
            lx, ly, lz = wx, wy, wz
            bx = by = bz = 0.0
        for i in range(3):
            jac[i, k] = t[0, i] * lx + t[1, i] * ly + t[2, i] * lz
            jac[3 + i, k] = t[0, i] * bx + t[1, i] * by + t[2, i] * bz
    return position, rotation


@helper()
def _solve(a: FloatArray, b: FloatArray, m: int) -> bool:
    """Solve a x = b (first m rows/columns) in place, x in b; False if singular.

    LU with partial pivoting. The pivot is chosen and its row swapped in
    without branches on the values (a swap with itself when it is in place),
    and the diagonal keeps the pivots' reciprocals: mispredicted branches and
    divisions were most of its time. (A copy for exactly six equations, whose
    loops LLVM unrolls, took 175 ns against 215, but a second of compiling on
    a first run: not kept.)
    """
    for k in range(m):
        p, big = k, abs(a[k, k])
        for i in range(k + 1, m):
            v = abs(a[i, k])
            larger = v > big  # False for NaN, as the pivot search always was
            p = i if larger else p
            big = v if larger else big
        if big == 0.0:
            return False
        for j in range(k, m):  # (columns < k are not read again)
            x = a[k, j]
            a[k, j] = a[p, j]
            a[p, j] = x
        x = b[k]
        b[k] = b[p]
        b[p] = x
        bk, inverse = b[k], 1.0 / a[k, k]
        a[k, k] = inverse
        for i in range(k + 1, m):
            f = a[i, k] * inverse
            for j in range(k + 1, m):
                a[i, j] -= f * a[k, j]
            b[i] -= f * bk
    for k in range(m - 1, -1, -1):
        s = b[k]
        for j in range(k + 1, m):
            s -= a[k, j] * b[j]
        b[k] = s * a[k, k]
    return True


@helper()
def _damped_step(jac, n, e, pull, use_pull, damping, normal, y, dq):
    r"""Damped least-squares step (to subtract from q) into ``dq[:n]``.

    n >= 6: :math:`J^T (J J^T + \lambda I)^{-1} (e + J z) - z` (z = ``pull``
    when ``use_pull``); n < 6: :math:`(J^T J + \lambda I)^{-1} J^T e`.
    ``normal`` (>= 6, >= 6) and ``y`` (>= 6,) are scratch space.
    """
    m = min(n, 6)
    for i in range(m):
        for j in range(m):
            s = 0.0
            if n < 6:  # J^T J
                for r in range(6):
                    s += jac[r, i] * jac[r, j]
            else:  # J J^T
                for k in range(n):
                    s += jac[i, k] * jac[j, k]
            normal[i, j] = s
        normal[i, i] += damping
        if n < 6:  # J^T e
            s = 0.0
            for r in range(6):
                s += jac[r, i] * e[r]
        else:  # e + J z
            s = e[i]
            if use_pull:
                for k in range(n):
                    s += jac[i, k] * pull[k]
        y[i] = s
    _solve(normal, y, m)  # positive definite: never singular
    for k in range(n):
        if n < 6:
            dq[k] = y[k]
            continue
        s = 0.0
        for i in range(6):  # J^T y (- z)
            s += jac[i, k] * y[i]
        dq[k] = s - pull[k] if use_pull else s


@helper()
def _first_guess(features: np.ndarray, starts: FloatArray, target: FloatArray, q):
    """Copy into ``q`` the candidate start whose tool pose is nearest ``target``.

    ``features`` (16, count) float32: per candidate (column), 16 numbers whose
    dot product with the row-major target matrix is its score (the smallest
    wins); ``starts`` (count, n): the candidates' coordinates. Candidates run
    along rows, and in single precision, so that the scoring is SIMD code.
    """
    count = features.shape[1]
    if count == 0:
        return
    score = np.empty(count, dtype=np.float32)
    f, t, f32 = features, target, np.float32
    t0, t1, t2, t3 = f32(t[0, 0]), f32(t[0, 1]), f32(t[0, 2]), f32(t[0, 3])
    t4, t5, t6, t7 = f32(t[1, 0]), f32(t[1, 1]), f32(t[1, 2]), f32(t[1, 3])
    t8, t9, t10, t11 = f32(t[2, 0]), f32(t[2, 1]), f32(t[2, 2]), f32(t[2, 3])
    for c in range(count):  # one pass: each score is stored once
        score[c] = (
            f[15, c]
            + t0 * f[0, c]
            + t1 * f[1, c]
            + t2 * f[2, c]
            + t3 * f[3, c]
            + t4 * f[4, c]
            + t5 * f[5, c]
            + t6 * f[6, c]
            + t7 * f[7, c]
            + t8 * f[8, c]
            + t9 * f[9, c]
            + t10 * f[10, c]
            + t11 * f[11, c]
        )
    best, low = 0, score[0]
    for c in range(1, count):
        if score[c] < low:
            best, low = c, score[c]
    for k in range(q.shape[0]):
        q[k] = starts[best, k]


@entry_point(
    outputs=("states",),
    contiguous=("chain", "target", "q_ref", "features", "starts", "weights"),
)
def run(
    chain: FloatArray,
    target: FloatArray,
    q_ref: FloatArray,
    states: FloatArray,
    row: int,
    tol2: float,
    max_steps: int,
    guess: bool,
    features: npt.NDArray[np.float32],
    starts: FloatArray,
    check: bool,
    weights: FloatArray,
    part: int,
) -> tuple[int, float, float, float, int]:
    """One run of damped Newton steps from ``q``, until it converges or stalls.

    Args:
        chain: (n + 1, CHAIN_WIDTH) chain (module docstring).
        target: (4, 4) homogeneous target of the tool in the base frame [m].
        q_ref: (n,) configuration redundant arms are pulled towards.
        states: (m, 2 n + N_STATS) states; row ``row`` is this solve's: the
            start ``q`` (overwritten by the last iterate), the best
            configuration so far and the running statistics (ERR2 inf and
            STEPS 0 at first), all updated in place. A block of states and a
            row index, so that a call from Python makes no array view.
        row: The row of ``states``.
        tol2: Squared convergence threshold on |e|.
        max_steps: Step budget over all runs.
        guess: Start from the candidate nearest the target
            instead of ``q``.
        features: (16, count) float32 candidate features (:func:`_first_guess`).
        starts: (count, n) candidate coordinates.
        check: Test first that ``target`` is finite and rigid (the test and
            tolerance of ``workbench.poses``).
        weights: (6,) weights of the error's entries [x, y, z, rx, ry, rz]
            (target frame) and of the Jacobian's rows: ones for the full pose,
            0 for an entry left free (e.g. ``(1, 1, 1, 0, 0, 0)``: the
            position only). ERR2 is the weighted error; POSITION and ROTATION
            are the tool's true distance and angle from the target.
        part: :data:`PART_POSE` (the weighted SE(3) log error), or a partial
            target (:data:`PART_POSITION`, :data:`PART_FREE_X` … Z), whose
            error and Jacobian are :func:`_part_error`'s (``weights`` unused).

    Returns:
        ``(status, err2, position, rotation, steps)``: CONVERGED, STALLED (a
        restart is due), EXHAUSTED (no steps left) or NOT_RIGID (``target``
        is not finite and rigid; nothing done), then the statistics
        ERR2, POSITION, ROTATION and STEPS of the best configuration so far
        (a tuple: Python reads them without converting the state).
    """
    n = chain.shape[0] - 1
    state = states[row]
    q, best_q, stats = state[:n], state[n : 2 * n], state[2 * n :]
    status = NOT_RIGID
    if check and not is_rigid(target):
        return status, stats[ERR2], stats[POSITION], stats[ROTATION], int(stats[STEPS])
    if guess:
        _first_guess(features, starts, target, q)
    # Scratch space: frames of the joints and tool, matrices and vectors.
    frames, work = np.empty((n + 1, 12)), np.empty((23, max(n, 6)))
    jac, jac_free, normal = work[0:6], work[6:12], work[12:18]
    e, dq, pull, q_next, y = work[18], work[19], work[20], work[21], work[22]
    square, redundant = n == 6, n > 6
    steps = int(stats[STEPS])
    run_start = stall_at = steps
    stall_level = math.inf
    while True:
        _forward(chain, q, frames)
        err2 = 0.0
        if part == PART_POSE:
            position = _error(target, frames, e)
            rotation = math.sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5])
            for i in range(6):
                e[i] *= weights[i]
                err2 += e[i] * e[i]
        else:  # its Jacobian too (the step below needs it unless converged)
            position, rotation = _part_error(chain, frames, target, part, e, jac, True)
            for i in range(6):
                err2 += e[i] * e[i]
        if err2 < stats[ERR2]:
            stats[ERR2], stats[POSITION], stats[ROTATION] = err2, position, rotation
            for k in range(n):
                best_q[k] = q[k]
            if err2 <= tol2:
                stats[STEPS] = steps
                status = CONVERGED
                break
        if err2 < stall_level:
            stall_level, stall_at = STALL_RATIO * err2, steps
        if steps >= max_steps:
            stats[STEPS] = steps
            status = EXHAUSTED
            break
        if steps - stall_at >= STALL_STEPS or steps - run_start >= RUN_STEPS:
            stats[STEPS] = steps
            status = STALLED
            break
        steps += 1

        if part == PART_POSE:
            _jacobian(chain, frames, jac)
            for i in range(6):
                for k in range(n):
                    jac[i, k] *= weights[i]
        newton = False
        if square:  # Newton step J^-1 e
            for i in range(6):
                for j in range(6):
                    normal[i, j] = jac[i, j]
                dq[i] = e[i]
            if _solve(normal, dq, n):  # n == 6
                step2 = 0.0
                for k in range(6):
                    step2 += dq[k] * dq[k]
                if step2 <= _MAX_STEP2:
                    newton = True
                elif step2 < _SINGULAR_STEP2:  # long: shortened
                    shorten = MAX_STEP / math.sqrt(step2)
                    for k in range(6):
                        dq[k] *= shorten
                    newton = True
                # else near-singular J (or NaN): the damped step
        damping = DAMPING_GAIN * err2 + DAMPING_FLOOR
        use_pull = redundant and err2 > _NULL_OFF_ERROR2
        if not newton:
            if use_pull:
                for k in range(n):
                    d = q_ref[k] - q[k]
                    if chain[k, 18] == WRAP_UNBOUNDED:  # shortest way round
                        d -= _TAU * math.floor(d / _TAU + 0.5)
                    pull[k] = NULL_GAIN * d
            _damped_step(jac, n, e, pull, use_pull, damping, normal, y, dq)
        clipped = False
        for k in range(n):
            x = q[k] - dq[k]
            lo, hi = chain[k, 16], chain[k, 17]
            if chain[k, 18] == WRAP_FULL_TURN:  # comes back in at the other end
                if x > hi:
                    x -= _TAU
                elif x < lo:
                    x += _TAU
            q_next[k] = x
            clipped |= x < lo or x > hi
        if clipped and redundant and err2 < _ACTIVE_SET_ERROR2:
            # Freeze the joints pushed out: the others take over their motion.
            # (No pull here: it stops above ACTIVE_SET_ERROR.)
            for k in range(n):
                free = chain[k, 16] <= q_next[k] <= chain[k, 17]
                for r in range(6):
                    jac_free[r, k] = jac[r, k] if free else 0.0
            # use_pull is False here (err2 < ACTIVE_SET_ERROR^2 = NULL_OFF_ERROR^2);
            # passed as the variable: a literal False would compile a copy.
            _damped_step(jac_free, n, e, pull, use_pull, damping, normal, y, dq)
            for k in range(n):
                q_next[k] = q[k] - dq[k]
        for k in range(n):
            q[k] = min(max(q_next[k], chain[k, 16]), chain[k, 17])
    return status, stats[ERR2], stats[POSITION], stats[ROTATION], int(stats[STEPS])


@helper()
def _splitmix(state: np.ndarray) -> float:
    """Next uniform draw in [0, 1) of the SplitMix64 generator ``state`` (1,) uint64."""
    state[0] += _GOLDEN
    z = state[0]
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z ^= z >> np.uint64(31)
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@entry_point(
    outputs=("out_q", "out_stats"),
    contiguous=(
        "chain",
        "targets",
        "q_ref",
        "q_start",
        "features",
        "starts",
        "weights",
    ),
)
def solve_batch(
    chain: FloatArray,
    targets: FloatArray,
    q_ref: FloatArray,
    q_start: FloatArray,
    features: npt.NDArray[np.float32],
    starts: FloatArray,
    tol2: float,
    max_steps: int,
    seed: int,
    weights: FloatArray,
    part: int,
    out_q: FloatArray,
    out_stats: FloatArray,
) -> None:
    """Solve every target of ``targets`` (N, 4, 4), restarts drawn in compiled code.

    Args:
        chain: (n + 1, CHAIN_WIDTH) chain.
        targets: (N, 4, 4) targets, already checked finite and rigid.
        q_ref: (1 or N, n) pull references (one for all, or one per target).
        q_start: (0, 1 or N, n) starts; none: the nearest candidate.
        features: (16, count) float32 candidate features (:func:`_first_guess`).
        starts: (count, n) candidate coordinates.
        tol2: Squared convergence threshold on |e|.
        max_steps: Step budget per target.
        seed: Seed of the restart draws; target i draws from SplitMix64 seeded
            with ``seed + i * golden``, so a result does not depend on the batch.
        weights: (6,) weights of the error's entries (:func:`run`).
        part: What is aimed at (:func:`run`).
        out_q: (N, n) best configuration per target.
        out_stats: (N, N_STATS) statistics per target.
    """
    n = chain.shape[0] - 1
    low, span = np.empty(n), np.empty(n)
    for k in range(n):
        lo, hi = chain[k, 16], chain[k, 17]
        low[k] = lo if math.isfinite(lo) else -UNBOUNDED_SPAN
        span[k] = (hi if math.isfinite(hi) else UNBOUNDED_SPAN) - low[k]
    states = np.empty((1, 2 * n + N_STATS))
    state = states[0]
    q, best_q, stats = state[:n], state[n : 2 * n], state[2 * n :]
    draws = np.empty(1, dtype=np.uint64)
    for i in range(targets.shape[0]):
        target = targets[i]
        for j in range(N_STATS):
            stats[j] = 0.0
        stats[ERR2] = math.inf
        ref = q_ref[i if q_ref.shape[0] > 1 else 0]
        guess = q_start.shape[0] == 0
        if not guess:
            start = q_start[i if q_start.shape[0] > 1 else 0]
            for k in range(n):
                q[k] = start[k]
        draws[0] = np.uint64(seed) + np.uint64(i) * _GOLDEN
        # Targets are checked already; False as a computed bool, not a literal
        # (a literal argument would compile another specialisation of run).
        check = i < 0
        while (
            run(chain, target, ref, states, 0, tol2, max_steps, guess, features,
                starts, check, weights, part)[0]
            == STALLED
        ):  # fmt: skip
            guess = check  # False (see above)
            for k in range(n):
                q[k] = low[k] + span[k] * _splitmix(draws)
            stats[RESTARTS] += 1.0
        for k in range(n):
            out_q[i, k] = best_q[k]
        for j in range(N_STATS):
            out_stats[i, j] = stats[j]


@entry_point(outputs=("jac",), contiguous=("chain", "q"))
def chain_kinematics(chain: FloatArray, q: FloatArray, jac: FloatArray) -> FloatArray:
    """Tool pose (4, 4) in the base frame at ``q`` (n,); LOCAL Jacobian into ``jac``."""
    n = chain.shape[0] - 1
    frames = np.empty((n + 1, 12))
    _forward(chain, q, frames)
    _jacobian(chain, frames, jac)
    pose = np.empty((4, 4))
    f = frames[n]
    for i in range(4):
        for j in range(3):
            pose[i, j] = f[3 * i + j] if i < 3 else 0.0
        pose[i, 3] = f[9 + i] if i < 3 else 1.0
    return pose


@entry_point(outputs=("jac",), contiguous=("chain", "q"))
def chain_jacobians(chain: FloatArray, q: FloatArray, jac: FloatArray) -> None:
    """LOCAL tool Jacobians at chain coordinates ``q`` (N, n) into ``jac`` (N, 6, n).

    One pass of :func:`_forward` and :func:`_jacobian` per configuration.
    """
    n = chain.shape[0] - 1
    frames = np.empty((n + 1, 12))
    for b in range(q.shape[0]):
        _forward(chain, q[b], frames)
        _jacobian(chain, frames, jac[b])
