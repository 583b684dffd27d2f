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
from dataclasses import FrozenInstanceError
from itertools import repeat

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


class IKSolution:
    """One closed-form branch (immutable).

    Attributes:
        q: Configuration, shape (6,) [rad], read-only; each angle is the
            representative (mod 2π) within the joint limits when one is, else
            in (−π, π] — or, when ``q_previous`` was given, the one nearest it.
        branch: Label, e.g. ``"right/elbow-up/no-flip"`` (see module docs).
        index: Position of ``branch`` in :data:`BRANCHES`.
        within_limits: True if every joint of ``q`` is within its limits.
        wrist_singular: True if |sin θ5| <= :data:`WRIST_SINGULAR_TOL`; θ4 and θ6
            are then one member of a one-parameter family.

    The eight solutions of one :func:`analytic` call share its results: the
    joint values stay plain floats until a ``q`` is first read, then one
    read-only (8, 6) array is made and each ``q`` is a row of it. That keeps a
    call to a few microseconds when not every branch is looked at (building
    eight dataclasses with eight arrays cost more than the IK itself).
    Equality is identity; the fields are read-only properties (assigning one
    raises ``dataclasses.FrozenInstanceError``).
    """

    __slots__ = ("_index", "_shared")

    def __init__(self, shared: list, index: int) -> None:
        # private: built by analytic() with the results shared by the eight
        self._shared = shared
        self._index = index

    @property
    def q(self) -> FloatArray:
        """Configuration (6,) [rad], read-only."""
        shared = self._shared
        rows = shared[3]
        if rows is None:
            rows = shared[3] = _read_only_rows(shared[0])
        return rows[self._index]

    @property
    def branch(self) -> str:
        """Label, e.g. ``"right/elbow-up/no-flip"``."""
        return BRANCHES[self._index]

    @property
    def index(self) -> int:
        """Position of ``branch`` in :data:`BRANCHES`."""
        return self._index

    @property
    def within_limits(self) -> bool:
        """True if every joint of ``q`` is within its limits."""
        return self._shared[1][self._index]

    @property
    def wrist_singular(self) -> bool:
        """True if |sin θ5| <= :data:`WRIST_SINGULAR_TOL`."""
        return self._shared[2][self._index >> 1]

    def __repr__(self) -> str:
        return (
            f"IKSolution(q={self.q!r}, branch={self.branch!r}, index={self.index}, "
            f"within_limits={self.within_limits}, "
            f"wrist_singular={self.wrist_singular})"
        )

    def __reduce__(self) -> tuple[object, tuple[object, ...]]:
        return (
            _restore_solution,
            (self.q.tolist(), self.index, self.within_limits, self.wrist_singular),
        )


def _frozen_field(name: str) -> property:
    """``IKSolution.<name>`` with a setter and deleter that raise, as frozen."""
    getter = IKSolution.__dict__[name].fget

    def refuse(self: IKSolution, *value: object) -> None:
        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    return property(getter, refuse, refuse, getter.__doc__)


for _name in ("q", "branch", "index", "within_limits", "wrist_singular"):
    setattr(IKSolution, _name, _frozen_field(_name))
del _name

_INDICES = tuple(range(len(BRANCHES)))


