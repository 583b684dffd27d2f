r"""Exact evaluation of candidate base poses for a task (closed form, limits, scene).

A candidate base pose is :math:`B = \mathrm{Trans}(x, y, z)\, R_z(\psi)` in the
world frame (:func:`base_transform`); task pose :math:`T` is then
:math:`B^{-1} T` in the base frame. :class:`PlacementEvaluator` solves every
:math:`B^{-1} T` of a batch of candidates in one closed-form call
(:meth:`~workbench.ik.Solver.solve_batch`) and keeps, per pose, the
*usable* branches: they reach the pose, some 2π representative of every angle
is within its limits (the one nearest the middle of the limits, as the maps
take it), and, with a scene, the configuration touches nothing (no distance
<= 0 between the links or with an obstacle). The dexterity of a branch is
:math:`|\det J| = |K s e w|` [m³] from the analytic factors
(:func:`workbench.singularities.compute_conditions`), its singularity margin
:func:`~workbench.workspace.measures.singularity_margin`; the best branch of a
pose is its usable branch of largest dexterity.

For a path (ordered poses), the arm must follow every sample without a jump
(:func:`follow_path`): a chain of usable solutions, one per sample, each
joint moving by at most :data:`PATH_STEP_MAX` from one sample to the next. The
branch label may change along the chain only where two branches meet (a
singularity crossed in joint space, as a joint-space trajectory may); a wrist
flip (θ4 and θ6 turning by π) or a change of arm or elbow posture is a jump.
Of the chains, the one of largest worst dexterity is kept.

**Seven-axis arms** (SRS: ψ, Franka: q7; :func:`workbench.ik.get_solver`)
are verified exactly at the :math:`K` values of the redundancy parameter of
their map (:func:`workbench.workspace.redundant.redundancy_values`), the same
meaning of *exact* as their maps: every :math:`B^{-1} T` of a batch of
candidates is solved at every value in one call of
:func:`workbench.ik.analytic_batch`, and a pose's *solutions* are its
(value, branch) pairs, :math:`K \times B` of them (B = 8 for SRS, 4 for
Franka); a pose reachable only between the values counts as missed. Usable
as above (reaches, a representative of every angle within the limits,
collision-free). The dexterity is Yoshikawa's manipulability
:math:`\sqrt{\det(J J^T)}` [m³] of the 6 × 7 tool Jacobian
(:func:`workbench.ik.compute_tool_poses`, as the maps; by Cauchy–Binet the
sum of the squares of seven 6 × 6 minors, each m³ as |det J| of a 6R arm). A
6 × 7 Jacobian has no shoulder, elbow and wrist factors: a seven-axis
placement has no singularity margin (NaN); the manipulability, zero on every
locus, ranks it. :attr:`Placement.redundancy` holds, per task pose, the
parameter value of the solution kept (the best usable one; for a path, the
chain's). A path is followed by a chain over the (value, branch) solutions,
each joint stepping by at most :data:`PATH_STEP_MAX`: the parameter may
change between samples (it is free) where the joints stay continuous.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.collision import CollisionChecker, Scene
from workbench.errors import InputError
from workbench.ik import (
    FAMILIES,
    Solver,
    UnsupportedRobotError,
    analytic_batch,
    compute_tool_poses,
    get_family,
    get_family_refusal,
    get_solver,
)
from workbench.model.robot import Robot
from workbench.singularities import compute_conditions, get_factorisation
from workbench.validation import as_finite_array
from workbench.workspace._placement_kernel import chain_parents
from workbench.workspace._reference import limit_representatives
from workbench.workspace.measures import singularity_margin

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

#: Largest step [rad] of any joint between consecutive samples of a path
#: along one branch; a larger one is a jump (a flip, or a change of branch at
#: a singularity), so the branch does not follow the path.
PATH_STEP_MAX = math.pi / 4.0


@dataclass(frozen=True, slots=True)
class Placement:
    """One base pose and how well it serves the task (exact values).

    Attributes:
        x, y, z: Base position in the world frame [m].
        yaw: Base rotation about the world z axis [rad].
        all_reachable: Every task pose has a usable branch (for a path: one
            branch follows the whole path without a flip).
        missed: Task poses without a usable branch.
        min_dexterity: Smallest |det J| [m³] over the task (best usable branch
            of each pose; for a path, along :attr:`branch`); NaN if none.
            Seven-axis arms: Yoshikawa's √det(J Jᵀ) [m³].
        min_singularity_margin: Smallest singularity margin [1] likewise
            (< 1: a pose is near-singular); NaN if none, and for seven-axis
            arms (no factors of det J).
        branch: Label of one branch usable at every pose, the one of largest
            worst dexterity (seven-axis arms: at some parameter value per
            pose); for a path, the labels along the chain that follows it
            (``"a -> b"`` where it crosses a singularity); None if there is
            none.
        redundancy: Seven-axis arms: per task pose, the redundancy parameter
            (ψ or q7) [rad] of the solution kept (best usable; for a path,
            along the chain), NaN where none; None for six-axis arms.
    """

    x: float
    y: float
    z: float
    yaw: float
    all_reachable: bool
    missed: int
    min_dexterity: float
    min_singularity_margin: float
    branch: str | None
    redundancy: tuple[float, ...] | None = None

    @property
    def base_pose(self) -> FloatArray:
        """(4, 4) pose B of the base in the world frame [m]."""
        return base_transform(self.x, self.y, self.z, self.yaw)

    def rank_key(self) -> tuple[bool, int, bool, float, float]:
        """Sort key, smaller is better.

        Every pose reached first, then fewer missed poses, then a worst
        singularity margin >= 1 (no pose near-singular), then the larger worst
        dexterity, then the larger worst margin.
        """
        dexterity = _or_inf(-self.min_dexterity)
        margin = _or_inf(-self.min_singularity_margin)
        clear = self.min_singularity_margin >= 1.0
        return (not self.all_reachable, self.missed, not clear, dexterity, margin)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: the fields by name, NaN as None."""
        return {
            "x": self.x,
            "y": self.y,
            "z": self.z,
            "yaw": self.yaw,
            "all_reachable": self.all_reachable,
            "missed": self.missed,
            "min_dexterity": None
            if math.isnan(self.min_dexterity)
            else self.min_dexterity,
            "min_singularity_margin": (
                None
                if math.isnan(self.min_singularity_margin)
                else self.min_singularity_margin
            ),
            "branch": self.branch,
            "redundancy": None
            if self.redundancy is None
            else [None if math.isnan(v) else v for v in self.redundancy],
        }


