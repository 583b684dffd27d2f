r"""The closed-form solver of one robot: the one door into the compiled kernels.

:func:`get_closed_form` gives the :class:`ClosedFormSolver` of a robot, built on
first use and cached per robot object through a weak reference
(:func:`~workbench.model.per_robot.per_robot`). It holds what every solve of
that robot needs: the family (``"opw"``, PUMA-type, kernel
``_puma_kernel``; ``"ur"``, kernel ``_ur_kernel``), the arm's constants packed
into the kernel's record, the branch labels, and the named slots of the
kernel's flags. :func:`~workbench.ik.analytic`,
:func:`~workbench.ik.analytic_batch` and the online planner all solve through
it, so the pose checks, the wording of errors and the choice of kernel live
here once.

OPW branch labels (UR labels: :data:`UR_BRANCHES`) are physical, so that one
posture of the PUMA carries the same label in both DH models of the workbench
(and agrees with the ``l/r``, ``u/d``, ``n/f`` letters of Robotics Toolbox's
``Puma560.ikine_a``):

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
:func:`ClosedFormSolver.solve_batch`) has bits ``4·left + 2·down + flip``; UR
branches ``4·left + 2·down + wrist-down``.
"""

from __future__ import annotations

import threading
import types
import weakref
from dataclasses import FrozenInstanceError

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import DimensionError, InputError
from workbench.ik._atan2_kernel import atan2_into
from workbench.ik._kernel_common import (
    FLAG_COUNT,
    FLAG_SHOULDER_SINGULAR,
    FLAG_SOME_UNREACHED,
    FLAG_WITHIN_LIMITS,
    FLAG_WRIST_SINGULAR,
    IN_CYLINDER,
    NOT_RIGID,
    OK,
    continuing_branch,
)
from workbench.ik._puma import UnreachableError, UnsupportedRobotError
from workbench.ik._refine_kernel import refine_batch, refine_pose, refinement_chain
from workbench.ik._targets import as_targets, check_poses, pose_rows
from workbench.ik.families import BRANCHES, UR_BRANCHES, require_family
from workbench.model.per_robot import per_robot
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

#: Poses per chunk of :meth:`ClosedFormSolver.solve_batch` (its three
#: (N, N_ANGLES) buffers take 1.1–1.2 MB; chunks of 256 to 4096 poses were no
#: faster on 1M poses).
BATCH_CHUNK = 2048

_NO_PREVIOUS = np.empty(0)


