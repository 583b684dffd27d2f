r"""Degenerate directions of an OPW (PUMA-type) or UR-type arm at its singularities.

At a singular configuration the Jacobian :math:`J` (6 × 6, rows [linear;
angular], base axes) has a left null vector :math:`u = [f; m]`
(:math:`u^T J = 0`: the twist component the arm cannot produce, read as a
wrench [force; moment] that does no work on any joint) and a right null vector
:math:`v` (:math:`J v = 0`: joint motion that moves nothing, i.e. self-motion).
u depends on the point the linear rows refer to; here that is the **wrist
point** C: the wrist centre of an OPW arm (where axes 4, 5, 6 meet), the point
where axes 5 and 6 meet on a UR arm. The tool-frame vector of Pinocchio's own
Jacobian follows exactly: :math:`u_{\text{tool}} \propto [f; m + (C - p) \times f]`
with p the tool frame origin.

Everything is read from the joint axes at q (Pinocchio's joint Jacobians: unit
direction :math:`z_i`, times the joint sign of the DH chain, and a point
:math:`o_i` of each axis, base axes), not from frame names. With
:math:`c_i = z_i \times (C - o_i)` the linear column of joint i at C and
:math:`k = z_2` the shoulder axis (axes 2, 3 parallel; UR: 2, 3, 4):

OPW: :math:`c_4 = c_5 = c_6 = 0`, so :math:`J_C` is block triangular.

* shoulder (C in the plane through axis 1 parallel to k): :math:`c_1 \parallel
  z_1 \times k` and :math:`c_2, c_3 \perp k`, so :math:`u = [k; 0]` — C cannot move
  along the shoulder axis (Kang: "degenerate z1 direction");
* elbow (:math:`c_3 \parallel c_2`, both :math:`\parallel k \times r` with r the
  part of :math:`C - o_2` normal to k): :math:`u = [a; 0]`,
  :math:`a \propto c_1 \times (k \times r)`, :math:`a \cdot r > 0` — the line
  through C along a meets axes 1, 2 and 3. Without a shoulder offset (a1 = 0,
  the PUMAs) it is the line from the point where axes 1 and 2 meet to C; Kang's
  "x1" holds only with the upper arm horizontal and d2 + d3 = 0
  (``docs/errata-kang-singularities.md``);
* wrist (:math:`z_6 \parallel z_4`): :math:`u = [f; x_4]`, :math:`x_4 = \sin\alpha_4\,
  z_4 \times z_5` (the DH x4 axis, normal to all three wrist axes), f solving the
  arm block :math:`c_i \cdot f = -z_i \cdot x_4` for i = 1, 2, 3.

UR: axes 5 and 6 pass through C, so :math:`m \parallel n = z_5 \times z_6` and
four conditions remain, from joints 1–4. Let :math:`S = k \cdot c_1` (± the
shoulder distance):

* shoulder (S = 0): :math:`u = [k; 0]`, as for OPW;
* elbow (θ3 = 0 or π: axes 2, 3, 4 in one plane, normal :math:`g = k \times
  \ell`, :math:`\ell` along the upper arm): :math:`f = \alpha \ell + \beta k`,
  :math:`m = \mu n` with
  :math:`(\alpha, \beta, \mu) \propto (-h, 0, n \cdot k) \times (\ell \cdot c_1, S, n
  \cdot z_1)`, h the distance of C from that plane; :math:`\alpha > 0`;
* wrist (θ5 = 0 or π: axis 6 parallel to axes 2, 3, 4, so :math:`n \perp k`):
  :math:`u \propto [-(n \cdot z_1)\, k;\ S\, n]`, the moment along :math:`+x_4`.

Off its locus the same formula is the direction the arm is about to lose: its
residual :math:`\lVert u^T J \rVert` grows linearly with the distance from the
locus (for the shoulder it equals |shoulder| [m]), so the function reports
rather than raises; ``condition`` holds that distance. At a configuration on two
loci at once the left null space is two-dimensional: u is one vector of it, and
the SVD vector need not match.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.singularities.conditions import (
    SINGULARITY_KINDS,
    PumaFactorisation,
    URFactorisation,
    compute_conditions,
    find_puma_factorisation,
    get_factorisation,
)

FloatArray = npt.NDArray[np.float64]

_PAPER_AXES = {"shoulder": "z1", "elbow": "x1", "wrist": None}
_TINY = 1e-12  # [m, 1]: a vector this short has no direction


@dataclass(frozen=True, slots=True)
class DegenerateDirection:
    """The lost directions at one (near-)singular configuration.

    Attributes:
        kind: ``"shoulder"``, ``"elbow"`` or ``"wrist"``.
        q: The configuration, shape (6,) [rad].
        direction: Analytic left null vector u, unit, shape (6,), [linear;
            angular] in base axes, reference point ``reference_point``.
        residual: ``‖uᵀ J‖`` with Pinocchio's J moved to the reference point
            (0 on the locus).
        sigma_min: Smallest singular value of that J.
        svd_direction: Left singular vector of ``sigma_min``, signed like u.
        self_motion: Right singular vector of ``sigma_min``, shape (6,), unit
            joint velocity [rad/s] with ``J v ≈ 0``; largest entry positive.
        paper_axis: Kang's stated direction (``"z1"``, ``"x1"``) for the PUMA
            tables, else None.
        paper_direction: That axis in base axes, shape (3,), or None.
        angle_to_paper_deg: Angle [deg] in [0, 90] between the line of u's
            linear part and the paper's axis, or None.
        family: ``"opw"`` or ``"ur"``.
        reference: What the reference point is
            (:attr:`~workbench.singularities.conditions.PumaFactorisation.reference`).
        reference_point: The reference point C in base coordinates, (3,) [m].
        condition: Signed distance of q from this locus (unit per kind, see
            :data:`~workbench.singularities.conditions.CONDITION_UNITS`).
        tool_direction: The same u for Pinocchio's tool Jacobian
            (``robot.jacobian(q)``, reference point the tool frame origin), unit.
        tool_residual: ``‖u_toolᵀ J_tool‖``.
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
    family: str
    reference: str
    reference_point: FloatArray
    condition: float
    tool_direction: FloatArray
    tool_residual: float