def _or_inf(value: float) -> float:
    return math.inf if math.isnan(value) else value


def base_transform(x: float, y: float, z: float, yaw: float) -> FloatArray:
    """(4, 4) ``Trans(x, y, z) · Rz(yaw)`` [m, rad]: a base pose in the world frame."""
    out = np.eye(4)
    c, s = math.cos(yaw), math.sin(yaw)
    out[:2, :2] = [[c, -s], [s, c]]
    out[:3, 3] = x, y, z
    return out


def follow_path(
    q: FloatArray,
    usable: BoolArray,
    dexterity: FloatArray,
    wraps: BoolArray,
) -> tuple[float, npt.NDArray[np.int64]] | None:
    """The chain of solutions that follows a path with the largest worst dexterity.

    Args:
        q: (K, S, n) the S solutions [rad] of each of the K samples, each
            angle a representative within the limits where ``usable``.
        usable: (K, S) the solutions the chain may use.
        dexterity: (K, S) their dexterity (any measure, larger is better).
        wraps: (n,) joints whose limits span 2π or more: their step is taken
            modulo 2π (the joint may turn on past ±π); the others must step
            between their representatives, inside their limits.

    Returns:
        ``(worst dexterity along the chain, (K,) solution index per sample)``,
        or None if no chain steps by at most :data:`PATH_STEP_MAX` in every
        joint between consecutive samples. Ties: the first solution.

    The search (max–min over the S solutions of consecutive samples) is the
    compiled :func:`~workbench.workspace._placement_kernel.chain_parents`.
    """
    parent = np.empty(usable.shape, dtype=np.int64)
    worst, last = chain_parents(
        np.ascontiguousarray(q, dtype=np.float64),
        np.ascontiguousarray(usable, dtype=np.bool_),
        np.ascontiguousarray(dexterity, dtype=np.float64),
        np.ascontiguousarray(wraps, dtype=np.bool_),
        PATH_STEP_MAX,
        parent,
    )
    if worst == -np.inf:
        return None
    chain = np.empty(len(parent), dtype=np.int64)
    chain[-1] = last
    for k in range(len(parent) - 1, 0, -1):
        chain[k - 1] = parent[k, chain[k]]
    return float(worst), chain


