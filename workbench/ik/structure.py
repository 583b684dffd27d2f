r"""Kinematic structure of a 6R or 7R arm read from its Pinocchio model.

The joint axes of any serial chain of n = 6 (or 7) revolute joints are read
at ``q = 0`` (Pinocchio's joint Jacobian gives each axis as a line: direction
and a point), and a standard DH table is fitted to those lines:

* frame 0 has z0 on axis 1, its origin at the foot of the perpendicular from
  the base origin, x0 along the base x axis projected on the plane ⊥ z0;
* frame k (k = 1..n-1) has z_k on axis k + 1, x_k along the common normal of
  axes k and k + 1 (through the previous origin when they are parallel,
  along ±z_{k-1} × z_k when they meet, the sign with x_k · x_{k-1} >= 0 at
  q = 0, so that the theta offset is within ±90°: the wrist labels then
  refer to the robot's own zero, as the DH tables of the PUMA models do);
* 6R: frame 6 is frame 5 turned by θ6 (its row is all zero);
* 7R: frame 7 is frame 6 turned by θ7 and moved along axis 7 to the foot of
  the tool origin (``d7``), its x along the tool's x projected on the plane ⊥
  axis 7 (``theta_offset`` of row 7): the flange row of published 7R tables
  (the iiwa's ``d7 = 0.126 m``), so that ``tool`` is the identity when the
  tool frame is DH frame 7.

Each axis direction is the joint's positive direction times a sign
``joint_sign`` (θ_k = s_k q_k + θ_{0,k}), chosen so that z0 points up (z0 ·
base z >= 0) and parallel axes of a family point the same way. The constant
base-to-frame-0 transform and the frame-n-to-tool transform are kept, so that
FK(q) = base · DH(q) · tool exactly for the fitted chain.

Four families have a closed form (two of 6R arms, two of 7R arms), each a
conjunction of geometric tests on the lines (angles in rad, distances in m):

* ``"opw"`` (ortho-parallel shoulder, spherical wrist: PUMA, KUKA KR, ABB
  IRB, Fanuc, Stäubli): axes 1 ⊥ 2, 2 ∥ 3, 3 ⊥ 4, 4 ⊥ 5, 5 ⊥ 6, and axes 4, 5, 6
  meet in one point;
* ``"ur"`` (Universal Robots and its clones): axes 1 ⊥ 2, 2 ∥ 3 ∥ 4, 4 ⊥ 5,
  5 ⊥ 6, and axes 5 and 6 meet;
* ``"srs"`` (7R, spherical shoulder, elbow and wrist: KUKA LBR iiwa): axes
  1 ⊥ 2, 2 ⊥ 3 and axes 1, 2, 3 meet in one point (the shoulder S); 3 ⊥ 4,
  4 ⊥ 5 and axes 3, 4, 5 meet in one point (the elbow E); 5 ⊥ 6, 6 ⊥ 7 and
  axes 5, 6, 7 meet in one point (the wrist W); S ≠ E ≠ W;
* ``"franka"`` (7R, the Franka Panda and FR3 geometry): axes 1 ⊥ 2, 2 ⊥ 3 and
  axes 1, 2, 3 meet in one point (S); 3 ⊥ 4 and 4 ⊥ 5 with non-zero common
  normals (the elbow offsets a3, a4); 5 ⊥ 6, meeting; 6 ⊥ 7 with a non-zero
  common normal (a6); any lengths of this pattern.

An arm passes a family's tests when every angle test is within
:data:`CALIBRATION_ANGLE_TOL` and every distance test within
:data:`CALIBRATION_DISTANCE_TOL`: a calibrated URDF (joint-origin deltas of
1e-4…1e-3 rad and 0.1…1 mm, or the iiwa 14 of ROS-Industrial, whose joint 2
and 4 origins are 0.436 mm off axis) is of its family, its closed form is
that of the idealised structure (the fitted chain with the family's right
angles and zeros made exact) and every branch is carried to the model
(:mod:`workbench.ik._refine_kernel`). How far the model is from the idealised
structure is :attr:`KinematicStructure.deviation`. A chain that fits none of
the families of its joint count raises :class:`UnsupportedRobotError` naming
each failed test of each family and the deviation from the nearest one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import UnsupportedRobotError
from workbench.model.dh import DHJoint, DHTable
from workbench.model.per_robot import per_robot
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]

#: Geometric tolerance of the structure tests, in rad for angles between axes
#: and in m for distances between them. URDF files round angles (π/2 written
#: 1.570796325 is 1.8e-9 off) and many round to 4 decimals (π/2 written 1.5708
#: is 3.67e-6 off; example-robot-data's xArm7 also has axes 1, 2, 3 meeting to
#: 1.08e-6 m), so exact tests, or 1e-6, would refuse real files; 1e-5 admits
#: 4-decimal rounding, whose deviation the refinement on the model's own chain
#: removes, and a structure broken by 1e-4 rad or 1e-4 m is refused.
STRUCTURE_TOL = 1e-5

#: Largest angle deviation [rad] of a family's tests that is still of the family
#: (a calibrated arm, solved through the closed form of the idealised structure
#: and carried to the model): the bound certified by
#: ``tests/test_ik_calibrated.py``, against 1e-4…1e-3 rad of a robot calibration.
CALIBRATION_ANGLE_TOL = 1e-2

#: Largest distance deviation [m] of a family's tests that is still of the
#: family, against 0.1…1 mm of a robot calibration (see
#: :data:`CALIBRATION_ANGLE_TOL`).
CALIBRATION_DISTANCE_TOL = 5e-3

#: Lengths below this [m] count as zero when choosing a common normal.
_TINY = 1e-12

#: Joint counts of the chains with a closed form: 6R arms (OPW, UR) and 7R
#: arms (SRS, Franka), whose seventh joint is the redundancy.
JOINT_COUNTS = (6, 7)


@dataclass(frozen=True, slots=True)
class StructureDeviation:
    """How far a model is from the idealised structure of its family.

    Attributes:
        angle: Largest deviation of the family's angle tests [rad] (axes that
            should be perpendicular or parallel).
        angle_test: The test it comes from, e.g. ``"2∥3"``.
        distance: Largest deviation of the family's distance tests [m] (axes
            that should meet, or meet in one point).
        distance_test: The test it comes from, e.g. ``"1,2,3 meet"``.
    """

    angle: float
    angle_test: str
    distance: float
    distance_test: str

    @property
    def calibrated(self) -> bool:
        """True if the model is off its family by more than URDF rounding.

        (More than :data:`STRUCTURE_TOL` in angle or distance: a calibrated
        arm, whose branches are carried from the idealised structure to the
        model.)
        """
        return max(self.angle, self.distance) > STRUCTURE_TOL

    def describe(self) -> str:
        """``"3.2e-04 rad (2∥3), 4.4e-04 m (1,2,3 meet)"``: for messages and output."""
        return (
            f"{self.angle:.2g} rad ({self.angle_test}), "
            f"{self.distance:.2g} m ({self.distance_test})"
        )


@dataclass(frozen=True, slots=True)
class KinematicStructure:
    """A 6R or 7R arm as base · standard DH chain · tool, and its family.

    Attributes:
        family: ``"opw"`` or ``"ur"`` (6R), ``"srs"`` or ``"franka"`` (7R).
        table: Fitted standard DH table, n = 6 or 7 rows; rows are exact
            (±π/2, 0) where the family requires it.
        joint_sign: (n,) ±1.0: DH angle θ_k = s_k q_k + θ_{0,k}.
        base: (4, 4) pose of DH frame 0 in the robot's base frame [m].
        tool: (4, 4) pose of the tool frame in DH frame n [m].
        deviation: How far the model is from the idealised structure, the
            largest angle [rad] and distance [m] of the family's tests: within
            :data:`CALIBRATION_ANGLE_TOL` and :data:`CALIBRATION_DISTANCE_TOL`.
        residual: Largest FK difference [m, rad] between the model and
            base · DH(q) · tool on a few configurations.
    """

    family: str
    table: DHTable
    joint_sign: tuple[float, ...]
    base: FloatArray
    tool: FloatArray
    deviation: StructureDeviation
    residual: float


def axis_lines(robot: Robot) -> tuple[FloatArray, FloatArray]:
    """Joint axes of a 6R or 7R chain at q = 0 as lines in the base frame.

    Returns:
        ``(directions, points)``, each (n, 3), n = 6 or 7: unit direction of
        positive rotation and the point of the axis nearest the base origin [m].

    Raises:
        UnsupportedRobotError: If the model is not a serial chain of six or
            seven one-degree-of-freedom revolute joints carrying the tool frame.
    """
    model = robot.model
    name = robot.name
    n = model.nq
    if robot.mimic_joints:
        followers = ", ".join(map(str, robot.mimic_joints))
        raise UnsupportedRobotError(
            f"robot {name!r} has mimic joints ({followers}), closed-form IK needs "
            "6 (or 7) independent revolute joints"
        )
    if n not in JOINT_COUNTS or model.nv != n or model.njoints != n + 1:
        raise UnsupportedRobotError(
            f"robot {name!r} has {model.nq} joint variables, closed-form IK needs "
            "a chain of 6 (or 7) revolute joints"
        )
    if list(model.parents) != [0, *range(n)]:
        raise UnsupportedRobotError(f"robot {name!r} is not a serial chain")
    if model.frames[robot.tool_frame_id].parentJoint != n:
        raise UnsupportedRobotError(
            f"tool frame {robot.tool_frame!r} of robot {name!r} is not carried by "
            f"joint {n}"
        )
    data = model.createData()
    jac = pin.computeJointJacobians(model, data, np.zeros(n))
    linear, angular = jac[:3].T, jac[3:].T
    norms = np.linalg.norm(angular, axis=1)
    bad = [k + 1 for k in range(n) if abs(norms[k] - 1.0) > 1e-12]
    if bad:
        raise UnsupportedRobotError(
            f"robot {name!r}: joints {bad} are not revolute, closed-form IK needs {n}R"
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
        robot: A 6R or 7R chain (see :func:`axis_lines`).
        signs: (n,) ±1, multiplying each joint's axis direction.
        tol: Axes closer than this to parallel [rad] count as parallel (the
            common normal is then taken through the previous origin, as for
            the family's parallel axes of a calibrated arm, whose common
            normal proper may be metres away).

    Returns:
        The n rows, the base pose of DH frame 0 and the tool pose in frame n,
        (4, 4) each.
    """
    w, p = axis_lines(robot)
    joints = len(w)
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
    for k in range(1, joints):
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
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, np.zeros(joints))
    tool_at_zero = data.oMf[robot.tool_frame_id].homogeneous
    if joints == 6:
        rows.append((0.0, 0.0, 0.0, 0.0))
    else:  # the flange row: d7 to the foot of the tool origin, x along the tool's
        d = float((tool_at_zero[:3, 3] - o_prev) @ z_prev)
        x = tool_at_zero[:3, 0] - z_prev * float(tool_at_zero[:3, 0] @ z_prev)
        if np.linalg.norm(x) > 1e-6:
            x /= np.linalg.norm(x)
        else:  # the tool's x along axis 7: keep frame 6's
            x = x_prev
        rows.append((_signed_angle(x_prev, x, z_prev), d, 0.0, 0.0))
        o_prev, x_prev = o_prev + d * z_prev, x
    last = np.eye(4)
    last[:3, :3] = np.column_stack([x_prev, np.cross(z_prev, x_prev), z_prev])
    last[:3, 3] = o_prev
    tool = np.asarray(np.linalg.solve(last, tool_at_zero), dtype=np.float64)
    return rows, base, tool


