r"""One IK solution for a pose, and one pair for a pick and a place: the selection rule.

Every caller that needs one configuration of a tool pose (``workbench ik``,
``workbench plan pick-place``, ``trajectory.pick_and_place_from_poses``, the
online planner's first command, the fish-cutting program) asks
:func:`select` (one pose) or :func:`~workbench.ik.pick_place_configurations` (two poses
chosen together), so the command line and Python give the same
configuration, to the bit, for the same request.

Candidates are the closed-form branches (``ik.analytic``) of an arm of a
known family; every rule chooses among those **within the joint limits**
(none: :class:`~workbench.errors.InfeasibleError`). The rules
(:data:`RULES`):

* ``"limit_margin"`` (:data:`DEFAULT_RULE`): the largest limit margin
  :math:`\min_k \min(q_k - l_k,\ u_k - q_k)` [rad];
* ``"nearest"``: the smallest distance to ``q_near`` [rad], each joint's
  difference wrapped to [−π, π) (``ik.nearest``);
* ``"branch"``: the named ``branch``;
* ``"first_within_limits"``: the first branch in the order of the labels.

Without ``rule`` the rule is ``"branch"`` when ``branch`` is given, else
``"nearest"`` when ``q_near`` is given, else ``"limit_margin"``. Ties go to
the first branch in label order. When ``q_near`` is given, each angle of a
six-axis solution is the representative (mod 2π) nearest it.

A seven-axis arm (SRS: arm angle ψ, Franka: q7) is solved at ``redundancy``
when given (every branch at that value, then the rule), else the value and
the branch come from ``ik.choose_redundancy`` with ``criterion``
(``"limit_margin"``, ``"manipulability"`` or ``"nearest"``; default
``"nearest"`` for the rule ``"nearest"``, else ``"limit_margin"``), over every
branch (``"limit_margin"``, ``"nearest"``), the named one (``"branch"``) or
the first that reaches the pose within the limits at some value
(``"first_within_limits"``).

An arm of no family is solved numerically (``ik.numeric``, started from
``q_near``, else from its deterministic default guess; seed 0), branch
``"numeric"``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InfeasibleError, InputError
from workbench.ik._puma import LIMIT_TOL, TAU
from workbench.ik.closed_form import analytic
from workbench.ik.families import Family, get_family
from workbench.ik.numerical import TARGET_PARTS, numeric
from workbench.ik.redundancy import CRITERIA, choose_redundancy
from workbench.ik.solution import IKSolution
from workbench.ik.solver import get_solver
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]

#: The rules of :func:`select`.
RULES = ("limit_margin", "nearest", "branch", "first_within_limits")
#: The rule when neither ``branch`` nor ``q_near`` is given.
DEFAULT_RULE = "limit_margin"
#: Branch label of a solution of the numerical IK.
NUMERIC_BRANCH = "numeric"


@dataclass(frozen=True, slots=True)
class IKChoice:
    """The configuration chosen for one pose, and how.

    Attributes:
        q: Configuration, shape (nq,) [rad], read-only.
        branch: Closed-form branch label, or ``"numeric"``.
        index: Position of ``branch`` in ``ik.get_branches(robot)``; None
            for the numerical IK.
        within_limits: True if every joint of ``q`` is within its limits.
        redundancy: Seven-axis arms: the value of the redundancy parameter
            [rad] (ψ or q7); None otherwise.
        rule: The rule applied (one of :data:`RULES`), or ``"numeric"``.
        criterion: Seven-axis arms whose value was chosen: the criterion of
            ``ik.choose_redundancy``; None otherwise.
        score: What the choice maximised: the limit margin [rad]
            (``"limit_margin"``), minus the distance to ``q_near`` [rad]
            (``"nearest"``) or, for a chosen seven-axis value, the
            criterion's score; None when nothing was maximised (``"branch"``,
            ``"first_within_limits"`` at a given value, ``"numeric"``).
        solution: The closed-form solution object (with its singularity
            flags: ``wrist_singular``, ...); None for the numerical IK.
    """

    q: FloatArray
    branch: str
    index: int | None
    within_limits: bool
    redundancy: float | None
    rule: str
    criterion: str | None
    score: float | None
    solution: IKSolution | None


@dataclass(frozen=True, slots=True)
class _Request:
    """A checked request: the rule and its arguments."""

    rule: str
    q_near: FloatArray | None
    branch: str | None
    redundancy: float | None
    criterion: str | None
    seven_axis: bool


def compute_limit_margin(q: FloatArray, lower: FloatArray, upper: FloatArray) -> float:
    """Smallest distance [rad] of a joint to one of its limits (< 0 outside).

    Args:
        q: Configuration (n,) [rad].
        lower: Lower joint limits (n,) [rad].
        upper: Upper joint limits (n,) [rad].
    """
    # on lists: a fifth of the time of NumPy's reductions on seven values
    return min(
        min(v - lo, hi - v)
        for v, lo, hi in zip(q.tolist(), lower.tolist(), upper.tolist(), strict=True)
    )


def _distance(q: FloatArray, reference: FloatArray) -> float:
    """Euclidean norm [rad] of the joint differences, each wrapped to [−π, π)."""
    step = np.remainder(q - reference + math.pi, TAU) - math.pi
    return float(math.sqrt(float(step @ step)))


def _request(
    robot: Robot,
    family: Family | None,
    rule: str | None,
    q_near: npt.ArrayLike | None,
    branch: str | None,
    redundancy: float | None,
    criterion: str | None,
) -> _Request:
    """The arguments checked, the rule resolved (module docs).

    Raises:
        InputError: On an unknown rule, branch or criterion, a rule without
            its argument, or an argument the arm or the rule does not take.
    """
    if rule is None:
        rule = (
            "branch"
            if branch is not None
            else "nearest"
            if q_near is not None
            else DEFAULT_RULE
        )
    if rule not in RULES:
        raise InputError(f"rule must be one of {', '.join(RULES)}, got {rule!r}")
    near = None if q_near is None else robot.check_configuration(q_near).copy()
    if rule == "nearest" and near is None:
        raise InputError('rule "nearest" needs q_near (a configuration)')
    labels = None if family is None else family.branches
    if rule == "branch":
        if branch is None:
            raise InputError('rule "branch" needs branch (a label)')
        if labels is None:
            raise InputError(
                f"branch {branch!r} given, but robot {robot.name} has no "
                "closed-form IK (its solution is numerical)"
            )
        if branch not in labels:
            raise InputError(f"unknown branch {branch!r}; valid: {', '.join(labels)}")
    elif branch is not None:
        raise InputError(f'branch {branch!r} given with rule "{rule}": it is the rule')
    seven_axis = family is not None and family.redundant
    for name, value in (("redundancy", redundancy), ("criterion", criterion)):
        if value is not None and not seven_axis:
            raise InputError(
                f"{name} is for seven-axis arms of the SRS or Franka family, not "
                f"{robot.name}"
            )
    value = None
    if redundancy is not None:
        if criterion is not None:
            raise InputError("criterion chooses a value: not with redundancy")
        try:
            value = float(redundancy)
        except (TypeError, ValueError):
            raise InputError(
                f"redundancy must be a number [rad], got {redundancy!r}"
            ) from None
    if criterion is not None and criterion not in CRITERIA:
        raise InputError(
            f"criterion must be one of {', '.join(CRITERIA)}, got {criterion!r}"
        )
    if seven_axis and value is None and criterion is None:
        criterion = "nearest" if rule == "nearest" else "limit_margin"
    if criterion == "nearest" and near is None:
        raise InputError('criterion "nearest" needs q_near (a configuration)')
    return _Request(rule, near, branch, value, criterion, seven_axis)


def _choice(
    request: _Request,
    solution: IKSolution,
    score: float | None,
    redundancy: float | None,
    criterion: str | None = None,
) -> IKChoice:
    q = np.array(solution.q, dtype=np.float64)
    q.setflags(write=False)
    return IKChoice(
        q=q,
        branch=solution.branch,
        index=int(solution.index),
        within_limits=bool(solution.within_limits),
        redundancy=redundancy,
        rule=request.rule,
        criterion=criterion,
        score=score,
        solution=solution,
    )


def _best(
    robot: Robot, request: _Request, solutions: Sequence[IKSolution], what: str
) -> tuple[IKSolution, float | None]:
    """The solution within the limits the rule prefers, and its score.

    Raises:
        InfeasibleError: If none is within the limits (on the named branch).
    """
    within = [s for s in solutions if s.within_limits]
    if request.rule == "branch":
        within = [s for s in within if s.branch == request.branch]
    if not within:
        on = ""
        if request.branch is not None:
            reached = any(s.branch == request.branch for s in solutions)
            on = f" on branch {request.branch}" + (
                "" if reached else " (which does not reach it)"
            )
        message = (
            f"the {what} has no IK solution within the joint limits{on}: none of "
            f"the {len(solutions)} closed-form branches reaching it is within them"
        )
        raise InfeasibleError(message)
    if request.rule == "nearest" and request.q_near is not None:
        distances = [_distance(s.q, request.q_near) for s in within]
        top = int(np.argmin(distances))  # the first on a tie, as ik.nearest
        return within[top], -distances[top]
    if request.rule == "limit_margin":
        margins = [compute_limit_margin(s.q, robot.lower, robot.upper) for s in within]
        top = int(np.argmax(margins))  # the first on a tie
        return within[top], margins[top]
    return within[0], None


def _numeric(
    robot: Robot,
    target: pin.SE3 | npt.ArrayLike,
    near: FloatArray | None,
    part: str = "pose",
):
    result = numeric(robot, target, q0=near, part=part)
    if not result.success:
        what = "pose" if part == "pose" else f"target ({part})"
        raise InfeasibleError(
            f"numerical IK found no solution for {robot.name}: the {what} is "
            f"probably out of reach (best residual {result.position_error:.3g} m, "
            f"{result.rotation_error:.3g} rad after {result.iterations} iterations, "
            f"{result.restarts} restarts)"
        )
    q = np.array(result.q)
    q.setflags(write=False)
    within = bool(
        np.all(q >= robot.lower - LIMIT_TOL) and np.all(q <= robot.upper + LIMIT_TOL)
    )
    return IKChoice(q, NUMERIC_BRANCH, None, within, None, "numeric", None, None, None)


def _chosen_value(
    robot: Robot,
    request: _Request,
    target: pin.SE3 | npt.ArrayLike,
    branch: str | None,
    q_previous: FloatArray | None,
) -> IKChoice:
    """A seven-axis arm's value and branch by ``ik.choose_redundancy``."""
    criterion = request.criterion or "limit_margin"
    choice = choose_redundancy(
        robot,
        target,
        criterion=criterion,
        q_previous=q_previous if criterion == "nearest" else None,
        branch=branch,
    )
    return _choice(request, choice.solution, choice.score, choice.value, criterion)


