r"""Analytic singularities of OPW (PUMA-type) and UR-type arms: det J factors, classes.

For a 6R arm whose standard DH table (:math:`\theta_i = q_i + \theta_{0,i}`) has
:math:`a_1 = 0`, :math:`\alpha_1 = \pm 90°`, :math:`\alpha_2 = 0`,
:math:`\alpha_3, \alpha_4, \alpha_5 = \pm 90°` and :math:`a_4 = a_5 = d_5 = 0`
(a spherical wrist centred at the origin of frame 4), the Jacobian of any tool
point, rows [linear; angular] in base axes, is block triangular and

.. math::
    \det J = K\, s\, e\, w, \qquad
    K = -\sigma_1\, a_2\, L_3\, \sin\alpha_4 \sin\alpha_5,

with :math:`\sigma_i = \sin\alpha_i`, :math:`L_3 = \sqrt{a_3^2 + d_4^2}` [m] and
the three signed distances (the *conditions*)

* shoulder :math:`s = a_2 c_2 + a_3 c_{23} + \sigma_3 d_4 s_{23}` [m]: the x1
  coordinate of the wrist centre, i.e. its distance from the plane through the
  base axis z0 parallel to the shoulder axis z1 (Kang's Eq. 1);
* elbow :math:`e = (a_3 s_3 - \sigma_3 d_4 c_3) / L_3` [1]: the sine of the
  angle between the upper arm (x2) and the line from the elbow to the wrist
  centre seen along z2 (Kang's Eq. 2, divided by :math:`L_3`);
* wrist :math:`w = s_5` [1]: zero when the axes z3 and z5 are collinear (Eq. 3).

The signs come from each robot's own table: they differ between ``puma560``
(Angeles, :math:`K = -a_2 L_3`) and ``puma560-kang`` (Kang, :math:`K = +a_2 L_3`).

Any other arm of the two closed-form families (:mod:`workbench.ik.structure`
recognises them from the joint axes) gets the same factorisation from its
fitted DH chain, :math:`\theta_i = s_i q_i + \theta_{0,i}`, with the product of
the joint signs :math:`s_i` folded into K (the base and tool transforms do not
change det J):

* OPW with a shoulder offset a1 (KUKA, ABB, Fanuc): the shoulder distance is
  :math:`s = a_1 + a_2 c_2 + a_3 c_{23} + \sigma_3 d_4 s_{23}`, the rest as above;
* UR type (axes 2, 3, 4 parallel): :math:`K = -\sigma_1 \sigma_4 \sigma_5 a_2 a_3`,
  shoulder :math:`s = a_1 + a_2 c_2 + a_3 c_{23} + a_4 c_{234} + \sigma_4 d_5
  s_{234}` (the x1 coordinate of the point where axes 5 and 6 meet, from the
  base axis), elbow :math:`e = s_3`, wrist :math:`w = s_5` (axis 6 parallel to
  axes 2, 3, 4).

Tests check :math:`\det J = K s e w` against Pinocchio's Jacobian to 1e-9
relative on every supported model. The derivation is in
``docs/errata-kang-singularities.md``; the loci in joint space (any OPW or
UR-type arm) are in :mod:`workbench.singularities.loci`, the degenerate
directions (any such arm, derived from its joint axes) in
:mod:`workbench.singularities.directions`, the numeric measures of any robot in
:mod:`workbench.singularities.measures`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.ik import Family, get_family, get_family_refusal, get_structure
from workbench.model.dh import DHTable
from workbench.model.robot import Robot
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]

#: The singularity types, in the order of the det J factors.
SINGULARITY_KINDS = ("shoulder", "elbow", "wrist")
#: Units of the signed distances of :data:`SINGULARITY_KINDS`.
CONDITION_UNITS = {"shoulder": "m", "elbow": "1 (sine)", "wrist": "1 (sine)"}

#: |shoulder distance| [m] at or below which a configuration counts as
#: shoulder-singular: 1 cm of the wrist centre from the singular plane.
SHOULDER_TOL = 0.01
#: |elbow sine| at or below which a configuration counts as elbow-singular (1°).
ELBOW_TOL = math.sin(math.radians(1.0))
#: |sin θ5| at or below which a configuration counts as wrist-singular (1°).
WRIST_TOL = math.sin(math.radians(1.0))

_DH_TOL = 1e-12  # DH angles and lengths that must be exactly 0 or ±90°


class NotPumaTypeError(InputError):
    """The robot has no DH table of PUMA type, so there is no analytic form."""


@dataclass(frozen=True, slots=True)
class PumaFactorisation:
    r"""Constants of :math:`\det J = K\, s\, e\, w` of an OPW (PUMA-type) arm.

    The formulas differ between the arm geometries they are derived for: this
    class holds those of an OPW arm (axes 2 ∥ 3, spherical wrist),
    :class:`URFactorisation` those of a UR-type arm; each states its geometry
    (:attr:`parallel_axes`, :attr:`wrist_axes`) and is chosen for an arm whose
    :class:`~workbench.ik.Family` has it (:meth:`fits`).

    Attributes:
        robot: Robot (table) name.
        sigma1: :math:`\sin\alpha_1` (±1).
        sigma3: :math:`\sin\alpha_3` (±1).
        wrist_sign: :math:`\sin\alpha_4 \sin\alpha_5` (±1).
        a2: Upper arm length [m].
        a3: Elbow offset [m].
        d4: Forearm length [m].
        forearm: :math:`L_3 = \sqrt{a_3^2 + d_4^2}` [m].
        constant: :math:`K` [m²], so that det J [m³] = K · s [m] · e · w.
        theta_offset: Offsets of the six joint angles, shape (6,) [rad].
        a1: Shoulder offset [m] (0 for the PUMA tables).
        a4: UR: offset of axis 5 along the arm [m]; 0 for OPW.
        d5: UR: distance from axis 4 to the wrist point along axis 5 [m].
        sigma4: :math:`\sin\alpha_4` (±1).
        joint_sign: (6,) ±1: DH angle θ_i = s_i q_i + θ_{0,i}.
        family: ``"opw"`` (class constant), the family's name for display.
        parallel_axes: (2, 3), the parallel axes (1-based) the formulas need.
        wrist_axes: (4, 5, 6), the axes meeting at the reference point C.
        measure_formula: The formula selector of the compiled measures
            (``workspace._measure_kernel``): 0.0 OPW, 1.0 UR.
    """

    robot: str
    sigma1: float
    sigma3: float
    wrist_sign: float
    a2: float
    a3: float
    d4: float
    forearm: float
    constant: float
    theta_offset: tuple[float, ...]
    a1: float = 0.0
    a4: float = 0.0
    d5: float = 0.0
    sigma4: float = 1.0
    joint_sign: tuple[float, ...] = (1.0,) * 6
    kinds: ClassVar[tuple[str, ...]] = SINGULARITY_KINDS
    family: ClassVar[str] = "opw"
    parallel_axes: ClassVar[tuple[int, ...]] = (2, 3)
    wrist_axes: ClassVar[tuple[int, ...]] = (4, 5, 6)
    measure_formula: ClassVar[float] = 0.0

    @classmethod
    def fits(cls, family: Family) -> bool:
        """Whether the formulas of this class hold for arms of ``family``."""
        return (
            family.joint_count == 6
            and family.parallel_axes == cls.parallel_axes
            and family.wrist_axes == cls.wrist_axes
        )

    @classmethod
    def arm_lengths(cls, a3: float, d4: float) -> tuple[float, float]:
        """``(forearm, length)`` [m] from DH lengths ``a3``, ``d4`` [m].

        ``forearm`` is the reach from axis 3 to the wrist point in the arm
        plane, ``length`` the factor of K besides a2.
        """
        forearm = math.hypot(a3, d4)
        return forearm, forearm

    @property
    def spherical_wrist(self) -> bool:
        """True if the reference point is a wrist centre (three axes meet)."""
        return len(self.wrist_axes) == 3

    @property
    def reference(self) -> str:
        """What the reference point C is: ``"wrist centre (axes 4, 5, 6 meet)"``."""
        axes = self.wrist_axes
        named = ", ".join(map(str, axes[:-1])) + f" and {axes[-1]}"
        if self.spherical_wrist:
            return f"wrist centre (axes {', '.join(map(str, axes))} meet)"
        return f"wrist point (axes {named} meet)"

    @property
    def wrist_reach(self) -> float:
        """Distance [m] from axis 3 to the wrist point in the arm plane."""
        return self.forearm

    @property
    def elbow_angle(self) -> float:
        """The angle β [rad] with elbow sine ∝ sin(θ3 − β)."""
        return math.atan2(self.sigma3 * self.d4, self.a3)

    @property
    def wrist_offset(self) -> complex:
        """The wrist point from the end of the arm in the arm plane [m]: 0."""
        return 0j

    def wrist_plane_point(
        self, t2: npt.ArrayLike, t3: npt.ArrayLike, t4: npt.ArrayLike
    ) -> npt.NDArray[np.complex128]:
        """The wrist centre in the arm plane as x1 + i y1 (from frame 1) [m].

        DH angles, broadcast together; θ4 does not move the wrist centre.
        """
        t2, t3 = (np.asarray(t, dtype=np.float64) for t in (t2, t3))
        arm = self.a2 + (self.a3 - 1j * self.sigma3 * self.d4) * np.exp(1j * t3)
        return np.exp(1j * t2) * arm

    def example_theta4(self, theta2: float, theta3: float) -> float:
        """θ4 [rad] of the shoulder examples (``loci``): 0, it moves no wrist centre."""
        return 0.0

    def conditions(self, theta: FloatArray) -> SingularityConditions:
        """The signed distances at DH angles ``theta`` (..., 6) [rad]."""
        t2, t3, t5 = theta[..., 1], theta[..., 2], theta[..., 4]
        t23 = t2 + t3
        shoulder = self.a1 + self.a2 * np.cos(t2) + self.a3 * np.cos(t23)
        shoulder = shoulder + self.sigma3 * self.d4 * np.sin(t23)
        elbow = (
            self.a3 * np.sin(t3) - self.sigma3 * self.d4 * np.cos(t3)
        ) / self.forearm
        return SingularityConditions(shoulder, elbow, np.sin(t5))

    def describe(self) -> dict[str, str]:
        """The factors as plain-text formulas with this table's signs."""
        sign = "+" if self.sigma3 > 0 else "−"
        offsets = any(abs(o) > 0.0 for o in self.theta_offset)
        note = " (θi includes its DH theta offset)" if offsets else ""
        return {
            "det_j": "det J = K · shoulder · elbow · wrist  [m³]",
            "constant": (
                f"K = {-self.sigma1 * self.wrist_sign:+.0f} · a2 · √(a3² + d4²)"
                f" = {self.constant:+.6f} m²"
            ),
            "shoulder": (
                f"{'a1 + ' if self.a1 else ''}a2 c2 + a3 c23 {sign} d4 s23  [m]{note}"
            ),
            "elbow": f"(a3 s3 {'−' if self.sigma3 > 0 else '+'} d4 c3) / √(a3² + d4²)",
            "wrist": "s5",
        }