def _tests(w: FloatArray, p: FloatArray) -> dict[str, tuple[str, float, str]]:
    """Every structure test a family may use: name -> (what fails, deviation, unit).

    Only the tests of the chain's joint count n = len(w) are computed.
    """
    n = len(w)
    c = {(i, j): float(np.linalg.norm(np.cross(w[i], w[j]))) for i in range(n)
         for j in range(i + 1, n)}  # fmt: skip

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

    def concurrent(i: int, pairs: bool) -> tuple[str, float, str]:
        """Axes i, i+1, i+2 through one point (``pairs``: each pair meets too)."""
        what = f"axes {i + 1}, {i + 2}, {i + 3} do not meet in one point"
        if min(c[i, i + 1], c[i + 1, i + 2]) <= _TINY:
            return what, math.inf, "m"
        f_first = _common_normal(p[i], w[i], p[i + 1], w[i + 1], 0.0)[1]
        f_second = _common_normal(p[i + 1], w[i + 1], p[i + 2], w[i + 2], 0.0)[0]
        gap = float(np.linalg.norm(f_first - f_second))
        if pairs:
            gap = max(gap, meet(i, i + 1)[1], meet(i + 1, i + 2)[1])
        return what, gap, "m"

    if n == 6:
        return {
            "1⊥2": perpendicular(0, 1),
            "2∥3": parallel(1, 2),
            "3∥4": parallel(2, 3),
            "3⊥4": perpendicular(2, 3),
            "4⊥5": perpendicular(3, 4),
            "5⊥6": perpendicular(4, 5),
            "4,5 meet": meet(3, 4),
            "5,6 meet": meet(4, 5),
            "4,5,6 meet": concurrent(3, pairs=False),
        }
    return {
        "1⊥2": perpendicular(0, 1),
        "2⊥3": perpendicular(1, 2),
        "3⊥4": perpendicular(2, 3),
        "4⊥5": perpendicular(3, 4),
        "5⊥6": perpendicular(4, 5),
        "6⊥7": perpendicular(5, 6),
        "5,6 meet": meet(4, 5),
        "1,2,3 meet": concurrent(0, pairs=True),
        "3,4,5 meet": concurrent(2, pairs=True),
        "5,6,7 meet": concurrent(4, pairs=True),
    }


