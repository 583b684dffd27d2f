r"""Compiled serial-chain kinematics and the Levenberg–Marquardt loop of ``numeric``.

Everything here is compiled with Numba (``cache=True``: compiled once per
machine on first use, then loaded from the cache). The module is kept whole,
although longer than the usual ~300 lines: Numba's cache of a function is not
invalidated when a function it calls changes in *another* file, so the
kernels that call each other live in one file. Only :func:`run`,
:func:`solve_batch` and :func:`chain_kinematics` are entry points; the rest
is inlined into them.

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
  ``WRAP_UNBOUNDED`` (a continuous joint: never clipped).

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

import numba
import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

CHAIN_WIDTH = 19
REVOLUTE, PRISMATIC = 0.0, 1.0
WRAP_NONE, WRAP_FULL_TURN, WRAP_UNBOUNDED = 0.0, 1.0, 2.0

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

ACTIVE_SET_ERROR = 0.3
"""Redundant arms re-solve a step that crosses a limit while |e| < this."""

UNBOUNDED_SPAN = math.pi
"""Restarts draw unbounded coordinates within +-this [rad]."""

#: Fast acceptance of a target: columns x, y of R orthonormal, z = x × y and
#: the bottom row, each within RIGIDITY_TOL / 5 (``workbench.poses``), as one
#: sum of squares. A target that fails it takes the exact checks in Python.
FAST_TOL2 = (1e-6 / 5.0) ** 2

_MAX_STEP2, _SINGULAR_STEP2 = MAX_STEP**2, SINGULAR_STEP**2
_NULL_OFF_ERROR2, _ACTIVE_SET_ERROR2 = NULL_OFF_ERROR**2, ACTIVE_SET_ERROR**2
_PI, _TAU = math.pi, 2.0 * math.pi
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")
_inline = numba.njit(cache=True, nogil=True, error_model="numpy")


@_inline
def _forward(chain: FloatArray, q: FloatArray, rot: FloatArray, pos: FloatArray):
    """Poses of the joints (rows 0..n-1) and the tool (row n) in the base frame.

    ``rot`` (n + 1, 3, 3) and ``pos`` (n + 1, 3) are filled.
    """
    n = chain.shape[0] - 1
    a = np.empty((3, 3))
    e = np.empty((3, 3))
    for k in range(n + 1):
        c = chain[k]
        r, p = rot[k], pos[k]
        if k == 0:
            for i in range(3):  # the placement itself
                for j in range(3):
                    a[i, j] = c[3 * i + j]
                p[i] = c[9 + i]
        else:
            parent, parent_p = rot[k - 1], pos[k - 1]
            for i in range(3):  # parent pose times the placement
                for j in range(3):
                    a[i, j] = (
                        parent[i, 0] * c[j] + parent[i, 1] * c[3 + j]
                        + parent[i, 2] * c[6 + j]
                    )  # fmt: skip
                p[i] = parent_p[i] + (
                    parent[i, 0] * c[9] + parent[i, 1] * c[10] + parent[i, 2] * c[11]
                )
        if k < n and c[15] == REVOLUTE:
            # Rodrigues: exp(a^ q) = cos I + sin a^ + (1 - cos) a a^T.
            s, co = math.sin(q[k]), math.cos(q[k])
            for i in range(3):
                for j in range(3):
                    e[i, j] = (1.0 - co) * c[12 + i] * c[12 + j]
                e[i, i] += co
            x, y, z = s * c[12], s * c[13], s * c[14]
            e[0, 1] -= z
            e[1, 0] += z
            e[0, 2] += y
            e[2, 0] -= y
            e[1, 2] -= x
            e[2, 1] += x
            for i in range(3):
                for j in range(3):
                    r[i, j] = a[i, 0] * e[0, j] + a[i, 1] * e[1, j] + a[i, 2] * e[2, j]
        else:
            for i in range(3):
                for j in range(3):
                    r[i, j] = a[i, j]
            if k < n:  # prismatic: translation q a along the joint axis
                for i in range(3):
                    p[i] += q[k] * (a[i, 0] * c[12] + a[i, 1] * c[13] + a[i, 2] * c[14])


@_inline
def _jacobian(chain: FloatArray, rot: FloatArray, pos: FloatArray, jac: FloatArray):
    """LOCAL Jacobian of the tool, (6, n), from the poses of :func:`_forward`."""
    n = chain.shape[0] - 1
    f, fp = rot[n], pos[n]
    w, d = np.empty(3), np.empty(3)
    for k in range(n):
        r, c = rot[k], chain[k]
        for i in range(3):  # joint axis in base axes
            w[i] = r[i, 0] * c[12] + r[i, 1] * c[13] + r[i, 2] * c[14]
        if c[15] == REVOLUTE:  # linear: w x (p_f - p_k); angular: w
            for i in range(3):
                d[i] = fp[i] - pos[k, i]
            lx = w[1] * d[2] - w[2] * d[1]
            ly = w[2] * d[0] - w[0] * d[2]
            lz = w[0] * d[1] - w[1] * d[0]
            angular = 1.0
        else:  # linear: w; angular: 0
            lx, ly, lz = w[0], w[1], w[2]
            angular = 0.0
        for i in range(3):  # into the tool's axes: R_f^T
            jac[i, k] = f[0, i] * lx + f[1, i] * ly + f[2, i] * lz
            jac[3 + i, k] = angular * (f[0, i] * w[0] + f[1, i] * w[1] + f[2, i] * w[2])


@_inline
def _error(target: FloatArray, rot: FloatArray, pos: FloatArray, e: FloatArray):
    r"""``e = log6(T^-1 oMf)`` (6,) of the tool pose (last row); returns |p_err|."""
    n = rot.shape[0] - 1
    f = rot[n]
    r, p, d = np.empty((3, 3)), np.empty(3), np.empty(3)
    for i in range(3):
        d[i] = pos[n, i] - target[i, 3]
    for i in range(3):  # R = R_t^T R_f, p = R_t^T (p_f - p_t)
        for j in range(3):
            r[i, j] = (
                target[0, i] * f[0, j] + target[1, i] * f[1, j] + target[2, i] * f[2, j]
            )
        p[i] = target[0, i] * d[0] + target[1, i] * d[1] + target[2, i] * d[2]
    # log3, robust at 0 and at pi: theta = atan2(|vee| / 2, (tr - 1) / 2).
    w = e[3:]
    w[0], w[1], w[2] = r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]
    co = 0.5 * (r[0, 0] + r[1, 1] + r[2, 2] - 1.0)
    si = 0.5 * math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    theta = math.atan2(si, co)
    if co > -0.9:  # w = theta / (2 sin theta) vee (Taylor near 0)
        factor = 0.5 + theta * theta / 12.0 if theta < 1e-4 else 0.5 * theta / si
        for i in range(3):
            w[i] *= factor
    else:  # near pi: the axis from the symmetric part cos I + (1 - cos) a a^T
        v = 1.0 - co
        m = 0
        for i in range(1, 3):
            if r[i, i] > r[m, m]:
                m = i
        d[m] = math.sqrt(max(r[m, m] - co, 0.0) / v)
        for i in range(3):
            if i != m:
                d[i] = 0.5 * (r[m, i] + r[i, m]) / (v * d[m])
        if d[0] * w[0] + d[1] * w[1] + d[2] * w[2] < 0.0:  # vee = 2 sin a
            theta = -theta
        for i in range(3):
            w[i] = theta * d[i]
        theta = abs(theta)
    # v = alpha p - w x p / 2 + beta (w . p) w  (the inverse of SE(3)'s V).
    t2 = theta * theta
    if theta < 1e-2:
        alpha, beta = 1.0 - t2 / 12.0 - t2 * t2 / 720.0, 1.0 / 12.0 + t2 / 720.0
    else:
        alpha = 0.5 * theta / math.tan(0.5 * theta)
        beta = (1.0 - alpha) / t2
    wp = beta * (w[0] * p[0] + w[1] * p[1] + w[2] * p[2])
    e[0] = alpha * p[0] - 0.5 * (w[1] * p[2] - w[2] * p[1]) + wp * w[0]
    e[1] = alpha * p[1] - 0.5 * (w[2] * p[0] - w[0] * p[2]) + wp * w[1]
    e[2] = alpha * p[2] - 0.5 * (w[0] * p[1] - w[1] * p[0]) + wp * w[2]
    return math.sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2])


@_inline
def _solve(a: FloatArray, b: FloatArray) -> bool:
    """Solve a x = b in place (x in b), LU with partial pivoting; False if singular."""
    m = b.shape[0]
    for k in range(m):
        p = k
        for i in range(k + 1, m):
            if abs(a[i, k]) > abs(a[p, k]):
                p = i
        if a[p, k] == 0.0:
            return False
        if p != k:
            for j in range(m):
                a[k, j], a[p, j] = a[p, j], a[k, j]
            b[k], b[p] = b[p], b[k]
        for i in range(k + 1, m):
            f = a[i, k] / a[k, k]
            for j in range(k + 1, m):
                a[i, j] -= f * a[k, j]
            b[i] -= f * b[k]
    for k in range(m - 1, -1, -1):
        s = b[k]
        for j in range(k + 1, m):
            s -= a[k, j] * b[j]
        b[k] = s / a[k, k]
    return True


@_inline
def _damped_step(jac, e, pull, use_pull, damping, dq):
    r"""Damped least-squares step (to subtract from q) into ``dq`` (n,).

    n >= 6: :math:`J^T (J J^T + \lambda I)^{-1} (e + J z) - z` (z = ``pull``
    when ``use_pull``); n < 6: :math:`(J^T J + \lambda I)^{-1} J^T e`.
    """
    n = jac.shape[1]
    m = min(n, 6)
    normal, y = np.empty((m, m)), np.empty(m)
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
        s = 0.0
        if n < 6:  # J^T e
            for r in range(6):
                s += jac[r, i] * e[r]
        else:  # e + J z
            s = e[i]
            if use_pull:
                for k in range(n):
                    s += jac[i, k] * pull[k]
        y[i] = s
    _solve(normal, y)  # positive definite: never singular
    if n < 6:
        for k in range(n):
            dq[k] = y[k]
        return
    for k in range(n):  # J^T y (- z)
        s = 0.0
        for i in range(6):
            s += jac[i, k] * y[i]
        dq[k] = s - pull[k] if use_pull else s


@_inline
def _roughly_rigid(pose: FloatArray) -> bool:
    """The fast acceptance test of a target (finite, rigid to RIGIDITY_TOL / 5)."""
    r00, r01, r02 = pose[0, 0], pose[0, 1], pose[0, 2]
    r10, r11, r12 = pose[1, 0], pose[1, 1], pose[1, 2]
    r20, r21, r22 = pose[2, 0], pose[2, 1], pose[2, 2]
    e0 = r00 * r00 + r10 * r10 + r20 * r20 - 1.0
    e1 = r01 * r01 + r11 * r11 + r21 * r21 - 1.0
    e2 = r00 * r01 + r10 * r11 + r20 * r21
    ex = r10 * r21 - r20 * r11 - r02  # x × y - z
    ey = r20 * r01 - r00 * r21 - r12
    ez = r00 * r11 - r10 * r01 - r22
    b0, b1, b2, b3 = pose[3, 0], pose[3, 1], pose[3, 2], pose[3, 3] - 1.0
    err2 = e0 * e0 + e1 * e1 + e2 * e2 + ex * ex + ey * ey + ez * ez
    err2 += b0 * b0 + b1 * b1 + b2 * b2 + b3 * b3
    # a NaN fails the comparison; an infinite translation makes the sum NaN
    return err2 <= FAST_TOL2 and (pose[0, 3] + pose[1, 3] + pose[2, 3]) * 0.0 == 0.0


@_inline
def _first_guess(seeds: FloatArray, target: FloatArray, q: FloatArray):
    """Copy into ``q`` the candidate whose tool pose is nearest ``target``.

    ``seeds`` (count, 16 + n): 16 features of the candidate's tool pose (its
    score is their dot product with the row-major target matrix), then its q.
    """
    best, best_score = 0, math.inf
    for c in range(seeds.shape[0]):
        s = seeds[c]
        score = s[15]
        for i in range(3):
            for j in range(4):
                score += s[4 * i + j] * target[i, j]
        if score < best_score:
            best, best_score = c, score
    for k in range(q.shape[0]):
        q[k] = seeds[best, 16 + k]


@_jit
def run(chain, target, q, q_ref, best_q, stats, tol2, max_steps, guess, seeds, check):
    """One run of damped Newton steps from ``q``, until it converges or stalls.

    Args:
        chain: (n + 1, CHAIN_WIDTH) chain (module docstring).
        target: (4, 4) homogeneous target of the tool in the base frame [m].
        q: (n,) start, chain coordinates; overwritten (the last iterate).
        q_ref: (n,) configuration redundant arms are pulled towards.
        best_q: (n,) best configuration so far, updated in place.
        stats: (N_STATS,) running statistics (ERR2 inf and STEPS 0 at first),
            updated in place.
        tol2: Squared convergence threshold on |e|.
        max_steps: Step budget over all runs.
        guess: Start from the candidate of ``seeds`` nearest the target
            instead of ``q``.
        seeds: (count, 16 + n) candidates (:func:`_first_guess`).
        check: Apply the fast rigidity test to ``target`` first.

    Returns:
        CONVERGED, STALLED (a restart is due), EXHAUSTED (no steps left) or
        NOT_RIGID (``target`` failed the fast rigidity test; nothing done).
    """
    if check and not _roughly_rigid(target):
        return NOT_RIGID
    n = q.shape[0]
    if guess:
        _first_guess(seeds, target, q)
    rot, pos = np.empty((n + 1, 3, 3)), np.empty((n + 1, 3))
    jac, jac_free = np.empty((6, n)), np.empty((6, n))
    e, dq, pull, q_next = np.empty(6), np.empty(n), np.empty(n), np.empty(n)
    lu = np.empty((6, 6))
    square, redundant = n == 6, n > 6
    steps = int(stats[STEPS])
    run_start = stall_at = steps
    stall_level = math.inf
    while True:
        _forward(chain, q, rot, pos)
        position = _error(target, rot, pos, e)
        err2 = (
            e[0] * e[0]
            + e[1] * e[1]
            + e[2] * e[2]
            + e[3] * e[3]
            + e[4] * e[4]
            + e[5] * e[5]
        )
        if err2 < stats[ERR2]:
            stats[ERR2], stats[POSITION] = err2, position
            stats[ROTATION] = math.sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5])
            for k in range(n):
                best_q[k] = q[k]
            if err2 <= tol2:
                stats[STEPS] = steps
                return CONVERGED
        if err2 < stall_level:
            stall_level, stall_at = STALL_RATIO * err2, steps
        if steps >= max_steps:
            stats[STEPS] = steps
            return EXHAUSTED
        if steps - stall_at >= STALL_STEPS or steps - run_start >= RUN_STEPS:
            stats[STEPS] = steps
            return STALLED
        steps += 1

        _jacobian(chain, rot, pos, jac)
        newton = False
        if square:
            for i in range(6):
                for j in range(6):
                    lu[i, j] = jac[i, j]
                dq[i] = e[i]
            if _solve(lu, dq):
                step2 = 0.0
                for k in range(n):
                    step2 += dq[k] * dq[k]
                if step2 <= _MAX_STEP2:
                    newton = True
                elif step2 < _SINGULAR_STEP2:  # long: shortened
                    shorten = MAX_STEP / math.sqrt(step2)
                    for k in range(n):
                        dq[k] *= shorten
                    newton = True
                # else near-singular J (or NaN): damped step below
        damping = DAMPING_GAIN * err2 + DAMPING_FLOOR
        use_pull = False
        if not newton:
            use_pull = redundant and err2 > _NULL_OFF_ERROR2
            if use_pull:
                for k in range(n):
                    d = q_ref[k] - q[k]
                    if chain[k, 18] == WRAP_UNBOUNDED:  # shortest way round
                        d -= _TAU * math.floor(d / _TAU + 0.5)
                    pull[k] = NULL_GAIN * d
            _damped_step(jac, e, pull, use_pull, damping, dq)
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
            for k in range(n):
                free = chain[k, 16] <= q_next[k] <= chain[k, 17]
                for r in range(6):
                    jac_free[r, k] = jac[r, k] if free else 0.0
            # (use_pull is False here: the pull stops above ACTIVE_SET_ERROR)
            _damped_step(jac_free, e, pull, use_pull, damping, dq)
            for k in range(n):
                q_next[k] = q[k] - dq[k]
        for k in range(n):
            q[k] = min(max(q_next[k], chain[k, 16]), chain[k, 17])


@_inline
def _splitmix(state: np.ndarray) -> float:
    """Next uniform draw in [0, 1) of the SplitMix64 generator ``state`` (1,) uint64."""
    state[0] += _GOLDEN
    z = state[0]
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z ^= z >> np.uint64(31)
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@_jit
def solve_batch(
    chain, targets, q_ref, q_start, seeds, tol2, max_steps, seed, out_q, out_stats
):
    """Solve every target of ``targets`` (N, 4, 4), restarts drawn in compiled code.

    Args:
        chain: (n + 1, CHAIN_WIDTH) chain.
        targets: (N, 4, 4) targets, already checked finite and rigid.
        q_ref: (1 or N, n) pull references (one for all, or one per target).
        q_start: (0, 1 or N, n) starts; none: the nearest candidate of ``seeds``.
        seeds: (count, 16 + n) candidates.
        tol2: Squared convergence threshold on |e|.
        max_steps: Step budget per target.
        seed: Seed of the restart draws; target i draws from SplitMix64 seeded
            with ``seed + i * golden``, so a result does not depend on the batch.
        out_q: (N, n) best configuration per target.
        out_stats: (N, N_STATS) statistics per target.
    """
    n = chain.shape[0] - 1
    low, span = np.empty(n), np.empty(n)
    for k in range(n):
        lo, hi = chain[k, 16], chain[k, 17]
        low[k] = lo if math.isfinite(lo) else -UNBOUNDED_SPAN
        span[k] = (hi if math.isfinite(hi) else UNBOUNDED_SPAN) - low[k]
    q = np.empty(n)
    state = np.empty(1, dtype=np.uint64)
    for i in range(targets.shape[0]):
        stats = out_stats[i]
        for j in range(N_STATS):
            stats[j] = 0.0
        stats[ERR2] = math.inf
        ref = q_ref[i if q_ref.shape[0] > 1 else 0]
        guess = q_start.shape[0] == 0
        if not guess:
            start = q_start[i if q_start.shape[0] > 1 else 0]
            for k in range(n):
                q[k] = start[k]
        state[0] = np.uint64(seed) + np.uint64(i) * _GOLDEN
        while True:
            status = run(
                chain,
                targets[i],
                q,
                ref,
                out_q[i],
                stats,
                tol2,
                max_steps,
                guess,
                seeds,
                False,
            )
            if status != STALLED:
                break
            guess = False
            for k in range(n):
                q[k] = low[k] + span[k] * _splitmix(state)
            stats[RESTARTS] += 1.0


@_jit
def chain_kinematics(chain, q, jac):
    """Tool pose (4, 4) in the base frame at ``q`` (n,); LOCAL Jacobian into ``jac``."""
    n = chain.shape[0] - 1
    rot, pos = np.empty((n + 1, 3, 3)), np.empty((n + 1, 3))
    _forward(chain, q, rot, pos)
    _jacobian(chain, rot, pos, jac)
    pose = np.empty((4, 4))
    for i in range(4):
        for j in range(3):
            pose[i, j] = rot[n, i, j] if i < 3 else 0.0
        pose[i, 3] = pos[n, i] if i < 3 else 1.0
    return pose