@dataclass(frozen=True, slots=True)
class URFactorisation(PumaFactorisation):
    r"""Constants of :math:`\det J = K\, s\, e\, w` of a UR-type arm.

    Axes 2, 3, 4 parallel, axes 5 and 6 meeting at the wrist point:
    :math:`K = -\sigma_1 \sigma_4 \sigma_5 a_2 a_3`, shoulder :math:`s = a_1 +
    a_2 c_2 + a_3 c_{23} + a_4 c_{234} + \sigma_4 d_5 s_{234}`, elbow
    :math:`e = s_3`, wrist :math:`w = s_5` (fields: :class:`PumaFactorisation`).
    """

    family: ClassVar[str] = "ur"
    parallel_axes: ClassVar[tuple[int, ...]] = (2, 3, 4)
    wrist_axes: ClassVar[tuple[int, ...]] = (5, 6)
    measure_formula: ClassVar[float] = 1.0

    @classmethod
    def arm_lengths(cls, a3: float, d4: float) -> tuple[float, float]:
        """``(|a3|, a3)`` [m]: axis 3 to axis 4, and K's length besides a2."""
        return abs(a3), a3

    @property
    def elbow_angle(self) -> float:
        """0: the elbow sine is sin θ3."""
        return 0.0

    @property
    def wrist_offset(self) -> complex:
        """The wrist point from axis 4 in the arm plane at θ2 + θ3 + θ4 = 0 [m]."""
        return self.a4 - 1j * self.sigma4 * self.d5

    def wrist_plane_point(
        self, t2: npt.ArrayLike, t3: npt.ArrayLike, t4: npt.ArrayLike
    ) -> npt.NDArray[np.complex128]:
        """The wrist point (axes 5 and 6 meet) as x1 + i y1 (from frame 1) [m]."""
        t2, t3, t4 = (np.asarray(t, dtype=np.float64) for t in (t2, t3, t4))
        wrist = self.wrist_offset * np.exp(1j * (t3 + t4))
        arm = self.a2 + self.a3 * np.exp(1j * t3) + wrist
        return np.exp(1j * t2) * arm

    def example_theta4(self, theta2: float, theta3: float) -> float:
        """θ4 [rad] that keeps θ2 + θ3 + θ4 = 0 (the wrist offset along x1)."""
        return -theta2 - theta3

    def conditions(self, theta: FloatArray) -> SingularityConditions:
        """The signed distances at DH angles ``theta`` (..., 6) [rad]."""
        t2, t3, t5 = theta[..., 1], theta[..., 2], theta[..., 4]
        t23 = t2 + t3
        t234 = t23 + theta[..., 3]
        shoulder = self.a1 + self.a2 * np.cos(t2) + self.a3 * np.cos(t23)
        shoulder = shoulder + self.a4 * np.cos(t234)
        shoulder = shoulder + self.sigma4 * self.d5 * np.sin(t234)
        return SingularityConditions(shoulder, np.sin(t3), np.sin(t5))

    def describe(self) -> dict[str, str]:
        """The factors as plain-text formulas with this arm's signs."""
        sign = "+" if self.sigma4 > 0 else "−"
        return {
            "det_j": "det J = K · shoulder · elbow · wrist  [m³]",
            "constant": f"K = ±a2 · a3 = {self.constant:+.6f} m²",
            "shoulder": f"a1 + a2 c2 + a3 c23 + a4 c234 {sign} d5 s234  [m]",
            "elbow": "s3",
            "wrist": "s5",
        }


