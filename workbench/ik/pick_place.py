r"""The pick and the place configurations of a motion, chosen together.

The pair rule of :mod:`workbench.ik.selection` (its candidates, rules,
criteria and ties) for two poses: both on one branch where one serves both,
the pair that scores best (:func:`pick_place_configurations`).
"""

from __future__ import annotations

import math

import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InfeasibleError
from workbench.ik.closed_form import analytic
from workbench.ik.families import get_family
from workbench.ik.selection import (
    IKChoice,
    _best,
    _choice,
    _chosen_value,
    _distance,
    _feasible_branches,
    _numeric,
    _Request,
    _request,
    compute_limit_margin,
    select,
)
from workbench.model.robot import Robot


def pick_place_configurations(
    robot: Robot,
    pick: pin.SE3 | npt.ArrayLike,
    place: pin.SE3 | npt.ArrayLike,
    *,
    rule: str | None = None,
    q_near: npt.ArrayLike | None = None,
    branch: str | None = None,
    redundancy: float | None = None,
    criterion: str | None = None,
) -> tuple[IKChoice, IKChoice]:
    r"""The pick and the place configurations, chosen together.

    Where a branch reaches both poses within the limits, both are on one
    branch: of those branches, the one whose pair scores best, ties to the
    first label. The pair's score is, per rule: ``"limit_margin"`` the
    smaller of the two limit margins; ``"nearest"`` minus the joint motion
    :math:`d(q_{near}, q_{pick}) + d(q_{pick}, q_{place})` (distances as
    :func:`select`'s); ``"first_within_limits"`` the first such branch;
    ``"branch"`` the named one. A seven-axis arm without ``redundancy``
    chooses each pose's value on each such branch by ``criterion`` (for
    ``"nearest"``, the place's nearest the pick), the pair's score the
    smaller of the two scores (``"nearest"``: their sum). The place's angles
    are the representatives nearest the pick's (six axes), so the motion
    between them is the shortest.

    Where no branch serves both (and the rule is not ``"branch"``), the pick
    is :func:`select`'s and the place the solution nearest the pick
    (``select(place, q_near=pick.q)``, seven axes at the pick's
    ``redundancy`` when it was given, else at the value nearest the pick).

    Args:
        robot: As :func:`select`.
        pick: Pick pose of the tool frame in the base frame: ``pin.SE3`` or
            (4, 4) [m].
        place: Place pose, same forms.
        rule: As :func:`select` (the pick's ``q_near``, ``branch``).
        q_near: Configuration (nq,) [rad] the motion starts from: the
            reference of ``"nearest"`` for the pick.
        branch: The branch of both, for the rule ``"branch"``.
        redundancy: Seven-axis arms: both poses at this value [rad].
        criterion: Seven-axis arms without ``redundancy``: as :func:`select`.

    Returns:
        ``(pick, place)``, two :class:`IKChoice`, both within the limits; each
        ``score`` is its own pose's (for ``"nearest"``, the place's is minus
        its distance to the pick).

    Raises:
        InputError, UnreachableError: As :func:`select`, for either pose.
        InfeasibleError: If a pose has no solution within the limits, or
            with the rule ``"branch"`` the branch does not serve both.
    """
    family = get_family(robot)
    request = _request(robot, family, rule, q_near, branch, redundancy, criterion)
    if family is None:
        first = _numeric(robot, pick, request.q_near)
        return first, _numeric(robot, place, first.q)
    if request.seven_axis and request.redundancy is None:
        pair = _pair_chosen_values(robot, request, pick, place)
    else:
        pair = _pair_at_value(robot, request, pick, place)
    if pair is not None:
        return pair
    if request.rule == "branch":
        raise InfeasibleError(
            f"the place pose has no IK solution within the joint limits on the "
            f"pick's branch {request.branch}"
        )
    first = select(
        robot,
        pick,
        rule=request.rule,
        q_near=request.q_near,
        redundancy=request.redundancy,
        criterion=request.criterion,
    )
    chosen_value = request.seven_axis and request.redundancy is None
    second = select(
        robot,
        place,
        rule="nearest",
        q_near=first.q,
        redundancy=request.redundancy,
        criterion="nearest" if chosen_value else None,
    )
    return first, second


def _pair_at_value(
    robot: Robot, request: _Request, pick: pin.SE3 | npt.ArrayLike, place
) -> tuple[IKChoice, IKChoice] | None:
    """The best pair on one branch, six axes or seven at a given value; None: none."""
    value = request.redundancy
    picks = analytic(robot, pick, q_previous=request.q_near, redundancy=value)
    within = [s for s in picks if s.within_limits]
    if request.rule == "branch":
        within = [s for s in within if s.branch == request.branch]
    if not within:
        _best(robot, request, picks, "pick pose")  # raises why
    best: tuple[float, IKChoice, IKChoice] | None = None
    for first in within:
        places = analytic(robot, place, q_previous=first.q, redundancy=value)
        second = next(
            (s for s in places if s.index == first.index and s.within_limits), None
        )
        if second is None:
            continue
        if request.rule == "limit_margin":
            a, b = (
                compute_limit_margin(s.q, robot.lower, robot.upper)
                for s in (first, second)
            )
            pair_score = min(a, b)
        elif request.rule == "nearest" and request.q_near is not None:
            a = -_distance(first.q, request.q_near)
            b = -_distance(second.q, first.q)
            pair_score = a + b
        else:  # the first (or the named) branch serving both
            return (
                _choice(request, first, None, value),
                _choice(request, second, None, value),
            )
        if best is None or pair_score > best[0]:
            best = (
                pair_score,
                _choice(request, first, a, value),
                _choice(request, second, b, value),
            )
    return None if best is None else (best[1], best[2])


def _pair_chosen_values(
    robot: Robot, request: _Request, pick: pin.SE3 | npt.ArrayLike, place
) -> tuple[IKChoice, IKChoice] | None:
    """The best pair on one branch of a seven-axis arm, values chosen; None: none."""
    if request.rule == "branch" and request.branch is not None:
        common = [request.branch]
        feasible = _feasible_branches(robot, [pick, place])
        if request.branch not in feasible:
            _chosen_value(robot, request, pick, request.branch, request.q_near)
            return None  # the pick is reached on the branch, the place is not
    else:
        common = _feasible_branches(robot, [pick, place])
        if not common:
            return None
        if request.rule == "first_within_limits":
            common = common[:1]
    best: tuple[float, IKChoice, IKChoice] | None = None
    for label in common:
        first = _chosen_value(robot, request, pick, label, request.q_near)
        second = _chosen_value(robot, request, place, label, first.q)
        a, b = (-math.inf if c.score is None else c.score for c in (first, second))
        pair_score = a + b if request.criterion == "nearest" else min(a, b)
        if best is None or pair_score > best[0]:
            best = (pair_score, first, second)
    return None if best is None else (best[1], best[2])


__all__ = ["pick_place_configurations"]
