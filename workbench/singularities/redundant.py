r"""Singularities of SRS seven-axis arms (KUKA LBR iiwa): det(J Jᵀ) factorised.

For the fitted DH chain of an SRS arm (:mod:`workbench.ik.structure`, family
``"srs"``: a = 0, α1..α6 = σ_k π/2, α7 = 0, d2 = d4 = d6 = 0;
θ_k = s_k q_k + θ_{0,k}) take the wrist centre W as the reference point of
the 6 × 7 Jacobian, rows [linear; angular] in base axes. Axes 5, 6, 7 pass
through W, so

.. math::
    J_W = \begin{bmatrix} J_p & 0 \\ J_{\omega,a} & J_{\omega,w} \end{bmatrix},
    \qquad J_p = [z_0 \times SW,\ z_1 \times SW,\ z_2 \times SW,\ z_3 \times EW],

and, by Cauchy–Binet over its seven 6 × 6 minors (det(J Jᵀ) does not depend
on the reference point: moving it multiplies J by a matrix of determinant 1),

.. math::
    \det(J J^T) = (d_3 d_5 \sin\theta_4)^2 \left[\sin^2\theta_6
        \textstyle\sum A_i^2 + \sin^2\theta_2 \sum B_i^2\right] \quad [m^6]

* dropping an arm column k: :math:`\pm (SW \cdot (z_3 \times EW))
  \det(z_a, z_b, SW) \det(z_4, z_5, z_6)`, with :math:`|SW \cdot (z_3 \times
  EW)| = |d_3 d_5 \sin\theta_4|` and :math:`|\det(z_4, z_5, z_6)| = |\sin\theta_6|`;
  the minor without joint 4 is 0 (z_i × SW, i < 3, all ⊥ SW);
* dropping a wrist column: the arm's self-motion (null vector of J_p) turns
  the arm about SW, angular velocity ∝ det(z0, z1, z2) SW, |det(z0, z1, z2)| =
  |sin θ2|, times det(SW, w_a, w_b) of the two remaining wrist axes;
* A_i = det(z_a, z_b, SW) over the pairs of axes 1, 2, 3 (frame 2):
  :math:`A_1 = \sigma_2\sigma_4 d_5 s_4 c_3`,
  :math:`A_2 = -\sigma_1\sigma_4 d_5 s_2 s_4 s_3`,
  :math:`A_3 = \sigma_1\sigma_4 d_5 c_2 s_4 c_3 + \sigma_1\sigma_2 s_2
  (d_3 - \sigma_3\sigma_4 c_4 d_5)`; B_i over the pairs of axes 5, 6, 7
  (frame 4, the mirror image): :math:`B_1 = \sigma_5\sigma_6 s_6 (d_5 -
  \sigma_3\sigma_4 c_4 d_3) + \sigma_3\sigma_6 d_3 s_4 c_5 c_6`,
  :math:`B_2 = -\sigma_3\sigma_6 d_3 s_4 s_5 s_6`,
  :math:`B_3 = \sigma_3\sigma_5 d_3 s_4 c_5`.

With s4 ≠ 0, ΣA² = 0 iff s2 = 0 and c3 = 0 and ΣB² = 0 iff s6 = 0 and c5 = 0,
so J loses rank exactly on four loci (:data:`SRS_SINGULARITY_KINDS`; each a
distance, zero on the locus):

* ``elbow``: sin θ4 = 0 (signed, the arm stretched or folded); lost: W along SW;
* ``shoulder``: √(sin²θ2 + cos²θ3) (axes 1 and 3 aligned and the arm plane
  containing axis 2); lost: W along the forearm EW (a force along the line
  E W does no work on any joint);
* ``wrist``: √(sin²θ6 + cos²θ5) (axes 5 and 7 aligned and the arm plane
  containing axis 6); lost: the wrench of a force along the upper arm S E;
* ``shoulder_wrist``: √(sin²θ2 + sin²θ6) (both spherical joints degenerate:
  columns 1 = ±3 and 5 = ±7, rank ≤ 5); lost: the left null vector of the
  five other columns (their generalised cross product).

Besides, ``arm_angle``: |SW_xy| / |SW| (unsigned), zero with W on axis 1,
where the arm angle's reference plane is undefined (the algorithmic
singularity of the parametrisation; J keeps its rank, no twist is lost).
Tests check det(J Jᵀ) against Pinocchio's Jacobian, σ_min on each locus and
the lost directions against its left null space (``tests/test_singularities_srs.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.ik import Family, get_family, get_family_refusal, get_structure
from workbench.model.robot import Robot
from workbench.singularities.conditions import dh_angles

FloatArray = npt.NDArray[np.float64]

#: The loci of an SRS arm: the four where its 6 × 7 Jacobian loses rank, then
#: the algorithmic singularity of the arm angle.
SRS_SINGULARITY_KINDS = ("elbow", "shoulder", "wrist", "shoulder_wrist", "arm_angle")
#: Units of the distances of :data:`SRS_SINGULARITY_KINDS`.
SRS_CONDITION_UNITS = {
    "elbow": "1 (sine, signed)",
    "shoulder": "1 (√(sin²θ2 + cos²θ3))",
    "wrist": "1 (√(sin²θ6 + cos²θ5))",
    "shoulder_wrist": "1 (√(sin²θ2 + sin²θ6))",
    "arm_angle": "1 (|SW_xy| / |SW|)",
}


class NotSRSArmError(InputError):
    """The robot is not an SRS seven-axis arm, so there is no analytic form."""


@dataclass(frozen=True, slots=True)
class SRSFactorisation:
    """The constants of the SRS det(J Jᵀ) read off the fitted DH chain.

    Attributes:
        robot: Robot name.
        sigma: (6,) sin α_k (±1) of joints 1..6.
        d1: Shoulder height along axis 1 [m].
        d3: Upper arm, S to E [m].
        d5: Forearm, E to W [m].
        joint_sign: (7,) ±1: DH angle θ_k = s_k q_k + θ_{0,k}.
        theta_offset: (7,) θ_{0,k} [rad].
        base: (4, 4) pose of DH frame 0 in the robot's base frame [m].
    """

    robot: str
    sigma: tuple[float, ...]
    d1: float
    d3: float
    d5: float
    joint_sign: tuple[float, ...]
    theta_offset: tuple[float, ...]
    base: FloatArray
    #: The axes (1-based) meeting at the shoulder S, the elbow E and the wrist W.
    shoulder_axes: ClassVar[tuple[int, ...]] = (1, 2, 3)
    elbow_axes: ClassVar[tuple[int, ...]] = (3, 4, 5)
    wrist_axes: ClassVar[tuple[int, ...]] = (5, 6, 7)

    @classmethod
    def fits(cls, family: Family) -> bool:
        """Whether arms of ``family`` have this geometry (three spherical joints)."""
        return (
            family.shoulder_axes == cls.shoulder_axes
            and family.elbow_axes == cls.elbow_axes
            and family.wrist_axes == cls.wrist_axes
        )


@dataclass(frozen=True, slots=True)
class SRSConditions:
    """Distances of configurations to the SRS loci, each shape ``q.shape[:-1]``.

    Attributes:
        elbow: sin θ4 [1], signed.
        shoulder: √(sin²θ2 + cos²θ3) [1].
        wrist: √(sin²θ6 + cos²θ5) [1].
        shoulder_wrist: √(sin²θ2 + sin²θ6) [1].
        arm_angle: |SW_xy| / |SW| [1]: sine of the angle of SW from axis 1.
    """

    elbow: FloatArray
    shoulder: FloatArray
    wrist: FloatArray
    shoulder_wrist: FloatArray
    arm_angle: FloatArray

    def as_dict(self) -> dict[str, FloatArray]:
        """The distances keyed by :data:`SRS_SINGULARITY_KINDS`."""
        return {kind: getattr(self, kind) for kind in SRS_SINGULARITY_KINDS}


@dataclass(frozen=True, slots=True)
class SRSDegenerateDirection:
    """The twist an SRS arm cannot produce at a configuration on a locus.

    Attributes:
        kind: One of the first four :data:`SRS_SINGULARITY_KINDS`.
        direction: (6,) unit left null vector u = [f; m] of J (uᵀ J = 0 on
            the locus), linear rows at ``reference_point``, base axes.
        reference_point: The wrist centre W, (3,) [m], base frame.
        condition: The distance of q from the locus (:class:`SRSConditions`).
    """

    kind: str
    direction: FloatArray
    reference_point: FloatArray
    condition: float


def get_srs_factorisation(robot: Robot) -> SRSFactorisation:
    """The SRS constants of a robot (its fitted structure, cached per robot).

    Raises:
        NotSRSArmError: If the robot is not an SRS seven-axis arm.
    """
    family = get_family(robot)
    if family is None:
        reason = get_family_refusal(robot)
        raise NotSRSArmError(f"robot {robot.name!r} is not an SRS arm: {reason}")
    if not SRSFactorisation.fits(family):
        raise NotSRSArmError(
            f"robot {robot.name!r} is a {family.name!r} arm, not an SRS "
            "seven-axis arm (spherical shoulder, elbow and wrist)"
        )
    structure = get_structure(robot)
    j = structure.table.joints
    return SRSFactorisation(
        robot=robot.name,
        sigma=tuple(float(np.sign(x.alpha)) for x in j[:6]),
        d1=j[0].d,
        d3=j[2].d,
        d5=j[4].d,
        joint_sign=tuple(structure.joint_sign),
        theta_offset=tuple(x.theta_offset for x in j),
        base=structure.base,
    )


def find_srs_factorisation(robot: Robot) -> SRSFactorisation | None:
    """The SRS constants of an SRS seven-axis arm; None for any other arm.

    :func:`get_srs_factorisation` without the error, for callers that ask.
    """
    family = get_family(robot)
    if family is None or not SRSFactorisation.fits(family):
        return None
    return get_srs_factorisation(robot)


def _angles(fac: SRSFactorisation, q: npt.ArrayLike) -> FloatArray:
    """DH angles θ (..., 7) of robot joint values q (..., 7)."""
    return dh_angles(q, fac.joint_sign, fac.theta_offset)


def _frames(fac: SRSFactorisation, theta: FloatArray) -> list[FloatArray]:
    """Rotations R_0k (..., 3, 3), k = 0..6, of the DH chain (frame 0 axes)."""
    out = [np.broadcast_to(np.eye(3), (*theta.shape[:-1], 3, 3))]
    for k in range(6):
        c, s, sg = np.cos(theta[..., k]), np.sin(theta[..., k]), fac.sigma[k]
        zero = np.zeros_like(c)
        local = np.stack(
            [
                np.stack([c, zero, sg * s], -1),
                np.stack([s, zero, -sg * c], -1),
                np.stack([zero, zero + sg, zero], -1),
            ],
            -2,
        )
        out.append(out[-1] @ local)
    return out


def compute_srs_conditions(robot: Robot, q: npt.ArrayLike) -> SRSConditions:
    """Distances of ``q`` (..., 7) [rad] to the SRS loci (module docstring).

    Raises:
        NotSRSArmError: If the robot is not an SRS arm.
        InputError: If ``q`` is not (..., 7) or not finite.
    """
    fac = get_srs_factorisation(robot)
    theta = _angles(fac, q)
    s2, c3 = np.sin(theta[..., 1]), np.cos(theta[..., 2])
    c5, s6 = np.cos(theta[..., 4]), np.sin(theta[..., 5])
    rot = _frames(fac, theta)
    sw = fac.d3 * rot[2][..., :, 2] + fac.d5 * rot[4][..., :, 2]
    return SRSConditions(
        elbow=np.sin(theta[..., 3]),
        shoulder=np.hypot(s2, c3),
        wrist=np.hypot(s6, c5),
        shoulder_wrist=np.hypot(s2, s6),
        arm_angle=np.hypot(sw[..., 0], sw[..., 1]) / np.linalg.norm(sw, axis=-1),
    )


def compute_srs_det_jjt(robot: Robot, q: npt.ArrayLike) -> FloatArray:
    """det(J Jᵀ) [m⁶] of the 6 × 7 Jacobian from the factorisation, ``q.shape[:-1]``.

    Equals det(J Jᵀ) of Pinocchio's Jacobian of any point of the last link,
    in any axes (module docstring).
    """
    fac = get_srs_factorisation(robot)
    t = _angles(fac, q)
    s1, s2, s3, s4, s5, s6 = fac.sigma
    sn, cs = np.sin(t), np.cos(t)
    d3, d5 = fac.d3, fac.d5
    a1 = s2 * s4 * d5 * sn[..., 3] * cs[..., 2]
    a2 = -s1 * s4 * d5 * sn[..., 1] * sn[..., 3] * sn[..., 2]
    a3 = s1 * s4 * d5 * cs[..., 1] * sn[..., 3] * cs[..., 2] + s1 * s2 * sn[..., 1] * (
        d3 - s3 * s4 * cs[..., 3] * d5
    )
    b1 = (
        s5 * s6 * sn[..., 5] * (d5 - s3 * s4 * cs[..., 3] * d3)
        + s3 * s6 * d3 * sn[..., 3] * cs[..., 4] * cs[..., 5]
    )
    b2 = -s3 * s6 * d3 * sn[..., 3] * sn[..., 4] * sn[..., 5]
    b3 = s3 * s5 * d3 * sn[..., 3] * cs[..., 4]
    shoulder = a1**2 + a2**2 + a3**2
    wrist = b1**2 + b2**2 + b3**2
    elbow = (d3 * d5 * sn[..., 3]) ** 2
    return elbow * (sn[..., 5] ** 2 * shoulder + sn[..., 1] ** 2 * wrist)


def _unit(v: FloatArray) -> FloatArray:
    return v / np.linalg.norm(v)


def _cross_of_columns(columns: FloatArray) -> FloatArray:
    """The generalised cross product of five 6-vectors (6, 5): ⊥ each of them."""
    out = np.empty(6)
    for k in range(6):
        rows = [r for r in range(6) if r != k]
        out[k] = (-1.0) ** k * np.linalg.det(columns[rows])
    return out


def compute_srs_degenerate_direction(
    robot: Robot, q: npt.ArrayLike, kind: str
) -> SRSDegenerateDirection:
    """The lost twist direction of locus ``kind`` at one configuration q (7,) [rad].

    Args:
        robot: An SRS arm.
        q: Configuration on (or near) the locus [rad].
        kind: ``"elbow"``, ``"shoulder"``, ``"wrist"`` or ``"shoulder_wrist"``.

    Returns:
        u = [f; m] (module docstring), reference point W; off the locus the
        same formula (its residual ‖uᵀ J‖ grows with the distance).

    Raises:
        NotSRSArmError: If the robot is not an SRS arm.
        InputError: If ``kind`` is not one of those four (``"arm_angle"`` is
            no singularity of J: no twist is lost) or ``q`` is not (7,).
    """
    kinds = SRS_SINGULARITY_KINDS[:4]
    if kind not in kinds:
        extra = " (the arm angle's singularity loses no twist)" * (kind == "arm_angle")
        raise InputError(f"kind must be one of {kinds}, got {kind!r}{extra}")
    fac = get_srs_factorisation(robot)
    theta = _angles(fac, q)
    if theta.shape != (7,):
        raise InputError(f"q must have shape (7,), got shape {theta.shape}")
    base = np.asarray(fac.base)
    rot = [base[:3, :3] @ r for r in _frames(fac, theta)]
    z = [r[:, 2] for r in rot]  # axis k + 1 is z_k
    shoulder = base[:3, :3] @ np.array([0.0, 0.0, fac.d1]) + base[:3, 3]
    elbow = shoulder + fac.d3 * z[2]
    wrist = elbow + fac.d5 * z[4]
    sw = wrist - shoulder
    if kind == "elbow":
        u = np.concatenate([_unit(sw), np.zeros(3)])
    elif kind == "shoulder":
        u = np.concatenate([_unit(wrist - elbow), np.zeros(3)])
    elif kind == "wrist":
        f = _unit(elbow - shoulder)
        u = _unit(np.concatenate([f, np.cross(shoulder - wrist, f)]))
    else:  # columns 1, 2, 4, 5, 6 of J_W (3 = ±1, 7 = ±5 on the locus)
        points = (shoulder, shoulder, elbow, wrist, wrist)
        axes = (z[0], z[1], z[3], z[4], z[5])
        cols = np.array(
            [
                np.concatenate([np.cross(a, wrist - p), a])
                for a, p in zip(axes, points, strict=True)
            ]
        ).T
        u = _unit(_cross_of_columns(cols))
    condition = getattr(compute_srs_conditions(robot, q), kind)
    return SRSDegenerateDirection(kind, u, wrist, float(condition))


__all__ = [
    "SRS_CONDITION_UNITS",
    "SRS_SINGULARITY_KINDS",
    "NotSRSArmError",
    "SRSConditions",
    "SRSDegenerateDirection",
    "SRSFactorisation",
    "compute_srs_conditions",
    "compute_srs_degenerate_direction",
    "compute_srs_det_jjt",
    "get_srs_factorisation",
]
