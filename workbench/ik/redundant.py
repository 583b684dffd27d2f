r"""The closed form of one seven-axis arm: the one door into the 7R kernels.

A seven-axis arm of a supported family (:mod:`workbench.ik.structure`:
``"srs"``, spherical shoulder, elbow and wrist, e.g. the KUKA LBR iiwa;
``"franka"``, the Franka Panda/FR3 geometry) has, for one tool pose, a
one-parameter family of configurations per branch. Fixing the redundancy
parameter leaves finitely many:

* SRS: the arm angle ψ [rad] in (−π, π], the angle, right-handed about the unit
  vector from the shoulder S to the wrist W, from the reference plane (S, E0,
  W: the arm with θ3 = 0 reaching the same W) to the arm plane (S, E, W); 8
  branches (:data:`SRS_BRANCHES`), kernel :mod:`workbench.ik._srs_kernel`;
* Franka: q7 [rad], the robot's own value of joint 7, within its limits; 8
  branches (:data:`FRANKA_BRANCHES`), kernel :mod:`workbench.ik._franka_kernel`.

:func:`get_redundant_solver` gives a robot's :class:`RedundantSolver`, built on
first use and cached per robot object (weakly). It checks every input, calls
the family's compiled kernel and words its failures; ``workbench.ik.analytic``
(``redundancy=``), the redundancy choice (:mod:`workbench.ik.redundancy`), the
online planner and the command line all solve through it.

On a model that is of its family only up to its rounding (a URDF written with
4 decimals: the xArm7), every reached branch is then refined on the model's
own chain, the parameter held (:mod:`workbench.ik._refine_redundant_kernel`):
exact to 1e-12 there too; a branch that does not converge does not reach.
"""

from __future__ import annotations

import math
import types
import weakref
from dataclasses import FrozenInstanceError, dataclass
from typing import cast

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError, NonFiniteError
from workbench.ik import _franka_kernel, _refine_redundant_kernel, _srs_kernel
from workbench.ik._kernel_common import nearest_or_kept
from workbench.ik._puma import UnreachableError
from workbench.ik._redundant_common import (
    ELBOW_SINGULAR,
    NOT_RIGID,
    OK,
    PARAMETER_SINGULAR,
    SHOULDER_SINGULAR,
    WITHIN_LIMITS,
    WRIST_SINGULAR,
)
from workbench.ik._refine_kernel import refinement_chain
from workbench.ik._targets import as_targets, check_poses, pose_rows
from workbench.ik.families import Family, IntervalFunction, require_family
from workbench.ik.structure import UnsupportedRobotError
from workbench.model.per_robot import per_robot
from workbench.model.robot import Robot
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

#: Branch labels of SRS arms (index order: ``_srs_kernel``'s module docs).
SRS_BRANCHES: tuple[str, ...] = _srs_kernel.BRANCHES
#: Branch labels of Franka arms (index order: ``_franka_kernel``'s module docs).
FRANKA_BRANCHES: tuple[str, ...] = _franka_kernel.BRANCHES

#: Poses per chunk of the rigidity check of :meth:`RedundantSolver.solve_batch`
#: (4096: 50 ns a pose, in cache; 65536 and more were 30 % slower).
CHECK_CHUNK = 4096

_NO_PREVIOUS = np.empty(0)
#: The SRS record the refinement of a Franka arm is given (it holds q7, not ψ).
_NO_ARM_ANGLE = np.zeros(1, dtype=_srs_kernel.GEOMETRY_DTYPE)
_NO_ARM_ANGLE.setflags(write=False)
_FLOAT64 = np.dtype(np.float64)