def _read_only_rows(values: list[float]) -> list[FloatArray]:
    q_all = np.array(values)
    q_all.shape = (len(values) // 6, 6)
    q_all.setflags(write=False)
    return list(q_all)


def _solutions(
    values: list[float], within: list[bool], singular: list[bool]
) -> list[IKSolution]:
    """The eight :class:`IKSolution` of one result of :func:`_solve`."""
    return list(map(IKSolution, repeat([values, within, singular, None], 8), _INDICES))


def _restore_solution(
    q: list[float], index: int, within_limits: bool, wrist_singular: bool
) -> IKSolution:
    """Unpickle one :class:`IKSolution` (it alone, not its siblings)."""
    within, singular = [False] * 8, [False] * 4
    within[index], singular[index >> 1] = within_limits, wrist_singular
    rows: list[FloatArray | None] = [None] * 8
    rows[index] = _read_only_rows(q)[0]
    return IKSolution([None, within, singular, rows], index)


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
    prev = None if q_previous is None else _previous(robot, q_previous)
    return _solutions(*_solve(geo, rows, prev))


def _previous(robot: Robot, q_previous: npt.ArrayLike) -> list[float]:
    """``q_previous`` checked (``Robot.check_configuration``), as floats."""
    if (
        type(q_previous) is np.ndarray
        and q_previous.shape == (robot.nq,)
        and q_previous.dtype.char == "d"
    ):
        prev = q_previous.tolist()
        total = sum(prev)
        if total - total == 0.0:  # finite (inf - inf and NaN are NaN)
            return prev
    return robot.check_configuration(q_previous).tolist()


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
    The batch version in ``_closed_form_batch`` follows the same steps. What the
    branches share is computed once: the elbow angle θ3 takes two values (right
    arm elbow-up = left arm elbow-down), θ1 and the rows of A one per arm.
    :func:`_solve_twins` does the same for one (arm, elbow), bit for bit.
    """
    (nx, ox, ax, px), (ny, oy, ay, py), (nz, oz, az, pz), _ = rows
    if geo.sin_alpha6 != 0.0:  # R' = R Rx(-alpha6): its z column is z5
        ca, sa = geo.cos_alpha6, geo.sin_alpha6
        ox, ax = ca * ox - sa * ax, sa * ox + ca * ax
        oy, ay = ca * oy - sa * ay, sa * oy + ca * ay
        oz, az = ca * oz - sa * az, sa * oz + ca * az
    if geo.d6 != 0.0:  # wrist centre
        px, py, pz = px - geo.d6 * ax, py - geo.d6 * ay, pz - geo.d6 * az
    pz -= geo.d1
    r2 = px * px + py * py
    low, high, cylinder = geo.reach_test
    distance = math.sqrt(r2 + pz * pz)
    if not (low <= distance and distance <= high and r2 >= cylinder):
        check_reach(geo, px, py, pz)  # raises UnreachableError
    s1g, s3g, a2, ell = geo.sigma1, geo.sigma3, geo.a2, geo.forearm
    g, sigma5 = geo.sigma4 * geo.sigma5, geo.sigma5
    mg = -g
    sd = s1g * geo.offset
    rho2 = r2 - geo.offset * geo.offset
    if rho2 < 0.0:
        rho2 = 0.0
    rho, y1 = math.sqrt(rho2), s1g * pz
    k = (rho2 + pz * pz - a2 * a2 - ell * ell) / (2.0 * a2 * ell)
    if k > 1.0:
        k = 1.0
    elif k < -1.0:
        k = -1.0
    sgm = math.sqrt(1.0 - k * k)
    cb, sb = geo.cos_beta, geo.sin_beta
    big_a = a2 + ell * k
    right = 1.0 if sd >= 0.0 else -1.0  # sign of x1 on the right arm
    pi, atan2, sqrt, rem = math.pi, math.atan2, math.sqrt, math.remainder
    (l1, l2, l3, l4, l5, l6), (u1, u2, u3, u4, u5, u6) = geo.bounds
    # a DH angle t of joint j in [k_j, K_j] is its own joint value (no wrapping)
    (k1, kk1), (k2, kk2), (k3, kk3), (k4, kk4), (k5, kk5), (k6, kk6) = geo.keep
    wrist_plain = geo.wrist_plain
    if prev is not None:  # joint value near prev: n + remainder(t - offset - n)
        n1, n2, n3, n4, n5, n6 = prev
        o1, o2, o3, o4, o5, o6 = geo.theta_offset
    # elbow: sin(gamma) = +sg on the right arm elbow-up and left arm elbow-down
    kcb, ksb, y1a = k * cb, k * sb, y1 * big_a
    sg_up = geo.up_sign * right * sgm  # sin(gamma) of the right arm elbow-up
    elbows = []
    for sg in (sg_up, -sg_up):
        c3, s3 = kcb + sg * sb, sg * cb - ksb
        t3 = atan2(s3, c3)
        if prev is not None:
            q3 = n3 + rem(t3 - o3 - n3, TAU)
        elif k3 <= t3 and t3 <= kk3:
            q3 = t3
        else:
            q3 = _wrap(geo, 2, t3)
        big_b = ell * sg
        ok3 = True if l3 <= q3 and q3 <= u3 else False
        elbows.append((c3, s3, q3, ok3, big_b, y1 * big_b))
    up, down = elbows
    a10, a11, a12 = s1g * nz, s1g * oz, s1g * az
    s13 = s3g * s1g
    pysd, pxsd = py * sd, px * sd
    values: list[float] = []
    within: list[bool] = []
    singular: list[bool] = []
    for x1, arm in ((right * rho, (up, down)), (-right * rho, (down, up))):
        if r2 > 0.0:
            c1, s1 = (px * x1 - pysd) / r2, (py * x1 + pxsd) / r2
        else:  # wrist centre on the base axis (D = 0): theta1 is free
            t1 = geo.theta_offset[0] + (prev[0] if prev is not None else 0.0)
            c1, s1 = math.cos(t1), math.sin(t1)
        t1 = atan2(s1, c1)
        if prev is not None:
            q1 = n1 + rem(t1 - o1 - n1, TAU)
        elif k1 <= t1 and t1 <= kk1:
            q1 = t1
        else:
            q1 = _wrap(geo, 0, t1)
        ok1 = True if l1 <= q1 and q1 <= u1 else False
        # rows of A = Rx(alpha1)^T Rz(-theta1) R'
        a00, a01, a02 = c1 * nx + s1 * ny, c1 * ox + s1 * oy, c1 * ax + s1 * ay
        m10 = s13 * (s1 * nx - c1 * ny)
        m11 = s13 * (s1 * ox - c1 * oy)
        m12 = s13 * (s1 * ax - c1 * ay)
        xa = x1 * big_a
        for c3, s3, q3, ok3, big_b, yb in arm:
            c2, s2 = xa + yb, y1a - x1 * big_b
            t2 = atan2(s2, c2)
            norm = sqrt(c2 * c2 + s2 * s2)
            if norm > 0.0:
                c2, s2 = c2 / norm, s2 / norm
            else:  # wrist centre on the shoulder axis: theta2 is free
                c2, s2 = 1.0, 0.0
            c23, s23 = c2 * c3 - s2 * s3, s2 * c3 + c2 * s3
            # M = R36 Rx(alpha6)^T = Rx(alpha3)^T Rz(-theta23) A
            m02 = c23 * a02 + s23 * a12
            m22 = s3g * (s23 * a02 - c23 * a12)
            m00, m01 = c23 * a00 + s23 * a10, c23 * a01 + s23 * a11
            h = sqrt(m02 * m02 + m12 * m12)
            if h > WRIST_SINGULAR_TOL:  # (c4, s4) = (m02, m12) / h, scale-free
                t4 = atan2(m12, m02)
                t6 = atan2(g * (m12 * m00 - m02 * m10), g * (m12 * m01 - m02 * m11))
                t5 = atan2(sigma5 * h, mg * m22)
                singular.append(False)
            else:
                t4, t5, t6 = _singular_wrist(
                    geo, m00, m01, m02, m10, m11, m12, m22, prev
                )
                singular.append(True)
            t4f = t4 - pi if t4 > 0.0 else t4 + pi
            t6f = t6 - pi if t6 > 0.0 else t6 + pi
            if prev is not None:
                q2 = n2 + rem(t2 - o2 - n2, TAU)
                q4 = n4 + rem(t4 - o4 - n4, TAU)
                q4f = n4 + rem(t4f - o4 - n4, TAU)
                q5 = n5 + rem(t5 - o5 - n5, TAU)
                q5f = n5 + rem(-t5 - o5 - n5, TAU)
                q6 = n6 + rem(t6 - o6 - n6, TAU)
                q6f = n6 + rem(t6f - o6 - n6, TAU)
            elif wrist_plain:
                q2 = t2 if k2 <= t2 and t2 <= kk2 else _wrap(geo, 1, t2)
                q4, q4f, q5, q5f, q6, q6f = t4, t4f, t5, -t5, t6, t6f
            else:
                q2 = t2 if k2 <= t2 and t2 <= kk2 else _wrap(geo, 1, t2)
                q4 = t4 if k4 <= t4 and t4 <= kk4 else _wrap(geo, 3, t4)
                q4f = t4f if k4 <= t4f and t4f <= kk4 else _wrap(geo, 3, t4f)
                q5 = t5 if k5 <= t5 and t5 <= kk5 else _wrap(geo, 4, t5)
                q5f = -t5 if k5 <= -t5 and -t5 <= kk5 else _wrap(geo, 4, -t5)
                q6 = t6 if k6 <= t6 and t6 <= kk6 else _wrap(geo, 5, t6)
                q6f = t6f if k6 <= t6f and t6f <= kk6 else _wrap(geo, 5, t6f)
            values += (q1, q2, q3, q4, q5, q6, q1, q2, q3, q4f, q5f, q6f)
            # (comparisons in a condition, where CPython specialises them)
            if ok1 and ok3 and l2 <= q2 and q2 <= u2:
                within.append(
                    True
                    if l4 <= q4
                    and q4 <= u4
                    and l5 <= q5
                    and q5 <= u5
                    and l6 <= q6
                    and q6 <= u6
                    else False
                )
                within.append(
                    True
                    if l4 <= q4f
                    and q4f <= u4
                    and l5 <= q5f
                    and q5f <= u5
                    and l6 <= q6f
                    and q6f <= u6
                    else False
                )
            else:
                within += (False, False)
    return values, within, singular


def _solve_twins(
    geo: PumaGeometry, rows: list[list[float]], prev: list[float], pair: int
) -> tuple[list[float], list[float], bool, bool]:
    """The wrist twins ``2 pair`` and ``2 pair + 1`` near ``prev``, for tracking.

    The operations of :func:`_solve` for that one (arm, elbow) pair with
    ``prev`` given, written out straight, so the values are bit for bit those
    of the full solve at a third of its cost (the online planner's cycle).

    Returns:
        Joint values of the no-flip and flip twin and their within-limits flags.
    """
    (nx, ox, ax, px), (ny, oy, ay, py), (nz, oz, az, pz), _ = rows
    if geo.sin_alpha6 != 0.0:  # R' = R Rx(-alpha6): its z column is z5
        ca, sa = geo.cos_alpha6, geo.sin_alpha6
        ox, ax = ca * ox - sa * ax, sa * ox + ca * ax
        oy, ay = ca * oy - sa * ay, sa * oy + ca * ay
        oz, az = ca * oz - sa * az, sa * oz + ca * az
    if geo.d6 != 0.0:  # wrist centre
        px, py, pz = px - geo.d6 * ax, py - geo.d6 * ay, pz - geo.d6 * az
    pz -= geo.d1
    r2 = px * px + py * py
    low, high, cylinder = geo.reach_test
    distance = math.sqrt(r2 + pz * pz)
    if not (low <= distance and distance <= high and r2 >= cylinder):
        check_reach(geo, px, py, pz)  # raises UnreachableError
    s1g, s3g, a2, ell = geo.sigma1, geo.sigma3, geo.a2, geo.forearm
    g, sigma5 = geo.sigma4 * geo.sigma5, geo.sigma5
    sd = s1g * geo.offset
    rho2 = r2 - geo.offset * geo.offset
    if rho2 < 0.0:
        rho2 = 0.0
    rho, y1 = math.sqrt(rho2), s1g * pz
    k = (rho2 + pz * pz - a2 * a2 - ell * ell) / (2.0 * a2 * ell)
    if k > 1.0:
        k = 1.0
    elif k < -1.0:
        k = -1.0
    sgm = math.sqrt(1.0 - k * k)
    cb, sb = geo.cos_beta, geo.sin_beta
    big_a = a2 + ell * k
    right = 1.0 if sd >= 0.0 else -1.0
    atan2, rem, pi = math.atan2, math.remainder, math.pi
    n1, n2, n3, n4, n5, n6 = prev
    o1, o2, o3, o4, o5, o6 = geo.theta_offset
    # elbow
    sg_up = geo.up_sign * right * sgm
    sg = -sg_up if (pair ^ (pair >> 1)) & 1 else sg_up
    kcb, ksb, y1a = k * cb, k * sb, y1 * big_a
    c3, s3 = kcb + sg * sb, sg * cb - ksb
    q3 = n3 + rem(atan2(s3, c3) - o3 - n3, TAU)
    big_b = ell * sg
    yb = y1 * big_b
    # arm
    x1 = (right if pair < 2 else -right) * rho
    if r2 > 0.0:
        c1, s1 = (px * x1 - py * sd) / r2, (py * x1 + px * sd) / r2
    else:  # wrist centre on the base axis (D = 0): theta1 is free
        t1 = o1 + n1
        c1, s1 = math.cos(t1), math.sin(t1)
    q1 = n1 + rem(atan2(s1, c1) - o1 - n1, TAU)
    s13 = s3g * s1g
    a00, a01, a02 = c1 * nx + s1 * ny, c1 * ox + s1 * oy, c1 * ax + s1 * ay
    a10, a11, a12 = s1g * nz, s1g * oz, s1g * az
    m10 = s13 * (s1 * nx - c1 * ny)
    m11 = s13 * (s1 * ox - c1 * oy)
    m12 = s13 * (s1 * ax - c1 * ay)
    # shoulder and wrist
    c2, s2 = x1 * big_a + yb, y1a - x1 * big_b
    q2 = n2 + rem(atan2(s2, c2) - o2 - n2, TAU)
    norm = math.sqrt(c2 * c2 + s2 * s2)
    if norm > 0.0:
        c2, s2 = c2 / norm, s2 / norm
    else:  # wrist centre on the shoulder axis: theta2 is free
        c2, s2 = 1.0, 0.0
    c23, s23 = c2 * c3 - s2 * s3, s2 * c3 + c2 * s3
    m02 = c23 * a02 + s23 * a12
    m22 = s3g * (s23 * a02 - c23 * a12)
    m00, m01 = c23 * a00 + s23 * a10, c23 * a01 + s23 * a11
    h = math.sqrt(m02 * m02 + m12 * m12)
    if h > WRIST_SINGULAR_TOL:
        t4 = atan2(m12, m02)
        t6 = atan2(g * (m12 * m00 - m02 * m10), g * (m12 * m01 - m02 * m11))
        t5 = atan2(sigma5 * h, -g * m22)
    else:
        t4, t5, t6 = _singular_wrist(geo, m00, m01, m02, m10, m11, m12, m22, prev)
    t4f = t4 - pi if t4 > 0.0 else t4 + pi
    t6f = t6 - pi if t6 > 0.0 else t6 + pi
    q4 = n4 + rem(t4 - o4 - n4, TAU)
    q4f = n4 + rem(t4f - o4 - n4, TAU)
    q5 = n5 + rem(t5 - o5 - n5, TAU)
    q5f = n5 + rem(-t5 - o5 - n5, TAU)
    q6 = n6 + rem(t6 - o6 - n6, TAU)
    q6f = n6 + rem(t6f - o6 - n6, TAU)
    (l1, l2, l3, l4, l5, l6), (u1, u2, u3, u4, u5, u6) = geo.bounds
    # (comparisons in a condition, where CPython specialises them)
    if l1 <= q1 and q1 <= u1 and l3 <= q3 and q3 <= u3 and l2 <= q2 and q2 <= u2:
        within = (
            True
            if l4 <= q4 and q4 <= u4 and l5 <= q5 and q5 <= u5 and l6 <= q6 and q6 <= u6
            else False
        )
        within_f = (
            True
            if l4 <= q4f
            and q4f <= u4
            and l5 <= q5f
            and q5f <= u5
            and l6 <= q6f
            and q6f <= u6
            else False
        )
    else:
        within = within_f = False
    return [q1, q2, q3, q4, q5, q6], [q1, q2, q3, q4f, q5f, q6f], within, within_f


def _wrap(geo: PumaGeometry, j: int, theta: float) -> float:
    """Joint value of DH angle ``theta`` in [−π, π] outside ``geo.keep[j]``.

    :func:`wrap_to_limits` of ``theta - offset``; with a zero offset the
    remainder is ``theta`` itself (or π for −π), so only the shifts by
    multiples of 2π are tried.
    """
    if geo.theta_offset[j] != 0.0:
        return wrap_to_limits(theta - geo.theta_offset[j], geo.lower[j], geo.upper[j])
    if theta <= -math.pi:
        theta += TAU
    lo, hi = geo.bounds[0][j], geo.bounds[1][j]
    if lo <= theta <= hi:
        return theta
    for z in (theta + TAU, theta - TAU, theta + 2.0 * TAU, theta - 2.0 * TAU):
        if lo <= z <= hi:
            return z
    return theta


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
