r"""Degenerate directions of a PUMA-type arm at its singularities.

At a singular configuration the Jacobian :math:`J` (6 × 6, rows [linear;
angular], base axes, reference point at the wrist centre) has a left null
vector :math:`u` (:math:`u^T J = 0`: the tool twist direction the arm cannot
produce, read as a wrench [force; moment] that does no work on any joint) and
a right null vector :math:`v` (:math:`J v = 0`: the joint motion that moves
nothing, i.e. joint speed lost to self-motion). Analytically:

* shoulder: :math:`u = [z_1; 0]` — the wrist centre cannot move along the
  shoulder axis z1 (Kang: "degenerate z1 direction");
* elbow: :math:`u = [(p - o_1)/\lVert p - o_1 \rVert; 0]` — the wrist centre
  cannot move towards or away from the shoulder. Kang says "x1": that holds
  only when the upper arm is horizontal (θ2' = 0 mod π) and the shoulder
  offset :math:`d_2 + d_3` is 0 (see ``docs/errata-kang-singularities.md``);
* wrist: :math:`u = [f; x_4]` — no angular velocity about x4 (normal to the
  collinear z3, z5 and to z4) from the wrist; :math:`f` solves
  :math:`J_{\text{arm}}^T u = 0` for joints 1–3.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.singularities.conditions import SINGULARITY_KINDS, get_puma_factorisation

FloatArray = npt.NDArray[np.float64]

_PAPER_AXES = {"shoulder": "z1", "elbow": "x1", "wrist": None}


@dataclass(frozen=True, slots=True)
class DegenerateDirection:
    """The lost directions at one singular configuration.

    Attributes:
        kind: ``"shoulder"``, ``"elbow"`` or ``"wrist"``.
        q: The configuration, shape (6,) [rad].
        direction: Analytic left null vector u, unit, shape (6,), [linear;
            angular] in base axes, reference point the wrist centre.
        residual: ``‖uᵀ J‖`` with Pinocchio's J (0 on the locus).
        sigma_min: Smallest singular value of Pinocchio's J.
        svd_direction: Left singular vector of ``sigma_min``, signed like u.
        self_motion: Right singular vector of ``sigma_min``, shape (6,), unit
            joint velocity [rad/s] with ``J v ≈ 0``; largest entry positive.
        paper_axis: Kang's stated direction (``"z1"``, ``"x1"``) or None.
        paper_direction: That axis in base axes, shape (3,), or None.
        angle_to_paper_deg: Angle [deg] in [0, 90] between the line of u's
            linear part and the paper's axis, or None.
    """

    kind: str
    q: FloatArray
    direction: FloatArray
    residual: float
    sigma_min: float
    svd_direction: FloatArray
    self_motion: FloatArray
    paper_axis: str | None
    paper_direction: FloatArray | None
    angle_to_paper_deg: float | None


def compute_wrist_center_jacobian(robot: Robot, q: npt.ArrayLike) -> FloatArray:
    """Tool Jacobian moved to the wrist centre (origin of DH frame 4), (6, 6).

    For both PUMA models the tool frame is the wrist centre, so this equals
    ``robot.jacobian(q)``.
    """
    jac = robot.jacobian(q).copy()
    offset = robot.fk(q, "frame4").translation - robot.fk(q).translation
    jac[:3] += np.cross(jac[3:].T, offset).T
    return jac


def compute_degenerate_direction(
    robot: Robot, q: npt.ArrayLike, kind: str
) -> DegenerateDirection:
    """Left and right null directions of J at a configuration on a locus.

    Args:
        robot: A PUMA-type robot (its URDF has frames ``frame1`` .. ``frame6``).
        q: A configuration on the ``kind`` locus, shape (6,) [rad].
        kind: ``"shoulder"``, ``"elbow"`` or ``"wrist"``.

    Returns:
        The analytic direction, checked against Pinocchio's Jacobian.

    Raises:
        InputError: If ``kind`` is unknown or ``q`` is invalid.
        NotPumaTypeError: If the robot is not of PUMA type.
    """
    if kind not in SINGULARITY_KINDS:
        raise InputError(
            f"unknown singularity kind {kind!r}; valid: {', '.join(SINGULARITY_KINDS)}"
        )
    get_puma_factorisation(robot)
    q = robot.check_configuration(q)
    frame1, frame4 = robot.fk(q, "frame1"), robot.fk(q, "frame4")
    jac = compute_wrist_center_jacobian(robot, q)
    u = np.zeros(6)
    if kind == "shoulder":
        u[:3] = frame1.rotation[:, 2]
    elif kind == "elbow":
        u[:3] = frame4.translation - frame1.translation
    else:
        u[3:] = frame4.rotation[:, 0]
        # f · J_lin[:, j] = -x4 · J_ang[:, j] for the arm joints j = 1, 2, 3.
        rhs = -jac[3:, :3].T @ u[3:]
        u[:3] = np.linalg.lstsq(jac[:3, :3].T, rhs, rcond=None)[0]
    u /= np.linalg.norm(u)
    left, sv, right_t = np.linalg.svd(jac)
    svd_u = left[:, -1] * (1.0 if left[:, -1] @ u >= 0.0 else -1.0)
    v = right_t[-1]
    v = v * np.sign(v[np.argmax(np.abs(v))])
    axis_name = _PAPER_AXES[kind]
    paper = angle = None
    if axis_name is not None:
        column = 2 if axis_name == "z1" else 0
        paper = frame1.rotation[:, column].copy()
        cosine = abs(paper @ u[:3]) / np.linalg.norm(u[:3])
        angle = float(np.degrees(np.arccos(min(cosine, 1.0))))
    return DegenerateDirection(
        kind=kind,
        q=q,
        direction=u,
        residual=float(np.linalg.norm(u @ jac)),
        sigma_min=float(sv[-1]),
        svd_direction=svd_u,
        self_motion=v,
        paper_axis=axis_name,
        paper_direction=paper,
        angle_to_paper_deg=angle,
    )
