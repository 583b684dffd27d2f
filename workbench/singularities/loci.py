r"""Singular loci of OPW (PUMA-type) and UR-type arms in joint space.

In DH angles :math:`\theta_i = s_i q_i + \theta_{0,i}` of the robot's table (its
own PUMA table, or the one fitted to its joint axes, see
:mod:`workbench.singularities.conditions`); every function here returns joint
variables q [rad]:

* elbow: OPW :math:`\theta_3 = \operatorname{atan2}(\sigma_3 d_4, a_3)`
  (extended, the largest distance of the wrist centre from axis 2) and that + π
  (retracted, the smallest) — 87.308° and −92.692° for Kang's table; UR θ3 = 0
  (stretched) and π (folded);
* shoulder: for each θ3 (UR: and θ4) up to two values of θ2
  (:func:`solve_shoulder_theta2`);
* wrist: θ5 = 0 (mod π).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench.model.dh import DHTable
from workbench.model.robot import Robot
from workbench.singularities.conditions import (
    PumaFactorisation,
    find_puma_factorisation,
    get_factorisation,
)

FloatArray = npt.NDArray[np.float64]

#: Default height [m] of the wrist point above the shoulder in the shoulder
#: examples of the PUMA tables (Kang's Fig. 2); other arms use
#: :data:`HEIGHT_FRACTION` of their reach.
PUMA_HEIGHT = 0.35
#: Height of the wrist point above the shoulder in the shoulder examples, as a
#: fraction of the reach |a2| + forearm (0.35 m is 0.405 of the PUMA's).
HEIGHT_FRACTION = 0.4


def _wrap(angle: FloatArray | float) -> FloatArray:
    """Angles wrapped to (−π, π]."""
    return np.pi - np.mod(np.pi - np.asarray(angle, dtype=np.float64), 2.0 * np.pi)


def _theta(fac: PumaFactorisation, joint: int, q: npt.ArrayLike) -> FloatArray:
    """DH angle of ``joint`` (0-based) from its joint variable [rad]."""
    q = np.asarray(q, dtype=np.float64)
    return fac.joint_sign[joint] * q + fac.theta_offset[joint]


def _q(fac: PumaFactorisation, joint: int, theta: npt.ArrayLike) -> FloatArray:
    """Joint variable of ``joint`` (0-based) from its DH angle [rad]."""
    theta = np.asarray(theta, dtype=np.float64)
    return fac.joint_sign[joint] * (theta - fac.theta_offset[joint])


def get_elbow_singular_theta3(robot: Robot | DHTable) -> FloatArray:
    """The two elbow-singular values of q3 [rad] in (−π, π]: extended, retracted.

    Extended and retracted are the largest and smallest distance of the wrist
    centre from axis 2 (UR: of axis 4 from axis 2), where the elbow sine vanishes.
    """
    fac = get_factorisation(robot)
    extended = fac.elbow_angle
    return _wrap(_q(fac, 2, np.array([extended, extended + math.pi])))


def solve_shoulder_theta2(
    robot: Robot | DHTable, theta3: npt.ArrayLike, theta4: npt.ArrayLike = 0.0
) -> FloatArray:
    r"""q2 on the shoulder locus for given q3 (UR: and q4) [rad].

    The shoulder distance is :math:`a_1 + \operatorname{Re}(e^{i\theta_2} Z)`
    with :math:`Z = a_2 + (a_3 - i\sigma_3 d_4) e^{i\theta_3}` (OPW) or
    :math:`Z = a_2 + a_3 e^{i\theta_3} + (a_4 - i\sigma_4 d_5)
    e^{i(\theta_3 + \theta_4)}` (UR), so it vanishes at
    :math:`\theta_2 = -\arg Z \pm \arccos(-a_1 / |Z|)`; NaN where
    :math:`|Z| < |a_1|` (the wrist point cannot reach the singular plane).

    Args:
        robot: An OPW or UR-type robot (or a PUMA-type DH table).
        theta3: Joint variable q3 [rad], any shape.
        theta4: Joint variable q4 [rad] (UR arms only), broadcast with theta3.

    Returns:
        Shape ``broadcast(theta3, theta4).shape + (2,)`` [rad] in (−π, π].
    """
    fac = get_factorisation(robot)
    big_z = fac.wrist_plane_point(0.0, _theta(fac, 2, theta3), _theta(fac, 3, theta4))
    with np.errstate(invalid="ignore"):
        spread = np.arccos(-fac.a1 / np.abs(big_z))
    first = -np.angle(big_z) + spread
    theta2 = np.stack([first, first - 2.0 * spread], axis=-1)
    return _wrap(_q(fac, 1, theta2))


def compute_example_configurations(
    robot: Robot | DHTable, *, height: float | None = None
) -> dict[str, FloatArray]:
    """One configuration on each locus, like Kang's Figs. 2 and 3.

    Returns ``"shoulder, elbow up"`` and ``"shoulder, elbow down"`` (wrist
    point ``height`` [m] above the shoulder, on the singular plane),
    ``"elbow, extended"`` and ``"elbow, retracted"`` (upper arm raised 30°),
    and ``"wrist"`` (θ5 = 0). In DH angles the other joints are 0 (UR: θ2 + θ3
    + θ4 = 0 in the shoulder examples), and θ5 = 90° outside the wrist case,
    so that one factor only vanishes. Elbow up means, as in the inverse
    kinematics, that the elbow lies counterclockwise of the line from the
    shoulder to the wrist point (UR: to axis 4), seen in the arm plane with x1
    forward and z0 up. Shapes (6,) [rad], each angle shifted by 2π into its
    joint limits where possible (the retracted elbow lies outside the PUMA's
    limits).

    Args:
        robot: An OPW or UR-type robot (or a PUMA-type DH table).
        height: Height of the wrist point above the shoulder [m]; default
            :data:`PUMA_HEIGHT` for the PUMA tables, else
            :data:`HEIGHT_FRACTION` of the reach.
    """
    fac = get_factorisation(robot)
    if height is None:
        if find_puma_factorisation(robot) is not None:
            height = PUMA_HEIGHT
        else:
            height = HEIGHT_FRACTION * (abs(fac.a2) + fac.wrist_reach)
    raised = math.radians(30.0) * fac.sigma1  # θ2 raising x2 above x1
    theta = np.array([0.0, raised, 0.0, 0.0, math.pi / 2, 0.0])

    def joint_values(th: FloatArray) -> FloatArray:
        return _wrap(np.array([_q(fac, i, th[i]) for i in range(6)]))

    out: dict[str, FloatArray] = {}
    beta, forearm, offset = fac.elbow_angle, fac.wrist_reach, fac.wrist_offset
    # The wrist point at (x1, y1) = (−a1, σ1·height) (y1 = σ1 z0); axis 4 (UR)
    # is then at that point minus the wrist offset, with θ2 + θ3 + θ4 = 0.
    axis4 = -fac.a1 + 1j * fac.sigma1 * height - offset
    cos_rel = (abs(axis4) ** 2 - fac.a2**2 - forearm**2) / (2 * fac.a2 * forearm)
    rel = math.acos(float(np.clip(cos_rel, -1.0, 1.0)))
    for t3 in (beta + rel, beta - rel):
        elbow_to_wrist = fac.a2 + forearm * np.exp(1j * (t3 - beta))
        planar = float(np.angle(axis4) - np.angle(elbow_to_wrist))
        th = theta.copy()
        th[2] = t3
        th[3] = fac.example_theta4(planar, t3)
        q = joint_values(th)
        for q2 in solve_shoulder_theta2(robot, q[2], q[3]):
            th[1] = float(_theta(fac, 1, q2))
            wrist = complex(fac.wrist_plane_point(th[1], th[2], th[3]))
            if wrist.imag * fac.sigma1 <= 0.0:
                continue
            to = wrist - offset * np.exp(1j * (th[1] + th[2] + th[3]))  # UR: axis 4
            # 2D cross product (forward, up) of shoulder->wrist and shoulder->elbow.
            cross = fac.sigma1 * (to.real * math.sin(th[1]) - to.imag * math.cos(th[1]))
            q_on = q.copy()
            q_on[1] = q2
            out[f"shoulder, elbow {'up' if cross > 0 else 'down'}"] = q_on
    elbow_theta3 = get_elbow_singular_theta3(robot)
    for label, q3 in zip(("extended", "retracted"), elbow_theta3, strict=True):
        q = joint_values(theta)
        q[2] = q3
        out[f"elbow, {label}"] = q
    th = theta.copy()
    th[2], th[4] = math.radians(-30.0) * fac.sigma1, 0.0
    out["wrist"] = joint_values(th)
    order = (
        "shoulder, elbow up",
        "shoulder, elbow down",
        "elbow, extended",
        "elbow, retracted",
        "wrist",
    )
    lower, upper = _limits(robot)
    return {key: _into_limits(lower, upper, out[key]) for key in order if key in out}


def _limits(robot: Robot | DHTable) -> tuple[FloatArray, FloatArray]:
    if isinstance(robot, DHTable):
        return (
            np.array([j.lower for j in robot.joints]),
            np.array([j.upper for j in robot.joints]),
        )
    return robot.lower, robot.upper


def _into_limits(lower: FloatArray, upper: FloatArray, q: FloatArray) -> FloatArray:
    """``q`` with each angle shifted by ±2π where that brings it within limits."""
    out = q.copy()
    for i in range(q.size):
        for shifted in (q[i], q[i] + 2 * np.pi, q[i] - 2 * np.pi):
            if lower[i] <= shifted <= upper[i]:
                out[i] = shifted
                break
    return out