@dataclass(frozen=True, slots=True)
class FeasibleRedundancy:
    """The values of the redundancy parameter that reach one pose within the limits.

    Attributes:
        parameter: ``"arm angle"`` (SRS, ψ) or ``"q7"`` (Franka).
        range: ``(low, high)`` [rad], every value the parameter takes: (−π, π)
            for ψ, joint 7's limits for q7.
        branches: The branch labels, in the order of ``intervals``.
        intervals: Per branch, sorted disjoint closed intervals ``(lo, hi)``
            [rad] of the parameter where that branch reaches the pose with
            every joint within its limits.
        union: Sorted disjoint closed intervals [rad] where some branch does.
        circular: True for the arm angle (SRS): ψ and ψ + 2π are one arm, so
            an interval ending at π and one starting at −π are one arc
            through ±π (they stay two here, each within ``range``); False
            for q7, a joint with limits.
    """

    parameter: str
    range: tuple[float, float]
    branches: tuple[str, ...]
    intervals: tuple[tuple[tuple[float, float], ...], ...]
    union: tuple[tuple[float, float], ...]
    circular: bool


class RedundantIKSolution:
    """One branch of a seven-axis arm for one value of the redundancy parameter.

    Immutable (assigning a field raises ``dataclasses.FrozenInstanceError``);
    the solutions of one solve share its read-only result arrays.

    Attributes:
        q: Configuration (7,) [rad], read-only: each angle the representative
            (mod 2π) within the joint limits when one is, else in (−π, π] — or
            the one nearest ``q_previous`` when it was given.
        branch: Label, one of the solver's ``branches``.
        index: Position of ``branch`` in the solver's ``branches``.
        redundancy: The value of the redundancy parameter [rad] (ψ or q7).
        within_limits: True if every joint of ``q`` is within its limits.
        shoulder_singular: The branch meets its shoulder twin.
        elbow_singular: The branch meets its elbow twin.
        wrist_singular: The branch meets its wrist twin.
        parameter_singular: The parameter is degenerate here (SRS: the wrist
            centre on axis 1, where the arm angle's reference plane is taken
            with θ1 = 0).
    """

    __slots__ = ("_index", "_shared")

    _index: int
    _shared: tuple[FloatArray, list[int], tuple[str, ...], float]

    def __init__(
        self,
        shared: tuple[FloatArray, list[int], tuple[str, ...], float],
        index: int,
    ) -> None:
        # private: built by RedundantSolver.solve; shared = (q, flags, labels, value)
        object.__setattr__(self, "_shared", shared)
        object.__setattr__(self, "_index", index)

    def __setattr__(self, name: str, value: object) -> None:
        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name: str) -> None:
        raise FrozenInstanceError(f"cannot delete field {name!r}")

    @property
    def q(self) -> FloatArray:
        """Configuration (7,) [rad], read-only."""
        return self._shared[0][self._index]

    @property
    def branch(self) -> str:
        """Branch label."""
        return self._shared[2][self._index]

    @property
    def index(self) -> int:
        """Position of ``branch`` in the solver's ``branches``."""
        return self._index

    @property
    def redundancy(self) -> float:
        """Value of the redundancy parameter [rad]."""
        return self._shared[3]

    @property
    def within_limits(self) -> bool:
        """True if every joint is within its limits."""
        return self._shared[1][self._index] & WITHIN_LIMITS != 0

    @property
    def shoulder_singular(self) -> bool:
        """True if the branch meets its shoulder twin."""
        return self._shared[1][self._index] & SHOULDER_SINGULAR != 0

    @property
    def elbow_singular(self) -> bool:
        """True if the branch meets its elbow twin."""
        return self._shared[1][self._index] & ELBOW_SINGULAR != 0

    @property
    def wrist_singular(self) -> bool:
        """True if the branch meets its wrist twin."""
        return self._shared[1][self._index] & WRIST_SINGULAR != 0

    @property
    def parameter_singular(self) -> bool:
        """True if the redundancy parameter is degenerate at this pose."""
        return self._shared[1][self._index] & PARAMETER_SINGULAR != 0

    def __repr__(self) -> str:
        return (
            f"RedundantIKSolution(q={self.q!r}, branch={self.branch!r}, "
            f"index={self.index}, redundancy={self.redundancy!r}, "
            f"within_limits={self.within_limits}, "
            f"shoulder_singular={self.shoulder_singular}, "
            f"elbow_singular={self.elbow_singular}, "
            f"wrist_singular={self.wrist_singular}, "
            f"parameter_singular={self.parameter_singular})"
        )

    def __reduce__(self) -> tuple[object, tuple[object, ...]]:
        return (RedundantIKSolution, (self._shared, self._index))


