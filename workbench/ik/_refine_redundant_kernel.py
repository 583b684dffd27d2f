r"""Compiled Newton refinement of seven-axis branches on the robot's true chain.

The seven-axis closed forms (:mod:`workbench.ik._srs_kernel`,
:mod:`workbench.ik._franka_kernel`) solve the *idealised* structure fitted to
the joint axes. A URDF that is of a family only up to its rounding (π/2 written
``1.5708``, 3.67e-6 rad off: example-robot-data's xArm7) gets branches that
miss its pose by about that deviation times the reach. As for six axes
(:mod:`workbench.ik._refine_kernel`, whose tolerances and step rules this module
shares), each such branch is the start of Newton steps on the model's own chain
(``_chain.get_chain``), the redundancy parameter held at its value:

* Franka (the parameter is q7, a joint of the model): the six joints 1–6, q7
  fixed, :math:`q_{1..6} \leftarrow q_{1..6} - J_6^T (J_6 J_6^T + \lambda
  I)^{-1} e` (J_6 the first six columns of the LOCAL Jacobian of the tool);
* SRS (the parameter is the arm angle ψ, which the model does not define: it
  is read on the idealised chain, ``_srs_kernel.parameter_of``): the seven
  joints, for the square system :math:`r(q) = [e;\ ψ(q) - ψ^*]` (7),
  :math:`q \leftarrow q - A^T (A A^T + \lambda I)^{-1} r`, A = [J; ∇ψ] (7, 7),
  ∇ψ by central differences (:data:`PARAMETER_STEP`).

:math:`e = \log_6(T^{-1} M(q))`, λ = |r|² (Levenberg–Marquardt's damping of
Yamashita and Fukushima). A branch is kept when its FK residual, position [m]
and rotation [rad], and for SRS |ψ(q) − ψ*| [rad], are within ``ACCEPT``
times ``POSITION_TOL`` and ``ROTATION_TOL``; else its row is NaN (not
reached), never returned with a larger residual. Unlike six axes there is no
valley search: a branch Newton does not bring there is dropped.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point, helper
from workbench.ik._chain_kernel import (
    _damped_step,
    _forward,
    _jacobian,
    _products,
    _solve,
)
from workbench.ik._kernel_common import remainder
from workbench.ik._refine_kernel import (
    ACCEPT,
    CHORD_GATE,
    CHORD_RATIO,
    EVENT_SHIFT,
    FAST_STEPS,
    MERGED,
    POLISH,
    REFINE_STEPS,
    ROTATION_TOL,
    TWIN_TOL,
    UNLISTED,
    UNLISTED_SHIFT,
    VANISHED,
    _back,
    _factor,
    _fast_error,
    keep_best,
    pose_error,
    solution_gap,
    step_back,
    write_flags,
)
from workbench.ik._refine_kernel import _refine_pose as refine_six
from workbench.ik._srs_kernel import _arm_angle

FloatArray = npt.NDArray[np.float64]

#: Step [rad] of the central differences of ψ(q): their truncation error,
#: ~1e-12 relative, and rounding, ~1e-10, only slow Newton's last step.
PARAMETER_STEP = 1e-6
#: ψ depends on the first this many joints only (``_srs_kernel._arm_angle``
#: reads θ1…θ4: the elbow and the wrist centre): ∂ψ/∂q5…q7 are 0, exactly,
#: and are not differenced.
ARM_ANGLE_JOINTS = 4
#: Joints (0-based) whose DH angle is 0 or π where the idealised arm folds
#: (the elbow θ4, the shoulder θ2, the wrist θ6), and the step [rad] a start on
#: the fold is moved across it when Newton finds nothing from it (the model's
#: solutions near a fold lie about √deviation from it: 0.02–0.06 rad for
#: 1e-4…1e-3 of deviation).
FOLD_JOINTS = (3, 1, 5)
FOLD_STEP = 0.05
#: Rows of the scratch array of :func:`_refine_row` and :func:`_newton_srs`
#: (12 columns).
WORK_ROWS = 30


@helper()
def _arm_angle_of(geo, q: FloatArray, theta: FloatArray) -> float:
    """ψ [rad] of robot joint values ``q`` (7,) on the idealised SRS chain."""
    for j in range(7):
        theta[j] = geo.joint_sign[j] * q[j] + geo.theta_offset[j]
    return _arm_angle(geo, theta)


@helper()
def _newton_srs(chain, geo, target, value: float, q, work) -> bool:
    """Newton steps on the square system [e; ψ(q) − ψ*] of one SRS row, or False.

    The fast path of a regular row (``_refine_kernel._newton``'s, for seven
    joints): A = [J; ∇ψ] (7, 7) by LU, no damping, ∇ψ by forward differences
    (:data:`PARAMETER_STEP`) at the start only (the row of ψ then converges
    linearly, at a rate of its change over the step), the first-order error of
    ``_refine_kernel._fast_error``. Stops at ``POLISH`` times the
    tolerances, or where the residual stops decreasing within ``ACCEPT``
    (``q`` the best iterate); anything else returns False and the caller
    takes :func:`_refine_row`. ``work``: (:data:`WORK_ROWS`, 12) scratch.
    """
    frames = work[0:8]
    lu = work[15:22, 0:7]
    r, previous = work[22, 0:7], work[23, 0:7]
    theta, shifted = work[26, 0:7], work[27, 0:7]
    gradient, pivots = work[24, 0:7], work[25, 0:7]
    sines, cosines = work[28, 0:7], work[29, 0:7]
    for k in range(7):
        sines[k], cosines[k] = math.sin(q[k]), math.cos(q[k])
    last = math.inf
    fresh = False  # whether lu holds the factors of the previous step's A
    for step in range(FAST_STEPS + 1):
        for k in range(7):
            frames[k, 0], frames[k, 1] = sines[k], cosines[k]
        _products(chain, q, frames)
        size = _fast_error(target, frames, r)
        psi = _arm_angle_of(geo, q, theta)
        r[6] = remainder(psi - value)
        size = max(size, abs(r[6]) / ROTATION_TOL)
        if size <= POLISH:
            return True
        if not size < last:  # the previous iterate was the best
            for k in range(7):
                q[k] = previous[k]
            return last <= ACCEPT
        if step == FAST_STEPS:
            return False
        if fresh and size <= CHORD_GATE and size <= CHORD_RATIO * last:
            fresh = False  # the previous step's factors (``_refine_kernel._newton``)
            last = size
            _back(lu, pivots, r)
            for k in range(7):
                previous[k] = q[k]
                step_back(q, k, r[k], sines, cosines)
            continue
        last = size
        _jacobian(chain, frames, lu)  # (rows 0-5; row 6 holds ∇ψ)
        if step == 0:  # ∇ψ of the start: ψ is smooth, the start near the end
            for k in range(7):
                shifted[k] = q[k]
                gradient[k] = 0.0  # (ψ reads ARM_ANGLE_JOINTS joints only)
            for k in range(ARM_ANGLE_JOINTS):
                shifted[k] = q[k] + PARAMETER_STEP
                gradient[k] = (
                    remainder(_arm_angle_of(geo, shifted, theta) - psi) / PARAMETER_STEP
                )
                shifted[k] = q[k]
        for k in range(7):
            lu[6, k] = gradient[k]
        if not _factor(lu, pivots):
            return False
        fresh = True
        _back(lu, pivots, r)
        for k in range(7):
            previous[k] = q[k]
            step_back(q, k, r[k], sines, cosines)
    return False


@helper()
def _refine_row(chain, geo, srs: bool, target, value: float, q, work) -> bool:
    """Newton steps on one branch ``q`` (7,) in place; whether it is within tolerance.

    Steps are taken until the residual is ``POLISH`` times the tolerances, has
    not decreased for ``STALL_STEPS`` steps, or ``REFINE_STEPS`` are taken;
    ``q`` is then the best iterate. ``geo``: the SRS record whose ψ is held at
    ``value`` when ``srs`` (else q7 is held, and ``geo`` is not read).
    ``work``: (:data:`WORK_ROWS`, 12) scratch.
    """
    frames = work[0:8]
    jac, normal = work[8:15, 0:7], work[15:22, 0:7]  # jac row 6: ∇ψ (SRS)
    r, dq, y = work[22, 0:7], work[23, 0:7], work[24, 0:7]
    best_q, theta, shifted = work[25, 0:7], work[26, 0:7], work[27, 0:7]
    rows = 7 if srs else 6
    no_pull = work.shape[0] < 0  # False, as a computed bool (no literal copy)
    dq[6] = 0.0
    best, best_step = math.inf, 0
    for step in range(REFINE_STEPS + 1):
        _forward(chain, q, frames)
        error = pose_error(target, frames, r)
        if srs:
            r[6] = remainder(_arm_angle_of(geo, q, theta) - value)
            error = max(error, abs(r[6]) / ROTATION_TOL)
        best, best_step, stop = keep_best(error, best, best_step, step, q, best_q)
        if stop:
            break
        damping = 0.0
        for i in range(rows):
            damping += r[i] * r[i]
        _jacobian(chain, frames, jac)
        if not srs:  # the first six columns: q7 stays
            _damped_step(jac, 6, r, dq, no_pull, damping, normal, y, dq)
        else:
            for k in range(7):
                jac[6, k] = 0.0  # (ψ reads ARM_ANGLE_JOINTS joints only)
            for k in range(ARM_ANGLE_JOINTS):
                for j in range(7):
                    shifted[j] = q[j]
                shifted[k] = q[k] + PARAMETER_STEP
                up = _arm_angle_of(geo, shifted, theta)
                shifted[k] = q[k] - PARAMETER_STEP
                down = _arm_angle_of(geo, shifted, theta)
                jac[6, k] = remainder(up - down) / (2.0 * PARAMETER_STEP)
            for i in range(7):  # A Aᵀ + λ I, and y = r
                for j in range(7):
                    s = 0.0
                    for k in range(7):
                        s += jac[i, k] * jac[j, k]
                    normal[i, j] = s
                normal[i, i] += damping
                y[i] = r[i]
            _solve(normal, y, 7)  # positive definite: never singular
            for k in range(7):  # Aᵀ y
                s = 0.0
                for i in range(7):
                    s += jac[i, k] * y[i]
                dq[k] = s
        for k in range(rows):  # (a turn of 2π or more is none: the angle stays near)
            q[k] -= remainder(dq[k])
    for k in range(7):
        q[k] = best_q[k]
    return best <= ACCEPT


@helper()
def _unheld(q, x, reached: int, skip: int) -> bool:
    """No reached row of ``q`` (B, 7) but ``skip`` holds ``x`` (:data:`TWIN_TOL`)."""
    for c in range(q.shape[0]):
        if c != skip and reached >> c & 1 and solution_gap(q[c], x) <= TWIN_TOL:
            return False
    return True


@helper()
def _other_start(chain, geo, srs, target, value, start, solution, q, reached, b, work):
    """Carry row ``b`` to a solution no other row holds, from near ``start`` (7,).

    Tried in turn: the start mirrored through ``solution`` (7,) (the model's
    two solutions near a fold of the idealised arm lie on either side of it),
    if ``solution`` is a solution; then the start with one of the fold joints
    (4, 2, 6: elbow, shoulder, wrist) moved by ±:data:`FOLD_STEP` (a start on
    the fold itself, where the idealised arm's reach test is widened, gives
    Newton no direction across it). Leaves the solution in ``q[b]``.

    Returns:
        Whether one was found.
    """
    x = np.empty(7)
    for attempt in range(-1, 6):
        for k in range(7):
            x[k] = start[k]
        if attempt < 0:
            if not solution[0] == solution[0]:
                continue
            for k in range(7):
                x[k] = start[k] + remainder(start[k] - solution[k])
        else:
            joint = FOLD_JOINTS[attempt >> 1]
            x[joint] += FOLD_STEP if attempt & 1 == 0 else -FOLD_STEP
        if _refine_row(chain, geo, srs, target, value, x, work) and _unheld(
            q, x, reached, b
        ):
            for k in range(7):
                q[b, k] = x[k]
            return True
    return False


@helper()
def _refine_branches(chain, geo, srs: bool, target, value: float, q, work) -> int:
    """Carry the reached rows (not NaN) of ``q`` (B, 7) to the chain; NaN the others.

    A row that lands on the solution of another (twins that start at, or
    near, the idealised arm's fold, e.g. its stretched elbow: the model's two
    solutions lie on either side, about √deviation apart) leaves it to the row
    whose start is nearer; that row, or one that does not converge, is
    carried again from other starts near its own (:func:`_other_start`). A
    row that still finds no solution of its own is NaN and sets ``MERGED``
    (it had converged onto another's) or ``VANISHED``. A row that moves more
    than ``UNLISTED_SHIFT`` from its start is in a valley of the model's
    near-singular solutions (e.g. θ2 → 0, axes 1 and 3 aligned), which is not
    searched here: ``UNLISTED`` says the model may have solutions there that
    no row holds.

    Returns:
        A bit mask of the branches that reach, plus ``VANISHED`` and
        ``MERGED`` (``_refine_kernel``'s bits).
    """
    starts, solution = np.empty((q.shape[0], 7)), np.empty(7)
    reached, events = 0, 0
    for b in range(q.shape[0]):
        row = q[b]
        if not row[0] == row[0]:
            continue
        for k in range(7):
            starts[b, k] = row[k]
        if not _newton_srs(chain, geo, target, value, row, work) and not _refine_row(
            chain, geo, srs, target, value, row, work
        ):
            for k in range(7):
                solution[k] = np.nan
            if _other_start(
                chain, geo, srs, target, value, starts[b], solution, q, reached, b,
                work,
            ):  # fmt: skip
                reached |= 1 << b
            else:
                for k in range(7):
                    row[k] = np.nan
                events |= VANISHED
            continue
        reached |= 1 << b
        if solution_gap(starts[b], row) > UNLISTED_SHIFT:  # a valley, not searched
            events |= UNLISTED
        a = -1
        for c in range(q.shape[0]):
            if c != b and reached >> c & 1 and solution_gap(q[c], row) <= TWIN_TOL:
                a = c
        if a < 0:
            continue
        near_a = solution_gap(starts[a], q[a]) <= solution_gap(starts[b], row)
        loser = b if near_a else a
        for k in range(7):
            solution[k] = row[k]
        if not _other_start(
            chain, geo, srs, target, value, starts[loser], solution, q, reached,
            loser, work,
        ):  # fmt: skip
            for k in range(7):
                q[loser, k] = np.nan
            reached &= ~(1 << loser)
            events |= MERGED
    return reached | events


@helper()
def _fixed_last(chain: FloatArray, value: float, out: FloatArray) -> None:
    """The six-joint chain ``out`` (7, CHAIN_WIDTH) of ``chain`` (8, ·), q7 = value.

    Rows 0–5 are the first six joints; row 6 is the tool placement in joint
    6's frame with joint 7 turned to ``value``: P7 · exp(a7 q7) · P_tool.
    """
    for r in range(6):
        for c in range(chain.shape[1]):
            out[r, c] = chain[r, c]
    for c in range(chain.shape[1]):
        out[6, c] = 0.0
    x, y, z = chain[6, 12], chain[6, 13], chain[6, 14]
    s, co = math.sin(value), math.cos(value)
    vers = 1.0 - co
    turn = np.empty(9)  # Rodrigues: cos I + sin a^ + (1 - cos) a aᵀ, row-major
    turn[0], turn[4], turn[8] = co + vers * x * x, co + vers * y * y, co + vers * z * z
    turn[1], turn[3] = vers * x * y - s * z, vers * x * y + s * z
    turn[2], turn[6] = vers * x * z + s * y, vers * x * z - s * y
    turn[5], turn[7] = vers * y * z - s * x, vers * y * z + s * x
    middle = np.empty(9)  # R7 · turn
    for i in range(3):
        for j in range(3):
            middle[3 * i + j] = (
                chain[6, 3 * i] * turn[j]
                + chain[6, 3 * i + 1] * turn[3 + j]
                + chain[6, 3 * i + 2] * turn[6 + j]
            )
    for i in range(3):  # (R7 turn, p7) · (R_tool, p_tool)
        for j in range(3):
            out[6, 3 * i + j] = (
                middle[3 * i] * chain[7, j]
                + middle[3 * i + 1] * chain[7, 3 + j]
                + middle[3 * i + 2] * chain[7, 6 + j]
            )
        out[6, 9 + i] = (
            chain[6, 9 + i]
            + middle[3 * i] * chain[7, 9]
            + middle[3 * i + 1] * chain[7, 10]
            + middle[3 * i + 2] * chain[7, 11]
        )


@helper()
def _refine_fixed_last(chain, target, value: float, q, six, rows, work) -> int:
    """A Franka arm's rows ``q`` (B, 7) at q7 = ``value``, carried as a 6R arm.

    With q7 held the arm is a six-joint chain (:func:`_fixed_last` into
    ``six``), carried by the six-axis refinement (``_refine_kernel``: its
    valley search finds the model's solutions where the idealised arm has a
    one-parameter family, e.g. θ2 = 0, axes 1 and 3 aligned). ``rows`` (B, 6)
    and ``work`` (30, 12) are scratch.

    Returns:
        As ``_refine_kernel``'s: the reached mask plus its event bits.
    """
    _fixed_last(chain, value, six)
    for b in range(q.shape[0]):
        for k in range(6):
            rows[b, k] = q[b, k]
    reached = refine_six(six, target, rows, work)
    for b in range(q.shape[0]):
        for k in range(6):
            q[b, k] = rows[b, k]
        q[b, 6] = value if reached >> b & 1 else np.nan
    return reached


@entry_point(outputs=("q", "flags"), contiguous=("chain", "pose"))
def refine_pose(
    chain: FloatArray,
    arm_angle_geometry: np.ndarray,
    srs: bool,
    pose: FloatArray,
    value: float,
    q: FloatArray,
    flags: npt.NDArray[np.uint8],
) -> int:
    """Refine the branches of one pose on the true chain.

    Args:
        chain: (8, CHAIN_WIDTH) packed true chain (``_chain_kernel``).
        arm_angle_geometry: (1,) SRS record (``_srs_kernel.pack_geometry``)
            whose arm angle is held at ``value`` when ``srs``; else any
            record of that dtype (not read: q7 is held).
        srs: True for an SRS arm (ψ held), False for a Franka arm (q7 held).
        pose: (4, 4) target pose of the tool frame in the base frame [m].
        value: The redundancy parameter [rad]: ψ (SRS) or q7 (Franka).
        q: (B, 7) branches of the closed form [rad], NaN rows for those that
            do not reach; refined in place, NaN where refinement fails.
        flags: (B,) uint8 bits of ``_flags`` per branch (the closed form's),
            rewritten as ``_refine_kernel.write_flags`` says.

    Returns:
        The solve-level byte (``ik.SolveFlag`` bits): a branch vanished,
        branches merged, solutions unlisted; 0 when every branch carried over.
    """
    work = np.empty((WORK_ROWS, 12))
    if srs:
        reached = _refine_branches(
            chain, arm_angle_geometry[0], srs, pose, value, q, work
        )
    else:
        reached = _refine_fixed_last(
            chain, pose, value, q, np.empty((7, chain.shape[1])),
            np.empty((q.shape[0], 6)), np.empty((30, 12)),
        )  # fmt: skip
    return write_flags(chain, q, flags, reached)


@entry_point(
    outputs=("q", "valid", "solve_flags"), contiguous=("chain", "targets", "values")
)
def refine_batch(
    chain: FloatArray,
    arm_angle_geometry: np.ndarray,
    srs: bool,
    targets: FloatArray,
    values: FloatArray,
    q: FloatArray,
    valid: npt.NDArray[np.bool_],
    solve_flags: npt.NDArray[np.uint8],
) -> int:
    """Refine the branches of N poses on the true chain.

    Args:
        chain: (8, CHAIN_WIDTH) packed true chain.
        arm_angle_geometry: As :func:`refine_pose`.
        srs: True for an SRS arm (ψ held), False for a Franka arm (q7 held).
        targets: (N, 4, 4) target poses [m].
        values: (N,) the redundancy parameter of each pose [rad].
        q: (N, B, 7) branches [rad] (NaN rows where not valid), refined in
            place; NaN where refinement fails.
        valid: (N, B) True where a branch reaches; rewritten.
        solve_flags: (N,) uint8 output, the solve-level byte of each pose.

    Returns:
        The number of branches that were valid and failed.
    """
    work = np.empty((WORK_ROWS, 12))
    six, rows, six_work = (
        np.empty((7, chain.shape[1])),
        np.empty((q.shape[1], 6)),
        np.empty((30, 12)),
    )
    geo = arm_angle_geometry[0]
    failed = 0
    for i in range(targets.shape[0]):
        if srs:
            reached = _refine_branches(
                chain, geo, srs, targets[i], values[i], q[i], work
            )
        else:
            reached = _refine_fixed_last(
                chain, targets[i], values[i], q[i], six, rows, six_work
            )
        for b in range(q.shape[1]):
            alive = reached >> b & 1 != 0
            failed += valid[i, b] and not alive
            valid[i, b] = alive
        solve_flags[i] = (reached >> EVENT_SHIFT) & 0xFF
    return failed
