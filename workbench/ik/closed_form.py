r"""Closed-form inverse kinematics of PUMA-type arms: all eight branches.

The solution is derived from the robot's own DH table (see
:mod:`workbench.ik._puma` for which tables qualify), not from one printed
table; ``docs/errata-kang-ik.md`` derives it and lists what is wrong in Kang
(2007)'s printed formulas.

Branch labels are physical, so that one posture of the PUMA carries the same
label in both DH models of the workbench (and agrees with the ``l/r``, ``u/d``,
``n/f`` letters of Robotics Toolbox's ``Puma560.ikine_a``):

* ``right`` / ``left``: the shoulder offset :math:`D = d_2 + d_3` lies to the
  right / left of the horizontal direction from the base axis to the wrist
  centre, seen from above (z0 up), like a human right / left arm. In DH terms
  right means :math:`\sigma_1 D x > 0`, x the wrist centre's coordinate along
  x1; with D = 0, right means x > 0.
* ``elbow-up`` / ``elbow-down``: the elbow (origin of frame 2) lies above /
  below the line from the shoulder to the wrist centre, heights along z0.
* ``no-flip`` / ``flip``: the wrist axis z5 has a positive / negative component
  along x4, i.e. :math:`\sigma_5 \sin\theta_5 > 0` (σ5 the sign of α5). The flip
  twin of a solution is :math:`(\theta_4 + \pi, -\theta_5, \theta_6 + \pi)`.

Branch ``i`` of :data:`BRANCHES` (also the second axis of
:func:`analytic_batch`) has bits ``4·left + 2·down + flip``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.ik._closed_form_batch import analytic_batch
from workbench.ik._puma import (
    TAU,
    WRIST_SINGULAR_TOL,
    PumaGeometry,
    UnreachableError,
    UnsupportedRobotError,
    check_reach,
    get_geometry,
    wrap_to_limits,
)
from workbench.ik._targets import pose_rows
from workbench.robot import Robot
from workbench.validation import as_vector

FloatArray = npt.NDArray[np.float64]

#: Branch names; index = 4·left + 2·down + flip.
BRANCHES: tuple[str, ...] = tuple(
    f"{arm}/elbow-{elbow}/{wrist}"
    for arm in ("right", "left")
    for elbow in ("up", "down")
    for wrist in ("no-flip", "flip")
)


@dataclass(frozen=True, slots=True)
class IKSolution:
    """One closed-form branch.

    Attributes:
        q: Configuration, shape (6,) [rad], read-only; each angle is the
            representative (mod 2π) within the joint limits when one is, else
            in (−π, π] — or, when ``q_previous`` was given, the one nearest it.
        branch: Label, e.g. ``"right/elbow-up/no-flip"`` (see module docs).
        index: Position of ``branch`` in :data:`BRANCHES`.
        within_limits: True if every joint of ``q`` is within its limits.
        wrist_singular: True if |sin θ5| <= :data:`WRIST_SINGULAR_TOL`; θ4 and θ6
            are then one member of a one-parameter family.
    """

    q: FloatArray
    branch: str
    index: int
    within_limits: bool
    wrist_singular: bool


# The generated __init__ of a frozen dataclass costs ~1 µs; writing the slots
# through their descriptors costs a third of that and matters for 8 solutions.
_SET_Q, _SET_BRANCH, _SET_INDEX, _SET_WITHIN, _SET_SINGULAR = (
    IKSolution.__dict__[f].__set__ for f in IKSolution.__slots__
)


def _new_solution(
    q: FloatArray, index: int, within_limits: bool, wrist_singular: bool
) -> IKSolution:
    sol = object.__new__(IKSolution)
    _SET_Q(sol, q)
    _SET_BRANCH(sol, BRANCHES[index])
    _SET_INDEX(sol, index)
    _SET_WITHIN(sol, within_limits)
    _SET_SINGULAR(sol, wrist_singular)
    return sol


def analytic(
    robot: Robot,
    target: pin.SE3 | npt.ArrayLike,
    *,
    q_previous: npt.ArrayLike | None = None,
) -> list[IKSolution]:
    """Every closed-form IK branch of a PUMA-type arm.

    Args:
        robot: Robot with a PUMA-type DH table (``puma560``, ``puma560-kang``).
        target: Pose of the tool frame (the wrist centre frame 6) in the base
            frame: ``pin.SE3`` or a (4, 4) homogeneous matrix [m].
        q_previous: Optional configuration (6,) [rad] of the previous path
            sample. Each returned angle is then the representative (mod 2π)
            nearest to it, and at a wrist singularity θ4/θ6 are split so that
            the step from ``q_previous`` is shortest (else θ4 = 0).

    Returns:
        Eight :class:`IKSolution`, in the order of :data:`BRANCHES`. At a
        shoulder or elbow singularity some coincide; at a wrist singularity the
        flip twin is the continuity member turned by π about z4 and z6.

    Raises:
        UnsupportedRobotError: If the robot has no PUMA-type DH table.
        UnreachableError: If the wrist centre is out of reach or inside the
            cylinder of radius |d2 + d3| around the base axis.
        DimensionError: If ``target`` is not (4, 4) or ``q_previous`` not (6,).
        NonFiniteError: If an entry is NaN or infinite.
        InputError: If ``target`` is not rigid (see ``poses.RIGIDITY_TOL``).
    """
    geo = get_geometry(robot)
    rows = pose_rows(target)
    prev = (
        None if q_previous is None else robot.check_configuration(q_previous).tolist()
    )
    values, within, singular = _solve(geo, rows, prev)
    q_all = np.array(values)
    q_all.shape = (8, 6)
    q_all.setflags(write=False)
    return [
        _new_solution(q, i, within[i], singular[i >> 1]) for i, q in enumerate(q_all)
    ]


def nearest(solutions: Sequence[IKSolution], q_previous: npt.ArrayLike) -> IKSolution:
    """The solution nearest to ``q_previous``, angles compared modulo 2π.

    Generalises Kang's rule "if θ4 jumps by ≈ π, take the other solution": the
    distance is the Euclidean norm of the joint differences, each wrapped to
    [−π, π), so the flip twin (θ4 and θ6 off by π) loses near a wrist
    singularity and no joint counts a 2π jump. For representatives near
    ``q_previous`` as well, pass it to :func:`analytic`.

    Args:
        solutions: Candidates, e.g. the result of :func:`analytic`.
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


