r"""Constants of a PUMA-type arm read off its standard DH table, and its errors.

A *PUMA-type* arm here is any 6R arm whose standard DH table
(:math:`T_i = R_z(\theta_i) T_z(d_i) T_x(a_i) R_x(\alpha_i)`, with
:math:`\theta_i = q_i + \theta_{0,i}`) has

* :math:`\alpha_1 = \pm 90°` (shoulder axis z1 at right angles to the base
  axis z0, at height :math:`d_1`, at the distance :math:`a_1` from it: the
  shoulder offset of KUKA, ABB and Fanuc arms; 0 on the PUMA);
* :math:`\alpha_2 = 0` (joints 2 and 3 parallel: a planar elbow);
* :math:`\alpha_3, \alpha_4, \alpha_5 = \pm 90°` and
  :math:`a_4 = a_5 = d_5 = a_6 = 0` (a spherical wrist centred at the origin of
  frames 4 and 5; :math:`d_6` and :math:`\alpha_6` are free);
* :math:`a_2 \ne 0` and a forearm :math:`(a_3, d_4) \ne 0`; the shoulder
  offset :math:`D = d_2 + d_3` and every theta offset are free.

Both PUMA models of the workbench are of this type, with opposite signs of
:math:`\alpha_1, \alpha_4, \alpha_5`. A robot without a DH table (any URDF)
gets one fitted to its joint axes by :mod:`workbench.ik.structure`, with a
joint sign per axis (θ = s q + θ0) and the constant base and tool transforms
folded into the target.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from workbench.errors import UnsupportedRobotError
from workbench.ik.structure import get_structure
from workbench.model.dh import DHTable
from workbench.model.per_robot import per_robot
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]

TAU = 2.0 * math.pi

#: Tolerance on the DH angles and lengths that must be exactly 0 or ±90°.
_DH_TOL = 1e-12

#: Joint values this far [rad] beyond a limit still count as within it, so that
#: a configuration recovered to rounding from one at its limit is not rejected.
LIMIT_TOL = 1e-9


#: |sin θ5| at or below which the wrist counts as singular (z3 ∥ z5). θ4 and θ6
#: are then split by continuity; the split costs at most this times π of
#: orientation error, so the tolerance is kept below the 1e-9 accuracy goal.
WRIST_SINGULAR_TOL = 1e-10

#: |sin| of the elbow angle (OPW: γ = θ3 + β; UR: θ3) at or below which the
#: elbow counts as singular (stretched or folded: elbow-up and elbow-down
#: meet). The sine is the root of 1 − cos², so a pose at the singularity
#: rounded to 1e-16 gives about 1e-8: the tolerance is above that.
ELBOW_SINGULAR_TOL = 1e-7

#: The reach tests of a fitted structure are widened by this many times its
#: residual (``KinematicStructure.residual``, the FK difference of the model
#: and the idealised chain on a few configurations): a pose the model reaches
#: may lie that far outside the idealised arm's reach. It is then clamped onto
#: the idealised boundary and refined on the model (``_refine_kernel``), which
#: reports it as not reached if it truly is not.
MODEL_ERROR_SLACK = 10.0


def _one_turn(lower: float, upper: float) -> bool:
    """Whether a joint's value is its angle in (−π, π]: limits inside or around it."""
    inside = lower >= -math.pi and upper <= math.pi
    return inside or (lower <= -math.pi and upper >= math.pi)


