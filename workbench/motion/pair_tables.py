r"""Clearance tables of link pairs whose spheres overlap, over their relative joints.

Links near each other in the chain are often closer than the spheres' excess
(``spheres.DEFAULT_TOLERANCE``): the spheres of the UR5's base and upper arm,
or of its forearm and wrist 2, overlap in most configurations while the meshes
are 1–3 cm apart. The planner lets an entry overlap as much as it does at the
start and the goal, plus a margin (:func:`~workbench.motion.plan`), which for
such a pair closes much of the configuration space: 61–79 % of the samples
of VAMP's paths through MotionBenchMaker's UR5 cage are refused by these
pairs alone (``docs/motion.md``), and their spheres are the dearest part of
an evaluation.

A pair whose relative pose depends on one or two joints (those that move one
of its links and not the other) gets a table over those joints instead: at
each node of a grid (:data:`STEP_1D`, :data:`STEP_2D`; a joint with a range of
a turn or more is periodic) its clearance,

.. math:: c = \max(g, \sigma d) \text{ where } d > 0, \quad
   c = \text{NaN where the meshes touch},

with :math:`d` the exact distance of its meshes (coal; their convex hulls'
bound where that is positive) and :math:`g` its spheres' clearance at the
node, :math:`\sigma` = :data:`SHARE`. The kernel takes the value of the
nearest node, plus the pair's allowance, without visiting its spheres; at a
NaN node the spheres tell (:mod:`workbench.motion._sphere_kernel`). Only pairs
whose spheres overlap at a quarter or more of the nodes of a coarser
screening grid (:data:`SCREEN_STEP`, :data:`INSEPARABLE`) get a table.

The tables are no certificate between the nodes: the exact check of the
trajectory judges the motion, and a trajectory it refuses is planned again
without them (:func:`~workbench.motion.plan`).
"""

from __future__ import annotations

import math
from typing import NamedTuple, Protocol

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.collision.checker import CollisionChecker
from workbench.model.robot import Robot
from workbench.motion.spheres import SphereModel
from workbench.progress import ProgressCallback

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Grid step [rad] of a pair that one joint moves.
STEP_1D = math.radians(2.0)
#: Grid step [rad] of a pair that two joints move.
STEP_2D = math.radians(5.0)
#: Grid step [rad] of the screening, whose nodes decide which pairs get a
#: table (:data:`INSEPARABLE`).
SCREEN_STEP = math.radians(15.0)
#: A pair gets a table when its spheres overlap at this share of the
#: screening nodes or more (spheres that overlap at fewer are near contacts
#: of the meshes, not the spheres' excess).
INSEPARABLE = 0.25
#: The share of the exact distance a table gives as the pair's clearance.
SHARE = 0.5
#: Most joints a pair's table may span.
MAX_JOINTS = 2


class PairTables(NamedTuple):
    """The tables of a checker's P pairs, packed for the kernels.

    Attributes:
        start: (P,) offset of pair k's values in ``values``; -1: no table.
        joint: (P, 2) the q indices of its joints (-1 past the last).
        cells: (P, 2) cells along each joint.
        periodic: (P, 2) 1 where the joint's grid spans a turn.
        lower: (P, 2) [rad] where each joint's grid starts.
        step: (P, 2) [rad] its cell width (a node at each cell's centre).
        values: (N,) [m], the clearances of every table at its nodes (NaN
            where the meshes touch), the first joint's cells slowest.
        pairs: The pairs with a table, by link names.
    """

    start: IntArray
    joint: IntArray
    cells: IntArray
    periodic: IntArray
    lower: FloatArray
    step: FloatArray
    values: FloatArray
    pairs: tuple[tuple[str, str], ...]


class SphereClearances(Protocol):
    """What the tables read of a sphere checker (``SphereChecker``)."""

    spheres: SphereModel
    pairs: tuple[tuple[str, str], ...]

    def clearances(self, q: npt.ArrayLike) -> FloatArray:
        """Clearances (L + P,) [m] of the links, then of the pairs, at ``q``."""
        ...


def no_tables(n_pairs: int) -> PairTables:
    """Tables for none of ``n_pairs`` pairs."""
    return PairTables(
        np.full(n_pairs, -1, dtype=np.int64),
        np.full((n_pairs, MAX_JOINTS), -1, dtype=np.int64),
        np.ones((n_pairs, MAX_JOINTS), dtype=np.int64),
        np.zeros((n_pairs, MAX_JOINTS), dtype=np.int64),
        np.zeros((n_pairs, MAX_JOINTS)),
        np.ones((n_pairs, MAX_JOINTS)),
        np.zeros(0),
        (),
    )