#: The factorisations, each chosen for the arms whose family it fits.
FACTORISATIONS: tuple[type[PumaFactorisation], ...] = (
    PumaFactorisation,
    URFactorisation,
)


def _puma_table_problem(table: DHTable | None, name: str) -> str | None:
    """Why ``table`` is not a PUMA-type DH table; None when it is one."""
    if table is None:
        return (
            f"{name}: no DH table, so no analytic singularity conditions "
            "(the numeric measures still apply)"
        )
    if table.nq != 6:
        return f"{table.name}: PUMA type needs 6 joints, got {table.nq}"
    j = table.joints
    must_be_zero = {"a1": j[0].a, "α2": j[1].alpha, "a4": j[3].a}
    must_be_zero |= {"a5": j[4].a, "d5": j[4].d}
    for label, value in must_be_zero.items():
        if abs(value) > _DH_TOL:
            return f"{table.name}: PUMA type needs {label} = 0"
    for index in (0, 2, 3, 4):
        if abs(abs(math.sin(j[index].alpha)) - 1.0) > _DH_TOL:
            return f"{table.name}: PUMA type needs α{index + 1} = ±90°"
    if j[1].a == 0.0 or math.hypot(j[2].a, j[3].d) == 0.0:
        return f"{table.name}: PUMA type needs a2 ≠ 0 and (a3, d4) ≠ 0"
    return None