@dataclass(frozen=True, slots=True)
class PumaGeometry:
    r"""What the closed form needs of one robot, computed once.

    Signs :math:`\sigma_i = \operatorname{sign}\alpha_i` are ±1.0. The forearm,
    seen in frame 2 at :math:`\theta_3 = 0`, is the vector
    :math:`(a_3, -\sigma_3 d_4) = L(\cos\beta, \sin\beta)`.

    Attributes:
        sigma1, sigma3, sigma4, sigma5: Signs of alpha 1, 3, 4, 5.
        d1: Shoulder height on the base axis [m].
        offset: Shoulder offset :math:`D = d_2 + d_3` along z1 [m].
        a1: Shoulder offset along x1, from the base axis to the shoulder [m].
        a2: Upper arm length [m].
        forearm: :math:`L = \sqrt{a_3^2 + d_4^2}` [m].
        cos_beta, sin_beta: Direction of the forearm in frame 2.
        up_sign: Sign of :math:`\sin\gamma` (γ = θ3 + β) of the elbow-up
            solution of a right arm; the left arm's is the opposite.
        d6: Tool offset along z5 [m].
        cos_alpha6, sin_alpha6: Twist of the last row.
        theta_offset: Theta offsets, (6,) [rad].
        lower, upper: Joint limits of the robot, (6,) [rad].
        plain: Per joint, True when the DH angle in (−π, π] is the joint
            value: zero offset, unit sign, and limits inside [−π, π] (no other
            turn is within them) or containing it (it always is).
        bounds: ``(lower - LIMIT_TOL, upper + LIMIT_TOL)``, the tests of
            "within limits".
        joint_sign: DH angle θ = s q + θ0 per joint, (6,) of ±1.0.
        base_inv: (4, 4) inverse of the pose of DH frame 0 in the base frame.
        tool_inv: (4, 4) inverse of the pose of the tool in DH frame 6.
        reach: Reachable distance of the wrist centre from the shoulder (the
            point on axis 2 nearest axis 1), in the arm's plane when
            a1 != 0, ``(low, high)`` [m].
        reach_test: ``(low, high, cylinder)``: the distance bounds of the
            kernel's reach tests with their slack folded in, and the squared
            radius below which the wrist centre is inside the cylinder.
    """

    sigma1: float
    sigma3: float
    sigma4: float
    sigma5: float
    d1: float
    offset: float
    a1: float
    a2: float
    forearm: float
    cos_beta: float
    sin_beta: float
    up_sign: float
    d6: float
    cos_alpha6: float
    sin_alpha6: float
    theta_offset: tuple[float, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    plain: tuple[bool, ...]
    joint_sign: tuple[float, ...]
    base_inv: np.ndarray
    tool_inv: np.ndarray
    bounds: tuple[tuple[float, ...], tuple[float, ...]]
    reach: tuple[float, float]
    reach_test: tuple[float, float, float]


def _sign_of_right_angle(
    alpha: float, name: str, robot: str, tol: float = _DH_TOL
) -> float:
    for sign in (1.0, -1.0):
        if abs(math.remainder(alpha - sign * math.pi / 2.0, TAU)) <= tol:
            return sign
    raise UnsupportedRobotError(
        f"robot {robot!r} is not PUMA-type: {name} = {math.degrees(alpha):.6g} deg, "
        "closed-form IK needs ±90 deg"
    )


def _require_zero(value: float, name: str, robot: str) -> None:
    if abs(value) > _DH_TOL:
        raise UnsupportedRobotError(
            f"robot {robot!r} is not PUMA-type: {name} = {value:.6g}, closed-form "
            "IK needs 0"
        )


def geometry_from_dh(
    table: DHTable,
    lower: npt.ArrayLike,
    upper: npt.ArrayLike,
    *,
    joint_sign: tuple[float, ...] = (1.0,) * 6,
    base: npt.ArrayLike | None = None,
    tool: npt.ArrayLike | None = None,
    model_error: float = 0.0,
) -> PumaGeometry:
    """Check that ``table`` is PUMA-type and compute its constants.

    Args:
        table: Standard DH table of the arm.
        lower: Lower joint limits, shape (6,) [rad].
        upper: Upper joint limits, shape (6,) [rad].
        joint_sign: DH angle θ = s q + θ0 per joint, (6,) of ±1.
        base: (4, 4) pose of DH frame 0 in the base frame; None for identity.
        tool: (4, 4) pose of the tool in the last DH frame; None for identity.
        model_error: FK difference [m] of the robot's model and this table
            (0 for the table of the model itself); the reach tests are widened
            by :data:`MODEL_ERROR_SLACK` times it.

    Raises:
        UnsupportedRobotError: If the table is not PUMA-type (the message names
            the first offending parameter).
    """
    name = table.name
    if table.nq != 6:
        raise UnsupportedRobotError(
            f"robot {name!r} has {table.nq} joints, closed-form IK needs 6"
        )
    j1, j2, j3, j4, j5, j6 = table.joints
    sigma1 = _sign_of_right_angle(j1.alpha, "alpha1", name)
    sigma3 = _sign_of_right_angle(j3.alpha, "alpha3", name)
    sigma4 = _sign_of_right_angle(j4.alpha, "alpha4", name)
    sigma5 = _sign_of_right_angle(j5.alpha, "alpha5", name)
    _require_zero(math.remainder(j2.alpha, TAU), "alpha2", name)
    for value, label in ((j4.a, "a4"), (j5.a, "a5"), (j5.d, "d5")):
        _require_zero(value, label, name)
    _require_zero(j6.a, "a6", name)
    forearm = math.hypot(j3.a, j4.d)
    if abs(j2.a) <= _DH_TOL or forearm <= _DH_TOL:
        raise UnsupportedRobotError(
            f"robot {name!r} is not PUMA-type: needs a2 != 0 and (a3, d4) != 0"
        )
    offset = j2.d + j3.d
    lower_t = tuple(float(x) for x in np.asarray(lower, dtype=np.float64))
    upper_t = tuple(float(x) for x in np.asarray(upper, dtype=np.float64))
    offsets = tuple(j.theta_offset for j in table.joints)
    signs = tuple(float(x) for x in joint_sign)
    plain = tuple(
        o == 0.0 and s == 1.0 and _one_turn(lo, hi)
        for o, s, lo, hi in zip(offsets, signs, lower_t, upper_t, strict=True)
    )
    if j1.a == 0.0:  # distance in 3-D from the shoulder, the offset included
        reach = (
            math.hypot(abs(j2.a) - forearm, offset),
            math.hypot(abs(j2.a) + forearm, offset),
        )
    else:  # distance in the arm's plane, per arm
        reach = (abs(abs(j2.a) - forearm), abs(j2.a) + forearm)
    slack = 1e-12 * reach[1] + MODEL_ERROR_SLACK * model_error
    radius = max(abs(offset) - MODEL_ERROR_SLACK * model_error, 0.0)
    return PumaGeometry(
        sigma1=sigma1,
        sigma3=sigma3,
        sigma4=sigma4,
        sigma5=sigma5,
        d1=j1.d,
        offset=offset,
        a1=j1.a,
        a2=j2.a,
        forearm=forearm,
        cos_beta=j3.a / forearm,
        sin_beta=-sigma3 * j4.d / forearm,
        up_sign=-sigma1 * math.copysign(1.0, j2.a),
        d6=j6.d,
        cos_alpha6=math.cos(j6.alpha),
        sin_alpha6=math.sin(j6.alpha),
        theta_offset=offsets,
        lower=lower_t,
        upper=upper_t,
        plain=plain,
        joint_sign=signs,
        base_inv=np.linalg.inv(np.eye(4) if base is None else np.asarray(base)),
        tool_inv=np.linalg.inv(np.eye(4) if tool is None else np.asarray(tool)),
        bounds=(
            tuple(x - LIMIT_TOL for x in lower_t),
            tuple(x + LIMIT_TOL for x in upper_t),
        ),
        reach=reach,
        reach_test=(
            reach[0] - slack,
            reach[1] + slack,
            radius * radius * (1.0 - 1e-12),
        ),
    )


@per_robot
def get_geometry(robot: Robot) -> PumaGeometry:
    """The :class:`PumaGeometry` of a robot, built on first use and cached.

    From the robot's DH table when it has one and the tool frame is the
    table's last frame (the PUMA models); else from the DH chain fitted to its
    joint axes (:func:`~workbench.ik.structure.get_structure`), base and tool
    transforms included.

    Cached per robot object, weakly (:func:`~workbench.model.per_robot.per_robot`):
    a lookup costs no hashing of the DH table, and a robot with other limits
    (:meth:`Robot.with_limits`) is another key.

    Raises:
        UnsupportedRobotError: If the robot is not of the OPW/PUMA family.
    """
    table = robot.dh_table
    if table is not None and robot.tool_frame == table.tool_frame:
        with contextlib.suppress(UnsupportedRobotError):  # else: from the axes
            return geometry_from_dh(table, robot.lower, robot.upper)
    structure = get_structure(robot)
    if structure.family != "opw":
        raise UnsupportedRobotError(
            f"robot {robot.name!r} is of the {structure.family.upper()} family, "
            "not PUMA/OPW"
        )
    return geometry_from_dh(
        structure.table,
        robot.lower,
        robot.upper,
        joint_sign=structure.joint_sign,
        base=structure.base,
        tool=structure.tool,
        model_error=structure.residual,
    )
