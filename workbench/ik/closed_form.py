r"""Closed-form inverse kinematics of OPW (PUMA-type) and UR-type arms.

The solution is derived from the robot's own DH table when it has one (the
PUMA models, see :mod:`workbench.ik._puma` for which tables qualify), else from
the DH chain fitted to its joint axes (:mod:`workbench.ik.structure`, which
recognises the family), not from one printed table; ``docs/errata-kang-ik.md``
derives the OPW solution and lists what is wrong in Kang (2007)'s printed
formulas, ``docs/closed-form-ik.md`` covers any arm. The target is always the
pose of the robot's tool frame: base and tool transforms are folded in.

OPW branch labels (UR labels: :data:`UR_BRANCHES`, defined in
:mod:`workbench.ik._ur_kernel`) are physical, so that one posture of the PUMA
carries the same label in both DH models of the workbench (and agrees with the
``l/r``, ``u/d``, ``n/f`` letters of Robotics Toolbox's ``Puma560.ikine_a``):

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

import types
from collections.abc import Sequence
from dataclasses import FrozenInstanceError
from functools import lru_cache

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.ik import _puma_kernel as kernel
from workbench.ik import _ur_kernel as ur_kernel
from workbench.ik._atan2_kernel import atan2_into
from workbench.ik._puma import (
    TAU,
    WRIST_SINGULAR_TOL,
    UnreachableError,
    UnsupportedRobotError,
    check_reach,
    get_geometry,
)
from workbench.ik._targets import as_targets, check_poses, pose_rows
from workbench.ik.structure import get_structure
from workbench.model.robot import Robot
from workbench.validation import as_vector

FloatArray = npt.NDArray[np.float64]

#: Branch names; index = 4·left + 2·down + flip.
BRANCHES: tuple[str, ...] = tuple(
    f"{arm}/elbow-{elbow}/{wrist}"
    for arm in ("right", "left")
    for elbow in ("up", "down")
    for wrist in ("no-flip", "flip")
)

#: Branch names of UR-type arms; index = 4·left + 2·down + wrist-down.
UR_BRANCHES: tuple[str, ...] = tuple(
    f"shoulder-{arm}/elbow-{elbow}/wrist-{wrist}"
    for arm in ("right", "left")
    for elbow in ("up", "down")
    for wrist in ("up", "down")
)


@lru_cache(maxsize=16)
def get_solver(robot: Robot) -> tuple[str, types.ModuleType, np.ndarray]:
    """The closed form of a robot: family, compiled kernel, packed constants.

    Cached per robot object. The family is ``"opw"`` for PUMA-type arms
    (``_puma_kernel``) and ``"ur"`` (``_ur_kernel``).

    Raises:
        UnsupportedRobotError: If the robot has no closed form (the message
            says which axes fail which test).
    """
    table = robot.dh_table
    if table is None or robot.tool_frame != table.tool_frame:
        structure = get_structure(robot)
    else:
        try:
            return "opw", kernel, kernel.packed_geometry(robot)
        except UnsupportedRobotError:  # the table is not PUMA-type: the axes
            structure = get_structure(robot)
    if structure.family == "ur":
        return (
            "ur",
            ur_kernel,
            ur_kernel.pack_geometry(structure, robot.lower, robot.upper),
        )
    return "opw", kernel, kernel.packed_geometry(robot)


def get_branches(robot: Robot) -> tuple[str, ...]:
    """Branch labels of a robot's closed form (:data:`BRANCHES` or UR's)."""
    return UR_BRANCHES if get_solver(robot)[0] == "ur" else BRANCHES


class IKSolution:
    """One closed-form branch (immutable).

    Attributes:
        q: Configuration, shape (6,) [rad], read-only; each angle is the
            representative (mod 2π) within the joint limits when one is, else
            in (−π, π] — or, when ``q_previous`` was given, the one nearest it.
        branch: Label, e.g. ``"right/elbow-up/no-flip"`` (see module docs) or
            ``"shoulder-left/elbow-up/wrist-down"`` (UR-type arms).
        index: Position of ``branch`` in :data:`BRANCHES` (UR:
            :data:`UR_BRANCHES`).
        within_limits: True if every joint of ``q`` is within its limits.
        wrist_singular: True if |sin θ5| <= :data:`WRIST_SINGULAR_TOL`; θ4 and θ6
            (UR: θ6 and θ2 + θ3 + θ4) are then one member of a one-parameter
            family.
        shoulder_singular: True if the two shoulder (arm) solutions meet.

    The eight solutions of one :func:`analytic` call share its result arrays
    (each ``q`` is a row of one read-only (8, 6) array). Equality is identity;
    the fields are read-only properties (assigning one raises
    ``dataclasses.FrozenInstanceError``).
    """

    __slots__ = ("_index", "_shared")

    def __init__(
        self, shared: tuple[FloatArray, list[bool], tuple[str, ...]], index: int
    ) -> None:
        # private: built by analytic(); shared = (q of the 8 branches, flags)
        self._shared = shared
        self._index = index

    @property
    def q(self) -> FloatArray:
        """Configuration (6,) [rad], read-only."""
        return self._shared[0][self._index]

    @property
    def branch(self) -> str:
        """Label, e.g. ``"right/elbow-up/no-flip"``."""
        return self._shared[2][self._index]

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
        return self._shared[1][8 + (self._index >> 1)]

    @property
    def shoulder_singular(self) -> bool:
        """True if the right and left arms meet (shoulder singularity).

        The wrist centre is then on the cylinder |D| around the base axis (to
        1e-10 m); on the base axis itself θ1 is free and this solution is one
        member of a one-parameter family.
        """
        return self._shared[1][12]

    def __repr__(self) -> str:
        return (
            f"IKSolution(q={self.q!r}, branch={self.branch!r}, index={self.index}, "
            f"within_limits={self.within_limits}, "
            f"wrist_singular={self.wrist_singular}, "
            f"shoulder_singular={self.shoulder_singular})"
        )

    def __reduce__(self) -> tuple[object, tuple[object, ...]]:
        return (IKSolution, (self._shared, self._index))


def _frozen_field(name: str) -> property:
    """``IKSolution.<name>`` with a setter and deleter that raise, as frozen."""
    getter = IKSolution.__dict__[name].fget

    def refuse(self: IKSolution, *value: object) -> None:
        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    return property(getter, refuse, refuse, getter.__doc__)


for _name in (
    "q",
    "branch",
    "index",
    "within_limits",
    "wrist_singular",
    "shoulder_singular",
):
    setattr(IKSolution, _name, _frozen_field(_name))
del _name


def analytic(
    robot: Robot,
    target: pin.SE3 | npt.ArrayLike,
    *,
    q_previous: npt.ArrayLike | None = None,
) -> list[IKSolution]:
    """Every closed-form IK branch of an OPW (PUMA-type) or UR-type arm.

    Args:
        robot: A 6R arm of either family (see :mod:`workbench.ik.structure`):
            ``puma560``, ``puma560-kang``, ``ur5``, a KUKA/ABB/Fanuc URDF, ...
        target: Pose of the robot's tool frame in the base frame: ``pin.SE3``
            or a (4, 4) homogeneous matrix [m].
        q_previous: Optional configuration (6,) [rad] of the previous path
            sample. Each returned angle is then the representative (mod 2π)
            nearest to it, and at a wrist singularity θ4/θ6 are split so that
            the step from ``q_previous`` is shortest (else θ4 = 0).

    Returns:
        One :class:`IKSolution` per branch that reaches the pose, in the order
        of the labels (:data:`BRANCHES`, UR: :data:`UR_BRANCHES`): all eight
        unless a shoulder offset (a1 != 0, or a UR arm) lets only some reach.
        At a shoulder or elbow singularity some coincide; at a wrist
        singularity the flip twin is the continuity member turned by π.

    Raises:
        UnsupportedRobotError: If the robot has no closed form.
        UnreachableError: If the wrist centre is out of reach or inside the
            cylinder of radius |D| (the shoulder offset) around the base axis.
        DimensionError: If ``target`` is not (4, 4) or ``q_previous`` not (6,).
        NonFiniteError: If an entry is NaN or infinite.
        InputError: If ``target`` is not rigid (see ``poses.RIGIDITY_TOL``).
    """
    family, solver, geometry = get_solver(robot)
    if type(target) is pin.SE3:
        pose = target.homogeneous
    elif (
        type(target) is np.ndarray and target.shape == (4, 4) and target.dtype == float
    ):
        pose = target
    else:
        pose = np.array(pose_rows(target))  # every check, with its error
    prev = _NO_PREVIOUS if q_previous is None else _previous(robot, q_previous)
    q, flags = solve_one(robot, geometry, pose, prev, solver)
    q.setflags(write=False)
    flag_list = flags.tolist()
    shared = (q, flag_list, UR_BRANCHES if family == "ur" else BRANCHES)
    if not flag_list[13]:
        return [IKSolution(shared, index) for index in _INDICES]
    reached = q[:, 0] == q[:, 0]  # False on the NaN rows of an arm out of reach
    return [IKSolution(shared, index) for index in _INDICES if reached[index]]


_INDICES = tuple(range(len(BRANCHES)))
_NO_PREVIOUS = np.empty(0)


def _previous(robot: Robot, q_previous: npt.ArrayLike) -> FloatArray:
    """``q_previous`` checked (``Robot.check_configuration``), as floats."""
    if (
        type(q_previous) is np.ndarray
        and q_previous.shape == (6,)
        and q_previous.dtype == float
        and np.isfinite(q_previous).all()
    ):
        return q_previous
    return robot.check_configuration(q_previous)


def solve_one(
    robot: Robot,
    geometry: np.ndarray,
    pose: FloatArray,
    prev: FloatArray,
    solver: types.ModuleType = kernel,
) -> tuple[FloatArray, npt.NDArray[np.bool_]]:
    """The kernel's solve of one pose, its failures turned into errors.

    Args:
        robot: The robot ``geometry`` was packed from.
        geometry: ``get_solver(robot)[2]``.
        pose: (4, 4) float array, the target.
        prev: (6,) previous configuration [rad], or (0,) for none.
        solver: ``get_solver(robot)[1]``, the compiled kernel module.

    Returns:
        ``q`` (8, 6) [rad] and ``flags`` (12,): within limits per branch, then
        wrist singular per (arm, elbow) pair (see ``_puma_kernel.solve_pose``).

    Raises:
        UnreachableError, NonFiniteError, InputError: As :func:`analytic`.
    """
    q, flags = np.empty((8, 6)), np.empty(14, dtype=bool)
    status = solver.solve_pose(geometry, pose, prev, q, flags, True)
    if status == kernel.NOT_RIGID:  # the exact checks raise, or accept it
        pose_rows(pose)
        status = solver.solve_pose(geometry, pose, prev, q, flags, False)
    if status != kernel.OK:
        if solver is ur_kernel:
            _explain_ur(geometry, pose)
        check_reach(get_geometry(robot), *kernel.wrist_centre(geometry[0], pose))
    return q, flags


def _explain_ur(geometry: np.ndarray, pose: FloatArray) -> None:
    """Raise the :class:`UnreachableError` of a pose a UR-type arm cannot reach."""
    status, distance = ur_kernel.diagnose(geometry, pose)
    geo = geometry[0]
    if status == ur_kernel.IN_CYLINDER:
        radius = abs(float(geo["offset"]))
        raise UnreachableError(distance, (radius, radius), "cylinder")
    a2, a3 = abs(float(geo["a2"])), abs(float(geo["a3"]))
    raise UnreachableError(distance, (abs(a2 - a3), a2 + a3), "reach")


def analytic_batch(
    robot: Robot, targets: npt.ArrayLike
) -> tuple[FloatArray, npt.NDArray[np.bool_]]:
    """Every closed-form IK branch of N poses, vectorised.

    The kernel of :func:`analytic` in three stages per chunk of poses: the
    arguments of every atan2 (a compiled loop that LLVM vectorises, four poses
    at a time; the rare singular poses after it, one by one), all the atan2 in
    one compiled loop that LLVM vectorises (:mod:`workbench.ik._atan2_kernel`,
    several times faster than one libm call each), the joint values (compiled
    loop).

    Args:
        robot: A 6R arm of either family (as :func:`analytic`).
        targets: Shape (N, 4, 4), homogeneous poses of the tool frame in the
            base frame [m].

    Returns:
        ``q`` of shape (N, 8, 6) [rad], branch axis in the order of
        :data:`BRANCHES`, wrapped as by :func:`analytic` (θ4 = 0 at a wrist
        singularity), equal to it up to the last bits of the atan2; and
        ``valid`` of shape (N, 8), True where the branch reaches the pose
        (every branch, unless a shoulder offset a1 or a UR arm lets only some
        reach). Rows of branches that do not reach are NaN. Joint limits are
        not applied: test ``(robot.lower <= q) & (q <= robot.upper)`` for that.

    Raises:
        UnsupportedRobotError: If the robot has no closed form.
        DimensionError: If ``targets`` is not (N, 4, 4).
        NonFiniteError: If an entry is NaN or infinite.
        InputError: If a pose is not rigid (``poses.RIGIDITY_TOL``).
    """
    _, solver, geometry = get_solver(robot)
    poses = as_targets(targets)
    count = len(poses)
    q, valid = np.empty((count, 8, 6)), np.empty((count, 8), dtype=bool)
    size = min(count, _CHUNK)
    y, x, angles = np.empty((3, size, solver.N_ANGLES))
    status = np.empty(size, dtype=np.int8)
    exact = np.empty(size, dtype=np.int64)
    odd = np.empty(size, dtype=np.uint8)
    for start in range(0, count, _CHUNK):
        chunk = poses[start : start + _CHUNK]
        n = len(chunk)
        codes = status[:n], exact[:n], odd[:n]
        # the vectorised stage takes flat arrays, its fallback (N, 4, 4) and (N, S)
        flat = chunk.reshape(-1), y[:n].reshape(-1), x[:n].reshape(-1)
        shaped = chunk, y[:n], x[:n]
        flagged = solver.batch_arguments(geometry, *flat, *codes, True)
        if flagged and solver.batch_fallback(geometry, *shaped, *codes) >= 0:
            check_poses(chunk, start)  # the exact checks raise, or accept all
            if solver.batch_arguments(geometry, *flat, *codes, False):
                solver.batch_fallback(geometry, *shaped, *codes)
        atan2_into(flat[1], flat[2], angles[:n].reshape(-1))
        solver.batch_assemble(
            geometry, angles[:n], y[:n], status[:n], exact[:n],
            q[start : start + n], valid[start : start + n],
        )  # fmt: skip
    return q, valid


#: Poses per chunk of :func:`analytic_batch` (its three (N, N_ANGLES) buffers
#: take 1.1–1.2 MB; chunks of 256 to 4096 poses were no faster on 1M poses).
_CHUNK = 2048


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


__all__ = [
    "BRANCHES",
    "UR_BRANCHES",
    "WRIST_SINGULAR_TOL",
    "IKSolution",
    "UnreachableError",
    "UnsupportedRobotError",
    "analytic",
    "analytic_batch",
    "nearest",
]