def get_puma_factorisation(robot: Robot | DHTable) -> PumaFactorisation:
    """Derive the factorisation of det J from the robot's DH table.

    Raises:
        NotPumaTypeError: If the robot has no DH table, or its table is not of
            PUMA type (the message says which parameter breaks it).
    """
    table = robot if isinstance(robot, DHTable) else robot.dh_table
    problem = _puma_table_problem(table, getattr(robot, "name", "robot"))
    if problem is not None or table is None:
        raise NotPumaTypeError(str(problem))
    j = table.joints
    sigma1, sigma3 = round(math.sin(j[0].alpha)), round(math.sin(j[2].alpha))
    wrist_sign = round(math.sin(j[3].alpha)) * round(math.sin(j[4].alpha))
    a2, a3, d4 = j[1].a, j[2].a, j[3].d
    forearm = math.hypot(a3, d4)
    if a2 == 0.0 or forearm == 0.0:
        raise NotPumaTypeError(f"{table.name}: PUMA type needs a2 ≠ 0 and (a3, d4) ≠ 0")
    return PumaFactorisation(
        robot=table.name,
        sigma1=float(sigma1),
        sigma3=float(sigma3),
        wrist_sign=float(wrist_sign),
        a2=a2,
        a3=a3,
        d4=d4,
        forearm=forearm,
        constant=-sigma1 * a2 * forearm * wrist_sign,
        theta_offset=tuple(joint.theta_offset for joint in j),
        sigma4=float(round(math.sin(j[3].alpha))),
    )


