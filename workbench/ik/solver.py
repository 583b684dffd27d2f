r"""The closed form of one robot, for every family: the one door into the kernels.

:func:`get_solver` gives the :class:`Solver` of a robot, built on first use and
cached per robot object through a weak reference
(:func:`~workbench.model.per_robot.per_robot`). One type serves every family:
six-axis arms (``"opw"``, PUMA-type, kernel ``_puma_kernel``; ``"ur"``, kernel
``_ur_kernel``; no redundancy, ``parameter`` None) and seven-axis arms
(``"srs"``, spherical shoulder, elbow and wrist, e.g. the KUKA LBR iiwa,
kernel ``_srs_kernel``, parameter the arm angle ψ; ``"franka"``, the Franka
Panda/FR3 geometry, kernel ``_franka_kernel``, parameter q7), whose closed form
takes the value of the redundancy parameter (``redundancy=`` [rad]). It holds
what every solve of that robot needs: the family, the arm's constants packed
into the kernel's record, the branch labels; it checks every input, calls the
family's compiled kernel and words its failures.
:func:`~workbench.ik.analytic`, :func:`~workbench.ik.analytic_batch`, the
redundancy choice, the online planner, the workspace atlas and the command
line all solve through it. Every solve returns
:class:`~workbench.ik.IKSolution`\ s, whose flags are the per-branch bits of
:mod:`workbench.ik._flags` (one encoding for every kernel).

On a model that is of its family only up to its rounding, or a calibrated
arm within ``CALIBRATION_ANGLE_TOL`` and ``CALIBRATION_DISTANCE_TOL`` of it
(:attr:`Solver.deviation`), every reached branch is then carried to the
model's own chain (``_refine_kernel``, ``_refine_redundant_kernel``; a
seven-axis arm with the parameter held): exact to 1e-12 there too; a branch
without a solution of the model does not reach, and what could not be placed
is the solve's :class:`~workbench.ik.SolveFlag` byte
(``Solutions.solve_flags``, the third value of :meth:`Solver.solve_arrays`,
``solve_batch(..., solve_flags=)``).

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
:meth:`Solver.solve_batch`) has bits ``4·left + 2·down + flip``; UR
branches ``4·left + 2·down + wrist-down``.
Seven-axis labels: :data:`~workbench.ik.SRS_BRANCHES`,
:data:`~workbench.ik.FRANKA_BRANCHES` (index order: the kernels' module docs).
"""

from __future__ import annotations

import functools
import math
import threading
import types
import weakref
from typing import Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench._compiled import (
    compile_in_background,
    interpreted,
    is_compiled,
    is_interpreting,
)
from workbench.errors import (
    DimensionError,
    InputError,
    UnreachableError,
    UnsupportedRobotError,
)
from workbench.ik import _refine_redundant_kernel as refine_redundant
from workbench.ik import _srs_kernel
from workbench.ik._atan2_kernel import atan2_into
from workbench.ik._chain import compiled_entry
from workbench.ik._flags import SOLUTIONS_UNLISTED, WITHIN_LIMITS
from workbench.ik._kernel_common import (
    IN_CYLINDER,
    NOT_RIGID,
    OK,
    continuing_branch,
    nearest_or_kept,
)
from workbench.ik._puma import MODEL_ERROR_SLACK
from workbench.ik._refine_kernel import refine_batch, refine_pose, refinement_chain
from workbench.ik._targets import as_targets, check_poses, pose_rows
from workbench.ik.families import BRANCHES, UR_BRANCHES, Family, require_family
from workbench.ik.redundant import (
    FeasibleRedundancy,
    check_redundancy,
    feasible_union,
    format_intervals,
)
from workbench.ik.solution import Solutions
from workbench.ik.structure import StructureDeviation, get_structure
from workbench.model.per_robot import per_robot
from workbench.model.robot import Robot
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
FlagArray = npt.NDArray[np.uint8]

#: Poses per chunk of a six-axis :meth:`Solver.solve_batch` (its three
#: (N, N_ANGLES) buffers take 1.1–1.2 MB; chunks of 256 to 4096 poses were no
#: faster on 1M poses).
BATCH_CHUNK = 2048
#: Poses per chunk of the rigidity check of a seven-axis
#: :meth:`Solver.solve_batch` (4096: 50 ns a pose, in cache; 65536 and more
#: were 30 % slower).
CHECK_CHUNK = 4096