def compute_joint_axes(robot: Robot, q: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Joint axes at ``q`` as lines, directions signed like the DH chain's z axes.

    Returns:
        ``(z, o)``, each (6, 3), base axes: unit direction of each axis (the
        joint's positive rotation times its DH joint sign) and the point of the
        axis nearest the base origin [m].

    Raises:
        NotPumaTypeError: If the robot is neither OPW nor UR type.
    """
    fac = get_factorisation(robot)
    q = robot.check_configuration(q)
    data = robot.model.createData()
    jac = pin.computeJointJacobians(robot.model, data, q)  # WORLD: [o × w; w]
    angular, linear = jac[3:].T, jac[:3].T
    points = np.cross(angular, linear)
    return angular * np.asarray(fac.joint_sign)[:, None], points


def _meet(o1: FloatArray, z1: FloatArray, o2: FloatArray, z2: FloatArray) -> FloatArray:
    """Midpoint of the common normal of two non-parallel lines [m]."""
    c = np.cross(z1, z2)
    r = o2 - o1
    t = float(np.cross(r, z2) @ c) / float(c @ c)
    s = float(np.cross(r, z1) @ c) / float(c @ c)
    return 0.5 * (o1 + t * z1 + o2 + s * z2)


def _wrist_point(fac: PumaFactorisation, z: FloatArray, o: FloatArray) -> FloatArray:
    i = fac.wrist_axes[0] - 1  # the first two wrist axes meet at the point
    return _meet(o[i], z[i], o[i + 1], z[i + 1])


def compute_wrist_point(robot: Robot, q: npt.ArrayLike) -> FloatArray:
    """The reference point C at ``q``, (3,) [m], base coordinates.

    OPW: the wrist centre, where axes 4, 5 and 6 meet; UR: where axes 5 and 6
    meet (the point whose x1 coordinate is the shoulder condition).
    """
    z, o = compute_joint_axes(robot, q)
    return _wrist_point(get_factorisation(robot), z, o)


def compute_wrist_center_jacobian(robot: Robot, q: npt.ArrayLike) -> FloatArray:
    """Tool Jacobian with its linear rows moved to the wrist point, (6, 6).

    The wrist point is :func:`compute_wrist_point`. For both PUMA models the
    tool frame is the wrist centre, so this equals ``robot.jacobian(q)``.
    """
    jac = robot.jacobian(q).copy()
    offset = compute_wrist_point(robot, q) - robot.fk(q).translation
    jac[:3] += np.cross(jac[3:].T, offset).T
    return jac


def _unit(v: FloatArray, kind: str) -> FloatArray:
    norm = float(np.linalg.norm(v))
    if norm <= _TINY:
        raise InputError(
            f"no unique {kind} degenerate direction here: the configuration is "
            "singular in more than one way"
        )
    return v / norm


def _opw_direction(
    kind: str, z: FloatArray, o: FloatArray, point: FloatArray, sigma4: float
) -> FloatArray:
    k, cols = z[1], np.cross(z, point - o)
    u = np.zeros(6)
    if kind == "shoulder":
        u[:3] = k
    elif kind == "elbow":
        r = point - o[1]
        r -= k * float(k @ r)
        a = np.cross(cols[0], np.cross(k, r))
        u[:3] = a if float(a @ r) >= 0.0 else -a
    else:
        u[3:] = sigma4 * _unit(np.cross(z[3], z[4]), kind)  # DH x4
        # f · c_j = -x4 · z_j for the arm joints j = 1, 2, 3.
        rhs = -z[:3] @ u[3:]
        u[:3] = np.linalg.lstsq(cols[:3], rhs, rcond=None)[0]
    return _unit(u, kind)


def _ur_direction(
    kind: str, z: FloatArray, o: FloatArray, point: FloatArray, sigma4: float
) -> FloatArray:
    k, cols = z[1], np.cross(z, point - o)
    x4 = sigma4 * _unit(np.cross(z[3], z[4]), kind)
    n = _unit(np.cross(z[4], z[5]), kind)
    n = n if float(n @ x4) >= 0.0 else -n
    shoulder = float(k @ cols[0])
    u = np.zeros(6)
    if kind == "shoulder":
        u[:3] = k
    elif kind == "wrist":
        u[:3] = -float(n @ z[0]) * k
        u[3:] = shoulder * n
        u = u if float(u[3:] @ x4) >= 0.0 else -u
    else:
        ell = o[2] - o[1]
        ell = _unit(ell - k * float(k @ ell), kind)  # along the upper arm
        height = float((point - o[1]) @ np.cross(k, ell))
        alpha, beta, mu = np.cross(
            [-height, 0.0, float(n @ k)],
            [float(ell @ cols[0]), shoulder, float(n @ z[0])],
        )
        u[:3] = alpha * ell + beta * k
        u[3:] = mu * n
        u = u if alpha >= 0.0 else -u
    return _unit(u, kind)


#: The analytic degenerate direction of each factorisation's arm geometry.
_DIRECTIONS = {PumaFactorisation: _opw_direction, URFactorisation: _ur_direction}


def _paper_axis(
    robot: Robot, q: FloatArray, kind: str, u: FloatArray
) -> tuple[str | None, FloatArray | None, float | None]:
    """Kang's axis for the PUMA tables (DH frame 1 of the robot's own table)."""
    if find_puma_factorisation(robot) is None:
        return None, None, None
    axis_name = _PAPER_AXES[kind]
    if axis_name is None or robot.dh_table is None:
        return None, None, None
    frame1 = robot.dh_table.frame_transforms(q)[1]
    paper = frame1[:3, 2 if axis_name == "z1" else 0].copy()
    cosine = abs(paper @ u[:3]) / np.linalg.norm(u[:3])
    return axis_name, paper, float(np.degrees(np.arccos(min(float(cosine), 1.0))))


def compute_degenerate_direction(
    robot: Robot, q: npt.ArrayLike, kind: str
) -> DegenerateDirection:
    """Left and right null directions of J at a configuration on a locus.

    Args:
        robot: An OPW (PUMA-type) or UR-type robot.
        q: A configuration on (or near) the ``kind`` locus, shape (6,) [rad].
        kind: ``"shoulder"``, ``"elbow"`` or ``"wrist"``.

    Returns:
        The analytic direction, checked against Pinocchio's Jacobian. Off the
        locus it is still computed; ``condition`` and ``residual`` say how far.

    Raises:
        InputError: If ``kind`` is unknown, ``q`` is invalid, or the direction
            is not unique (q on two loci at once, in a way the formula of
            ``kind`` cannot resolve).
        NotPumaTypeError: If the robot is neither OPW nor UR type.
    """
    if kind not in SINGULARITY_KINDS:
        raise InputError(
            f"unknown singularity kind {kind!r}; valid: {', '.join(SINGULARITY_KINDS)}"
        )
    fac = get_factorisation(robot)
    q = robot.check_configuration(q)
    z, o = compute_joint_axes(robot, q)
    point = _wrist_point(fac, z, o)
    u = _DIRECTIONS[type(fac)](kind, z, o, point, fac.sigma4)
    tool_jac = robot.jacobian(q)
    offset = point - robot.fk(q).translation
    jac = tool_jac.copy()
    jac[:3] += np.cross(jac[3:].T, offset).T
    u_tool = np.concatenate([u[:3], u[3:] + np.cross(offset, u[:3])])
    u_tool /= np.linalg.norm(u_tool)
    left, sv, right_t = np.linalg.svd(jac)
    svd_u = left[:, -1] * (1.0 if left[:, -1] @ u >= 0.0 else -1.0)
    v = right_t[-1]
    v = v * np.sign(v[np.argmax(np.abs(v))])
    axis_name, paper, angle = _paper_axis(robot, q, kind, u)
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
        family=fac.family,
        reference=fac.reference,
        reference_point=point,
        condition=float(compute_conditions(robot, q).as_dict()[kind]),
        tool_direction=u_tool,
        tool_residual=float(np.linalg.norm(u_tool @ tool_jac)),
    )