def _solve(
    geo: PumaGeometry, rows: list[list[float]], prev: list[float] | None
) -> tuple[list[float], list[bool], list[bool]]:
    """Joint values (48, branch-major), within-limits (8) and singular (4) flags.

    Plain float arithmetic: for one pose this is several times faster than numpy.
    The batch version in ``_closed_form_batch`` follows the same steps.
    """
    (nx, ox, ax, px), (ny, oy, ay, py), (nz, oz, az, pz) = rows[:3]
    if geo.sin_alpha6 != 0.0:  # R' = R Rx(-alpha6): its z column is z5
        ca, sa = geo.cos_alpha6, geo.sin_alpha6
        ox, ax = ca * ox - sa * ax, sa * ox + ca * ax
        oy, ay = ca * oy - sa * ay, sa * oy + ca * ay
        oz, az = ca * oz - sa * az, sa * oz + ca * az
    if geo.d6 != 0.0:  # wrist centre
        px, py, pz = px - geo.d6 * ax, py - geo.d6 * ay, pz - geo.d6 * az
    pz -= geo.d1
    check_reach(geo, px, py, pz)
    s1g, s3g, a2, ell = geo.sigma1, geo.sigma3, geo.a2, geo.forearm
    g, sigma5 = geo.sigma4 * geo.sigma5, geo.sigma5
    sd = s1g * geo.offset
    r2 = px * px + py * py
    rho2 = max(r2 - geo.offset * geo.offset, 0.0)
    rho, y1 = math.sqrt(rho2), s1g * pz
    k = (rho2 + pz * pz - a2 * a2 - ell * ell) / (2.0 * a2 * ell)
    k = min(max(k, -1.0), 1.0)
    sgm = math.sqrt(1.0 - k * k)
    cb, sb = geo.cos_beta, geo.sin_beta
    big_a = a2 + ell * k
    right = 1.0 if sd >= 0.0 else -1.0  # sign of x1 on the right arm
    pi, atan2 = math.pi, math.atan2
    # joint value of DH angle t: as is when plain, else _joint(geo, j, t, prev)
    p1, p2, p3, p4, p5, p6 = geo.plain if prev is None else (False,) * 6
    (l1, l2, l3, l4, l5, l6), (u1, u2, u3, u4, u5, u6) = geo.bounds
    values: list[float] = []
    within: list[bool] = []
    singular: list[bool] = []
    for xs in (right, -right):
        x1 = xs * rho
        if r2 > 0.0:
            c1, s1 = (px * x1 - py * sd) / r2, (py * x1 + px * sd) / r2
        else:  # wrist centre on the base axis (D = 0): theta1 is free
            t1 = geo.theta_offset[0] + (prev[0] if prev is not None else 0.0)
            c1, s1 = math.cos(t1), math.sin(t1)
        t1 = atan2(s1, c1)
        q1 = t1 if p1 else _joint(geo, 0, t1, prev)
        ok1 = l1 <= q1 <= u1
        # rows of A = Rx(alpha1)^T Rz(-theta1) R'
        a00, a01, a02 = c1 * nx + s1 * ny, c1 * ox + s1 * oy, c1 * ax + s1 * ay
        a10, a11, a12 = s1g * nz, s1g * oz, s1g * az
        m10 = s3g * s1g * (s1 * nx - c1 * ny)
        m11 = s3g * s1g * (s1 * ox - c1 * oy)
        m12 = s3g * s1g * (s1 * ax - c1 * ay)
        for elbow in (1.0, -1.0):
            sg = geo.up_sign * xs * elbow * sgm
            c3, s3 = k * cb + sg * sb, sg * cb - k * sb
            big_b = ell * sg
            c2, s2 = x1 * big_a + y1 * big_b, y1 * big_a - x1 * big_b
            t2, t3 = atan2(s2, c2), atan2(s3, c3)
            norm = math.sqrt(c2 * c2 + s2 * s2)
            if norm > 0.0:
                c2, s2 = c2 / norm, s2 / norm
            else:  # wrist centre on the shoulder axis: theta2 is free
                c2, s2 = 1.0, 0.0
            c23, s23 = c2 * c3 - s2 * s3, s2 * c3 + c2 * s3
            # M = R36 Rx(alpha6)^T = Rx(alpha3)^T Rz(-theta23) A
            m02 = c23 * a02 + s23 * a12
            m22 = s3g * (s23 * a02 - c23 * a12)
            m00, m01 = c23 * a00 + s23 * a10, c23 * a01 + s23 * a11
            h = math.sqrt(m02 * m02 + m12 * m12)
            if h > WRIST_SINGULAR_TOL:  # (c4, s4) = (m02, m12) / h, scale-free
                t4 = atan2(m12, m02)
                t6 = atan2(g * (m12 * m00 - m02 * m10), g * (m12 * m01 - m02 * m11))
                t5 = atan2(sigma5 * h, -g * m22)
                singular.append(False)
            else:
                t4, t5, t6 = _singular_wrist(
                    geo, m00, m01, m02, m10, m11, m12, m22, prev
                )
                singular.append(True)
            t4f = t4 - pi if t4 > 0.0 else t4 + pi
            t6f = t6 - pi if t6 > 0.0 else t6 + pi
            q2 = t2 if p2 else _joint(geo, 1, t2, prev)
            q3 = t3 if p3 else _joint(geo, 2, t3, prev)
            q4, q4f = (
                (t4, t4f)
                if p4
                else (_joint(geo, 3, t4, prev), _joint(geo, 3, t4f, prev))
            )
            q5, q5f = (
                (t5, -t5)
                if p5
                else (_joint(geo, 4, t5, prev), _joint(geo, 4, -t5, prev))
            )
            q6, q6f = (
                (t6, t6f)
                if p6
                else (_joint(geo, 5, t6, prev), _joint(geo, 5, t6f, prev))
            )
            values += (q1, q2, q3, q4, q5, q6, q1, q2, q3, q4f, q5f, q6f)
            ok = ok1 and l2 <= q2 <= u2 and l3 <= q3 <= u3
            within.append(ok and l4 <= q4 <= u4 and l5 <= q5 <= u5 and l6 <= q6 <= u6)
            within.append(
                ok and l4 <= q4f <= u4 and l5 <= q5f <= u5 and l6 <= q6f <= u6
            )
    return values, within, singular


