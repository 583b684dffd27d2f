r"""Compiled per-pose measures of the workspace map, after the batch closed form.

:func:`fill_poses` writes the (N, 4, 4) poses of a run of flat grid indices;
:meth:`Solver.solve_batch_into` (the family kernel's batch stages)
gives every branch; :func:`measure_poses` then does, per pose, what
:func:`~workbench.workspace._reference.evaluate_block_reference` does with
NumPy, in the same arithmetic (the results are bitwise equal, tested to
1e-6): the representative of each angle nearest the middle of its limits
(in limits, margin), the analytic factors :math:`s, e, w` of
:mod:`workbench.singularities.conditions` from
:math:`\theta = s_i q_i + \theta_{0,i}` and :math:`|\det J| = |K s e w|`
(computed once per (arm, elbow) pair where the branches share
:math:`q_1..q_3`, as OPW wrist twins do), and the best branch. The per-voxel
measures follow in NumPy (``_reference.summarise_voxels``).

The factor constants come packed in one float64 array (:data:`FACTOR_SLOTS`),
the joint constants in a (:data:`JOINT_ROWS`, 6) one. Compiled with
:mod:`workbench._compiled` (one signature per entry point, cache keyed on this
module and what it imports).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point, helper

FloatArray = npt.NDArray[np.float64]

#: Slots of the packed factor constants (see ``PumaFactorisation``).
FACTOR_SLOTS = (
    "ur", "constant", "a1", "a2", "a3", "d4", "a4", "sigma3d4", "sigma4d5",
    "forearm", "shoulder_tol", "elbow_tol", "wrist_tol",
)  # fmt: skip
_UR, _K, _A1, _A2, _A3, _D4, _A4, _S3D4, _S4D5, _L3, _TS, _TE, _TW = range(13)
#: Slots of the per-joint constants (rows): sign, theta offset, lower, upper,
#: middle of the limits, bounded (1.0 or 0.0).
JOINT_ROWS = 6
_SIGN, _OFFSET, _LOWER, _UPPER, _MID, _BOUNDED = range(JOINT_ROWS)

TAU = 2.0 * math.pi
#: 1 / 2π, the turns of an angle (the reference multiplies by it too).
INV_TAU = 1.0 / TAU


@helper(forceinline=True)
def branch_limits(
    joints: FloatArray, q: FloatArray, i: int, b: int
) -> tuple[bool, float]:
    """Whether branch ``b`` of pose ``i`` is within the limits, and its margin [rad].

    Each bounded angle ``q[i, b, j]`` is taken as its representative ``+ 2πk``
    nearest the middle of its limits (``rint((mid − q) / 2π)`` turns), as
    :func:`workbench.workspace._reference.limit_representatives` does.

    Args:
        joints: (JOINT_ROWS, n) per-joint constants (module slots).
        q: (N, B, n) joint values [rad].
        i: Pose.
        b: Branch.
    """
    within = True
    margin = math.inf
    for j in range(q.shape[2]):
        if joints[_BOUNDED, j] != 0.0:
            shifted = represent(joints[_MID, j], q[i, b, j])
            lo, hi = joints[_LOWER, j], joints[_UPPER, j]
            within &= (shifted >= lo) & (shifted <= hi)
            margin = min(margin, min(shifted - lo, hi - shifted))
    return within, margin


@helper(forceinline=True)
def write_representatives(
    joints: FloatArray, q: FloatArray, i: int, b: int, out: FloatArray, row: int
) -> None:
    """Write branch ``b`` of pose ``i`` to ``out[row]`` (angles as branch_limits)."""
    for j in range(q.shape[2]):
        value = q[i, b, j]
        if joints[_BOUNDED, j] != 0.0:
            value = represent(joints[_MID, j], value)
        out[row, j] = value


@helper(forceinline=True)
def represent(mid: float, value: float) -> float:
    """The representative ``value + 2πk`` [rad] nearest ``mid`` (ties: even k)."""
    turns: float = np.rint((mid - value) * INV_TAU)
    return value + turns * TAU


@entry_point(outputs=("poses",), contiguous=("positions", "rotations"))
def fill_poses(
    positions: FloatArray, rotations: FloatArray, first: int, poses: FloatArray
) -> None:
    """Poses of flat grid indices ``first .. first + N − 1``, voxel-major.

    Args:
        positions: (B, 3) voxel centres [m] of the block, base frame.
        rotations: (O, 3, 3) orientation matrices.
        first: Flat index (voxel·O + orientation within the block) of pose 0.
        poses: (N, 4, 4) output, homogeneous poses of the tool frame.
    """
    count = rotations.shape[0]
    for i in range(poses.shape[0]):
        v, o = divmod(first + i, count)
        for r in range(3):
            for c in range(3):
                poses[i, r, c] = rotations[o, r, c]
            poses[i, r, 3] = positions[v, r]
            poses[i, 3, r] = 0.0
        poses[i, 3, 3] = 1.0


@entry_point(
    outputs=("counts", "measures", "dexterity"),
    contiguous=("q", "valid", "factors", "joints"),
)
def measure_poses(
    factors: FloatArray,
    joints: FloatArray,
    q: FloatArray,
    valid: npt.NDArray[np.bool_],
    first: int,
    counts: npt.NDArray[np.uint8],
    measures: npt.NDArray[np.float32],
    dexterity: FloatArray,
) -> None:
    """Branch counts and best-branch measures of N solved poses.

    Args:
        factors: (len(FACTOR_SLOTS),) packed factor constants.
        joints: (JOINT_ROWS, 6) per-joint constants (module slots).
        q: (N, 8, 6) joint values [rad] of every branch (NaN rows unreached).
        valid: (N, 8) branch reaches the pose.
        first: Row of pose 0 in the outputs.
        counts: (2, P) output rows reached, in-limit branches.
        measures: (5, P) output rows dexterity [m³], |s| [m], |e|, |w|,
            limit margin [rad] of the best branch (NaN if none), float32.
        dexterity: (2, P) output float64 rows: the best branch's |det J|
            (NaN if none) and its singularity margin [1].
    """
    ur = factors[_UR] != 0.0
    k_det, a1, a2, a3 = factors[_K], factors[_A1], factors[_A2], factors[_A3]
    a4, s3d4, s4d5, ell = factors[_A4], factors[_S3D4], factors[_S4D5], factors[_L3]
    shoulder_tol, elbow_tol, wrist_tol = factors[_TS], factors[_TE], factors[_TW]
    for i in range(q.shape[0]):
        reached = 0
        usable = 0
        best_det = -1.0
        best_margin = -math.inf
        best_s = best_e = best_w = 0.0
        seen2 = seen3 = seen4 = math.nan  # the angles s and e were last computed at
        s = e = 0.0
        for b in range(8):
            if not valid[i, b]:
                continue
            reached += 1
            within, margin = branch_limits(joints, q, i, b)
            if not within:
                continue
            usable += 1
            q2, q3, q4 = q[i, b, 1], q[i, b, 2], q[i, b, 3]
            if not (q2 == seen2 and q3 == seen3 and (q4 == seen4 or not ur)):
                # a new (arm, elbow) pair: OPW twins share q1..q3, so s and e
                seen2, seen3, seen4 = q2, q3, q4
                t2 = q2 * joints[_SIGN, 1] + joints[_OFFSET, 1]
                t3 = q3 * joints[_SIGN, 2] + joints[_OFFSET, 2]
                t23 = t2 + t3
                s = a1 + a2 * math.cos(t2) + a3 * math.cos(t23)
                if ur:
                    t234 = t23 + (q4 * joints[_SIGN, 3] + joints[_OFFSET, 3])
                    s = s + a4 * math.cos(t234)
                    s = s + s4d5 * math.sin(t234)
                    e = math.sin(t3)
                else:
                    s = s + s3d4 * math.sin(t23)
                    e = (a3 * math.sin(t3) - s3d4 * math.cos(t3)) / ell
            w = math.sin(q[i, b, 4] * joints[_SIGN, 4] + joints[_OFFSET, 4])
            det = abs(k_det * s * e * w)
            if det > best_det or (det == best_det and margin > best_margin):
                best_det, best_margin = det, margin
                best_s, best_e, best_w = s, e, w
        row = first + i
        counts[0, row] = reached
        counts[1, row] = usable
        if usable:
            s, e, w = abs(best_s), abs(best_e), abs(best_w)
            measures[0, row] = best_det
            measures[1, row] = s
            measures[2, row] = e
            measures[3, row] = w
            measures[4, row] = best_margin
            dexterity[0, row] = best_det
            dexterity[1, row] = min(min(s / shoulder_tol, e / elbow_tol), w / wrist_tol)
        else:
            for m in range(5):
                measures[m, row] = np.nan
            dexterity[0, row] = np.nan
            dexterity[1, row] = np.nan
