r"""Compiled carrying of closed-form branches to the robot's own chain.

The closed forms solve the *idealised* structure fitted to the joint axes
(:mod:`workbench.ik.structure`: right angles exact, lengths within
``STRUCTURE_TOL`` of 0 set to 0). A URDF that is of a family only up to its
rounding (α = π/2 written ``1.570796325``, 1.8e-9 rad off), or a calibrated
arm within ``CALIBRATION_ANGLE_TOL`` and ``CALIBRATION_DISTANCE_TOL`` of it
(joint-origin deltas of 1e-4…1e-3 rad and 0.1…1 mm), then gets branches that
miss its pose by about that deviation times the reach. Each such branch is
the start of Newton steps on the true chain (``_chain.get_chain``), with the
forward kinematics and Jacobian of ``_chain_kernel``:

* the fast path (:func:`_carry_direct`, :func:`_newton`): J dq = e by LU,
  e the first-order error of :func:`_fast_error`; fold twins (one start, J
  singular there) moved apart along J's null direction; taken when every
  branch converges to a solution of its own;
* elsewhere the complete search (:func:`_search_pose`): damped steps

  .. math:: q \leftarrow q - J^T (J J^T + \lambda I)^{-1} e, \quad
     e = \log_6(T^{-1} M(q)), \quad \lambda = |e|^2

  (λ = |e|² is Levenberg–Marquardt's damping of Yamashita and Fukushima),
  restarts of twins mirrored through the solution found, the valley scan of
  :func:`_valley_search` where the idealised arm has (or is near) a
  one-parameter family of solutions, and a matching of solutions to branches.

A branch is kept when its FK residual, position :math:`|p(q) - p_T|` [m] and
rotation [rad], is within :data:`ACCEPT` times :data:`POSITION_TOL` and
:data:`ROTATION_TOL`; else it is reported as not reaching (its row NaN),
never returned with a larger residual. What the carrying could not place is
the solve-level byte (``ik.SolveFlag``: a branch vanished, branches merged,
solutions may be unlisted), which the entry points return.

Only robots whose model differs from the idealised structure are refined
(:func:`refinement_chain`): the DH tables of the PUMA models and clean URDFs
keep the closed form's speed.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point, helper
from workbench.ik._chain import get_chain
from workbench.ik._chain_kernel import (
    _damped_step,
    _error,
    _forward,
    _jacobian,
    _products,
    _solve,
)
from workbench.ik._flags import (
    BRANCH_VANISHED,
    BRANCHES_MERGED,
    ELBOW_SINGULAR,
    PARAMETER_SINGULAR,
    REACHED,
    SHOULDER_SINGULAR,
    SOLUTIONS_UNLISTED,
    WITHIN_LIMITS,
    WRIST_SINGULAR,
)
from workbench.ik._kernel_common import remainder
from workbench.ik._puma import LIMIT_TOL
from workbench.ik.structure import get_structure
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]

#: Largest FK position residual [m] of a returned branch.
POSITION_TOL = 1e-12
#: Largest FK rotation residual [rad] of a returned branch.
ROTATION_TOL = 1e-12
#: Refinement goes on until the residual is this fraction of the tolerances
#: (or stops decreasing).
POLISH = 1.0 / 16.0
#: A branch is kept when its residual (this chain's FK) is within this
#: fraction of the tolerances: a margin for FK codes that round differently.
ACCEPT = 0.5
#: Newton steps a branch may take (a regular one needs one or two; next to a
#: singularity of the true chain convergence is linear, halving per step).
REFINE_STEPS = 60
#: Newton steps of the fast path of a regular branch (:func:`_newton`; it needs
#: three from the closed form of a calibrated arm's idealised structure).
FAST_STEPS = 6
#: A Newton step of :func:`_newton` whose error [tolerances] is within this,
#: after a step that cut the error by :data:`CHORD_RATIO` or more, reuses that
#: step's factors of J: 1e3 tolerances (1e-9 m) is a step of ~1e-9 rad from a
#: J of ~1e-5 rad before, whose change (~1e-5 relative) leaves ~1e-14 m.
CHORD_GATE = 1e3
CHORD_RATIO = 1e-3
#: Steps shorter than this [rad] turn the sines and cosines of :func:`_newton`
#: by their Taylor series (to d⁷; the first term left out, d⁸/40320, is 3e-23
#: at 0.005) instead of calling the library per joint.
TRIG_STEP = 0.005
#: How far [rad, in joint space] twins that start at one fold point of the
#: idealised arm are moved apart along J's null direction (the model's
#: solutions lie about √deviation from the fold: 0.01–0.06 rad for 1e-4…1e-3),
#: and the inverse iterations that find that direction.
FOLD_STEP = 0.05
NULL_ITERATIONS = 4
#: Refinement stops when the residual has not decreased for this many steps.
STALL_STEPS = 20
#: ... or for this many once it is within :data:`ACCEPT` (a residual at the
#: rounding of the FK, 1e-14…1e-13 m on a calibrated arm, decreases no more).
SETTLED_STEPS = 2
#: Two refined branches this close [rad, each joint mod 2π] are one solution.
TWIN_TOL = 1e-8
#: Bits of :func:`_refine_pose`'s result above the branch mask (bits 0-7):
#: the solve-level bits of ``_flags`` (``SolveFlag``) shifted by
#: :data:`EVENT_SHIFT`.
EVENT_SHIFT = 8
VANISHED = BRANCH_VANISHED << EVENT_SHIFT
MERGED = BRANCHES_MERGED << EVENT_SHIFT
UNLISTED = SOLUTIONS_UNLISTED << EVENT_SHIFT
#: The per-branch bits of the closed form that the refinement keeps (the
#: idealised arm's singularities); REACHED and WITHIN_LIMITS are the model's.
KEPT_BITS = SHOULDER_SINGULAR | ELBOW_SINGULAR | WRIST_SINGULAR | PARAMETER_SINGULAR
#: A branch whose Newton steps move it farther than this [rad, a joint] from
#: the idealised arm's solution is near a singularity of the model (the shift
#: is about the deviation over the least singular value of J): the valley
#: through its start is searched for every solution.
SHIFT_GATE = 0.2
#: A branch that moves farther than this [rad, a joint] from the idealised
#: arm's solution is near a singularity (the shift is about the deviation over
#: σ): the model may have solutions there that no branch holds (more than the
#: idealised arm's), so the solve says so (``SOLUTIONS_UNLISTED``).
UNLISTED_SHIFT = 0.05
#: Solutions one pose may have on a calibrated arm that are kept (the 8
#: branches, and as many more found near singularities, then reported).
MAX_SOLUTIONS = 16
#: Valley search (:func:`_valley_search`): values of the fixed joint scanned
#: over a turn, Gauss–Newton steps of the other five per value, and the
#: steps of the root search between two scanned values. (Fewer inner steps,
#: 4 or 6, lose solutions that 8 find near the UR5's singularities.)
VALLEY_SCAN = 36
VALLEY_INNER_STEPS = 8
VALLEY_ROOT_STEPS = 40
#: Added to the diagonal of JᵀJ in the valley search, so that an exactly
#: singular J still gives a solvable system [1/m² ~ 1/rad²].
GRAM_SHIFT = 1e-24
#: The least squares of the other five joints stop at a step this short [rad].
VALLEY_STEP_TOL = 1e-15
#: The root search (regula falsi) and the golden section of the valley search
#: stop at a step or bracket this short [rad]: the root or least |e| is then
#: within Newton's reach (:func:`_refine_branch` takes it from there to the
#: tolerances).
VALLEY_ROOT_STEP = 1e-6
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
#: Newton's residual [tolerances] below which a branch that does not converge
#: is in a valley of solutions of the idealised arm (a singular wrist: the
#: valley search follows it), 1e-6 m or rad.
VALLEY_GATE = 1e6
#: A fitted structure whose FK differs from the model's by more than this
#: [m, and rotation entries] (``KinematicStructure.residual``) is refined; the
#: catalog's URDFs are within 6e-16.
EXACT_STRUCTURE_TOL = 1e-13


def refinement_chain(robot: Robot) -> FloatArray | None:
    """The packed model chain to refine a robot's branches on, or None.

    Args:
        robot: A robot with a closed form.

    Returns:
        ``get_chain(robot).packed``, (n + 1, CHAIN_WIDTH) read-only (n = 6 or
        7 joints), when the structure fitted to its axes differs from its
        model by more than :data:`EXACT_STRUCTURE_TOL`; else None (the closed
        form is exact).
    """
    if get_structure(robot).residual <= EXACT_STRUCTURE_TOL:
        return None
    chain = get_chain(robot)
    if not chain.identity:  # (a closed form needs n one-coordinate joints)
        return None
    return chain.packed


@helper(forceinline=True)
def pose_error(target: FloatArray, frames: FloatArray, e: FloatArray) -> float:
    """The FK residual in tolerances: the larger of position and rotation.

    Position [m] over :data:`POSITION_TOL`, rotation [rad] over
    :data:`ROTATION_TOL`. ``e`` (>= 6,) gets the error log6(T⁻¹ M(q)) of the
    tool (last row of ``frames``, ``_chain_kernel._forward``'s); a NaN error
    fails every test.
    """
    position = _error(target, frames, e) / POSITION_TOL
    rotation = math.sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5]) / ROTATION_TOL
    return max(position, rotation)


@helper(forceinline=True)
def keep_best(
    error: float, best: float, best_step: int, step: int, q: FloatArray, best_q
) -> tuple[float, int, bool]:
    """One step's bookkeeping of a refinement: the best iterate, and whether to stop.

    Copies ``q`` into ``best_q`` when ``error`` (in tolerances) is the least yet;
    stops at :data:`POLISH`, after :data:`STALL_STEPS` steps without progress
    (:data:`SETTLED_STEPS` once the best is within :data:`ACCEPT`: rounding,
    not the model, then limits the residual), at a NaN error or after
    :data:`REFINE_STEPS` steps.

    Returns:
        ``(best, best_step, stop)``.
    """
    if error < best:
        best, best_step = error, step
        for k in range(q.shape[0]):
            best_q[k] = q[k]
    elif not error == error or step - best_step >= (
        SETTLED_STEPS if best <= ACCEPT else STALL_STEPS
    ):
        return best, best_step, True
    return best, best_step, best <= POLISH or step == REFINE_STEPS


@helper()
def _refine_branch(chain: FloatArray, target: FloatArray, q: FloatArray, work) -> bool:
    """Newton steps on ``q`` (6,) in place; whether its residual is within tolerance.

    Steps are taken until the residual is :data:`POLISH` times the tolerance,
    has not decreased for :data:`STALL_STEPS` steps (next to a singularity a
    step may first increase it), or :data:`REFINE_STEPS` are taken; ``q`` is
    then the best iterate, and ``work[29, 11]`` its residual in tolerances.
    ``work``: (30, 12) scratch.
    """
    frames = work[0:7]
    jac, normal = work[7:13, 0:6], work[13:19, 0:6]
    e, dq, pull, y = work[19, 0:6], work[20, 0:6], work[21, 0:6], work[22, 0:6]
    best_q = work[23, 0:6]
    no_pull = work.shape[0] < 0  # False, as a computed bool (no literal copy)
    best, best_step = math.inf, 0
    for step in range(REFINE_STEPS + 1):
        _forward(chain, q, frames)
        error = pose_error(target, frames, e)
        best, best_step, stop = keep_best(error, best, best_step, step, q, best_q)
        if stop:
            break
        damping = 0.0
        for i in range(6):
            damping += e[i] * e[i]
        _jacobian(chain, frames, jac)
        _damped_step(jac, 6, e, pull, no_pull, damping, normal, y, dq)
        for k in range(6):  # (a turn of 2π or more is none: the angle stays near)
            q[k] -= remainder(dq[k])
    for k in range(6):
        q[k] = best_q[k]
    work[29, 11] = best
    return best <= ACCEPT


@helper()
def _gram(a: FloatArray, n: int, out: FloatArray) -> None:
    """``out[:n, :n]`` = AᵀA + :data:`GRAM_SHIFT` I for the (6, n) matrix A."""
    for i in range(n):
        for k in range(n):
            s = 0.0
            for r in range(6):
                s += a[r, i] * a[r, k]
            out[i, k] = s
        out[i, i] += GRAM_SHIFT


@helper()
def _inner(chain, target, x, j: int, work) -> float:
    """Gauss–Newton on the joints of ``x`` but ``j``; the residual's normal part.

    At most :data:`VALLEY_INNER_STEPS` steps of the least squares of the
    error over the five other joints. Leaves in ``work[19]`` the error e and in
    ``work[24:30, 0:5]`` the Jacobian J5 of those joints; returns |e|.
    """
    frames, jac = work[0:7], work[7:13, 0:6]
    j5, normal = work[24:30, 0:5], work[13:19, 0:6]
    e, dq = work[19, 0:6], work[20, 0:6]
    size = 0.0
    for step in range(VALLEY_INNER_STEPS + 1):
        _forward(chain, x, frames)
        _error(target, frames, e)
        _jacobian(chain, frames, jac)
        for r in range(6):
            for c in range(5):
                j5[r, c] = jac[r, c if c < j else c + 1]
        size = 0.0
        for r in range(6):
            size += e[r] * e[r]
        if step == VALLEY_INNER_STEPS:
            break
        _gram(j5, 5, normal)  # normal equations J5ᵀ J5 d = J5ᵀ e
        for a in range(5):
            s = 0.0
            for r in range(6):
                s += j5[r, a] * e[r]
            dq[a] = s
        if not _solve(normal, dq, 5):
            break
        moved = 0.0
        for c in range(5):
            x[c if c < j else c + 1] -= remainder(dq[c])
            moved += dq[c] * dq[c]
        if moved < VALLEY_STEP_TOL * VALLEY_STEP_TOL:
            break
    return math.sqrt(size)


@helper()
def _normal_part(work, previous) -> float:
    """E · n, n the unit normal of range(J5) with n · ``previous`` > 0 (``work``)."""
    j5, normal = work[24:30, 0:5], work[13:19, 0:6]
    e, n = work[19, 0:6], work[21, 0:6]
    for c in range(5):  # [J5ᵀ; previousᵀ] n = (0, ..., 0, 1)
        for r in range(6):
            normal[c, r] = j5[r, c]
        n[c] = 0.0
    for r in range(6):
        normal[5, r] = previous[r]
    n[5] = 1.0
    if not _solve(normal, n, 6):
        return 0.0
    length, part = 0.0, 0.0
    for r in range(6):
        length += n[r] * n[r]
    length = math.sqrt(length)
    for r in range(6):
        n[r] /= length
        previous[r] = n[r]
        part += e[r] * n[r]
    return part


@helper()
def solution_gap(a: FloatArray, b: FloatArray) -> float:
    """Largest joint difference [rad, mod 2π] of two configurations (n,)."""
    gap = 0.0
    for k in range(a.shape[0]):
        gap = max(gap, abs(remainder(a[k] - b[k])))
    return gap


@helper()
def _keep(sols: FloatArray, count: int, x: FloatArray) -> int:
    """Add ``x`` (6,) to the first ``count`` rows of ``sols`` unless it is there.

    Returns the new count (rows beyond ``sols``' size are not stored, but
    counted: the caller reports them).
    """
    for i in range(min(count, sols.shape[0])):
        if solution_gap(sols[i], x) <= TWIN_TOL:
            return count
    if count < sols.shape[0]:
        for k in range(6):
            sols[count, k] = x[k]
    return count + 1


@helper()
def _keep_near(chain, target, start, x, work, sols, count: int) -> int:
    """:func:`_keep` of solution ``x`` (6,), each angle the turn nearest ``start``.

    Along an exactly singular family an angle may drift by many turns (Newton
    moves freely along it), and the turn taken off it rounds away its last
    bits (1e-10 rad at 1e6 rad): the wrapped solution is refined again, and
    kept only if it is still within the tolerances.
    """
    moved = False
    for k in range(6):
        wrapped = start[k] + remainder(x[k] - start[k])
        moved |= wrapped != x[k]
        x[k] = wrapped
    if moved and not _refine_branch(chain, target, x, work):
        return count
    return _keep(sols, count, x)


@helper()
def _valley_search(chain, target, start, work, sols, count: int) -> int:
    """Every solution of the model along a near-singular valley through ``start``.

    Where the idealised arm has a one-parameter family of solutions, or is
    near one (a singular wrist's θ4/θ6 split, θ1 with the wrist centre on the
    base axis, θ2 with it on the shoulder axis, a stretched or folded elbow),
    the model's deviations fix finitely many members, along a valley of small
    residuals too curved for Newton to follow. The joint that moves most
    along J's null direction at ``start`` (6,) is fixed at :data:`VALLEY_SCAN`
    values over a turn, the five others solved by least squares at each; the
    normal part of the remaining error changes sign at the model's solutions,
    each found by regula falsi (Illinois) and refined by
    :func:`_refine_branch`. The two joints that move most are tried in turn;
    where neither finds a sign change that leads to a solution (a double
    root, where two branches meet: the normal part only touches 0), the
    least |e| by golden section.

    Returns:
        The new count of ``sols`` (as :func:`_keep`), every solution found
        added.
    """
    frames = work[0:7]
    e, v = work[19, 0:6], work[22, 0:6]
    previous = np.empty(6)
    x = np.empty(6)
    if not _null_direction(chain, start, work, v):  # (leaves frames at start)
        return count
    _error(target, frames, e)
    order = np.argsort(-np.abs(v))
    scanned, parts = np.empty((VALLEY_SCAN + 1, 6)), np.empty(VALLEY_SCAN + 1)
    width = 2.0 * math.pi / VALLEY_SCAN
    found = count
    for choice in range(2):
        j = order[choice]
        for k in range(6):
            x[k] = start[k]
        for i in range(VALLEY_SCAN + 1):
            x[j] = start[j] + i * width
            size = _inner(chain, target, x, j, work)
            if i == 0:  # e is normal to range(J5) at a least-squares optimum
                for r in range(6):
                    previous[r] = e[r] / size if size > 0.0 else 1.0
            parts[i] = _normal_part(work, previous)
            for k in range(6):
                scanned[i, k] = x[k]
        for i in range(VALLEY_SCAN):
            if (parts[i] > 0.0) == (parts[i + 1] > 0.0):
                continue
            for k in range(6):
                x[k] = scanned[i, k]
            a, b = start[j] + i * width, start[j] + (i + 1) * width
            size = _inner(chain, target, x, j, work)  # the normal at a: e
            for r in range(6):
                previous[r] = e[r] / size if size > 0.0 else 1.0
            ga = _normal_part(work, previous)
            x[j] = b
            _inner(chain, target, x, j, work)
            gb = _normal_part(work, previous)
            for _ in range(VALLEY_ROOT_STEPS):
                if ga == gb or abs(b - a) <= VALLEY_ROOT_STEP:
                    break
                t = b - gb * (b - a) / (gb - ga)
                x[j] = t
                _inner(chain, target, x, j, work)
                g = _normal_part(work, previous)
                if abs(t - b) <= VALLEY_ROOT_STEP:  # near enough: Newton finishes
                    break
                if (g > 0.0) == (gb > 0.0):
                    ga *= 0.5
                else:
                    a, ga = b, gb
                b, gb = t, g
            if _refine_branch(chain, target, x, work):
                count = _keep_near(chain, target, start, x, work, sols, count)
        if found < count:
            continue
        least = np.argmin(np.abs(parts[:VALLEY_SCAN]))
        for k in range(6):
            x[k] = scanned[least, k]
        a, b = start[j] + (least - 1) * width, start[j] + (least + 1) * width
        c, d = b - _GOLDEN * (b - a), a + _GOLDEN * (b - a)
        x[j] = c
        size_c = _inner(chain, target, x, j, work)
        x[j] = d
        size_d = _inner(chain, target, x, j, work)
        for _ in range(VALLEY_ROOT_STEPS):
            if b - a <= VALLEY_ROOT_STEP:
                break
            if size_c < size_d:
                b, d, size_d = d, c, size_c
                c = b - _GOLDEN * (b - a)
                x[j] = c
                size_c = _inner(chain, target, x, j, work)
            else:
                a, c, size_c = c, d, size_d
                d = a + _GOLDEN * (b - a)
                x[j] = d
                size_d = _inner(chain, target, x, j, work)
        x[j] = c if size_c < size_d else d
        _inner(chain, target, x, j, work)
        if _refine_branch(chain, target, x, work):
            count = _keep_near(chain, target, start, x, work, sols, count)
    return count


@helper(forceinline=True)
def _fast_error(target: FloatArray, frames: FloatArray, e: FloatArray) -> float:
    r"""The tool's error to first order into ``e`` (6,); its size in tolerances.

    ``e`` = [R_tᵀ(p − p_t); vee(R − Rᵀ)/2], R = R_tᵀ R(q): log6(T⁻¹ M(q)) up
    to second order, so that Newton steps on it converge quadratically as on
    log6 itself, without its atan2 and square roots. The size is the larger
    of |p − p_t| [m] over :data:`POSITION_TOL` and |vee(R − Rᵀ)|/2 = sin θ
    [rad] over :data:`ROTATION_TOL` (θ itself to 1e-13 relative below 1e-6
    rad; a rotation by more than π/2, trace R < 1, is infinitely far).
    """
    f = frames[frames.shape[0] - 1]
    dx, dy, dz = f[9] - target[0, 3], f[10] - target[1, 3], f[11] - target[2, 3]
    t00, t10, t20 = target[0, 0], target[1, 0], target[2, 0]
    t01, t11, t21 = target[0, 1], target[1, 1], target[2, 1]
    t02, t12, t22 = target[0, 2], target[1, 2], target[2, 2]
    r00 = t00 * f[0] + t10 * f[3] + t20 * f[6]
    r11 = t01 * f[1] + t11 * f[4] + t21 * f[7]
    r22 = t02 * f[2] + t12 * f[5] + t22 * f[8]
    r01 = t00 * f[1] + t10 * f[4] + t20 * f[7]
    r10 = t01 * f[0] + t11 * f[3] + t21 * f[6]
    r02 = t00 * f[2] + t10 * f[5] + t20 * f[8]
    r20 = t02 * f[0] + t12 * f[3] + t22 * f[6]
    r12 = t01 * f[2] + t11 * f[5] + t21 * f[8]
    r21 = t02 * f[1] + t12 * f[4] + t22 * f[7]
    e[0] = t00 * dx + t10 * dy + t20 * dz
    e[1] = t01 * dx + t11 * dy + t21 * dz
    e[2] = t02 * dx + t12 * dy + t22 * dz
    e[3] = 0.5 * (r21 - r12)
    e[4] = 0.5 * (r02 - r20)
    e[5] = 0.5 * (r10 - r01)
    position = dx * dx + dy * dy + dz * dz
    rotation = e[3] * e[3] + e[4] * e[4] + e[5] * e[5]
    if not r00 + r11 + r22 >= 1.0:  # (NaN too)
        return math.inf
    return max(math.sqrt(position) / POSITION_TOL, math.sqrt(rotation) / ROTATION_TOL)


@helper(forceinline=True)
def step_back(x: FloatArray, k: int, d: float, sines, cosines) -> None:
    """``x[k] -= d``, and its sine and cosine in ``sines[k]``, ``cosines[k]``.

    A step shorter than :data:`TRIG_STEP` turns them by the Taylor series of
    sin d and cos d (Newton's last steps: no library call); a longer one
    calls the library.
    """
    x[k] -= d
    if abs(d) < TRIG_STEP:
        d2 = d * d
        sd = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0)))
        cd = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0))
        s, c = sines[k], cosines[k]
        sines[k], cosines[k] = s * cd - c * sd, c * cd + s * sd
    else:
        sines[k], cosines[k] = math.sin(x[k]), math.cos(x[k])


@helper()
def _factor(a: FloatArray, pivots: FloatArray) -> bool:
    """LU with partial pivoting of the m × m ``a`` in place; False if singular.

    ``a`` keeps U (its diagonal as the pivots' reciprocals) and below it the
    multipliers of L, rows swapped as the pivots were; ``pivots`` (m,) the
    row swapped in at each step (as floats), m its length. :func:`_back`
    then solves with them, as often as needed: Newton's last step reuses the
    factors of the step before (:func:`_newton`).
    """
    m = pivots.shape[0]
    for k in range(m):
        p, big = k, abs(a[k, k])
        for i in range(k + 1, m):
            v = abs(a[i, k])
            larger = v > big  # False for NaN
            p = i if larger else p
            big = v if larger else big
        if big == 0.0:
            return False
        pivots[k] = p
        for j in range(m):  # (the multipliers of columns < k go with their row)
            x = a[k, j]
            a[k, j] = a[p, j]
            a[p, j] = x
        inverse = 1.0 / a[k, k]
        a[k, k] = inverse
        for i in range(k + 1, m):
            f = a[i, k] * inverse
            a[i, k] = f
            for j in range(k + 1, m):
                a[i, j] -= f * a[k, j]
    return True


@helper()
def _back(a: FloatArray, pivots: FloatArray, b: FloatArray) -> None:
    """Solve a x = b in place (x in ``b``, (m,)) with :func:`_factor`'s factors."""
    m = pivots.shape[0]
    for k in range(m):
        p = int(pivots[k])
        x = b[k]
        b[k] = b[p]
        b[p] = x
    for k in range(m):
        bk = b[k]
        for i in range(k + 1, m):
            b[i] -= a[i, k] * bk
    for k in range(m - 1, -1, -1):
        s = b[k]
        for j in range(k + 1, m):
            s -= a[k, j] * b[j]
        b[k] = s * a[k, k]


@helper()
def _newton(chain: FloatArray, target: FloatArray, x: FloatArray, work) -> bool:
    """Newton steps J dq = e on ``x`` (6,) in place; whether it converged.

    The fast path of a regular branch: the LOCAL Jacobian of the model's chain
    (``_chain_kernel``), LU of the 6 × 6 system itself (no damping), the
    first-order error of :func:`_fast_error`. A step whose error is within
    :data:`CHORD_GATE` after a Newton step that cut it by :data:`CHORD_RATIO`
    or more (the quadratic regime: the last step, from ~1e-11 m) solves with
    the previous step's factors (its J is ~1e-5 rad away: the error still
    drops to the FK's rounding). Steps stop at :data:`POLISH` times the
    tolerances, or where the residual stops decreasing (the FK's rounding)
    within :data:`ACCEPT`; ``x`` is then the best iterate. Anything else (no
    convergence in :data:`FAST_STEPS`, a singular J) returns False, and the
    caller takes the complete search. ``work``: (30, 12) scratch.
    """
    frames = work[0:7]
    lu = work[13:19, 0:6]
    e, previous = work[19, 0:6], work[20, 0:6]
    sines, cosines, pivots = work[24, 0:6], work[25, 0:6], work[26, 0:6]
    for k in range(6):
        sines[k], cosines[k] = math.sin(x[k]), math.cos(x[k])
    last = math.inf
    fresh = False  # whether lu holds the factors of the previous step's J
    for step in range(FAST_STEPS + 1):
        for k in range(6):
            frames[k, 0], frames[k, 1] = sines[k], cosines[k]
        _products(chain, x, frames)
        size = _fast_error(target, frames, e)
        if size <= POLISH:
            return True
        if not size < last:  # the previous iterate was the best
            for k in range(6):
                x[k] = previous[k]
            return last <= ACCEPT
        if step == FAST_STEPS:
            return False
        if fresh and size <= CHORD_GATE and size <= CHORD_RATIO * last:
            fresh = False  # (once: a further step takes a new J)
        else:
            _jacobian(chain, frames, lu)
            if not _factor(lu, pivots):
                return False
            fresh = True
        last = size
        _back(lu, pivots, e)
        for k in range(6):
            previous[k] = x[k]
            step_back(x, k, e[k], sines, cosines)
    return False


@helper()
def _farther(a: FloatArray, b: FloatArray, limit: float) -> bool:
    """Whether a joint of ``a``, ``b`` (6,) differs by over ``limit`` (mod 2π)."""
    for k in range(6):
        if abs(remainder(a[k] - b[k])) > limit:
            return True
    return False


@helper()
def _null_direction(chain, start, work, v) -> bool:
    """J's right singular vector of least σ at ``start`` (6,) into ``v`` (6,).

    Inverse iteration on JᵀJ + :data:`GRAM_SHIFT` I; False if it is singular
    even so. ``work``: (30, 12) scratch (rows 0–18).
    """
    frames, jac, normal = work[0:7], work[7:13, 0:6], work[13:19, 0:6]
    _forward(chain, start, frames)
    _jacobian(chain, frames, jac)
    for k in range(6):
        v[k] = 1.0
    for _ in range(NULL_ITERATIONS):
        _gram(jac, 6, normal)
        if not _solve(normal, v, 6):
            return False
        length = 0.0
        for k in range(6):
            length += v[k] * v[k]
        length = math.sqrt(length)
        for k in range(6):
            v[k] /= length
    return True


@helper()
def _carry_direct(chain, target, q, starts, work) -> int:
    """Every reached row of ``q`` (8, 6) by :func:`_newton` alone, or −1.

    The regular case of :func:`_search_pose`, at a fraction of its cost.
    Twins that start at one point (a fold of the idealised arm, e.g. its
    stretched elbow, where J is singular and the model's two solutions lie on
    either side) start from that point moved by ±:data:`FOLD_STEP` along J's
    null direction. The case is regular when every branch converges, none
    moves more than :data:`SHIFT_GATE`, and no start other than its own (or
    its twin's) is as near a branch's solution as the farthest-moved branch
    is to its own: the solutions are then distinct and the nearest-pair
    matching of the complete search would give each branch its own.
    ``starts`` (8, 6) gets the rows of ``q`` first.

    Twins at a fold from which neither side converges, where the least
    residual (Levenberg–Marquardt from the fold point, :func:`_refine_branch`)
    is above :data:`VALLEY_GATE` (the pose is past the model's fold), both
    vanish, as the complete search finds.

    Returns:
        The mask of reached branches plus ``VANISHED``, or −1 where the case
        is not regular (``q`` then partly carried: the caller restores it
        from ``starts``).
    """
    alive = 0
    for b in range(8):
        for k in range(6):
            starts[b, k] = q[b, k]
        if q[b, 0] == q[b, 0]:
            alive |= 1 << b
    twin = np.empty(8, dtype=np.int64)
    for b in range(8):
        twin[b] = -1
        if alive >> b & 1 == 0:
            continue
        for c in range(8):
            if (
                c != b
                and alive >> c & 1
                and not _farther(starts[b], starts[c], TWIN_TOL)
            ):
                twin[b] = c
    v = work[21, 0:6]
    largest, events = 0.0, 0
    for b in range(8):
        if alive >> b & 1 == 0:
            continue
        c = twin[b]
        if c >= 0:
            if c < b:  # (moved with its twin)
                continue
            if not _null_direction(chain, starts[b], work, v):
                return -1
            for k in range(6):
                q[b, k] = starts[b, k] + FOLD_STEP * v[k]
                q[c, k] = starts[b, k] - FOLD_STEP * v[k]
            one = _newton(chain, target, q[b], work)
            other = _newton(chain, target, q[c], work)
            if one != other:
                return -1
            if not one:  # no solution on either side: past the model's fold?
                for k in range(6):
                    q[b, k] = starts[b, k]
                if _refine_branch(chain, target, q[b], work):
                    return -1
                if not work[29, 11] > VALLEY_GATE:  # a valley: search it
                    return -1
                for k in range(6):  # the least residual is no solution: both vanish
                    q[b, k] = np.nan
                    q[c, k] = np.nan
                alive &= ~(1 << b | 1 << c)
                events |= VANISHED
                continue
            largest = max(largest, solution_gap(q[c], starts[c]))
            largest = max(largest, solution_gap(q[b], starts[b]))
            continue  # (a fold's two solutions, both held: none unlisted)
        if not _newton(chain, target, q[b], work):
            return -1
        shift = solution_gap(q[b], starts[b])
        largest = max(largest, shift)
        if shift > UNLISTED_SHIFT:
            events |= UNLISTED
    if largest > SHIFT_GATE:
        return -1
    for b in range(8):
        if alive >> b & 1 == 0:
            continue
        for c in range(8):
            if c == b or alive >> c & 1 == 0:
                continue
            if not _farther(q[b], q[c], TWIN_TOL):  # one solution, twice
                return -1
            if twin[b] != c and not _farther(starts[b], q[c], largest):
                return -1
    return alive | events


@helper()
def _refine_pose(
    chain: FloatArray, target: FloatArray, q: FloatArray, work: FloatArray
) -> int:
    """Carry the reached rows of ``q`` (8, 6) to the chain: :func:`_search_pose`.

    Tried first: :func:`_carry_direct`, which gives the same answer where the
    pose is regular; elsewhere the complete search from the closed form's rows.
    """
    starts = np.empty((8, 6))
    reached = _carry_direct(chain, target, q, starts, work)
    if reached >= 0:
        return reached
    for b in range(8):
        for k in range(6):
            q[b, k] = starts[b, k]
    return _search_pose(chain, target, q, work)


@helper()
def _search_pose(
    chain: FloatArray, target: FloatArray, q: FloatArray, work: FloatArray
) -> int:
    """Carry the reached rows (not NaN) of ``q`` (8, 6) to the chain; NaN the others.

    Every branch of the idealised arm is the start of Newton steps on the
    model (:func:`_refine_branch`); one that lands on a solution found before
    (twins that start at or near one point of a fold of the idealised arm,
    e.g. its stretched elbow: the model's two solutions lie on either side) is
    also carried from its start mirrored through that solution. A start that
    moves more than
    :data:`SHIFT_GATE`, or does not converge with a residual within
    :data:`VALLEY_GATE`, is near a singularity of the model, where solutions
    that no start leads to may lie: the valley through it is searched for
    every solution (:func:`_valley_search`). The solutions found are then
    given to the branches, the nearest (start, solution) pair first, each
    solution and branch once; a solution left over goes to a branch the
    idealised arm does not reach.

    Returns:
        A bit mask of the branches that reach (bits 0–7), plus
        :data:`VANISHED` (a branch of the idealised arm found no solution of
        its own: it did not converge), :data:`MERGED` (it converged, onto the
        solution another branch holds) and :data:`UNLISTED` (more solutions
        than branches, or a valley was searched: its scan may step over
        solutions, or a branch moved more than :data:`UNLISTED_SHIFT`: the
        solve says it may not list them all).
    """
    starts, sols = np.empty((8, 6)), np.empty((MAX_SOLUTIONS, 6))
    owner = np.empty(MAX_SOLUTIONS, dtype=np.int64)
    x = np.empty(6)
    alive, converged, near, count = 0, 0, 0, 0
    moved = False
    for b in range(8):
        if not q[b, 0] == q[b, 0]:
            continue
        alive |= 1 << b
        for k in range(6):
            starts[b, k] = q[b, k]
            x[k] = q[b, k]
        if _refine_branch(chain, target, x, work):
            converged |= 1 << b
            shift = solution_gap(x, starts[b])
            if shift > SHIFT_GATE:
                near |= 1 << b
            elif shift > UNLISTED_SHIFT:
                moved = True
            before = count
            count = _keep(sols, count, x)
            if count > before:
                continue
            for k in range(6):  # a twin's solution: the start mirrored through it
                x[k] = starts[b, k] + remainder(starts[b, k] - x[k])
            if _refine_branch(chain, target, x, work):
                count = _keep(sols, count, x)
        elif work[29, 11] <= VALLEY_GATE:
            near |= 1 << b
    for b in range(8):
        if near >> b & 1:
            count = _valley_search(chain, target, starts[b], work, sols, count)
    # a scanned valley may hold solutions between its samples: said, not hidden
    events = UNLISTED if count > MAX_SOLUTIONS or near != 0 or moved else 0
    count = min(count, MAX_SOLUTIONS)
    for i in range(count):
        owner[i] = -1
    free = alive
    while free:  # the nearest (start, solution) pair first
        best, pick, row = math.inf, -1, -1
        for b in range(8):
            if free >> b & 1:
                for i in range(count):
                    if owner[i] < 0:
                        gap = solution_gap(starts[b], sols[i])
                        if gap < best:
                            best, pick, row = gap, i, b
        if pick < 0:
            break
        owner[pick] = row
        free &= ~(1 << row)
    reached = alive & ~free
    for i in range(count):  # left over: to a branch the idealised arm misses
        if owner[i] >= 0:
            continue
        for b in range(8):
            if (reached | free) >> b & 1 == 0:
                owner[i] = b
                reached |= 1 << b
                break
        if owner[i] < 0:
            events |= UNLISTED
    for b in range(8):
        for k in range(6):
            q[b, k] = np.nan
    for i in range(count):
        if owner[i] >= 0:
            for k in range(6):
                q[owner[i], k] = sols[i, k]
    if free & converged:
        events |= MERGED
    if free & ~converged:
        events |= VANISHED
    return reached | events


@helper()
def write_flags(chain: FloatArray, q: FloatArray, flags, reached: int) -> int:
    """The per-branch bytes of refined rows ``q`` (B, n); the solve-level byte.

    A branch that reaches (bit b of ``reached``) keeps the closed form's
    :data:`KEPT_BITS`, gets ``REACHED`` and ``WITHIN_LIMITS`` of its refined
    joint values (± ``LIMIT_TOL``, the limits of ``chain``); the others get 0
    (a branch the idealised arm does not reach may hold a solution of the
    model: its singular bits are then 0).

    Returns:
        The solve-level bits (``_flags.SolveFlag``) of ``reached``.
    """
    for b in range(q.shape[0]):
        if reached >> b & 1 == 0:
            flags[b] = 0
            continue
        within = True
        for k in range(q.shape[1]):
            within &= chain[k, 16] - LIMIT_TOL <= q[b, k] <= chain[k, 17] + LIMIT_TOL
        kept = flags[b] & KEPT_BITS
        flags[b] = kept | REACHED | (WITHIN_LIMITS if within else 0)
    return (reached >> EVENT_SHIFT) & 0xFF


@entry_point(outputs=("q", "flags"), contiguous=("chain", "pose"))
def refine_pose(
    chain: FloatArray, pose: FloatArray, q: FloatArray, flags: npt.NDArray[np.uint8]
) -> int:
    """Carry the branches of one pose to the model's chain.

    Args:
        chain: (7, CHAIN_WIDTH) packed true chain (``_chain_kernel``).
        pose: (4, 4) target pose of the tool frame in the base frame [m].
        q: (8, 6) branches of the closed form [rad], NaN rows for those that
            do not reach; carried in place, NaN where no solution is found.
        flags: (8,) uint8 bits of ``_flags`` per branch (the closed form's),
            rewritten as :func:`write_flags` says.

    Returns:
        The solve-level byte (``ik.SolveFlag`` bits): a branch vanished,
        branches merged, solutions unlisted; 0 when every branch carried over.
    """
    work = np.empty((30, 12))
    reached = _refine_pose(chain, pose, q, work)
    return write_flags(chain, q, flags, reached)


@entry_point(outputs=("q", "valid", "solve_flags"), contiguous=("chain", "targets"))
def refine_batch(
    chain: FloatArray,
    targets: FloatArray,
    q: FloatArray,
    valid: npt.NDArray[np.bool_],
    solve_flags: npt.NDArray[np.uint8],
) -> int:
    """Carry the branches of N poses to the model's chain.

    Args:
        chain: (7, CHAIN_WIDTH) packed true chain.
        targets: (N, 4, 4) target poses [m].
        q: (N, 8, 6) branches [rad] (NaN rows where not valid), carried in
            place; NaN where no solution is found.
        valid: (N, 8) True where a branch reaches; rewritten.
        solve_flags: (N,) uint8 output, the solve-level byte of each pose (as
            :func:`refine_pose`'s).

    Returns:
        The number of branches that were valid and failed.
    """
    work = np.empty((30, 12))
    failed = 0
    for i in range(targets.shape[0]):
        reached = _refine_pose(chain, targets[i], q[i], work)
        for b in range(8):
            alive = reached >> b & 1 != 0
            failed += valid[i, b] and not alive
            valid[i, b] = alive
        solve_flags[i] = (reached >> EVENT_SHIFT) & 0xFF
    return failed