def get_factorisation(robot: Robot | DHTable) -> PumaFactorisation:
    """The factorisation of det J of any OPW or UR-type arm.

    From the robot's PUMA-type DH table when it has one
    (:func:`get_puma_factorisation`), else from the DH chain fitted to its
    joint axes (:func:`workbench.ik.get_structure`).

    Raises:
        NotPumaTypeError: If the robot fits neither family (the message names
            the axes that fail which test).
    """
    if isinstance(robot, DHTable):
        return get_puma_factorisation(robot)
    if _puma_table_problem(robot.dh_table, robot.name) is None:
        return get_puma_factorisation(robot)
    family = get_family(robot)
    if family is None:
        raise NotPumaTypeError(str(get_family_refusal(robot)))
    kind = next((f for f in FACTORISATIONS if f.fits(family)), None)
    if kind is None:
        raise NotPumaTypeError(
            f"robot {robot.name!r} is a {family.joint_count}-axis arm "
            f"({family.name.upper()} family: {family.title}), not a 6R arm with "
            "a PUMA-type factorisation"
        )
    structure = get_structure(robot)
    j = structure.table.joints
    sigma = [math.copysign(1.0, joint.alpha) for joint in j]
    signs = structure.joint_sign
    product = float(np.prod(signs))
    forearm, length = kind.arm_lengths(j[2].a, j[3].d)
    return kind(
        robot=robot.name,
        sigma1=sigma[0],
        sigma3=sigma[2],
        wrist_sign=sigma[3] * sigma[4],
        a2=j[1].a,
        a3=j[2].a,
        d4=j[3].d,
        forearm=forearm,
        constant=-sigma[0] * sigma[3] * sigma[4] * j[1].a * length * product,
        theta_offset=tuple(joint.theta_offset for joint in j),
        a1=j[0].a,
        a4=j[3].a,
        d5=j[4].d,
        sigma4=sigma[3],
        joint_sign=signs,
    )


@dataclass(frozen=True, slots=True)
class SingularityConditions:
    """Signed distances to the three singular loci (arrays broadcast over q[..., :]).

    Attributes:
        shoulder: x1 coordinate of the wrist centre [m].
        elbow: Elbow sine [1].
        wrist: sin θ5 [1].
    """

    shoulder: FloatArray
    elbow: FloatArray
    wrist: FloatArray

    def as_dict(self) -> dict[str, FloatArray]:
        """``{"shoulder": ..., "elbow": ..., "wrist": ...}``."""
        return {"shoulder": self.shoulder, "elbow": self.elbow, "wrist": self.wrist}