#: The tests of each family (keys of :func:`_tests`).
FAMILIES: dict[str, tuple[str, ...]] = {
    "opw": ("1⊥2", "2∥3", "3⊥4", "4⊥5", "5⊥6", "4,5 meet", "5,6 meet", "4,5,6 meet"),
    "ur": ("1⊥2", "2∥3", "3∥4", "4⊥5", "5⊥6", "5,6 meet"),
    "srs": ("1⊥2", "2⊥3", "1,2,3 meet", "3⊥4", "4⊥5", "3,4,5 meet", "5⊥6", "6⊥7",
            "5,6,7 meet"),
    "franka": ("1⊥2", "2⊥3", "1,2,3 meet", "3⊥4", "4⊥5", "5⊥6", "5,6 meet", "6⊥7"),
}  # fmt: skip

#: Joint count of each family's chains.
FAMILY_JOINTS: dict[str, int] = {"opw": 6, "ur": 6, "srs": 7, "franka": 7}

_FAMILY_NAMES = {
    "opw": "OPW (ortho-parallel shoulder, spherical wrist)",
    "ur": "UR (axes 2, 3, 4 parallel)",
    "srs": "SRS (spherical shoulder, elbow and wrist)",
    "franka": "Franka (spherical shoulder, offset elbow, offset wrist)",
}