def _feasible_branches(
    robot: Robot, targets: Sequence[pin.SE3 | npt.ArrayLike]
) -> list[str]:
    """The labels reaching every target within the limits at some value (7R)."""
    solver = get_solver(robot)
    feasible = [solver.feasible(target) for target in targets]
    labels = feasible[0].branches
    return [
        label for i, label in enumerate(labels) if all(f.intervals[i] for f in feasible)
    ]


def select(
    robot: Robot,
    target: pin.SE3 | npt.ArrayLike,
    *,
    rule: str | None = None,
    q_near: npt.ArrayLike | None = None,
    branch: str | None = None,
    redundancy: float | None = None,
    criterion: str | None = None,
    part: str = "pose",
) -> IKChoice:
    """The one configuration of ``robot`` that puts its tool frame at ``target``.

    Args:
        robot: Any serial arm; closed form for the OPW, UR, SRS and Franka
            families, else numerical.
        target: Pose of the tool frame in the base frame: ``pin.SE3`` or a
            (4, 4) homogeneous matrix [m].
        rule: One of :data:`RULES` (module docs); None: ``"branch"`` with
            ``branch``, else ``"nearest"`` with ``q_near``, else
            :data:`DEFAULT_RULE`.
        q_near: Configuration (nq,) [rad]: the reference of ``"nearest"``,
            the representatives of the angles (six axes), the start of the
            numerical IK.
        branch: A label of ``ik.get_branches(robot)``, for the rule
            ``"branch"``.
        redundancy: Seven-axis arms: the value of the redundancy parameter
            [rad] (ψ or q7) to solve at; None chooses it (``criterion``).
        criterion: Seven-axis arms without ``redundancy``: the criterion of
            ``ik.choose_redundancy`` (module docs for the default).
        part: What of the target is reached, a name of ``ik.TARGET_PARTS``:
            anything but ``"pose"`` (the position only, the position and a
            tool axis) is solved numerically from ``q_near`` (the closed forms
            take whole poses), with the rule ``"numeric"``.

    Returns:
        An :class:`IKChoice`: ``q`` within the limits for the closed form
        (``within_limits`` True), the solution object in ``solution``.

    Raises:
        InputError: Bad target or ``q_near`` (``DimensionError``,
            ``NonFiniteError``), unknown rule, branch or criterion, a rule
            without its argument, ``redundancy``/``criterion`` for an arm
            without the parameter, ``branch`` for an arm of no family.
        UnreachableError: If the closed form does not reach the pose.
        InfeasibleError: If no branch (or not ``branch``) is within the
            limits, or the numerical IK does not converge.
    """
    if part != "pose":
        if part not in TARGET_PARTS:
            raise InputError(
                f"part {part!r}: expected one of {', '.join(TARGET_PARTS)}"
            )
        if rule is not None or branch is not None or redundancy is not None:
            raise InputError(
                f"a partial target ({part}) is solved numerically: no rule, branch "
                "or redundancy applies"
            )
        near = None if q_near is None else robot.check_configuration(q_near)
        return _numeric(robot, target, near, part)
    family = get_family(robot)
    request = _request(robot, family, rule, q_near, branch, redundancy, criterion)
    if family is None:
        return _numeric(robot, target, request.q_near)
    if request.seven_axis and request.redundancy is None:
        only = request.branch
        if request.rule == "first_within_limits":
            common = _feasible_branches(robot, [target])
            if not common:  # the reason (out of reach, or out of the limits)
                return _chosen_value(robot, request, target, None, request.q_near)
            only = common[0]
        return _chosen_value(robot, request, target, only, request.q_near)
    solutions = analytic(
        robot, target, q_previous=request.q_near, redundancy=request.redundancy
    )
    chosen, score = _best(robot, request, solutions, "pose")
    return _choice(request, chosen, score, request.redundancy)


__all__ = [
    "DEFAULT_RULE",
    "NUMERIC_BRANCH",
    "RULES",
    "IKChoice",
    "compute_limit_margin",
    "select",
]