def find_puma_factorisation(robot: Robot | DHTable) -> PumaFactorisation | None:
    """The factorisation from a PUMA-type DH table; None for any other robot.

    :func:`get_puma_factorisation` without the error, for callers that ask.
    """
    table = robot if isinstance(robot, DHTable) else robot.dh_table
    if _puma_table_problem(table, robot.name) is not None:
        return None
    return get_puma_factorisation(robot)


def find_factorisation(robot: Robot) -> PumaFactorisation | None:
    """The factorisation of det J of an OPW or UR-type arm; None for any other.

    :func:`get_factorisation` without the error: None for an arm with no
    closed-form family or of a family without a 6R factorisation (seven-axis
    arms), so that callers ask instead of catching :class:`NotPumaTypeError`.
    """
    puma = find_puma_factorisation(robot)
    if puma is not None:
        return puma
    family = get_family(robot)
    if family is None or not any(f.fits(family) for f in FACTORISATIONS):
        return None
    return get_factorisation(robot)


def dh_angles(
    q: npt.ArrayLike, joint_sign: tuple[float, ...], theta_offset: tuple[float, ...]
) -> FloatArray:
    """DH angles θ = s q + θ0 (..., n) of robot joint values ``q`` (..., n).

    Raises:
        InputError: If the last axis of ``q`` is not n = ``len(joint_sign)``;
            ``NonFiniteError`` for a NaN or infinite entry.
    """
    count = len(joint_sign)
    q = np.asarray(q, dtype=np.float64)
    if q.ndim == 0 or q.shape[-1] != count:
        raise InputError(f"q must have shape (..., {count}), got shape {q.shape}")
    q = as_finite_array(q, q.shape, "q")
    return q * np.asarray(joint_sign) + np.asarray(theta_offset)


def _angles(fac: PumaFactorisation, q: npt.ArrayLike) -> FloatArray:
    return dh_angles(q, fac.joint_sign, fac.theta_offset)


def compute_conditions(
    robot: Robot | DHTable, q: npt.ArrayLike
) -> SingularityConditions:
    """Signed distances of ``q`` to the shoulder, elbow and wrist loci.

    Args:
        robot: An OPW or UR-type robot (or a PUMA-type DH table).
        q: Configurations, shape (..., 6) [rad].

    Returns:
        Arrays of shape ``q.shape[:-1]``; see :class:`SingularityConditions`.

    Raises:
        NotPumaTypeError: If the robot fits neither family.
        InputError: If ``q`` is not (..., 6) or not finite.
    """
    fac = get_factorisation(robot)
    return fac.conditions(_angles(fac, q))


def compute_det_j_analytic(robot: Robot | DHTable, q: npt.ArrayLike) -> FloatArray:
    """Determinant of the Jacobian [m³] from the factorisation, shape ``q.shape[:-1]``.

    Equals ``np.linalg.det(robot.jacobian(q))`` for any tool point on the last
    link (moving the reference point does not change the determinant).
    """
    fac = get_factorisation(robot)
    c = compute_conditions(robot, q)
    return fac.constant * c.shoulder * c.elbow * c.wrist


def classify_configuration(
    robot: Robot | DHTable,
    q: npt.ArrayLike,
    *,
    shoulder_tol: float = SHOULDER_TOL,
    elbow_tol: float = ELBOW_TOL,
    wrist_tol: float = WRIST_TOL,
) -> tuple[str, ...]:
    """The singularity types ``q`` is within tolerance of; ``()`` means none.

    Args:
        robot: An OPW or UR-type robot (or a PUMA-type DH table).
        q: One configuration, shape (6,) [rad].
        shoulder_tol: Tolerance on |shoulder distance| [m].
        elbow_tol: Tolerance on |elbow sine|.
        wrist_tol: Tolerance on |sin θ5|.

    Returns:
        A sub-tuple of :data:`SINGULARITY_KINDS`, e.g. ``("shoulder", "wrist")``.
    """
    conditions = compute_conditions(robot, as_finite_array(q, (6,), "q")).as_dict()
    tolerances = {"shoulder": shoulder_tol, "elbow": elbow_tol, "wrist": wrist_tol}
    return tuple(k for k in SINGULARITY_KINDS if abs(conditions[k]) <= tolerances[k])
