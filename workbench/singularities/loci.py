r"""Singular loci of PUMA-type arms in joint space, and a configuration on each.

* elbow: :math:`\theta_3 = \operatorname{atan2}(\sigma_3 d_4, a_3) - \theta_{0,3}`
  (extended, the largest distance of the wrist centre from the shoulder) and
  that + π (retracted, the smallest) — 87.308° and −92.692° for Kang's table;
* shoulder: for each θ3 two values of θ2 (:func:`solve_shoulder_theta2`);
* wrist: θ5 = −θ0,5 (mod π).

The factorisation behind them is in :mod:`workbench.singularities.conditions`.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench.model.dh import DHTable
from workbench.model.robot import Robot
from workbench.singularities.conditions import PumaFactorisation, get_puma_factorisation

FloatArray = npt.NDArray[np.float64]


def _wrap(angle: FloatArray | float) -> FloatArray:
    """Angles wrapped to (−π, π]."""
    return np.pi - np.mod(np.pi - np.asarray(angle, dtype=np.float64), 2.0 * np.pi)


def get_elbow_singular_theta3(robot: Robot | DHTable) -> FloatArray:
    """The two elbow-singular values of θ3: [extended, retracted] [rad] in (−π, π].

    Extended and retracted are the largest and smallest distance of the wrist
    centre from the shoulder, where the elbow sine vanishes.
    """
    fac = get_puma_factorisation(robot)
    extended = math.atan2(fac.sigma3 * fac.d4, fac.a3) - fac.theta_offset[2]
    return _wrap(np.array([extended, extended + math.pi]))


def solve_shoulder_theta2(robot: Robot | DHTable, theta3: npt.ArrayLike) -> FloatArray:
    r"""θ2 on the shoulder locus for given θ3: shape ``theta3.shape + (2,)`` [rad].

    The shoulder distance is :math:`A c_2 - B s_2` with
    :math:`A = a_2 + a_3 c_3 + \sigma_3 d_4 s_3` and :math:`B = L_3 e`; it
    vanishes at :math:`\theta_2 = \operatorname{atan2}(A, B)` and that + π.
    """
    fac = get_puma_factorisation(robot)
    t3 = np.asarray(theta3, dtype=np.float64) + fac.theta_offset[2]
    big_a = fac.a2 + fac.a3 * np.cos(t3) + fac.sigma3 * fac.d4 * np.sin(t3)
    big_b = fac.a3 * np.sin(t3) - fac.sigma3 * fac.d4 * np.cos(t3)
    first = np.arctan2(big_a, big_b) - fac.theta_offset[1]
    return _wrap(np.stack([first, first + np.pi], axis=-1))


def compute_example_configurations(
    robot: Robot | DHTable, *, height: float = 0.35
) -> dict[str, FloatArray]:
    """One configuration on each locus, like Kang's Figs. 2 and 3.

    Returns ``"shoulder, elbow up"`` and ``"shoulder, elbow down"`` (wrist
    centre ``height`` [m] above the shoulder, on the singular plane),
    ``"elbow, extended"`` and ``"elbow, retracted"`` (upper arm raised 30°),
    and ``"wrist"`` (θ5 = 0). The other joints are 0, and θ5 = 90° outside the
    wrist case, so that one factor only vanishes. Elbow up means, as in Kang's
    inverse kinematics, that the elbow lies counterclockwise of the line from
    the shoulder to the wrist centre, seen in the arm plane with x1 forward and
    z0 up. Shapes (6,) [rad], each angle shifted by 2π into its joint limits
    where possible (the retracted elbow lies outside the PUMA's limits).
    """
    fac = get_puma_factorisation(robot)
    off = np.asarray(fac.theta_offset)
    raised = math.radians(30.0) * fac.sigma1  # θ2' raising x2 above x1
    base = np.array([0.0, raised - off[1], 0.0, 0.0, math.pi / 2 - off[4], -off[5]])
    base[[0, 3]] = -off[[0, 3]]
    # In the x1-y1 plane |p - o1|² = a2² + L3² + 2 a2 L3 cos(θ3' - φ); the
    # base axis z0 is σ1·y1, so "height above the shoulder" is y1 = σ1·height.
    phi = math.atan2(fac.sigma3 * fac.d4, fac.a3)
    cos_rel = (height**2 - fac.a2**2 - fac.forearm**2) / (2 * fac.a2 * fac.forearm)
    rel = math.acos(float(np.clip(cos_rel, -1.0, 1.0)))
    out: dict[str, FloatArray] = {}
    for t3 in (phi + rel, phi - rel):
        for t2 in solve_shoulder_theta2(robot, t3 - off[2]) + off[1]:
            wrist_x, wrist_y = _wrist_in_frame1(fac, t2, t3)
            if wrist_y * fac.sigma1 <= 0.0:
                continue
            # 2D cross product (forward, up) of shoulder->wrist and shoulder->elbow.
            cross = fac.sigma1 * (wrist_x * np.sin(t2) - wrist_y * np.cos(t2))
            q = base.copy()
            q[1], q[2] = _wrap(t2 - off[1]), _wrap(t3 - off[2])
            out[f"shoulder, elbow {'up' if cross > 0 else 'down'}"] = q
    elbow_theta3 = get_elbow_singular_theta3(robot)
    for label, t3 in zip(("extended", "retracted"), elbow_theta3, strict=True):
        q = base.copy()
        q[2] = t3
        out[f"elbow, {label}"] = q
    wrist = base.copy()
    wrist[2], wrist[4] = math.radians(-30.0) * fac.sigma1 - off[2], -off[4]
    out["wrist"] = wrist
    table = robot if isinstance(robot, DHTable) else robot.dh_table
    order = ("shoulder, elbow up", "shoulder, elbow down", "elbow, extended")
    order += ("elbow, retracted", "wrist")
    return {key: _into_limits(table, out[key]) for key in order if key in out}


def _into_limits(table: DHTable | None, q: FloatArray) -> FloatArray:
    """``q`` with each angle shifted by ±2π where that brings it within limits."""
    if table is None:
        return q
    out = q.copy()
    for i, joint in enumerate(table.joints):
        for shifted in (q[i], q[i] + 2 * np.pi, q[i] - 2 * np.pi):
            if joint.lower <= shifted <= joint.upper:
                out[i] = shifted
                break
    return out


def _wrist_in_frame1(
    fac: PumaFactorisation, t2: FloatArray | float, t3: FloatArray | float
) -> tuple[FloatArray, FloatArray]:
    """(x1, y1) of the wrist centre for θ2', θ3' including offsets [m]."""
    t23 = np.asarray(t2) + np.asarray(t3)
    x1 = fac.a2 * np.cos(t2) + fac.a3 * np.cos(t23) + fac.sigma3 * fac.d4 * np.sin(t23)
    y1 = fac.a2 * np.sin(t2) + fac.a3 * np.sin(t23) - fac.sigma3 * fac.d4 * np.cos(t23)
    return x1, y1