def check_redundancy(value: object, parameter: str) -> float:
    """A value of the redundancy parameter as a finite float [rad].

    Raises:
        InputError: If it is not a real number (a bool is not).
        NonFiniteError: If it is NaN or infinite.
    """
    if isinstance(value, bool) or not isinstance(value, int | float | np.number):
        if isinstance(value, np.ndarray) and value.shape == ():
            return check_redundancy(value[()], parameter)
        raise InputError(f"redundancy ({parameter}) must be a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise NonFiniteError(f"redundancy ({parameter}) must be finite, got {number}")
    return number


def _union(
    intervals: tuple[tuple[tuple[float, float], ...], ...],
) -> tuple[tuple[float, float], ...]:
    """Sorted disjoint closed intervals covering those of every branch."""
    merged: list[list[float]] = []
    for lo, hi in sorted(iv for branch in intervals for iv in branch):
        if merged and lo <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], hi)
        else:
            merged.append([lo, hi])
    return tuple((lo, hi) for lo, hi in merged)


def format_intervals(intervals: tuple[tuple[float, float], ...]) -> str:
    """``"[a, b], [c, d]"`` with 6 significant digits [rad]."""
    return ", ".join(f"[{lo:.6g}, {hi:.6g}]" for lo, hi in intervals)


