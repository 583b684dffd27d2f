r"""Kinematic structure of a 6R arm read from its Pinocchio model.

The joint axes of any serial chain of six revolute joints are read at
``q = 0`` (Pinocchio's joint Jacobian gives each axis as a line: direction and
a point), and a standard DH table is fitted to those lines:

* frame 0 has z0 on axis 1, its origin at the foot of the perpendicular from
  the base origin, x0 along the base x axis projected on the plane ⊥ z0;
* frame k (k = 1..5) has z_k on axis k + 1, x_k along the common normal of
  axes k and k + 1 (through the previous origin when they are parallel,
  along ±z_{k-1} × z_k when they meet, the sign with x_k · x_{k-1} >= 0 at
  q = 0, so that the theta offset is within ±90°: the wrist labels then
  refer to the robot's own zero, as the DH tables of the PUMA models do);
* frame 6 is frame 5 turned by θ6 (its row is all zero).

Each axis direction is the joint's positive direction times a sign
``joint_sign`` (θ_k = s_k q_k + θ_{0,k}), chosen so that z0 points up (z0 ·
base z >= 0) and parallel axes of a family point the same way. The constant
base-to-frame-0 transform and the frame-6-to-tool transform are kept, so that
FK(q) = base · DH(q) · tool exactly for the fitted chain.

Two families have a closed form, each a conjunction of geometric tests on the
lines (angles in rad, distances in m, each within :data:`STRUCTURE_TOL`):

* ``"opw"`` (ortho-parallel shoulder, spherical wrist: PUMA, KUKA KR, ABB
  IRB, Fanuc, Stäubli): axes 1 ⊥ 2, 2 ∥ 3, 3 ⊥ 4, 4 ⊥ 5, 5 ⊥ 6, and axes 4, 5, 6
  meet in one point;
* ``"ur"`` (Universal Robots and its clones): axes 1 ⊥ 2, 2 ∥ 3 ∥ 4, 4 ⊥ 5,
  5 ⊥ 6, and axes 5 and 6 meet.

A chain that fits neither raises :class:`UnsupportedRobotError` naming each
failed test of each family.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.model.dh import DHJoint, DHTable
from workbench.model.per_robot import per_robot
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]

#: Geometric tolerance of the structure tests, in rad for angles between axes
#: and in m for distances between them. URDF files round angles (π/2 written
#: 1.570796325 is 1.8e-9 off), so exact tests would refuse real files; a
#: structure broken by 1e-3 rad or 1e-3 m is refused.
STRUCTURE_TOL = 1e-6

#: Lengths below this [m] count as zero when choosing a common normal.
_TINY = 1e-12


class UnsupportedRobotError(InputError):
    """The robot has no closed-form IK (not a 6R arm of a supported family)."""


@dataclass(frozen=True, slots=True)
class KinematicStructure:
    """A 6R arm as base · standard DH chain · tool, and its family.

    Attributes:
        family: ``"opw"`` or ``"ur"``.
        table: Fitted standard DH table; rows are exact (±π/2, 0) where the
            family requires it.
        joint_sign: (6,) ±1.0: DH angle θ_k = s_k q_k + θ_{0,k}.
        base: (4, 4) pose of DH frame 0 in the robot's base frame [m].
        tool: (4, 4) pose of the tool frame in DH frame 6 [m].
        deviation: Largest departure of the model from the idealised
            structure [rad or m], at most ``tol``.
        residual: Largest FK difference [m, rad] between the model and
            base · DH(q) · tool on a few configurations.
    """

    family: str
    table: DHTable
    joint_sign: tuple[float, ...]
    base: FloatArray
    tool: FloatArray
    deviation: float
    residual: float


def axis_lines(robot: Robot) -> tuple[FloatArray, FloatArray]:
    """Joint axes of a 6R chain at q = 0 as lines in the base frame.

    Returns:
        ``(directions, points)``, each (6, 3): unit direction of positive
        rotation and the point of the axis nearest the base origin [m].

    Raises:
        UnsupportedRobotError: If the model is not a serial chain of six
            one-degree-of-freedom revolute joints carrying the tool frame.
    """
    model = robot.model
    name = robot.name
    if robot.mimic_joints:
        followers = ", ".join(map(str, robot.mimic_joints))
        raise UnsupportedRobotError(
            f"robot {name!r} has mimic joints ({followers}), closed-form IK needs "
            "6 independent revolute joints"
        )
    if model.nq != 6 or model.nv != 6 or model.njoints != 7:
        raise UnsupportedRobotError(
            f"robot {name!r} has {model.nq} joint variables, closed-form IK needs "
            "a chain of 6 revolute joints"
        )
    if list(model.parents) != [0, 0, 1, 2, 3, 4, 5]:
        raise UnsupportedRobotError(f"robot {name!r} is not a serial chain")
    if model.frames[robot.tool_frame_id].parentJoint != 6:
        raise UnsupportedRobotError(
            f"tool frame {robot.tool_frame!r} of robot {name!r} is not carried by "
            "joint 6"
        )
    data = model.createData()
    jac = pin.computeJointJacobians(model, data, np.zeros(6))
    linear, angular = jac[:3].T, jac[3:].T
    norms = np.linalg.norm(angular, axis=1)
    bad = [k + 1 for k in range(6) if abs(norms[k] - 1.0) > 1e-12]
    if bad:
        raise UnsupportedRobotError(
            f"robot {name!r}: joints {bad} are not revolute, closed-form IK needs 6R"
        )
    # column (v, w) of a revolute joint about the line (p, w): v = p × w
    points = np.cross(angular, linear)
    return angular, points


def _common_normal(
    o: FloatArray, z: FloatArray, p: FloatArray, w: FloatArray, tol: float
) -> tuple[FloatArray, FloatArray, float, bool]:
    """Feet of the common normal of line (o, z) and line (p, w).

    Returns:
        ``(f, g, sin_angle, parallel)``: foot on the first line, foot on the
        second; for parallel lines (sin angle <= tol) f = o.
    """
    c = np.cross(z, w)
    sn = float(np.linalg.norm(c))
    if sn <= tol:
        return o, p + w * float(w @ (o - p)), sn, True
    r = p - o
    t = float(np.cross(r, w) @ c) / (sn * sn)
    u = float(np.cross(r, z) @ c) / (sn * sn)
    return o + t * z, p + u * w, sn, False


def _signed_angle(u: FloatArray, v: FloatArray, axis: FloatArray) -> float:
    return math.atan2(float(np.cross(u, v) @ axis), float(u @ v))


def fit_dh(
    robot: Robot, signs: tuple[float, ...], tol: float
) -> tuple[list[tuple[float, float, float, float]], FloatArray, FloatArray]:
    """Standard DH rows ``(theta_offset, d, a, alpha)`` fitted to the axes.

    Args:
        robot: A 6R chain (see :func:`axis_lines`).
        signs: (6,) ±1, multiplying each joint's axis direction.
        tol: Axes closer than this to parallel [rad] count as parallel.

    Returns:
        The six rows, the base pose of DH frame 0 and the tool pose in frame 6,
        (4, 4) each.
    """
    w, p = axis_lines(robot)
    z = w * np.asarray(signs)[:, None]
    o_prev, z_prev = p[0], z[0]
    x_prev = np.array([1.0, 0.0, 0.0]) - z_prev * z_prev[0]
    if np.linalg.norm(x_prev) < 1e-6:
        x_prev = np.array([0.0, 1.0, 0.0]) - z_prev * z_prev[1]
    x_prev /= np.linalg.norm(x_prev)
    base = np.eye(4)
    base[:3, :3] = np.column_stack([x_prev, np.cross(z_prev, x_prev), z_prev])
    base[:3, 3] = o_prev
    rows = []
    for k in range(1, 6):
        f, g, sn, parallel = _common_normal(o_prev, z_prev, p[k], z[k], tol)
        n = g - f
        length = float(np.linalg.norm(n))
        if length > _TINY:
            x = n / length
        elif not parallel:  # axes meet: the sign that keeps theta_offset small
            x = np.cross(z_prev, z[k]) / sn
            if float(x @ x_prev) < 0.0:
                x = -x
        else:  # the same line twice: keep x
            x = x_prev
        x = x - z[k] * float(x @ z[k])  # exactly ⊥ z_k (parallel within tol)
        x /= np.linalg.norm(x)
        rows.append(
            (
                _signed_angle(x_prev, x, z_prev),
                float((f - o_prev) @ z_prev),
                float(n @ x),
                _signed_angle(z_prev, z[k], x),
            )
        )
        o_prev, z_prev, x_prev = g, z[k], x
    rows.append((0.0, 0.0, 0.0, 0.0))
    frame6 = np.eye(4)
    frame6[:3, :3] = np.column_stack([x_prev, np.cross(z_prev, x_prev), z_prev])
    frame6[:3, 3] = o_prev
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, np.zeros(6))
    tool_at_zero = data.oMf[robot.tool_frame_id].homogeneous
    tool = np.asarray(np.linalg.solve(frame6, tool_at_zero), dtype=np.float64)
    return rows, base, tool


def _tests(w: FloatArray, p: FloatArray) -> dict[str, tuple[str, float, str]]:
    """Every structure test a family may use: name -> (what fails, deviation, unit)."""
    c = {(i, j): float(np.linalg.norm(np.cross(w[i], w[j]))) for i in range(6)
         for j in range(i + 1, 6)}  # fmt: skip

    def perpendicular(i: int, j: int) -> tuple[str, float, str]:
        dev = abs(math.asin(min(1.0, abs(float(w[i] @ w[j])))))
        return f"axes {i + 1} and {j + 1} are not perpendicular", dev, "rad"

    def parallel(i: int, j: int) -> tuple[str, float, str]:
        angle = math.asin(min(1.0, c[i, j]))
        return f"axes {i + 1} and {j + 1} are not parallel", angle, "rad"

    def meet(i: int, j: int) -> tuple[str, float, str]:
        if c[i, j] <= _TINY:
            gap = float(np.linalg.norm(np.cross(p[j] - p[i], w[i])))
        else:
            gap = abs(float((p[j] - p[i]) @ np.cross(w[i], w[j]))) / c[i, j]
        return f"axes {i + 1} and {j + 1} do not meet", gap, "m"

    def concurrent() -> tuple[str, float, str]:
        if min(c[3, 4], c[4, 5]) <= _TINY:
            return "axes 4, 5, 6 do not meet in one point", math.inf, "m"
        f45 = _common_normal(p[3], w[3], p[4], w[4], 0.0)[1]
        f56 = _common_normal(p[4], w[4], p[5], w[5], 0.0)[0]
        gap = float(np.linalg.norm(f45 - f56))
        return "axes 4, 5, 6 do not meet in one point", gap, "m"

    return {
        "1⊥2": perpendicular(0, 1),
        "2∥3": parallel(1, 2),
        "3∥4": parallel(2, 3),
        "3⊥4": perpendicular(2, 3),
        "4⊥5": perpendicular(3, 4),
        "5⊥6": perpendicular(4, 5),
        "4,5 meet": meet(3, 4),
        "5,6 meet": meet(4, 5),
        "4,5,6 meet": concurrent(),
    }


#: The tests of each family (keys of :func:`_tests`).
FAMILIES: dict[str, tuple[str, ...]] = {
    "opw": ("1⊥2", "2∥3", "3⊥4", "4⊥5", "5⊥6", "4,5 meet", "5,6 meet", "4,5,6 meet"),
    "ur": ("1⊥2", "2∥3", "3∥4", "4⊥5", "5⊥6", "5,6 meet"),
}

_FAMILY_NAMES = {
    "opw": "OPW (ortho-parallel shoulder, spherical wrist)",
    "ur": "UR (axes 2, 3, 4 parallel)",
}


def _signs(family: str, w: FloatArray) -> tuple[float, ...]:
    """Axis signs: z0 up, the parallel axes of the family pointing alike."""
    signs = [1.0] * 6
    signs[0] = -1.0 if w[0][2] < 0.0 else 1.0
    for k in (2, 3) if family == "ur" else (2,):
        signs[k] = -1.0 if float(w[1] @ w[k]) < 0.0 else 1.0
    return tuple(signs)


def _ideal_rows(
    family: str, rows: list[tuple[float, float, float, float]], tol: float
) -> list[tuple[float, float, float, float]]:
    """The fitted rows with the family's right angles and zeros made exact.

    Lengths within ``tol`` of 0 become 0 too: the sign of a shoulder offset of
    1e-32 m must not decide which arm is the right one.
    """
    half = math.pi / 2.0
    right = {0, 2, 3, 4} if family == "opw" else {0, 3, 4}
    zero_a = {3, 4} if family == "opw" else {4}
    out = []
    for k, (theta, d, a, alpha) in enumerate(rows):
        if k in right:
            alpha = math.copysign(half, alpha)
        elif k < 5:
            alpha = 0.0
        if k in zero_a or k == 5:
            a = 0.0
        if family == "opw" and k == 4:
            d = 0.0
        d = 0.0 if abs(d) <= tol else d
        a = 0.0 if abs(a) <= tol else a
        out.append((theta, d, a, alpha))
    return out


def _residual(robot: Robot, structure_rows: list, signs, base, tool) -> float:
    """Largest FK difference [m or rad] of the model and the fitted chain."""
    table = DHTable(
        robot.name, tuple(DHJoint(al, a, d, th) for th, d, a, al in structure_rows)
    )
    rng = np.random.default_rng(0)
    worst = 0.0
    for q in (np.zeros(6), *rng.uniform(-np.pi, np.pi, size=(8, 6))):
        fitted = base @ table.forward_kinematics(q * np.asarray(signs)) @ tool
        model = robot.fk(q).homogeneous
        worst = max(worst, float(np.abs(fitted[:3] - model[:3]).max()))
    return worst


@per_robot
def get_structure(robot: Robot) -> KinematicStructure:
    """The :func:`compute_structure` of a robot, cached per robot object (weakly).

    Raises:
        UnsupportedRobotError: As :func:`compute_structure`.
    """
    return compute_structure(robot)


def compute_structure(robot: Robot, tol: float = STRUCTURE_TOL) -> KinematicStructure:
    """Recognise the family of a 6R arm and fit its DH chain.

    Args:
        robot: Any robot; its tool frame is folded into ``tool``.
        tol: Tolerance of every structure test [rad or m].

    Raises:
        UnsupportedRobotError: If the robot is not a 6R chain, or fits neither
            family; the message names every failed test with its deviation.
    """
    w, p = axis_lines(robot)
    tests = _tests(w, p)
    failures = {}
    for family, names in FAMILIES.items():
        failed = [tests[n] for n in names if not tests[n][1] <= tol]
        if failed:
            failures[family] = failed
            continue
        signs = _signs(family, w)
        rows, base, tool = fit_dh(robot, signs, tol)
        rows = _ideal_rows(family, rows, tol)
        if abs(rows[1][2]) <= tol or (family == "ur" and abs(rows[2][2]) <= tol):
            failures[family] = [("the upper arm or forearm has zero length", 0.0, "m")]
            continue
        limits = zip(robot.lower, robot.upper, strict=True)
        table = DHTable(
            robot.name,
            tuple(
                DHJoint(al, a, d, th, lo, hi)
                for (th, d, a, al), (lo, hi) in zip(rows, limits, strict=True)
            ),
            tool_frame=robot.tool_frame,
            source="fitted to the joint axes of the model",
        )
        return KinematicStructure(
            family=family,
            table=table,
            joint_sign=signs,
            base=base,
            tool=tool,
            deviation=max(tests[n][1] for n in names),
            residual=_residual(robot, rows, signs, base, tool),
        )
    reasons = "; ".join(
        f"not {_FAMILY_NAMES[f]}: "
        + ", ".join(f"{what} (off by {dev:.3g} {unit})" for what, dev, unit in failed)
        for f, failed in failures.items()
    )
    raise UnsupportedRobotError(
        f"robot {robot.name!r} has no closed-form IK (tolerance {tol:g} rad/m): "
        f"{reasons}; use numerical IK"
    )
