r"""The redundancy parameter of a seven-axis arm: read it, where it reaches, choose it.

For one tool pose a seven-axis arm of the SRS or Franka family
(:mod:`workbench.ik.redundant`) has, per branch, a one-parameter family of
configurations, indexed by the arm angle ψ (SRS) or q7 (Franka), both [rad].

* :meth:`Solver.parameter_of <workbench.ik.Solver.parameter_of>` reads the
  parameter of configurations;
* :meth:`Solver.feasible <workbench.ik.Solver.feasible>` gives, per branch,
  the intervals of the parameter where the branch reaches the pose with every
  joint within its limits (the kernels': analytic for SRS arms, bisected to
  1e-12 rad for Franka arms);
* :func:`choose_redundancy` picks the value and the branch that maximise a
  criterion over those intervals.

The criteria (each a score to maximise, of the configuration q (7,) [rad]):

* ``"limit_margin"``: :math:`\min_k \min(q_k - l_k, u_k - q_k)` [rad], the
  smallest distance of a joint to one of its limits;
* ``"manipulability"``: :math:`\sqrt{\det(J J^T)}` of the 6×7 Jacobian of the
  tool frame (Yoshikawa's measure; the same in every frame, as
  ``det Ad = 1``);
* ``"nearest"``: minus the distance to ``q_previous`` [rad], each joint's
  difference wrapped to [−π, π).

The search is deterministic: every feasible interval of every branch is
sampled every :data:`SAMPLE_STEP` (at least :data:`MIN_SAMPLES` points, both
ends included), and the best sample of each interval is refined by
golden-section search between its neighbours to :data:`GOLDEN_TOL`. The
criteria are smooth within an interval except where the joint that sets the
limit margin changes (a kink, which golden-section search also brackets).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InfeasibleError, InputError, UnreachableError
from workbench.ik._puma import LIMIT_TOL
from workbench.ik._targets import pose_rows
from workbench.ik.batch_jacobians import compute_jacobians_local
from workbench.ik.solution import IKSolution
from workbench.ik.solver import Solver, get_solver
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]

#: The criteria of :func:`choose_redundancy`.
CRITERIA = ("limit_margin", "manipulability", "nearest")
#: Largest spacing [rad] of the samples of a feasible interval.
SAMPLE_STEP = 2.0 * math.pi / 720.0
#: Fewest samples of a feasible interval (its ends included).
MIN_SAMPLES = 5
#: Width [rad] of the bracket at which golden-section refinement stops.
GOLDEN_TOL = 1e-10

_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0  # 0.618…


@dataclass(frozen=True, slots=True)
class RedundancyChoice:
    """The value of the redundancy parameter chosen for a pose, and its branch.

    Attributes:
        value: The parameter [rad] (ψ or q7).
        solution: The chosen branch at ``value``, every angle the
            representative within its joint's limits.
        criterion: The criterion maximised (one of :data:`CRITERIA`).
        score: Its value at ``solution``: [rad] for ``"limit_margin"`` and
            ``"nearest"`` (minus the distance), Yoshikawa's measure for
            ``"manipulability"`` [m³ for a 6×7 Jacobian with three linear rows].
    """

    value: float
    solution: IKSolution
    criterion: str
    score: float


def _branch_index(solver: Solver, branch: str | int | None) -> int | None:
    if branch is None:
        return None
    if isinstance(branch, str):
        if branch not in solver.branches:
            raise InputError(
                f"branch {branch!r} is not one of {', '.join(solver.branches)}"
            )
        return solver.branches.index(branch)
    if isinstance(branch, bool) or not isinstance(branch, int | np.integer):
        raise InputError(f"branch must be a label or an index, got {branch!r}")
    if not 0 <= branch < len(solver.branches):
        raise InputError(
            f"branch index {branch} is not in 0..{len(solver.branches) - 1}"
        )
    return int(branch)


class _Scorer:
    """The criterion of one search: scores of (value, branch) pairs of one pose."""

    def __init__(
        self,
        solver: Solver,
        pose: FloatArray,
        criterion: str,
        q_previous: FloatArray | None,
    ) -> None:
        self.solver, self.pose, self.criterion = solver, pose, criterion
        self.q_previous = q_previous
        robot = solver.robot
        self.robot = robot
        self.lower, self.upper = robot.lower - LIMIT_TOL, robot.upper + LIMIT_TOL

    def configurations(self, values: FloatArray, branches: npt.NDArray[np.intp]):
        """(N, 7) configurations [rad] of the pairs, NaN rows where not reached."""
        poses = np.broadcast_to(self.pose, (len(values), 4, 4))
        q, _ = self.solver.solve_batch(poses, redundancy=values)
        return q[np.arange(len(values)), branches]

    def scores(self, q: FloatArray) -> FloatArray:
        """(N,) scores of (N, 7) configurations; −inf unreached or beyond limits."""
        ok = np.isfinite(q).all(axis=1)
        ok &= ((q >= self.lower) & (q <= self.upper)).all(axis=1)
        out = np.full(len(q), -np.inf)
        good = q[ok]
        if not len(good):
            return out
        if self.criterion == "limit_margin":
            out[ok] = np.minimum(good - self.robot.lower, self.robot.upper - good).min(
                axis=1
            )
        elif self.criterion == "manipulability":
            jac = compute_jacobians_local(self.robot, good)
            det = np.linalg.det(jac @ jac.transpose(0, 2, 1))
            out[ok] = np.sqrt(np.maximum(det, 0.0))
        elif self.q_previous is not None:  # "nearest"
            step = np.remainder(good - self.q_previous + np.pi, 2.0 * np.pi) - np.pi
            out[ok] = -np.sqrt(np.einsum("ij,ij->i", step, step))
        return out

    def __call__(
        self, values: FloatArray, branches: npt.NDArray[np.intp]
    ) -> FloatArray:
        return self.scores(self.configurations(values, branches))


def _samples(lo: float, hi: float) -> FloatArray:
    count = max(MIN_SAMPLES, math.ceil((hi - lo) / SAMPLE_STEP) + 1)
    return np.linspace(lo, hi, count)


def _golden(
    score: _Scorer,
    low: FloatArray,
    high: FloatArray,
    branches: npt.NDArray[np.intp],
) -> tuple[FloatArray, FloatArray]:
    """Golden-section maxima of K brackets at once: (values, scores), each (K,)."""
    a, b = low.copy(), high.copy()
    x1, x2 = b - _GOLDEN * (b - a), a + _GOLDEN * (b - a)
    f1, f2 = score(x1, branches), score(x2, branches)
    while (b - a).max() > GOLDEN_TOL:
        left = f1 >= f2  # the maximum is in [a, x2]: drop (x2, b]
        b = np.where(left, x2, b)
        a = np.where(left, a, x1)
        x_new = np.where(left, b - _GOLDEN * (b - a), a + _GOLDEN * (b - a))
        f_new = score(x_new, branches)
        x1, x2 = np.where(left, x_new, x2), np.where(left, x1, x_new)
        f1, f2 = np.where(left, f_new, f2), np.where(left, f1, f_new)
    best = f1 >= f2
    return np.where(best, x1, x2), np.where(best, f1, f2)


def _refuse(solver: Solver, pose: FloatArray, only: int | None) -> None:
    """Raise why no value of the parameter puts a branch on ``pose`` in limits.

    ``UnreachableError`` when no branch reaches the pose at any value: the
    SRS arm's reach does not depend on ψ (the kernel's error says so); a
    Franka arm's wrist point turns with q7, so its values are sampled (every
    :data:`SAMPLE_STEP`) and the error gives the distance nearest the reach.
    Else ``InfeasibleError``: the pose is reached, outside the joint limits.
    """
    if solver.parameter_range is None:  # (feasible refused it already)
        raise InputError(f"robot {solver.robot.name!r} has no redundancy")
    lo, hi = solver.parameter_range
    if solver.family.parameter_periodic:  # SRS: the reach does not depend on ψ
        solver.solve_arrays(pose, np.empty(0), redundancy=0.5 * (lo + hi))  # raises
    else:
        values = _samples(lo, hi)
        _, valid = solver.solve_batch(
            np.repeat(pose[None], len(values), 0), redundancy=values
        )
        if not valid.any():
            gaps = []
            for value in values:
                distance, low, high = solver.diagnose(pose, redundancy=float(value))
                gaps.append((max(low - distance, distance - high), distance, low, high))
            _, distance, low, high = min(gaps)
            raise UnreachableError(
                distance,
                (low, high),
                "reach",
                f"out of reach for every {solver.parameter} in [{lo:.6g}, {hi:.6g}] "
                f"rad (sampled every {math.degrees(SAMPLE_STEP):g}°): the wrist "
                f"point comes within {distance:.6g} m of the shoulder at best, the "
                f"elbow reaches [{low:.6g}, {high:.6g}] m",
            )
    which = "any branch" if only is None else f"branch {solver.branches[only]}"
    raise InfeasibleError(
        f"no {solver.parameter} puts {which} on the pose within the joint limits "
        "(the pose is reached outside them)"
    )


def choose_redundancy(
    robot: Robot,
    target: pin.SE3 | npt.ArrayLike,
    *,
    criterion: str = "limit_margin",
    q_previous: npt.ArrayLike | None = None,
    branch: str | int | None = None,
) -> RedundancyChoice:
    """The value of the redundancy parameter (and branch) best for a pose.

    Args:
        robot: A seven-axis arm of the SRS or Franka family.
        target: Pose of the tool frame in the base frame: ``pin.SE3`` or a
            (4, 4) homogeneous matrix [m].
        criterion: ``"limit_margin"``, ``"manipulability"`` or ``"nearest"``
            (module docs), maximised.
        q_previous: Configuration (7,) [rad], required by ``"nearest"``
            (distances wrapped to [−π, π) per joint).
        branch: Search this branch only (label or index); None: every branch.

    Returns:
        The best value found, its solution and score. Among equal scores the
        first branch, then the lowest value, wins.

    Raises:
        UnsupportedRobotError: If the robot has no closed form.
        UnreachableError: If no branch reaches the pose for any value.
        InfeasibleError: If some do, but none within the joint limits.
        InputError: A six-axis arm (no redundancy), bad criterion, branch,
            or ``"nearest"`` without ``q_previous``; ``DimensionError`` or
            ``NonFiniteError`` for bad arrays.
    """
    solver = get_solver(robot)
    if criterion not in CRITERIA:
        raise InputError(
            f"criterion must be one of {', '.join(CRITERIA)}, got {criterion!r}"
        )
    previous = None if q_previous is None else robot.check_configuration(q_previous)
    if criterion == "nearest" and previous is None:
        raise InputError('criterion "nearest" needs q_previous')
    only = _branch_index(solver, branch)
    pose = np.array(pose_rows(target))
    feasible = solver.feasible(pose)
    pieces = [
        (b, lo, hi)
        for b, intervals in enumerate(feasible.intervals)
        if only is None or b == only
        for lo, hi in intervals
    ]
    if not pieces:
        _refuse(solver, pose, only)
    score = _Scorer(solver, pose, criterion, previous)
    samples = [_samples(lo, hi) for _, lo, hi in pieces]
    values = np.concatenate(samples)
    owner = np.repeat(np.arange(len(pieces)), [len(s) for s in samples])
    branches = np.array([pieces[k][0] for k in owner], dtype=np.intp)
    sampled = score(values, branches)
    # per interval: its best sample, refined between the neighbouring samples
    starts = np.cumsum([0] + [len(s) for s in samples[:-1]])
    low, high, best_index = [], [], []
    for start, s in zip(starts, samples, strict=True):
        i = int(np.argmax(sampled[start : start + len(s)]))
        best_index.append(start + i)
        low.append(s[max(i - 1, 0)])
        high.append(s[min(i + 1, len(s) - 1)])
    interval_branch = np.array([b for b, _, _ in pieces], dtype=np.intp)
    refined, refined_score = _golden(
        score, np.array(low), np.array(high), interval_branch
    )
    # candidates: every refined point and every interval's best sample
    cand_value = np.concatenate([refined, values[best_index]])
    cand_score = np.concatenate([refined_score, sampled[best_index]])
    cand_branch = np.concatenate([interval_branch, interval_branch])
    order = np.lexsort((cand_value, cand_branch, -cand_score))
    top = int(order[0])
    if not math.isfinite(cand_score[top]):
        raise InfeasibleError(
            f"no {solver.parameter} puts a branch on the pose within the joint limits"
        )
    value, index = float(cand_value[top]), int(cand_branch[top])
    solutions = solver.solve(pose, redundancy=value)  # angles within the limits
    chosen = next(s for s in solutions if s.index == index)
    return RedundancyChoice(
        value=value, solution=chosen, criterion=criterion, score=float(cand_score[top])
    )


__all__ = [
    "CRITERIA",
    "GOLDEN_TOL",
    "MIN_SAMPLES",
    "SAMPLE_STEP",
    "RedundancyChoice",
    "choose_redundancy",
]