class RedundantSolver:
    """The closed form of one seven-axis arm; get it from :func:`get_redundant_solver`.

    Attributes:
        family: ``"srs"`` or ``"franka"``.
        branches: Branch labels (:data:`SRS_BRANCHES`, :data:`FRANKA_BRANCHES`).
        parameter: The redundancy parameter as messages name it: ``"arm
            angle"`` (ψ) or ``"q7"``.
        parameter_range: ``(low, high)`` [rad]: (−π, π) for ψ, joint 7's
            limits for q7.
        geometry: The arm's constants, the kernel's (1,) record, read-only.
    """

    __slots__ = (
        "__weakref__", "_arm_angle_geometry", "_family", "_indices", "_kernel",
        "_refine", "_robot", "branches", "family", "geometry", "parameter",
        "parameter_range",
    )  # fmt: skip

    def __init__(self, robot: Robot):
        """Recognise the family of ``robot`` and pack its constants.

        Raises:
            UnsupportedRobotError: If the robot is not a seven-axis arm of a
                supported family (the message says which axes fail which
                test, or points a six-axis arm to ``get_closed_form``).
        """
        family = require_family(robot)
        if not family.redundant:
            raise UnsupportedRobotError(
                f"robot {robot.name!r} is a six-axis arm ({family.name.upper()} "
                "family) with no redundancy: use ik.get_closed_form(robot), or "
                "ik.analytic without redundancy="
            )
        kernel = family.kernel
        geometry = family.pack(robot)
        geometry.setflags(write=False)
        self.family: str = family.name
        self._family: Family = family
        self.branches: tuple[str, ...] = kernel.BRANCHES
        self.parameter: str = kernel.PARAMETER
        lo, hi = kernel.parameter_range(geometry)
        self.parameter_range: tuple[float, float] = (float(lo), float(hi))
        self.geometry: np.ndarray = geometry
        self._kernel: types.ModuleType = kernel
        self._robot = weakref.ref(robot)
        self._indices = tuple(range(len(self.branches)))
        # the model's own chain where it is not exactly the idealised one
        # (a rounded URDF): every branch is then refined on it
        self._refine: FloatArray | None = refinement_chain(robot)
        self._arm_angle_geometry: np.ndarray = (
            geometry if self.family == "srs" else _NO_ARM_ANGLE
        )

    @property
    def robot(self) -> Robot:
        """The robot this solver was built for."""
        robot = self._robot()
        if robot is None:
            raise InputError("the robot of this redundant solver no longer exists")
        return robot

    def __repr__(self) -> str:
        robot = self._robot()
        name = "<gone>" if robot is None else robot.name
        return f"RedundantSolver({name!r}, family={self.family!r})"

    # -- one pose -------------------------------------------------------------
    def solve(
        self,
        target: pin.SE3 | npt.ArrayLike,
        value: float,
        *,
        q_previous: npt.ArrayLike | None = None,
    ) -> list[RedundantIKSolution]:
        """Every branch that reaches ``target`` for one value of the parameter.

        Args:
            target: Pose of the tool frame in the base frame: ``pin.SE3`` or
                a (4, 4) homogeneous matrix [m].
            value: The redundancy parameter [rad]: ψ (SRS) or q7 (Franka).
            q_previous: Optional configuration (7,) [rad]; each angle is then
                the representative (mod 2π) nearest it.

        Returns:
            One :class:`RedundantIKSolution` per branch that reaches, in the
            order of ``branches``.

        Raises:
            UnreachableError: If no branch reaches the pose for this value
                (the message says why, and for q7 which values reach).
            DimensionError, NonFiniteError, InputError: Bad target, value or
                ``q_previous``.
        """
        if (
            target.__class__ is np.ndarray
            and target.shape == (4, 4)
            and target.dtype is _FLOAT64
        ):
            pose = target
        elif target.__class__ is pin.SE3:
            pose = target.homogeneous
        else:
            pose = np.array(pose_rows(target))  # every check, with its error
        if value.__class__ is not float or not -math.inf < value < math.inf:
            value = check_redundancy(value, self.parameter)
        prev = _NO_PREVIOUS if q_previous is None else self._previous(q_previous)
        q, flags = self.solve_arrays(pose, value, prev)
        q.setflags(write=False)
        shared = (q, flags.tolist(), self.branches, value)
        first = q[:, 0].tolist()
        return [
            RedundantIKSolution(shared, i)
            for i in self._indices
            if first[i] == first[i]
        ]

    def solve_arrays(
        self, pose: FloatArray, value: float, q_previous: FloatArray
    ) -> tuple[FloatArray, npt.NDArray[np.uint8]]:
        """The kernel's solve of one pose, as arrays, its failures as errors.

        Args:
            pose: (4, 4) float64 target pose of the tool frame in the base
                frame [m].
            value: The redundancy parameter [rad], finite.
            q_previous: (7,) configuration [rad] (each angle is then the
                representative nearest it), or (0,) for none.

        Returns:
            ``q`` (B, 7) [rad], NaN rows for branches that do not reach, and
            ``flags`` (B,) uint8, bits :data:`WITHIN_LIMITS`,
            :data:`SHOULDER_SINGULAR`, :data:`ELBOW_SINGULAR`,
            :data:`WRIST_SINGULAR`, :data:`PARAMETER_SINGULAR` (re-exported
            here from the kernels' common module).

        Raises:
            UnreachableError, InputError: As :meth:`solve`.
        """
        q = np.empty((len(self._indices), 7))
        flags = np.empty(len(self._indices), dtype=np.uint8)
        status = self._kernel.solve_pose(
            self.geometry, pose, value, q_previous, q, flags, True
        )
        if status != OK:
            self._raise(status, pose, value)
        chain = self._refine
        if chain is not None and not self._refined(chain, pose, value, q, flags):
            raise UnreachableError(0.0, (0.0, 0.0), "model")
        return q, flags

    def _refined(
        self,
        chain: FloatArray,
        pose: FloatArray,
        value: float,
        q: FloatArray,
        flags: np.ndarray,
    ) -> int:
        """Refine the branches ``q`` (B, 7) on the model's own chain, in place.

        Returns:
            The number of branches that reach the pose on the model (the others
            are NaN rows now); the ``WITHIN_LIMITS`` bits of ``flags`` (B,)
            are updated.
        """
        return int(
            _refine_redundant_kernel.refine_pose(
                chain,
                self._arm_angle_geometry,
                self.family == "srs",
                pose,
                value,
                q,
                flags,
            )
        )

    def track(
        self,
        pose: FloatArray,
        value: float,
        q_predicted: FloatArray,
        branch: int,
        max_step2: float,
    ) -> tuple[FloatArray, int, bool]:
        """The branch that continues a motion (for the online planner).

        Every angle is taken as the representative nearest the prediction; the
        branch keeps its index if its squared step is within ``max_step2``,
        else (after a singularity) it is the nearest of all.

        Args:
            pose: (4, 4) float64 target pose of the tool frame in the base
                frame [m].
            value: The redundancy parameter [rad], finite.
            q_predicted: (7,) predicted configuration [rad].
            branch: Index of the last command's branch.
            max_step2: Largest squared joint step [rad²] that keeps the branch.

        Returns:
            ``(q, index, within)``: the configuration (7,) [rad], its branch
            index and whether it is within the joint limits.

        Raises:
            UnreachableError, InputError: As :meth:`solve`.
        """
        found = self.try_track(pose, value, q_predicted, branch, max_step2)
        if found is None:  # raises the error that says why
            self.solve_arrays(pose, value, q_predicted)
            raise UnreachableError(0.0, (0.0, 0.0), "model")  # (it raised)
        return found

    def _track_refined(
        self,
        chain: FloatArray,
        pose: FloatArray,
        value: float,
        q_predicted: FloatArray,
        branch: int,
        max_step2: float,
    ) -> tuple[FloatArray, int, bool] | None:
        """:meth:`try_track` on a model refined from the idealised arm."""
        q = np.empty((len(self._indices), 7))
        flags = np.empty(len(self._indices), dtype=np.uint8)
        status = self._kernel.solve_pose(
            self.geometry, pose, value, q_predicted, q, flags, True
        )
        if status != OK or not self._refined(chain, pose, value, q, flags):
            return None
        index = int(nearest_or_kept(q, q_predicted, branch, max_step2))
        return q[index].copy(), index, bool(flags[index] & WITHIN_LIMITS)

    def try_track(
        self,
        pose: FloatArray,
        value: float,
        q_predicted: FloatArray,
        branch: int,
        max_step2: float,
    ) -> tuple[FloatArray, int, bool] | None:
        """:meth:`track`, but None where no branch reaches (no error is built).

        For callers that probe values of the parameter (the online planner):
        the error of :meth:`track` says why a pose is out of reach, which
        takes a search over the parameter (milliseconds for q7).

        Returns:
            ``(q, index, within)`` as :meth:`track`, or None if the kernel's
            status is not OK (the pose out of reach for this value, or not
            rigid).
        """
        if self._refine is not None:
            return self._track_refined(
                self._refine, pose, value, q_predicted, branch, max_step2
            )
        q = np.empty(7)
        status, index, within = self._kernel.track(
            self.geometry, pose, value, q_predicted, branch, max_step2, q
        )
        if status != OK:
            return None
        return q, index, bool(within)

    def diagnose(self, pose: FloatArray, value: float) -> tuple[float, float, float]:
        """How far the wrist point is from the shoulder, and the arm's reach.

        Args:
            pose: (4, 4) float64 pose of the tool frame in the base frame [m].
            value: The redundancy parameter [rad] (a Franka arm's wrist point
                turns with q7; an SRS arm's wrist centre does not depend on ψ).

        Returns:
            ``(distance, low, high)`` [m]: the distance of the wrist point
            (SRS: wrist centre) from the shoulder, and the interval of
            distances the elbow reaches.
        """
        _, distance, low, high = self._kernel.diagnose(self.geometry, pose, value)
        return float(distance), float(low), float(high)

    def _previous(self, q_previous: npt.ArrayLike) -> FloatArray:
        """``q_previous`` checked (``Robot.check_configuration``), as floats."""
        return self.robot.check_configuration(q_previous)

    def _raise(self, status: int, pose: FloatArray, value: float) -> None:
        """Raise the error of a pose the kernel refused (``status`` not OK)."""
        if status == NOT_RIGID:  # the kernel's test is the exact one
            pose_rows(pose)  # raises the error that says why
            raise InputError("target is not a rigid transform")  # (pose_rows raised)
        distance, low, high = self.diagnose(pose, value)
        if self.family == "srs":
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

    # -- many poses, parameters, feasibility --------------------------------------
    def solve_batch(
        self, targets: npt.ArrayLike, values: float | npt.ArrayLike
    ) -> tuple[FloatArray, BoolArray]:
        """Every branch of N poses, each for its value of the parameter.

        Args:
            targets: (N, 4, 4) poses of the tool frame in the base frame [m].
            values: The redundancy parameter [rad], one for all or (N,).

        Returns:
            ``q`` (N, B, 7) [rad], NaN where a branch does not reach, each
            angle wrapped as by :meth:`solve`; ``valid`` (N, B), True where
            the branch reaches. Joint limits are not applied: test
            ``(robot.lower <= q) & (q <= robot.upper)`` for that.

        Raises:
            DimensionError, NonFiniteError: Bad shapes or entries.
            InputError: If a pose is not rigid (``poses.RIGIDITY_TOL``).
        """
        poses = as_targets(targets)
        count = len(poses)
        for start in range(0, count, CHECK_CHUNK):
            check_poses(poses[start : start + CHECK_CHUNK], start)
        if np.ndim(values) == 0:
            vals = np.full(count, check_redundancy(values, self.parameter))
        else:
            vals = as_finite_array(values, (count,), "redundancy")
        q = np.empty((count, len(self._indices), 7))
        valid = np.empty((count, len(self._indices)), dtype=bool)
        vals = np.ascontiguousarray(vals)
        self._kernel.solve_batch(self.geometry, poses, vals, q, valid)
        if self._refine is not None:
            _refine_redundant_kernel.refine_batch(
                self._refine,
                self._arm_angle_geometry,
                self.family == "srs",
                poses,
                vals,
                q,
                valid,
            )
        return q, valid

    def parameter_of(self, q: npt.ArrayLike) -> float | FloatArray:
        """The redundancy parameter [rad] of configurations.

        Args:
            q: (7,) or (N, 7) robot joint values [rad].

        Returns:
            A float for (7,), an (N,) array for (N, 7): ψ in [−π, π] (SRS; the
            θ1 = 0 reference when the wrist centre is on axis 1) or q7. On a
            model off its idealised structure (a rounded URDF) ψ is that of
            the idealised chain at ``q``, the value the refinement holds, so
            that :meth:`solve` at it gives ``q`` back.

        Raises:
            DimensionError, NonFiniteError: Bad shape or entries.
        """
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

        Raises:
            DimensionError, NonFiniteError, InputError: Bad target.
        """
        pose = np.array(pose_rows(target))
        intervals_of = cast(IntervalFunction, self._family.feasible_intervals)
        found = intervals_of(self.geometry, pose)
        intervals = tuple(
            tuple((float(lo), float(hi)) for lo, hi in branch) for branch in found
        )
        return FeasibleRedundancy(
            parameter=self.parameter,
            range=self.parameter_range,
            branches=self.branches,
            intervals=intervals,
            union=_union(intervals),
            circular=self.family == "srs",
        )


@per_robot
def get_redundant_solver(robot: Robot) -> RedundantSolver:
    """The :class:`RedundantSolver` of a seven-axis arm, cached per robot (weakly).

    Raises:
        UnsupportedRobotError: If the robot is not a seven-axis arm of the SRS
            or Franka family.
    """
    return RedundantSolver(robot)


def check_six_axis(robot: Robot, redundancy: object) -> None:
    """Refuse a redundancy parameter given for an arm without redundancy.

    Raises:
        InputError: If ``redundancy`` is not None (``robot`` is a 6R arm).
    """
    if redundancy is not None:
        raise InputError(
            f"robot {robot.name!r} has {robot.nq} joints and no redundancy: call "
            "without redundancy="
        )


__all__ = [
    "CHECK_CHUNK",
    "ELBOW_SINGULAR",
    "FRANKA_BRANCHES",
    "PARAMETER_SINGULAR",
    "SHOULDER_SINGULAR",
    "SRS_BRANCHES",
    "WITHIN_LIMITS",
    "WRIST_SINGULAR",
    "FeasibleRedundancy",
    "RedundantIKSolution",
    "RedundantSolver",
    "check_redundancy",
    "check_six_axis",
    "format_intervals",
    "get_redundant_solver",
]
