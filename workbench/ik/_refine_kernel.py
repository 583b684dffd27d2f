r"""Compiled Newton refinement of closed-form branches on the robot's true chain.

The closed forms solve the *idealised* structure fitted to the joint axes
(:mod:`workbench.ik.structure`: right angles exact, lengths within
``STRUCTURE_TOL`` of 0 set to 0). A URDF that is of a family only up to its
rounding (α = π/2 written ``1.570796325``, 1.8e-9 rad off) then gets branches
that miss its pose by about that deviation times the reach. Each such branch
is the start of a few Newton steps on the true chain (``_chain.get_chain``),
with the forward kinematics, Jacobian and error of ``_chain_kernel``:

.. math:: q \leftarrow q - J^T (J J^T + \lambda I)^{-1} e, \quad
   e = \log_6(T^{-1} M(q)), \quad \lambda = |e|^2

(J the LOCAL Jacobian of the tool; λ = |e|² is Levenberg–Marquardt's damping
of Yamashita and Fukushima: Newton's quadratic convergence where J is regular,
bounded steps where it is singular). Where the idealised arm has a
one-parameter family of solutions (singular wrist, wrist centre on the base
or shoulder axis) and Newton cannot follow the model's valley to its member,
:func:`_valley_search` looks for it. A branch is kept when its FK residual,
position :math:`|p(q) - p_T|` [m] and rotation :math:`|\log_3(R_T^T R(q))|`
[rad], is within :data:`ACCEPT` times :data:`POSITION_TOL` and
:data:`ROTATION_TOL`; else it is reported as not reaching (its row NaN),
never returned with a larger residual.

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
    _solve,
)
from workbench.ik._kernel_common import (
    FLAG_SOME_UNREACHED,
    FLAG_WITHIN_LIMITS,
    remainder,
)
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
#: Refinement stops when the residual has not decreased for this many steps.
STALL_STEPS = 20
#: Valley search (:func:`_valley_search`): values of the fixed joint scanned
#: over a turn, Gauss–Newton steps of the other five per value, and the
#: steps of the root search between two scanned values.
VALLEY_SCAN = 36
VALLEY_INNER_STEPS = 8
VALLEY_ROOT_STEPS = 40
#: Added to the diagonal of JᵀJ in the valley search, so that an exactly
#: singular J still gives a solvable system [1/m² ~ 1/rad²].
GRAM_SHIFT = 1e-24
#: The least squares of the other five joints stop at a step this short [rad];
#: the root search at a bracket this narrow [rad].
VALLEY_STEP_TOL = 1e-15
VALLEY_ROOT_TOL = 1e-15
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
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
    stops at :data:`POLISH`, after :data:`STALL_STEPS` steps without progress,
    at a NaN error or after :data:`REFINE_STEPS` steps.

    Returns:
        ``(best, best_step, stop)``.
    """
    if error < best:
        best, best_step = error, step
        for k in range(q.shape[0]):
            best_q[k] = q[k]
    elif not error == error or step - best_step >= STALL_STEPS:
        return best, best_step, True
    return best, best_step, best <= POLISH or step == REFINE_STEPS