def _labels(branches: tuple[str, ...], chain: npt.NDArray[np.int64]) -> str:
    """``"a -> b -> ..."``: the labels along a chain, each once per stretch."""
    names = [branches[int(chain[0])]]
    for index in chain[1:]:
        if branches[int(index)] != names[-1]:
            names.append(branches[int(index)])
    return " -> ".join(names)


class PlacementEvaluator:
    """Exact :class:`Placement` of candidate base poses for one task.

    Args:
        robot: An OPW or UR-type six-axis arm, or a seven-axis arm of the SRS
            or Franka family.
        task: (N, 4, 4) task poses of the tool frame in the world frame [m].
        scene: Obstacles in the world frame, or None (no collision check).
        ordered: The task is a path (one branch must follow it).
        redundancy: Seven-axis arms only, required: (K,) the values of the
            redundancy parameter [rad] to solve at (those of the map).

    Attributes:
        values: (K,) the parameter values [rad]; (1,) NaN for a six-axis arm.
        branches: The B branch labels of the closed form.

    Raises:
        UnsupportedRobotError: If the robot has no closed form.
        InputError: If ``redundancy`` is missing for a seven-axis arm, given
            for a six-axis one, or not a non-empty finite (K,) array.
    """

    def __init__(
        self,
        robot: Robot,
        task: FloatArray,
        scene: Scene | None,
        ordered: bool,
        redundancy: npt.ArrayLike | None = None,
    ):
        self.robot = robot
        self.solver = _closed_form(robot)
        self.seven_axis = self.solver.parameter is not None
        self.branches: tuple[str, ...] = self.solver.branches
        if self.seven_axis != (redundancy is not None):
            raise InputError(
                "base placement of a seven-axis arm needs the values of its "
                "redundancy parameter (those of its map); a six-axis arm has none"
            )
        self.values = np.full(1, np.nan)
        if redundancy is not None:
            values = np.asarray(redundancy, dtype=np.float64).reshape(-1)
            self.values = as_finite_array(values, (max(len(values), 1),), "redundancy")
        else:
            self.constant = abs(get_factorisation(robot).constant)
        self.task = np.asarray(task, dtype=np.float64)
        self.scene = scene
        self.ordered = ordered
        self.lower = np.asarray(robot.lower, dtype=np.float64)
        self.upper = np.asarray(robot.upper, dtype=np.float64)
        self.wraps = ~(self.upper - self.lower < 2.0 * math.pi)

    def evaluate(self, rows: npt.ArrayLike) -> list[Placement]:
        """Exact placements of candidate rows ``x, y, z, yaw`` (C, 4) [m, rad]."""
        rows = np.asarray(rows, dtype=np.float64).reshape(-1, 4)
        count, n = len(rows), len(self.task)
        inverse = np.linalg.inv(np.array([base_transform(*r) for r in rows]))
        targets = np.einsum("cij,njk->cnik", inverse, self.task).reshape(-1, 4, 4)
        q, valid = self._solve(targets)
        q, _, within = limit_representatives(q, self.lower, self.upper)
        within &= valid
        dexterity = np.full(valid.shape, np.nan)
        margin = np.full(valid.shape, np.nan)
        if within.any():
            dexterity[within], margin[within] = self._measures(q[within])
        # solutions of a pose: (value, branch) pairs, value-major
        shape = (count, n, len(self.values) * len(self.branches))
        q = q.reshape(*shape, q.shape[-1])
        within = within.reshape(shape)
        dexterity, margin = dexterity.reshape(shape), margin.reshape(shape)
        return [
            self._placement(rows[i], q[i], within[i], dexterity[i], margin[i])
            for i in range(count)
        ]

    def _solve(self, targets: FloatArray) -> tuple[FloatArray, BoolArray]:
        """Every solution of M poses: q (M·K, B, n) [rad], valid (M·K, B).

        Seven-axis arms: each pose at each of the K values, in one call.
        """
        if not self.seven_axis:
            return self.solver.solve_batch(targets)
        k = len(self.values)
        return analytic_batch(
            self.robot,
            np.repeat(targets, k, axis=0),
            redundancy=np.tile(self.values, len(targets)),
        )

    def _measures(self, q: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Dexterity [m³] and singularity margin [1] (NaN: none) of (M, n) q."""
        if self.seven_axis:
            return compute_tool_poses(self.robot, q)[2], np.full(len(q), np.nan)
        c = compute_conditions(self.robot, q)
        dexterity = self.constant * np.abs(c.shoulder * c.elbow * c.wrist)
        return dexterity, singularity_margin(c.shoulder, c.elbow, c.wrist)

    def _placement(
        self,
        row: FloatArray,
        q: FloatArray,
        within: BoolArray,
        dexterity: FloatArray,
        margin: FloatArray,
    ) -> Placement:
        """The placement of one candidate from its (N, S) solutions, S = K·B."""
        checker = self._checker(row)
        usable = within if checker is None else _collision_free(checker, q, within)
        reached = usable.any(axis=1)
        missed = int(np.count_nonzero(~reached))
        kept = np.argmax(np.where(usable, dexterity, -np.inf), axis=1)
        index = np.arange(len(kept))
        min_dexterity = min_margin = math.nan
        if reached.any():
            min_dexterity = float(np.min(dexterity[index, kept][reached]))
            min_margin = float(np.min(margin[index, kept][reached]))
        branch = None
        count = len(self.branches)
        if self.ordered:
            found = None if missed else follow_path(q, usable, dexterity, self.wraps)
            if found is not None:
                kept = found[1]
                min_dexterity = found[0]
                min_margin = float(np.min(margin[index, kept]))
                branch = _labels(self.branches, kept % count)
        else:
            # per branch: usable at some value at every pose, worst best dexterity
            per_value = np.where(usable, dexterity, -np.inf).reshape(len(q), -1, count)
            best = per_value.max(axis=1)
            everywhere = np.all(best > -np.inf, axis=0)
            if everywhere.any():
                worst = np.where(everywhere, np.min(best, axis=0), -np.inf)
                branch = self.branches[int(np.argmax(worst))]
        redundancy = None
        if self.seven_axis:
            value = self.values[kept // count]
            redundancy = tuple(np.where(reached, value, np.nan).tolist())
        all_reachable = missed == 0 and (branch is not None or not self.ordered)
        return Placement(
            x=float(row[0]),
            y=float(row[1]),
            z=float(row[2]),
            yaw=float(row[3]),
            all_reachable=bool(all_reachable),
            missed=missed,
            min_dexterity=min_dexterity,
            min_singularity_margin=min_margin,
            branch=branch,
            redundancy=redundancy,
        )

    def _checker(self, row: FloatArray) -> CollisionChecker | None:
        """A checker with the scene in the candidate's base frame; None without."""
        if self.scene is None:
            return None
        world_to_base = pin.SE3(np.linalg.inv(base_transform(*row)))
        obstacles = tuple(
            replace(o, placement=world_to_base * o.placement)
            for o in self.scene.obstacles
        )
        return CollisionChecker(self.robot, replace(self.scene, obstacles=obstacles))


def _closed_form(robot: Robot) -> Solver:
    """The closed form of ``robot``: six-axis, or seven-axis.

    Raises:
        UnsupportedRobotError: If the robot has no closed form.
    """
    family = get_family(robot)
    if family is None:
        reason = str(get_family_refusal(robot))
        names = ", ".join(name.upper() for name in FAMILIES)
        raise UnsupportedRobotError(
            f"base placement needs an arm of a closed-form family ({names}), "
            f"which {robot.name} is not ({reason.split(':')[0]})"
        )
    return get_solver(robot)


def _touches_nothing(checker: CollisionChecker, q: FloatArray) -> bool:
    distances = checker.compute_raw_distances(np.ascontiguousarray(q))
    return bool(distances.size == 0 or np.min(distances) > 0.0)


def _collision_free(
    checker: CollisionChecker, q: FloatArray, within: BoolArray
) -> BoolArray:
    """(N, S): the in-limit solutions whose configuration touches nothing."""
    free = within.copy()
    for pose, branch in zip(*np.nonzero(within), strict=True):
        free[pose, branch] = _touches_nothing(checker, q[pose, branch])
    return free


__all__ = [
    "PATH_STEP_MAX",
    "Placement",
    "PlacementEvaluator",
    "base_transform",
    "follow_path",
]