def _joint(geo: PumaGeometry, j: int, theta: float, prev: list[float] | None) -> float:
    """Joint value of DH angle ``theta``: near ``prev`` if given, else wrapped."""
    if prev is not None:
        p = prev[j]
        return p + math.remainder(theta - geo.theta_offset[j] - p, TAU)
    return wrap_to_limits(theta - geo.theta_offset[j], geo.lower[j], geo.upper[j])


def _singular_wrist(
    geo: PumaGeometry,
    m00: float,
    m01: float,
    m02: float,
    m10: float,
    m11: float,
    m12: float,
    m22: float,
    prev: list[float] | None,
) -> tuple[float, float, float]:
    """DH θ4, θ5, θ6 at a wrist singularity, from M = R36 Rx(α6)^T.

    θ4 = 0 (joint value), or with ``prev`` the split of the fixed θ4 ± θ6 that
    moves θ4 and θ6 by the same amount from ``prev``.
    """
    t4 = geo.theta_offset[3] + (prev[3] if prev is not None else 0.0)
    c4, s4 = math.cos(t4), math.sin(t4)
    g = geo.sigma4 * geo.sigma5
    t6 = math.atan2(g * (s4 * m00 - c4 * m10), g * (s4 * m01 - c4 * m11))
    if prev is not None:
        # z5 along +z3 (m22 > 0): theta4 + theta6 fixed, else theta4 - theta6
        kappa = -1.0 if m22 > 0.0 else 1.0
        e = math.remainder(t6 - geo.theta_offset[5] - prev[5], TAU)
        t4 -= kappa * e / 2.0
        c4, s4 = math.cos(t4), math.sin(t4)
        t6 = math.atan2(g * (s4 * m00 - c4 * m10), g * (s4 * m01 - c4 * m11))
    t5 = math.atan2(geo.sigma5 * (c4 * m02 + s4 * m12), -g * m22)
    return t4, t5, t6


__all__ = [
    "BRANCHES",
    "WRIST_SINGULAR_TOL",
    "IKSolution",
    "UnreachableError",
    "UnsupportedRobotError",
    "analytic",
    "analytic_batch",
    "nearest",
]