#: Rows (0-based) of each family's idealised DH table: with α = ±π/2 (the
#: others α = 0), with a = 0, with d = 0.
_IDEAL: dict[str, tuple[frozenset[int], frozenset[int], frozenset[int]]] = {
    "opw": (frozenset({0, 2, 3, 4}), frozenset({3, 4, 5}), frozenset({4})),
    "ur": (frozenset({0, 3, 4}), frozenset({4, 5}), frozenset()),
    "srs": (frozenset(range(6)), frozenset(range(7)), frozenset({1, 3, 5})),
    "franka": (frozenset(range(6)), frozenset({0, 1, 4, 6}), frozenset({1})),
}


def _signs(family: str, w: FloatArray) -> tuple[float, ...]:
    """Axis signs: z0 up, the parallel axes of the family pointing alike."""
    signs = [1.0] * len(w)
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
    right, zero_a, zero_d = _IDEAL[family]
    out = []
    for k, (theta, d, a, alpha) in enumerate(rows):
        alpha = math.copysign(half, alpha) if k in right else 0.0
        if k in zero_a:
            a = 0.0
        if k in zero_d:
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
    n = len(structure_rows)
    for q in (np.zeros(n), *rng.uniform(-np.pi, np.pi, size=(8, n))):
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


def _zero_lengths(
    family: str, rows: list[tuple[float, float, float, float]], tol: float
) -> str | None:
    """What a family needs non-zero and the fitted rows have zero, or None."""
    arm: tuple[float, ...]
    if family == "opw":
        arm = (rows[1][2],)
    elif family == "ur":
        arm = (rows[1][2], rows[2][2])
    else:  # S to E, E to W (SRS) or elbow to wrist (Franka)
        arm = (rows[2][1], rows[4][1])
    if min(map(abs, arm)) <= tol:
        return "the upper arm or forearm has zero length"
    if family == "franka" and min(abs(rows[k][2]) for k in (2, 3, 5)) <= tol:
        return "an elbow offset (a3, a4) or the wrist offset (a6) is zero"
    return None