class ClosedFormSolver:
    """The closed form of one robot; get it from :func:`get_closed_form`.

    Attributes:
        family: ``"opw"`` (PUMA-type) or ``"ur"``.
        branches: Branch labels, :data:`BRANCHES` or :data:`UR_BRANCHES`.
        geometry: The arm's constants, the kernel's (1,) record, read-only.
    """

    __slots__ = (
        "__weakref__", "_kernel", "_refine", "_robot", "_work", "branches", "family",
        "geometry",
    )  # fmt: skip

    def __init__(self, robot: Robot):
        """Recognise the family of ``robot`` and pack its constants.

        Raises:
            UnsupportedRobotError: If the robot has no closed form (the message
                says which axes fail which test).
        """
        family, branches, kernel, geometry = _family(robot)
        geometry.setflags(write=False)
        self.family: str = family
        self.branches = branches
        self.geometry: np.ndarray = geometry
        self._kernel: types.ModuleType = kernel
        self._robot = weakref.ref(robot)
        # the model's chain when it differs from the idealised structure
        self._refine: FloatArray | None = refinement_chain(robot)
        self._work = threading.local()  # each thread's buffers of solve_batch_into

    @property
    def robot(self) -> Robot:
        """The robot this solver was built for."""
        robot = self._robot()
        if robot is None:
            raise InputError("the robot of this closed-form solver no longer exists")
        return robot

    def __repr__(self) -> str:
        robot = self._robot()
        name = "<gone>" if robot is None else robot.name
        return f"ClosedFormSolver({name!r}, family={self.family!r})"

    # -- one pose -------------------------------------------------------------
    def solve(
        self,
        target: pin.SE3 | npt.ArrayLike,
        *,
        q_previous: npt.ArrayLike | None = None,
    ) -> list[IKSolution]:
        """Every branch that reaches ``target``: see :func:`workbench.ik.analytic`."""
        if type(target) is pin.SE3:
            pose = target.homogeneous
        elif (
            type(target) is np.ndarray
            and target.shape == (4, 4)
            and target.dtype == float
        ):
            pose = target
        else:
            pose = np.array(pose_rows(target))  # every check, with its error
        prev = _NO_PREVIOUS if q_previous is None else self._previous(q_previous)
        q, flags = np.empty((8, 6)), np.empty(FLAG_COUNT, dtype=bool)
        kernel = self._kernel
        if self._refine is not None or kernel.solve_pose(
            self.geometry, pose, prev, q, flags, True
        ):  # not OK (rechecked, or raises), or refined on the model
            q, flags = self.solve_arrays(pose, prev)
        q.setflags(write=False)
        flag_list = flags.tolist()
        shared = (q, flag_list, self.branches)
        if not flag_list[FLAG_SOME_UNREACHED]:
            return [IKSolution(shared, index) for index in _INDICES]
        reached = q[:, 0] == q[:, 0]  # False on the NaN rows of an arm out of reach
        return [IKSolution(shared, index) for index in _INDICES if reached[index]]

    def solve_arrays(
        self, pose: FloatArray, q_previous: FloatArray
    ) -> tuple[FloatArray, BoolArray]:
        """The kernel's solve of one pose, as arrays, its failures as errors.

        Args:
            pose: (4, 4) float array, the target pose of the tool frame in the
                base frame [m].
            q_previous: (6,) previous configuration [rad] (each angle is then
                the representative nearest it), or (0,) for none.

        Returns:
            ``q`` (8, 6) [rad], NaN rows for branches that do not reach, and
            ``flags`` (:data:`FLAG_COUNT`,), slots ``FLAG_*``.

        Raises:
            UnreachableError, NonFiniteError, InputError: As
                :func:`workbench.ik.analytic`.
        """
        q, flags = np.empty((8, 6)), np.empty(FLAG_COUNT, dtype=bool)
        kernel = self._kernel
        status = kernel.solve_pose(self.geometry, pose, q_previous, q, flags, True)
        if status == NOT_RIGID:  # the kernel's test is the exact one
            pose_rows(pose)  # raises the error that says why
            raise InputError("target is not a rigid transform")  # (pose_rows raised)
        if status != OK:
            self._explain(pose)
        if self._refine is not None and not refine_pose(self._refine, pose, q, flags):
            raise UnreachableError(0.0, (0.0, 0.0), "model")
        return q, flags

    def track(
        self,
        pose: FloatArray,
        q_predicted: FloatArray,
        pair: int,
        max_step2: float,
    ) -> tuple[FloatArray, int, bool]:
        """The branch that continues a motion (Kang's θ4 flip rule, generalised).

        Every angle is taken as the representative nearest the prediction;
        the branch is the nearer wrist twin of the last (arm, elbow) pair if
        within ``max_step2``, else (after a shoulder or elbow singularity) the
        nearest of all.

        Args:
            pose: (4, 4) target pose of the tool frame in the base frame [m].
            q_predicted: (6,) predicted configuration [rad], e.g. the linear
                extrapolation of the last two commands.
            pair: (Arm, elbow) pair of the last command's branch, ``index >> 1``.
            max_step2: Largest squared joint step [rad²] that keeps the pair.

        Returns:
            ``(q, index, within)``: the configuration (6,) [rad], its branch
            index and whether it is within the joint limits.

        Raises:
            UnreachableError, InputError: As :func:`workbench.ik.analytic`.
        """
        if self._refine is None:
            q = np.empty(6)
            status, index, within = self._kernel.track(
                self.geometry, pose, q_predicted, pair, max_step2, q
            )
            if status == OK:
                return q, index, within
        q_all, flags = self.solve_arrays(pose, q_predicted)  # refined, or raises
        index = continuing_branch(q_all, q_predicted, pair, max_step2)
        return q_all[index].copy(), index, bool(flags[FLAG_WITHIN_LIMITS + index])

    def _previous(self, q_previous: npt.ArrayLike) -> FloatArray:
        """``q_previous`` checked (``Robot.check_configuration``), as floats."""
        if (
            type(q_previous) is np.ndarray
            and q_previous.shape == (6,)
            and q_previous.dtype == float
            and np.isfinite(q_previous).all()
        ):
            return q_previous
        return self.robot.check_configuration(q_previous)

    def _explain(self, pose: FloatArray) -> None:
        """Raise the :class:`UnreachableError` of a pose the arm cannot reach."""
        status, distance, low, high = self._kernel.diagnose(self.geometry, pose)
        kind = "cylinder" if status == IN_CYLINDER else "reach"
        raise UnreachableError(distance, (low, high), kind)

    # -- many poses -----------------------------------------------------------
    def solve_batch(self, targets: npt.ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Every branch of N poses: see :func:`workbench.ik.analytic_batch`."""
        poses = as_targets(targets)
        count = len(poses)
        q, valid = np.empty((count, 8, 6)), np.empty((count, 8), dtype=bool)
        self.solve_batch_into(poses, q, valid)
        return q, valid

    def solve_batch_into(
        self, poses: FloatArray, q: FloatArray, valid: BoolArray
    ) -> None:
        """:meth:`solve_batch` into given arrays (no allocation of the results).

        Args:
            poses: (N, 4, 4) float64 C-contiguous poses of the tool frame in
                the base frame [m]; each is checked finite and rigid.
            q: (N, 8, 6) float64 output [rad], as :meth:`solve_batch`'s.
            valid: (N, 8) bool output.

        Raises:
            DimensionError: If the shapes do not match.
            NonFiniteError, InputError: As :func:`workbench.ik.analytic_batch`.
        """
        count = len(poses)
        for name, array, shape in (
            ("poses", poses, (count, 4, 4)),
            ("q", q, (count, 8, 6)),
            ("valid", valid, (count, 8)),
        ):
            if array.shape != shape:
                raise DimensionError(name, shape, array.shape)
        kernel, geometry = self._kernel, self.geometry
        (y, x, angles), status, exact, odd = self._batch_work()
        for start in range(0, count, BATCH_CHUNK):
            chunk = poses[start : start + BATCH_CHUNK]
            n = len(chunk)
            codes = status[:n], exact[:n], odd[:n]
            # the vectorised stage takes flat arrays, its fallback (N, 4, 4) and (N, S)
            flat = chunk.reshape(-1), y[:n].reshape(-1), x[:n].reshape(-1)
            shaped = chunk, y[:n], x[:n]
            flagged = kernel.batch_arguments(geometry, *flat, *codes, True)
            if flagged and kernel.batch_fallback(geometry, *shaped, *codes) >= 0:
                check_poses(chunk, start)  # the exact checks raise, or accept all
                if kernel.batch_arguments(geometry, *flat, *codes, False):
                    kernel.batch_fallback(geometry, *shaped, *codes)
            atan2_into(flat[1], flat[2], angles[:n].reshape(-1))
            kernel.batch_assemble(
                geometry, angles[:n], y[:n], status[:n], exact[:n],
                q[start : start + n], valid[start : start + n],
            )  # fmt: skip
        if self._refine is not None:
            refine_batch(self._refine, poses, q, valid)

    def _batch_work(self) -> tuple[FloatArray, np.ndarray, np.ndarray, np.ndarray]:
        """This thread's work arrays of :meth:`solve_batch_into`, made once.

        (3, BATCH_CHUNK, N_ANGLES) float64 stages, then the int8 status, int64
        exact flags and uint8 odd flags of BATCH_CHUNK poses. Reused by every
        call in the thread: allocating them per call made glibc map fresh
        pages each time once its mmap threshold is fixed (Dask's nanny sets
        ``MALLOC_TRIM_THRESHOLD_``), which halved the speed of small batches.
        """
        work: tuple[FloatArray, np.ndarray, np.ndarray, np.ndarray] | None
        work = getattr(self._work, "arrays", None)
        if work is None:
            work = (
                np.empty((3, BATCH_CHUNK, self._kernel.N_ANGLES)),
                np.empty(BATCH_CHUNK, dtype=np.int8),
                np.empty(BATCH_CHUNK, dtype=np.int64),
                np.empty(BATCH_CHUNK, dtype=np.uint8),
            )
            self._work.arrays = work
        return work


def _family(robot: Robot) -> tuple[str, tuple[str, ...], types.ModuleType, np.ndarray]:
    """Family name, branch labels, kernel module and packed constants of a 6R arm.

    From the robot's :class:`~workbench.ik.families.Family`
    (:func:`~workbench.ik.families.require_family`).
    """
    family = require_family(robot)
    if family.redundant:
        raise UnsupportedRobotError(
            f"robot {robot.name!r} is a seven-axis arm ({family.name.upper()} "
            "family): its closed form takes a redundancy parameter, use "
            "ik.get_redundant_solver(robot) or ik.analytic(..., redundancy=...)"
        )
    return family.name, family.branches, family.kernel, family.pack(robot)


@per_robot
def get_closed_form(robot: Robot) -> ClosedFormSolver:
    """The :class:`ClosedFormSolver` of ``robot``, cached per robot object (weakly).

    Raises:
        UnsupportedRobotError: If the robot has no closed form.
    """
    return ClosedFormSolver(robot)


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
        wrist_singular: True if |sin θ5| <= ``WRIST_SINGULAR_TOL``; θ4 and θ6
            (UR: θ6 and θ2 + θ3 + θ4) are then one member of a one-parameter
            family.
        shoulder_singular: True if the two shoulder (arm) solutions meet.

    The eight solutions of one solve share its result arrays (each ``q`` is a
    row of one read-only (8, 6) array). Equality is identity; the fields are
    read-only properties (assigning one raises
    ``dataclasses.FrozenInstanceError``).
    """

    __slots__ = ("_index", "_shared")

    def __init__(
        self, shared: tuple[FloatArray, list[bool], tuple[str, ...]], index: int
    ) -> None:
        # private: built by ClosedFormSolver.solve; shared = (q, flags, labels)
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
        return self._shared[1][FLAG_WITHIN_LIMITS + self._index]

    @property
    def wrist_singular(self) -> bool:
        """True if |sin θ5| <= ``WRIST_SINGULAR_TOL``."""
        return self._shared[1][FLAG_WRIST_SINGULAR + (self._index >> 1)]

    @property
    def shoulder_singular(self) -> bool:
        """True if the right and left arms meet (shoulder singularity).

        The wrist centre is then on the cylinder |D| around the base axis (to
        1e-10 m); on the base axis itself θ1 is free and this solution is one
        member of a one-parameter family.
        """
        return self._shared[1][FLAG_SHOULDER_SINGULAR]

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

_INDICES = tuple(range(len(BRANCHES)))

__all__ = [
    "BATCH_CHUNK",
    "BRANCHES",
    "FLAG_COUNT",
    "FLAG_SHOULDER_SINGULAR",
    "FLAG_SOME_UNREACHED",
    "FLAG_WITHIN_LIMITS",
    "FLAG_WRIST_SINGULAR",
    "UR_BRANCHES",
    "ClosedFormSolver",
    "IKSolution",
    "get_closed_form",
]