def build_pair_tables(
    checker: SphereClearances,
    exact: CollisionChecker,
    *,
    progress: ProgressCallback | None = None,
) -> PairTables:
    """The tables of the pairs of ``checker`` that need one (module docstring).

    Args:
        checker: A :class:`~workbench.motion.checker.SphereChecker` without
            scene or allowance (its pairs and sphere clearances are read).
        exact: The robot's exact checker without scene (its pair distances).
        progress: Called as ``progress(done, total)`` after each node of the
            tables (the screening, whose sphere clearances are cheap, decides
            their number first; a UR5's ~1500 nodes take seconds).

    Returns:
        The packed tables, aligned with ``checker.pairs``.
    """
    spheres = checker.spheres
    pairs = checker.pairs
    robot = spheres.robot
    model = robot.model
    joint_of = {link.link: link.joint for link in spheres.links}
    n_links = len(spheres.links)
    tables = no_tables(len(pairs))
    base = np.clip(np.zeros(robot.nq), robot.lower, robot.upper)
    by_joints: dict[tuple[int, ...], list[int]] = {}
    for k, (a, b) in enumerate(pairs):
        moving = _carried(model, joint_of[a]) ^ _carried(model, joint_of[b])
        joints = tuple(sorted(int(model.joints[j].idx_q) for j in moving))
        if 1 <= len(joints) <= MAX_JOINTS:
            by_joints.setdefault(joints, []).append(k)
    exact_pairs: dict[frozenset[str], list[int]] = {}
    for i, pair in enumerate(exact.pairs):
        exact_pairs.setdefault(frozenset((pair.body_a, pair.body_b)), []).append(i)
    chosen_by_joints: dict[tuple[int, ...], list[int]] = {}
    for joints, members in by_joints.items():
        screen = _nodes(base, joints, _grid(robot, joints, SCREEN_STEP))
        overlap = np.zeros(len(members))
        for node in screen:
            clear = checker.clearances(node)
            overlap += clear[n_links + np.array(members)] < 0.0
        chosen = [
            k
            for k, o in zip(members, overlap, strict=True)
            if o >= INSEPARABLE * len(screen) and frozenset(pairs[k]) in exact_pairs
        ]
        if chosen:
            chosen_by_joints[joints] = chosen
    grids = {
        joints: _grid(robot, joints, STEP_2D if len(joints) == 2 else STEP_1D)
        for joints in chosen_by_joints
    }
    total = sum(int(np.prod(grid[2])) for grid in grids.values())
    done = 0
    values: list[FloatArray] = []
    offset = 0
    named = []
    for joints, chosen in chosen_by_joints.items():
        grid = grids[joints]
        table = np.empty((len(chosen), int(np.prod(grid[2]))))
        for n, node in enumerate(_nodes(base, joints, grid)):
            clear = checker.clearances(node)
            for row, k in enumerate(chosen):
                d = _distance(exact, node, exact_pairs[frozenset(pairs[k])])
                g = clear[n_links + k]
                table[row, n] = max(g, SHARE * d) if d > 0.0 else math.nan
            done += 1
            if progress is not None:
                progress(done, total)
        lower, step, cells, periodic = grid
        for row, k in enumerate(chosen):
            width = len(joints)
            tables.start[k] = offset
            tables.joint[k, :width] = joints
            tables.cells[k, :width] = cells
            tables.periodic[k, :width] = periodic
            tables.lower[k, :width] = lower
            tables.step[k, :width] = step
            values.append(table[row])
            offset += table.shape[1]
            named.append(pairs[k])
    return tables._replace(
        values=np.concatenate(values) if values else np.zeros(0), pairs=tuple(named)
    )


def _distance(exact: CollisionChecker, q: FloatArray, pairs: list[int]) -> float:
    """The least distance [m] of the exact pairs ``pairs`` at ``q``, or a bound.

    Each pair's convex-hull bound where positive (``compute_pair_lower_bound``,
    a lower bound, ~0.1 ms), else its exact distance (~0.3 ms on a UR5).
    """
    least = math.inf
    for i in pairs:
        d = exact.compute_pair_lower_bound(q, i)
        if d <= 0.0:
            d = exact.compute_pair_distance(q, i)
        least = min(least, d)
    return least


def _carried(model: pin.Model, joint: int) -> set[int]:
    """The joints (Pinocchio indices) that move ``joint``'s frame, itself included."""
    out = set()
    while joint > 0:
        out.add(joint)
        joint = int(model.parents[joint])
    return out


def _grid(
    robot: Robot, joints: tuple[int, ...], step: float
) -> tuple[FloatArray, FloatArray, IntArray, IntArray]:
    """Start [rad], cell width [rad], cells and periodicity of each joint's grid.

    A joint whose range spans a turn gets the turn from -π (periodic), another
    its range.
    """
    lower, width, cells, periodic = [], [], [], []
    for j in joints:
        lo, hi = float(robot.lower[j]), float(robot.upper[j])
        turn = hi - lo >= 2.0 * math.pi
        if turn:
            lo, hi = -math.pi, math.pi
        n = max(1, math.ceil((hi - lo) / step))
        lower.append(lo)
        width.append((hi - lo) / n)
        cells.append(n)
        periodic.append(int(turn))
    return (
        np.array(lower),
        np.array(width),
        np.array(cells, dtype=np.int64),
        np.array(periodic, dtype=np.int64),
    )


def _nodes(
    base: FloatArray,
    joints: tuple[int, ...],
    grid: tuple[FloatArray, FloatArray, IntArray, IntArray],
) -> list[FloatArray]:
    """The configurations at the grid's nodes (cell centres), first joint slowest."""
    lower, width, cells, _ = grid
    axes = [
        lower[i] + (np.arange(cells[i]) + 0.5) * width[i] for i in range(len(joints))
    ]
    out = []
    for values in np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(
        -1, len(joints)
    ):
        q = base.copy()
        q[list(joints)] = values
        out.append(q)
    return out


__all__ = ["MAX_JOINTS", "SHARE", "PairTables", "build_pair_tables", "no_tables"]