def _deviation(
    tests: dict[str, tuple[str, float, str]], names: tuple[str, ...]
) -> StructureDeviation:
    """The largest angle and distance deviation of the tests ``names``."""
    angle = max((tests[n][1], n) for n in names if tests[n][2] == "rad")
    distance = max((tests[n][1], n) for n in names if tests[n][2] == "m")
    return StructureDeviation(angle[0], angle[1], distance[0], distance[1])


def compute_structure(
    robot: Robot,
    *,
    angle_tol: float = CALIBRATION_ANGLE_TOL,
    distance_tol: float = CALIBRATION_DISTANCE_TOL,
) -> KinematicStructure:
    """Recognise the family of a 6R or 7R arm and fit its DH chain.

    Args:
        robot: Any robot; its tool frame is folded into ``tool``.
        angle_tol: Largest deviation of a family's angle tests [rad].
        distance_tol: Largest deviation of a family's distance tests [m].

    Raises:
        UnsupportedRobotError: If the robot is not a 6R or 7R chain, or fits
            none of the families of its joint count; the message names every
            failed test with its deviation, and the deviation from the
            nearest family.
    """
    w, p = axis_lines(robot)
    tests = _tests(w, p)
    bound = {"rad": angle_tol, "m": distance_tol}
    failures = {}
    nearest: tuple[float, str] = (math.inf, "")
    for family, names in FAMILIES.items():
        if FAMILY_JOINTS[family] != len(w):
            continue
        failed = [tests[n] for n in names if not tests[n][1] <= bound[tests[n][2]]]
        if failed:
            failures[family] = failed
            excess = max(tests[n][1] / bound[tests[n][2]] for n in names)
            nearest = min(nearest, (excess, family))
            continue
        signs = _signs(family, w)
        rows, base, tool = fit_dh(robot, signs, angle_tol)
        rows = _ideal_rows(family, rows, STRUCTURE_TOL)
        zero = _zero_lengths(family, rows, STRUCTURE_TOL)
        if zero is not None:
            failures[family] = [(zero, 0.0, "m")]
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
            deviation=_deviation(tests, names),
            residual=_residual(robot, rows, signs, base, tool),
        )
    reasons = "; ".join(
        f"not {_FAMILY_NAMES[f]}: "
        + ", ".join(f"{what} (off by {dev:.3g} {unit})" for what, dev, unit in failed)
        for f, failed in failures.items()
    )
    closest = ""
    if nearest[1]:
        found = _deviation(tests, FAMILIES[nearest[1]])
        closest = (
            f"; deviation from the nearest family ({nearest[1].upper()}): "
            f"{found.describe()}"
        )
    raise UnsupportedRobotError(
        f"robot {robot.name!r} has no closed-form IK (bound {angle_tol:g} rad, "
        f"{distance_tol:g} m): {reasons}{closest}; use numerical IK"
    )