_NO_PREVIOUS = np.empty(0)
_FLOAT64 = np.dtype(np.float64)
_UINT8 = np.dtype(np.uint8)
_empty = np.empty
_NDARRAY = np.ndarray
_INF = math.inf
_solutions = Solutions.from_arrays
#: The SRS record the refinement of a Franka arm is given (it holds q7, not ψ).
_NO_ARM_ANGLE = np.zeros(1, dtype=_srs_kernel.GEOMETRY_DTYPE)
_NO_ARM_ANGLE.setflags(write=False)


class Solver:
    """The closed form of one robot, any family; get it from :func:`get_solver`.

    Attributes:
        family: The robot's :class:`~workbench.ik.Family` (name ``"opw"``,
            PUMA-type, or ``"ur"``: 6R; ``"srs"`` or ``"franka"``: 7R), from
            which the solver is built: kernel, packing, branches, parameter.
        branches: Branch labels (:data:`BRANCHES`, :data:`UR_BRANCHES`,
            ``SRS_BRANCHES``, ``FRANKA_BRANCHES``).
        nq: Joint count, 6 or 7.
        parameter: The redundancy parameter as messages name it: ``"arm
            angle"`` (ψ) or ``"q7"``; None on a six-axis arm.
        parameter_range: ``(low, high)`` [rad]: (−π, π) for ψ, joint 7's
            limits for q7; None on a six-axis arm.
        geometry: The arm's constants, the kernel's (1,) record, read-only.
    """

    __slots__ = (
        "__weakref__", "_arm_angle_geometry", "_indices", "_intervals",
        "_kernel", "_name", "_refine", "_refine_pose", "_robot", "_slack",
        "_solve_pose", "_warm", "_work", "branches",
        "family", "geometry", "nq", "parameter", "parameter_range",
    )  # fmt: skip

    def __init__(self, robot: Robot):
        """Recognise the family of ``robot`` and pack its constants.

        Raises:
            UnsupportedRobotError: If the robot has no closed form (the message
                says which axes fail which test).
        """
        family = require_family(robot)
        geometry = family.pack(robot)
        geometry.setflags(write=False)
        self.family: Family = family
        self.geometry: np.ndarray = geometry
        kernel = family.kernel
        self._kernel: types.ModuleType = kernel
        # the kernel's solve_pose; its compiled code itself after the first call
        self._solve_pose: Any = self._first_solve_pose
        # the refinement's refine_pose (calibrated arms), likewise
        self._refine_pose: Any = self._first_refine_pose
        # whether this process has the compiled kernels of solve (_compiling)
        self._warm = False
        self._robot = weakref.ref(robot)
        self._name = robot.name  # for the messages
        # the model's chain when it differs from the idealised structure
        self._refine: FloatArray | None = refinement_chain(robot)
        # how far past the idealised arm's reach the model may reach [m]
        self._slack = (
            0.0
            if self._refine is None
            else MODEL_ERROR_SLACK * get_structure(robot).residual
        )
        self._work = threading.local()  # each thread's buffers of solve_batch_into
        self.nq: int = family.joint_count
        self.branches: tuple[str, ...] = family.branches
        self.parameter: str | None = family.parameter
        self.parameter_range: tuple[float, float] | None = None
        self._intervals = family.feasible_intervals
        # the arm angle (SRS) is no joint: its refinement needs the SRS record
        self._arm_angle_geometry = (
            geometry if family.parameter_periodic else _NO_ARM_ANGLE
        )
        if family.redundant:
            lo, hi = kernel.parameter_range(geometry)
            self.parameter_range = (float(lo), float(hi))
        self._indices = tuple(range(len(self.branches)))

    @property
    def robot(self) -> Robot:
        """The robot this solver was built for."""
        robot = self._robot()
        if robot is None:
            raise InputError("the robot of this solver no longer exists")
        return robot

    @property
    def deviation(self) -> StructureDeviation | None:
        """How far the robot's model is from its family's ideal structure.

        The ``deviation`` of its :class:`~workbench.ik.KinematicStructure`:
        the largest angle [rad] and distance [m] of the family's tests
        (``.calibrated`` when beyond URDF rounding, ``STRUCTURE_TOL``); None
        for a PUMA DH table whose axes fit no structure.
        """
        try:
            structure = get_structure(self.robot)
        except UnsupportedRobotError:  # a PUMA DH table the axes do not fit
            return None
        return structure.deviation

    def __repr__(self) -> str:
        robot = self._robot()
        name = "<gone>" if robot is None else robot.name
        return f"Solver({name!r}, family={self.family.name!r})"

    # -- one pose -------------------------------------------------------------
    def solve(
        self,
        target: pin.SE3 | npt.ArrayLike,
        *,
        redundancy: float | None = None,
        q_previous: npt.ArrayLike | None = None,
    ) -> Solutions:
        """Every branch that reaches ``target``: see :func:`workbench.ik.analytic`.

        Args:
            target: Pose of the tool frame in the base frame: ``pin.SE3`` or a
                (4, 4) homogeneous matrix [m].
            redundancy: Seven-axis arms: the redundancy parameter [rad] (ψ or
                q7); None takes that of ``q_previous``. Six-axis arms: None.
            q_previous: Optional configuration (nq,) [rad]; each angle is then
                the representative (mod 2π) nearest it.

        Returns:
            The :class:`~workbench.ik.Solutions` of the solve: one
            :class:`~workbench.ik.IKSolution` per branch that reaches, in the
            order of ``branches``, built when read.

        Raises:
            UnreachableError: If no branch reaches the pose (the message says
                why).
            DimensionError, NonFiniteError, InputError: Bad target,
                ``redundancy`` or ``q_previous`` (a value given for a six-axis
                arm, none for a seven-axis arm without ``q_previous``).
        """
        if (
            target.__class__ is _NDARRAY
            and target.shape == (4, 4)
            and target.dtype is _FLOAT64
        ):
            pose = target
        elif target.__class__ is pin.SE3:
            pose = target.homogeneous
        else:
            pose = np.array(pose_rows(target))  # every check, with its error
        prev = _NO_PREVIOUS if q_previous is None else self._previous(q_previous)
        if not self._warm and self._compiling(pose, redundancy):
            with interpreted():  # milliseconds, while the kernels compile
                return self.solve(pose, redundancy=redundancy, q_previous=q_previous)
        if self.parameter is None:
            if redundancy is not None:
                raise self._no_redundancy()
            q, flags = _empty((8, 6)), _empty(8, _UINT8)  # (positional: faster)
            events = 0
            if self._solve_pose(self.geometry, pose, prev, q, flags, True):
                q, flags, events = self.solve_arrays(pose, prev)  # (raises)
            elif self._refine is not None:  # carried to the model's chain
                events = self._refine_pose(self._refine, pose, q, flags)
                if not flags.any():
                    raise UnreachableError(0.0, (0.0, 0.0), "model")
        else:
            if redundancy is None:
                if q_previous is None:
                    raise self._missing_redundancy()
                redundancy = float(self.parameter_of(prev))
            elif redundancy.__class__ is not float or not -_INF < redundancy < _INF:
                redundancy = check_redundancy(redundancy, self.parameter)
            q, flags = _empty((8, 7)), _empty(8, _UINT8)
            events = 0
            if self._solve_pose(self.geometry, pose, redundancy, prev, q, flags, True):
                q, flags, events = self.solve_arrays(pose, prev, redundancy=redundancy)
            elif self._refine is not None:
                events = self._refine_pose(
                    self._refine, self._arm_angle_geometry,
                    self.family.parameter_periodic, pose, redundancy, q, flags,
                )  # fmt: skip
                if not flags.any():
                    raise UnreachableError(0.0, (0.0, 0.0), "model")
        return _solutions(q, flags, self.branches, redundancy, events)

    def _compiling(self, pose: FloatArray, redundancy: float | None) -> bool:
        """Whether :meth:`solve`'s kernels compile in a background thread now.

        The first solve of a process whose kernels are not compiled (nor
        loaded from the cache) yet starts that thread, which runs them once on
        a copy of ``pose`` (``_compiled.compile_in_background``); this solve
        and the next ones run as Python (under a millisecond each, the same
        results to the last bits) until it has finished, instead of waiting
        the seconds of a first compile. A solve within ``interpreted`` runs as
        Python anyway.
        """
        if is_interpreting():
            return False
        refine = refine_pose if self.parameter is None else refine_redundant.refine_pose
        if is_compiled(self._kernel.solve_pose) and (
            self._refine is None or is_compiled(refine)
        ):
            self._warm = True
            return False
        if self.parameter is not None and redundancy is None:
            lo, hi = self.parameter_range or (0.0, 0.0)
            redundancy = 0.5 * (lo + hi)
        key = (self.family.name, self._refine is not None)
        warm_up = functools.partial(self._warm_up, pose.copy(), redundancy)
        if compile_in_background(key, warm_up):
            return True
        self._warm = True  # (a compile that failed raises in the call itself)
        return False

    def _warm_up(self, pose: FloatArray, redundancy: float | None) -> None:
        """Call :meth:`solve`'s kernels once on ``pose`` (compiling them)."""
        q = np.full((len(self._indices), self.nq), np.nan)
        flags = np.zeros(len(self._indices), dtype=np.uint8)
        if redundancy is None:
            status = self._kernel.solve_pose(
                self.geometry, pose, _NO_PREVIOUS, q, flags, True
            )
        else:
            status = self._kernel.solve_pose(
                self.geometry, pose, redundancy, _NO_PREVIOUS, q, flags, True
            )
        if self._refine is None:
            return
        if status != OK:  # nothing to carry, but the kernel compiles all the same
            q[:], flags[:] = np.nan, 0
        self._refined(self._refine, pose, redundancy, q, flags)

    def _first_solve_pose(self, *args: Any) -> int:
        """The kernel's ``solve_pose``, then its compiled code for later calls.

        Numba's dispatcher types every argument of every call to choose the
        compiled code (~0.3 µs of a solve); :meth:`solve` passes arguments of
        the one signature only (a float64 (4, 4) pose, float64 or empty
        ``q_previous``, a float parameter, fresh outputs), so that after the
        first call (which compiles, or loads from the cache) the compiled
        entry point is called directly (``_chain.compiled_entry``).
        """
        status = int(self._kernel.solve_pose(*args))
        if not is_interpreting():
            self._solve_pose = compiled_entry(self._kernel.solve_pose, args)
        return status

    def _first_refine_pose(self, *args: Any) -> int:
        """The refinement's ``refine_pose``, then its compiled code for later calls.

        As :meth:`_first_solve_pose`: :meth:`solve` passes the one signature's
        arguments (the packed chain, a float64 (4, 4) pose, fresh outputs).
        """
        kernel = refine_pose if self.parameter is None else refine_redundant.refine_pose
        events = int(kernel(*args))
        if not is_interpreting():
            self._refine_pose = compiled_entry(kernel, args)
        return events

    def solve_arrays(
        self,
        pose: FloatArray,
        q_previous: FloatArray,
        *,
        redundancy: float | None = None,
    ) -> tuple[FloatArray, FlagArray, int]:
        """The kernel's solve of one pose, as arrays, its failures as errors.

        Args:
            pose: (4, 4) float array, the target pose of the tool frame in the
                base frame [m].
            q_previous: (nq,) previous configuration [rad] (each angle is then
                the representative nearest it), or (0,) for none.
            redundancy: Seven-axis arms: the redundancy parameter [rad],
                finite (required); six-axis arms: None.

        Returns:
            ``q`` (B, nq) [rad], NaN rows for branches that do not reach, and
            ``flags`` (B,) uint8, the bits of :class:`~workbench.ik.Flag` per
            branch (0 where it does not reach), and the solve-level byte, the
            bits of :class:`~workbench.ik.SolveFlag` (0 on an exact model: on
            a calibrated arm, a branch of the idealised arm vanished or merged
            on the model, or solutions may be unlisted).

        Raises:
            UnreachableError, NonFiniteError, InputError: As :meth:`solve`.
        """
        count = len(self._indices)
        q, flags = np.empty((count, self.nq)), np.empty(count, dtype=np.uint8)
        if self.parameter is None:
            status = self._kernel.solve_pose(
                self.geometry, pose, q_previous, q, flags, True
            )
        else:
            if redundancy is None:
                raise self._missing_redundancy()
            status = self._kernel.solve_pose(
                self.geometry, pose, redundancy, q_previous, q, flags, True
            )
        if status != OK:
            if self._refine is not None and status != NOT_RIGID:
                self._raise_near_reach(pose, redundancy)
            self._raise(status, pose, redundancy)
        chain = self._refine
        if chain is None:
            return q, flags, 0
        solve_flags = self._refined(chain, pose, redundancy, q, flags)
        if not flags.any():
            raise UnreachableError(0.0, (0.0, 0.0), "model")
        return q, flags, solve_flags

    def _refined(
        self,
        chain: FloatArray,
        pose: FloatArray,
        value: float | None,
        q: FloatArray,
        flags: FlagArray,
    ) -> int:
        """Carry the branches ``q`` (B, nq) to the model's own chain, in place.

        Rows without a solution of the model are NaN, their ``flags`` 0; the
        ``REACHED`` and ``WITHIN_LIMITS`` bits are those of the model.

        Returns:
            The solve-level byte (:class:`~workbench.ik.SolveFlag` bits).
        """
        if value is None:
            return int(refine_pose(chain, pose, q, flags))
        return int(
            refine_redundant.refine_pose(
                chain, self._arm_angle_geometry, self.family.parameter_periodic,
                pose, value, q, flags,
            )
        )  # fmt: skip

    def track(
        self,
        pose: FloatArray,
        q_predicted: FloatArray,
        branch: int,
        max_step2: float,
        *,
        redundancy: float | None = None,
    ) -> tuple[FloatArray, int, bool]:
        """The branch that continues a motion (for the online planner).

        Every angle is taken as the representative nearest the prediction.
        Six-axis arms (Kang's θ4 flip rule, generalised): the nearer wrist
        twin of the last (arm, elbow) pair, ``branch >> 1``, if within
        ``max_step2``; seven-axis arms: the branch itself if within
        ``max_step2``; else (after a singularity) the nearest of all.

        Args:
            pose: (4, 4) float64 target pose of the tool frame in the base
                frame [m].
            q_predicted: (nq,) predicted configuration [rad], e.g. the linear
                extrapolation of the last two commands.
            branch: Index of the last command's branch.
            max_step2: Largest squared joint step [rad²] that keeps it.
            redundancy: Seven-axis arms: the redundancy parameter [rad],
                finite (required); six-axis arms: None.

        Returns:
            ``(q, index, within)``: the configuration (nq,) [rad], its branch
            index and whether it is within the joint limits.

        Raises:
            UnreachableError, InputError: As :meth:`solve`.
        """
        found = self.try_track(
            pose, q_predicted, branch, max_step2, redundancy=redundancy
        )
        if found is None:  # raises the error that says why
            self.solve_arrays(pose, q_predicted, redundancy=redundancy)
            raise UnreachableError(0.0, (0.0, 0.0), "model")  # (it raised)
        return found

    def try_track(
        self,
        pose: FloatArray,
        q_predicted: FloatArray,
        branch: int,
        max_step2: float,
        *,
        redundancy: float | None = None,
    ) -> tuple[FloatArray, int, bool] | None:
        """:meth:`track`, but None where no branch reaches (no error is built).

        For callers that probe values of the parameter (the online planner):
        the error of :meth:`track` says why a pose is out of reach, which
        takes a search over the parameter (milliseconds for q7).

        Returns:
            ``(q, index, within)`` as :meth:`track`, or None if the kernel's
            status is not OK (the pose out of reach, or not rigid).
        """
        seven = self.parameter is not None
        if seven and redundancy is None:
            raise self._missing_redundancy()
        if self._refine is None:
            q = np.empty(self.nq)
            if seven:
                status, index, within = self._kernel.track(
                    self.geometry, pose, redundancy, q_predicted, branch, max_step2, q
                )
            else:
                status, index, within = self._kernel.track(
                    self.geometry, pose, q_predicted, branch >> 1, max_step2, q
                )
            return (q, index, bool(within)) if status == OK else None
        chain, count = self._refine, len(self._indices)
        q_all = np.empty((count, self.nq))
        flags = np.empty(count, dtype=np.uint8)
        if seven:
            status = self._kernel.solve_pose(
                self.geometry, pose, redundancy, q_predicted, q_all, flags, True
            )
        else:
            status = self._kernel.solve_pose(
                self.geometry, pose, q_predicted, q_all, flags, True
            )
        if status != OK:
            return None
        self._refined(chain, pose, redundancy, q_all, flags)
        if not flags.any():
            return None
        if seven:
            index = int(nearest_or_kept(q_all, q_predicted, branch, max_step2))
        else:
            index = int(continuing_branch(q_all, q_predicted, branch >> 1, max_step2))
        return q_all[index].copy(), index, bool(flags[index] & WITHIN_LIMITS)

    def diagnose(
        self, pose: FloatArray, *, redundancy: float | None = None
    ) -> tuple[float, float, float]:
        """How far the wrist point is from the shoulder, and the arm's reach.

        Args:
            pose: (4, 4) float64 pose of the tool frame in the base frame [m].
            redundancy: Seven-axis arms: the redundancy parameter [rad] (a
                Franka arm's wrist point turns with q7; an SRS arm's wrist
                centre does not depend on ψ); six-axis arms: None.

        Returns:
            ``(distance, low, high)`` [m]: the distance of the wrist centre
            (Franka: wrist point) from the shoulder and the interval of
            distances the arm reaches; on a six-axis arm whose wrist centre
            is inside the cylinder of its shoulder offset, its distance from
            the base axis and ``(radius, radius)``.
        """
        if self.parameter is None:
            _, distance, low, high = self._kernel.diagnose(self.geometry, pose)
        else:
            value = 0.0 if redundancy is None else redundancy
            _, distance, low, high = self._kernel.diagnose(self.geometry, pose, value)
        return float(distance), float(low), float(high)

    def _previous(self, q_previous: npt.ArrayLike) -> FloatArray:
        """``q_previous`` checked (``Robot.check_configuration``), as floats."""
        if (
            type(q_previous) is np.ndarray
            and q_previous.shape == (self.nq,)
            and q_previous.dtype == float
            and np.isfinite(q_previous).all()
        ):
            return q_previous
        return self.robot.check_configuration(q_previous)

    def _no_redundancy(self) -> InputError:
        return InputError(
            f"robot {self._name!r} has {self.nq} joints and no redundancy: call "
            "without redundancy="
        )

    def _missing_redundancy(self) -> InputError:
        return InputError(
            f"robot {self._name!r} is a seven-axis arm: give redundancy= "
            f"(the {self.parameter} [rad]; ik.choose_redundancy(robot, target) "
            "chooses one, ik.get_solver(robot).parameter_of(q) reads it from a "
            "configuration), or q_previous= to keep its value"
        )

    def _near_reach(self, pose: FloatArray, value: float | None) -> bool:
        """Whether the idealised arm misses ``pose`` by at most the model's slack.

        On a calibrated arm the kernels' reach tests are widened by
        ``MODEL_ERROR_SLACK`` times the structure's residual; a pose they
        still refuse within that distance of the idealised reach (or, inside
        the reach, refused by another of the idealised arm's tests) may be
        reached by the model, whose solutions are then unlisted.
        """
        distance, low, high = self.diagnose(pose, redundancy=value)
        return low - self._slack <= distance <= high + self._slack

    def _raise_near_reach(self, pose: FloatArray, value: float | None) -> None:
        """Raise ``UnreachableError(kind="model")`` if :meth:`_near_reach`."""
        if not self._near_reach(pose, value):
            return
        distance, low, high = self.diagnose(pose, redundancy=value)
        raise UnreachableError(
            distance,
            (low, high),
            "model",
            f"the idealised {self.family.name.upper()} arm does not reach the pose "
            f"(wrist point at {distance:.6g} m from the shoulder, reach [{low:.6g}, "
            f"{high:.6g}] m), but within the model's deviation ({self._slack:.2g} m): "
            "the calibrated model may reach it, and its solutions are not listed; "
            "use numerical IK",
        )

    def _raise(self, status: int, pose: FloatArray, value: float | None) -> None:
        """Raise the error of a pose the kernel refused (``status`` not OK)."""
        if status == NOT_RIGID:  # the kernel's test is the exact one
            pose_rows(pose)  # raises the error that says why
            raise InputError("target is not a rigid transform")  # (pose_rows raised)
        if self.parameter is None:
            status, distance, low, high = self._kernel.diagnose(self.geometry, pose)
            kind = "cylinder" if status == IN_CYLINDER else "reach"
            raise UnreachableError(distance, (low, high), kind)
        distance, low, high = self.diagnose(pose, redundancy=value)
        if self.family.parameter_periodic:  # the SRS reach does not depend on ψ
            message = (
                f"out of reach for every arm angle: wrist centre at distance "
                f"{distance:.6g} m from the shoulder, reach is [{low:.6g}, "
                f"{high:.6g}] m"
            )
        else:
            union = self.feasible(pose).union
            reach = (
                f"feasible {self.parameter} (every joint within its limits): "
                f"{format_intervals(union)} rad"
                if union
                else f"no {self.parameter} reaches it within the joint limits"
            )
            where = (
                f"the wrist point ({distance:.6g} m from the shoulder) is within "
                f"the elbow's reach [{low:.6g}, {high:.6g}] m, but axis 5 cannot "
                "be normal to axis 6 there"
                if low <= distance <= high
                else f"wrist point at distance {distance:.6g} m from the "
                f"shoulder, the elbow reaches [{low:.6g}, {high:.6g}] m"
            )
            message = (
                f"out of reach for {self.parameter} = {value:.6g} rad: {where}; {reach}"
            )
        raise UnreachableError(distance, (low, high), "reach", message)

    # -- many poses -----------------------------------------------------------
    def solve_batch(
        self,
        targets: npt.ArrayLike,
        *,
        redundancy: float | npt.ArrayLike | None = None,
        solve_flags: FlagArray | None = None,
    ) -> tuple[FloatArray, BoolArray]:
        """Every branch of N poses: see :func:`workbench.ik.analytic_batch`.

        Args:
            targets: (N, 4, 4) poses of the tool frame in the base frame [m].
            redundancy: Seven-axis arms, required: the redundancy parameter
                [rad], one for all or (N,); six-axis arms: None.
            solve_flags: Optional (N,) uint8 output: each pose's solve-level
                byte, the bits of :class:`~workbench.ik.SolveFlag` (0 on an
                exact model; on a calibrated arm what carrying the branches to
                the model could not place).

        Returns:
            ``q`` (N, B, nq) [rad], NaN where a branch does not reach;
            ``valid`` (N, B), True where it reaches. Joint limits are not
            applied.

        Raises:
            DimensionError, NonFiniteError: Bad shapes or entries.
            InputError: If a pose is not rigid (``poses.RIGIDITY_TOL``), or
                ``redundancy`` is given for a six-axis arm or missing for a
                seven-axis arm.
        """
        poses = as_targets(targets)
        count = len(poses)
        q = np.empty((count, len(self._indices), self.nq))
        valid = np.empty((count, len(self._indices)), dtype=bool)
        self.solve_batch_into(
            poses, q, valid, redundancy=redundancy, solve_flags=solve_flags
        )
        return q, valid

    def solve_batch_into(
        self,
        poses: FloatArray,
        q: FloatArray,
        valid: BoolArray,
        *,
        redundancy: float | npt.ArrayLike | None = None,
        solve_flags: FlagArray | None = None,
    ) -> None:
        """:meth:`solve_batch` into given arrays (no allocation of the results).

        Args:
            poses: (N, 4, 4) float64 C-contiguous poses of the tool frame in
                the base frame [m]; each is checked finite and rigid.
            q: (N, B, nq) float64 output [rad], as :meth:`solve_batch`'s.
            valid: (N, B) bool output.
            redundancy: As :meth:`solve_batch`.
            solve_flags: As :meth:`solve_batch`: optional (N,) uint8 output.

        Raises:
            DimensionError: If the shapes do not match.
            NonFiniteError, InputError: As :meth:`solve_batch`.
        """
        count, branches = len(poses), len(self._indices)
        for name, array, shape in (
            ("poses", poses, (count, 4, 4)),
            ("q", q, (count, branches, self.nq)),
            ("valid", valid, (count, branches)),
        ):
            if array.shape != shape:
                raise DimensionError(name, shape, array.shape)
        if solve_flags is not None:
            if solve_flags.shape != (count,):
                raise DimensionError("solve_flags", (count,), solve_flags.shape)
            if solve_flags.dtype != _UINT8:
                raise InputError(
                    f"solve_flags must be a uint8 array, got {solve_flags.dtype}"
                )
            solve_flags[:] = 0
        events = np.empty(count, _UINT8) if solve_flags is None else solve_flags
        if self.parameter is None:
            if redundancy is not None:
                raise self._no_redundancy()
            self._batch_six(poses, q, valid)
            if self._refine is not None:
                refine_batch(self._refine, poses, q, valid, events)
                self._flag_near_reach(poses, None, valid, events)
            return
        if redundancy is None:
            raise self._missing_redundancy()
        for start in range(0, count, CHECK_CHUNK):
            check_poses(poses[start : start + CHECK_CHUNK], start)
        if np.ndim(redundancy) == 0:
            values = np.full(count, check_redundancy(redundancy, self.parameter))
        else:
            values = as_finite_array(redundancy, (count,), "redundancy")
        values = np.ascontiguousarray(values)
        self._kernel.solve_batch(self.geometry, poses, values, q, valid)
        if self._refine is not None:
            refine_redundant.refine_batch(
                self._refine, self._arm_angle_geometry, self.family.parameter_periodic,
                poses, values, q, valid, events,
            )  # fmt: skip
            self._flag_near_reach(poses, values, valid, events)

    def _flag_near_reach(
        self,
        poses: FloatArray,
        values: FloatArray | None,
        valid: BoolArray,
        events: FlagArray,
    ) -> None:
        """``SOLUTIONS_UNLISTED`` on the poses of a batch :meth:`_near_reach` says.

        (Those no branch reaches and no other bit explains, on a calibrated
        arm.)
        """
        for i in np.flatnonzero(~valid.any(axis=1) & (events == 0)).tolist():
            value = None if values is None else float(values[i])
            if self._near_reach(poses[i], value):
                events[i] |= SOLUTIONS_UNLISTED

    def _batch_six(self, poses: FloatArray, q: FloatArray, valid: BoolArray) -> None:
        """The six-axis kernels' three batch stages, chunk by chunk."""
        kernel, geometry = self._kernel, self.geometry
        (y, x, angles), status, exact, odd = self._batch_work()
        for start in range(0, len(poses), BATCH_CHUNK):
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

    def _batch_work(self) -> tuple[FloatArray, np.ndarray, np.ndarray, np.ndarray]:
        """This thread's work arrays of the six-axis batch, made once.

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

    # -- the redundancy parameter -------------------------------------------------
    def parameter_of(self, q: npt.ArrayLike) -> float | FloatArray:
        """The redundancy parameter [rad] of configurations of a seven-axis arm.

        Args:
            q: (7,) or (N, 7) robot joint values [rad].

        Returns:
            A float for (7,), an (N,) array for (N, 7): ψ in [−π, π] (SRS; the
            θ1 = 0 reference when the wrist centre is on axis 1) or q7. On a
            model off its idealised structure (a rounded URDF) ψ is that of
            the idealised chain at ``q``, the value the refinement holds, so
            that :meth:`solve` at it gives ``q`` back.

        Raises:
            InputError: On a six-axis arm (no redundancy).
            DimensionError, NonFiniteError: Bad shape or entries.
        """
        if self.parameter is None:
            raise self._no_redundancy()
        arr = np.asarray(q, dtype=np.float64) if not isinstance(q, np.ndarray) else q
        if arr.ndim == 2:
            rows = as_finite_array(arr, (arr.shape[0], 7), "q")
            out = np.empty(len(rows))
            self._kernel.parameter_of(self.geometry, rows, out)
            return out
        one = self.robot.check_configuration(q)
        value = np.empty(1)
        self._kernel.parameter_of(self.geometry, one.reshape(1, 7), value)
        return float(value[0])

    def feasible(self, target: pin.SE3 | npt.ArrayLike) -> FeasibleRedundancy:
        """The values of the parameter that reach ``target`` within the limits.

        Args:
            target: Pose of the tool frame in the base frame: ``pin.SE3`` or a
                (4, 4) homogeneous matrix [m].

        Returns:
            Per branch and in union, the closed intervals of the parameter
            [rad] (empty when the pose is out of reach or out of the limits):
            analytic for SRS arms, bisected to 1e-12 rad for Franka arms.

        Raises:
            InputError: On a six-axis arm (no redundancy).
            DimensionError, NonFiniteError, InputError: Bad target.
        """
        if (
            self.parameter is None
            or self.parameter_range is None
            or self._intervals is None
        ):
            raise self._no_redundancy()
        pose = np.array(pose_rows(target))
        found = self._intervals(self.geometry, pose)
        intervals = tuple(
            tuple((float(lo), float(hi)) for lo, hi in branch) for branch in found
        )
        return FeasibleRedundancy(
            parameter=self.parameter,
            range=self.parameter_range,
            branches=self.branches,
            intervals=intervals,
            union=feasible_union(intervals),
            circular=self.family.parameter_periodic,
        )


@per_robot
def get_solver(robot: Robot) -> Solver:
    """The :class:`Solver` of ``robot``, cached per robot object (weakly).

    Raises:
        UnsupportedRobotError: If the robot has no closed form (the message
            says which axes fail which test).
    """
    return Solver(robot)


__all__ = [
    "BATCH_CHUNK",
    "BRANCHES",
    "CHECK_CHUNK",
    "UR_BRANCHES",
    "Solver",
    "get_solver",
]
