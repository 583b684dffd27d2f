r"""Closed-form inverse kinematics of OPW (PUMA-type), UR-type and seven-axis arms.

The solution is derived from the robot's own DH table when it has one (the
PUMA models, see :mod:`workbench.ik._puma` for which tables qualify), else from
the DH chain fitted to its joint axes (:mod:`workbench.ik.structure`, which
recognises the family), not from one printed table; ``docs/errata-kang-ik.md``
derives the OPW solution and lists what is wrong in Kang (2007)'s printed
formulas, ``docs/closed-form-ik.md`` covers any arm. The target is always the
pose of the robot's tool frame: base and tool transforms are folded in.

The functions here are the front door for one call; each robot's
:class:`~workbench.ik.Solver` (:func:`~workbench.ik.get_solver`) does the work,
and holds the branch labels (physical, defined in :mod:`workbench.ik.solver`):
:data:`BRANCHES` for OPW arms, bits ``4·left + 2·down + flip``;
:data:`UR_BRANCHES` for UR-type arms.

A seven-axis arm (SRS or Franka family, :mod:`workbench.ik.redundant`) has
a one-parameter family of solutions per branch: :func:`analytic` and
:func:`analytic_batch` take the redundancy parameter (``redundancy=``: the
arm angle ψ or q7 [rad]), through the same solver;
:mod:`workbench.ik.redundancy` chooses a value.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.ik._puma import TAU, WRIST_SINGULAR_TOL
from workbench.ik.solution import IKSolution, Solutions
from workbench.ik.solver import BRANCHES, UR_BRANCHES, get_solver
from workbench.ik.turns import REPRESENTATIVES, expand_turns
from workbench.model.robot import Robot
from workbench.validation import as_vector

FloatArray = npt.NDArray[np.float64]


def analytic(
    robot: Robot,
    target: pin.SE3 | npt.ArrayLike,
    *,
    q_previous: npt.ArrayLike | None = None,
    redundancy: float | None = None,
    representatives: str = "one",
) -> Solutions:
    """Every closed-form IK branch of a 6R (OPW, UR) or 7R (SRS, Franka) arm.

    Args:
        robot: A 6R arm of either family (see :mod:`workbench.ik.structure`):
            ``puma560``, ``puma560-kang``, ``ur5``, a KUKA/ABB/Fanuc URDF, ...;
            or a seven-axis arm of the SRS (``iiwa14``) or Franka (``panda``)
            family.
        target: Pose of the robot's tool frame in the base frame: ``pin.SE3``
            or a (4, 4) homogeneous matrix [m].
        q_previous: Optional configuration (nq,) [rad] of the previous path
            sample. Each returned angle is then the representative (mod 2π)
            nearest to it, and at a 6R wrist singularity θ4/θ6 are split so
            that the step from ``q_previous`` is shortest (else θ4 = 0).
        redundancy: 7R arms only: the redundancy parameter [rad], the arm
            angle ψ (SRS) or q7 (Franka). None takes that of ``q_previous``
            (continuity); one of the two is required.
        representatives: ``"one"``: each angle once (below); ``"all"``: every
            representative within the limits of a joint whose range exceeds
            2π, each a solution labelled with its turns
            (:func:`workbench.ik.turns.expand_turns`).

    Returns:
        One :class:`IKSolution` per branch that reaches the pose, in the order
        of the labels (:data:`BRANCHES`, UR: :data:`UR_BRANCHES`): all eight
        unless a shoulder offset (a1 != 0, or a UR arm) lets only some reach.
        At a shoulder or elbow singularity some coincide; at a wrist
        singularity the flip twin is the continuity member turned by π.
        7R arms: one per branch reaching the pose for that value of the
        parameter (``IKSolution.redundancy`` holds it; None on 6R arms).

    Raises:
        UnsupportedRobotError: If the robot has no closed form.
        UnreachableError: If the wrist centre is out of reach or inside the
            cylinder of radius |D| (the shoulder offset) around the base axis
            (7R: no branch reaches for this value; the message says why).
        DimensionError: If ``target`` is not (4, 4) or ``q_previous`` not (nq,).
        NonFiniteError: If an entry is NaN or infinite.
        InputError: If ``target`` is not rigid (see ``poses.RIGIDITY_TOL``),
            ``redundancy`` is given for a 6R arm, or a 7R arm has neither
            ``redundancy`` nor ``q_previous``; or ``representatives`` is
            neither ``"one"`` nor ``"all"``.
    """
    solutions = get_solver(robot).solve(
        target, redundancy=redundancy, q_previous=q_previous
    )
    if representatives == "one":
        return solutions
    if representatives == "all":
        return expand_turns(robot, solutions)
    raise InputError(
        f"representatives must be one of {', '.join(REPRESENTATIVES)}, "
        f"got {representatives!r}"
    )


def analytic_batch(
    robot: Robot,
    targets: npt.ArrayLike,
    *,
    redundancy: float | npt.ArrayLike | None = None,
) -> tuple[FloatArray, npt.NDArray[np.bool_]]:
    """Every closed-form IK branch of N poses, vectorised.

    The kernel of :func:`analytic` in three stages per chunk of poses: the
    arguments of every atan2 (a compiled loop that LLVM vectorises, four poses
    at a time; the rare singular poses after it, one by one), all the atan2 in
    one compiled loop that LLVM vectorises (:mod:`workbench.ik._atan2_kernel`,
    several times faster than one libm call each), the joint values (compiled
    loop).

    Args:
        robot: A 6R arm of either family (as :func:`analytic`), or a 7R arm.
        targets: Shape (N, 4, 4), homogeneous poses of the tool frame in the
            base frame [m].
        redundancy: 7R arms only, required: the redundancy parameter [rad]
            (ψ or q7), one value for every pose or (N,).

    Returns:
        ``q`` of shape (N, 8, 6) [rad], branch axis in the order of
        :data:`BRANCHES`, wrapped as by :func:`analytic` (θ4 = 0 at a wrist
        singularity), equal to it up to the last bits of the atan2; and
        ``valid`` of shape (N, 8), True where the branch reaches the pose
        (every branch, unless a shoulder offset a1 or a UR arm lets only some
        reach). Rows of branches that do not reach are NaN. Joint limits are
        not applied: test ``(robot.lower <= q) & (q <= robot.upper)`` for that.
        7R arms: ``q`` (N, B, 7) and ``valid`` (N, B), B the arm's branch
        count (SRS 8, Franka 8), as :meth:`Solver.solve_batch
        <workbench.ik.Solver.solve_batch>`.

    Raises:
        UnsupportedRobotError: If the robot has no closed form.
        DimensionError: If ``targets`` is not (N, 4, 4) or ``redundancy`` not (N,).
        NonFiniteError: If an entry is NaN or infinite.
        InputError: If a pose is not rigid (``poses.RIGIDITY_TOL``), or
            ``redundancy`` is given for a 6R arm or missing for a 7R arm.
    """
    return get_solver(robot).solve_batch(targets, redundancy=redundancy)


def nearest(solutions: Sequence[IKSolution], q_previous: npt.ArrayLike) -> IKSolution:
    """The solution nearest to ``q_previous``, angles compared modulo 2π.

    Generalises Kang's rule "if θ4 jumps by ≈ π, take the other solution": the
    distance is the Euclidean norm of the joint differences, each wrapped to
    [−π, π), so the flip twin (θ4 and θ6 off by π) loses near a wrist
    singularity and no joint counts a 2π jump. For representatives near
    ``q_previous`` as well, pass it to :func:`analytic`.

    Args:
        solutions: Candidates, e.g. the result of :func:`analytic` (6R or 7R).
        q_previous: Configuration (nq,) [rad].

    Returns:
        The element of ``solutions`` (not a copy) with the smallest distance;
        the first one on a tie.

    Raises:
        InputError: If ``solutions`` is empty; ``DimensionError`` or
            ``NonFiniteError`` if ``q_previous`` is not a finite (nq,) vector.
    """
    if not solutions:
        raise InputError("nearest() needs at least one solution")
    q = np.array([s.q for s in solutions])
    p = as_vector(q_previous, q.shape[1], "q_previous")
    step = np.remainder(q - p + np.pi, TAU) - np.pi
    return solutions[int(np.argmin(np.einsum("ij,ij->i", step, step)))]


__all__ = [
    "BRANCHES",
    "UR_BRANCHES",
    "WRIST_SINGULAR_TOL",
    "IKSolution",
    "analytic",
    "analytic_batch",
    "nearest",
]