@helper()
def _refine_branch(chain: FloatArray, target: FloatArray, q: FloatArray, work) -> bool:
    """Newton steps on ``q`` (6,) in place; whether its residual is within tolerance.

    Steps are taken until the residual is :data:`POLISH` times the tolerance,
    has not decreased for :data:`STALL_STEPS` steps (next to a singularity a
    step may first increase it), or :data:`REFINE_STEPS` are taken; ``q`` is
    then the best iterate. ``work``: (30, 12) scratch.
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
def _valley_search(chain, target, q, work) -> bool:
    """Find the model's solution along a singular family of the idealised arm.

    Where the idealised arm has a one-parameter family of solutions (a singular
    wrist's θ4/θ6 split, θ1 with the wrist centre on the base axis, θ2 with it
    on the shoulder axis), the model's deviations fix one member, along a
    valley of residuals ~1e-9 too curved for Newton to follow. The joint that
    moves most along J's null direction is fixed at :data:`VALLEY_SCAN` values
    over a turn, the five others solved by least squares at each; the normal
    part of the remaining error changes sign at the model's solutions, found
    by regula falsi (Illinois) and refined by :func:`_refine_branch`. The two
    joints that move most are tried in turn.

    Returns whether ``q`` (6,) now holds a solution within the tolerances.
    """
    frames, jac, normal = work[0:7], work[7:13, 0:6], work[13:19, 0:6]
    e, v = work[19, 0:6], work[22, 0:6]
    previous = np.empty(6)
    start = np.empty(6)
    for k in range(6):
        start[k] = q[k]
        v[k] = 1.0
    _forward(chain, start, frames)
    _error(target, frames, e)
    _jacobian(chain, frames, jac)
    for _ in range(4):  # inverse iteration: J's right singular vector of least σ
        _gram(jac, 6, normal)
        if not _solve(normal, v, 6):
            return False
        length = 0.0
        for k in range(6):
            length += v[k] * v[k]
        length = math.sqrt(length)
        for k in range(6):
            v[k] /= length
    order = np.argsort(-np.abs(v))
    scanned, parts = np.empty((VALLEY_SCAN + 1, 6)), np.empty(VALLEY_SCAN + 1)
    x = np.empty(6)
    width = 2.0 * math.pi / VALLEY_SCAN
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
                if ga == gb or abs(b - a) <= VALLEY_ROOT_TOL:
                    break
                t = b - gb * (b - a) / (gb - ga)
                x[j] = t
                _inner(chain, target, x, j, work)
                g = _normal_part(work, previous)
                if (g > 0.0) == (gb > 0.0):
                    ga *= 0.5
                else:
                    a, ga = b, gb
                b, gb = t, g
            if _refine_branch(chain, target, x, work):
                for k in range(6):  # the turn of each angle nearest the start
                    q[k] = start[k] + remainder(x[k] - start[k])
                return True
        # no sign change that leads there: a double root (where the two arms
        # or elbows meet, the normal part only touches 0), the least |e| by
        # golden section around the scanned value of least |e|
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
            for k in range(6):
                q[k] = start[k] + remainder(x[k] - start[k])
            return True
    return False


@helper()
def _refine_pose(
    chain: FloatArray, target: FloatArray, q: FloatArray, work: FloatArray
) -> int:
    """Refine the reached rows (not NaN) of ``q`` (8, 6); NaN the ones that fail.

    A branch that Newton does not bring within the tolerances from the closed
    form gets the valley search (:func:`_valley_search`) from there.

    Returns a bit mask of the branches that reach.
    """
    start = np.empty(6)
    reached = 0
    for b in range(8):
        row = q[b]
        if not row[0] == row[0]:
            continue
        for k in range(6):
            start[k] = row[k]
        if _refine_branch(chain, target, row, work):
            reached |= 1 << b
            continue
        for k in range(6):
            row[k] = start[k]
        if _valley_search(chain, target, row, work):
            reached |= 1 << b
        else:
            for k in range(6):
                row[k] = np.nan
    return reached


@entry_point(outputs=("q", "flags"), contiguous=("chain", "pose"))
def refine_pose(
    chain: FloatArray, pose: FloatArray, q: FloatArray, flags: npt.NDArray[np.bool_]
) -> int:
    """Refine the branches of one pose on the true chain.

    Args:
        chain: (7, CHAIN_WIDTH) packed true chain (``_chain_kernel``).
        pose: (4, 4) target pose of the tool frame in the base frame [m].
        q: (8, 6) branches of the closed form [rad], NaN rows for those that
            do not reach; refined in place, NaN where refinement fails.
        flags: (FLAG_COUNT,) flags of ``solve_pose``: "within limits" and
            "some branches do not reach" (slot 13) are updated.

    Returns:
        The number of branches that reach.
    """
    work = np.empty((30, 12))
    reached = _refine_pose(chain, pose, q, work)
    count = 0
    for b in range(8):
        alive = reached >> b & 1 != 0
        count += alive
        within = alive
        for k in range(6):
            within &= chain[k, 16] - LIMIT_TOL <= q[b, k] <= chain[k, 17] + LIMIT_TOL
        flags[FLAG_WITHIN_LIMITS + b] = within
    flags[FLAG_SOME_UNREACHED] = count < 8
    return count


@entry_point(outputs=("q", "valid"), contiguous=("chain", "targets"))
def refine_batch(
    chain: FloatArray,
    targets: FloatArray,
    q: FloatArray,
    valid: npt.NDArray[np.bool_],
) -> int:
    """Refine the branches of N poses on the true chain.

    Args:
        chain: (7, CHAIN_WIDTH) packed true chain.
        targets: (N, 4, 4) target poses [m].
        q: (N, 8, 6) branches [rad] (NaN rows where not valid), refined in
            place; NaN where refinement fails.
        valid: (N, 8) True where a branch reaches; cleared where it fails.

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
    return failed
