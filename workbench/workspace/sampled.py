r"""Sampled workspace maps of arms without a closed form (7-axis, generic 6R).

Configurations are drawn uniformly within the joint limits, from
``numpy.random.default_rng([seed, block])``, so each block of samples is the
same on any worker. Each sample's tool pose (compiled chain kinematics,
:func:`workbench.ik.compute_tool_poses`) is binned to its nearest grid pose
(:meth:`PoseGrid.voxel_index`, :meth:`PoseGrid.orientation_index`); samples
outside the grid's box are dropped. A cell that a sample hits is reachable,
up to the binning: the sample's tool position lies within half a voxel (per
axis) of the voxel centre, its rotation within the set's covering radius of
the grid orientation. :func:`accumulate` keeps per cell the hit flag and the
largest manipulability √det(J Jᵀ), a reduction that does not depend on the
order of the samples, so that the map is bitwise the same however the blocks
are spread over workers.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.ik import compute_tool_poses
from workbench.model.robot import Robot
from workbench.workspace.grid import PoseGrid
from workbench.workspace.orientations import quat_xyzw_from_rotations

FloatArray = npt.NDArray[np.float64]
IndexArray = npt.NDArray[np.int64]


def _check_count(value: int, name: str, *, positive: bool) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise InputError(f"{name} must be an integer, got {value!r}")
    if value < (1 if positive else 0):
        bound = "positive" if positive else "non-negative"
        raise InputError(f"{name} must be {bound}, got {value}")
    return int(value)


def check_samplable(robot: Robot) -> None:
    """Raise unless a sampled map of ``robot`` can be built.

    Its joints must each have one coordinate and finite limits (revolute or
    prismatic, no continuous joint) and none may follow another (``<mimic>``):
    the compiled chain kinematics take independent joints.

    Raises:
        InputError: Naming the robot and what it has.
    """
    lower, upper = robot.lower, robot.upper
    if robot.nq != robot.nv or not (
        np.isfinite(lower).all() and np.isfinite(upper).all()
    ):
        raise InputError(
            f"{robot.name}: sampled maps need joints with finite limits and one "
            "coordinate each (no continuous joints)"
        )
    if robot.mimic_joints:
        followers = ", ".join(
            f"{m.joint} follows {m.leader}" for m in robot.mimic_joints
        )
        raise InputError(
            f"{robot.name}: sampled maps need independent joints, not mimic "
            f"joints ({followers})"
        )


def sample_configurations(
    robot: Robot, block: int, count: int, seed: int
) -> FloatArray:
    """The configurations of sample block ``block``, uniform within the limits.

    Args:
        robot: A serial arm whose joints each have one coordinate and finite
            limits (revolute or prismatic).
        block: Sample block index (>= 0).
        count: Number of configurations (>= 1).
        seed: Seed of the map (>= 0); the generator is
            ``default_rng([seed, block])``.

    Returns:
        (count, nq) configurations [rad or m].

    Raises:
        InputError: If an argument is not a non-negative integer (``count``
            positive), or a joint is continuous or unbounded.
    """
    block = _check_count(block, "block", positive=False)
    count = _check_count(count, "samples_per_block", positive=True)
    seed = _check_count(seed, "seed", positive=False)
    check_samplable(robot)
    rng = np.random.default_rng([seed, block])
    return rng.uniform(robot.lower, robot.upper, size=(count, robot.nq))


def sample_block(
    robot: Robot, grid: PoseGrid, block: int, samples_per_block: int, seed: int
) -> tuple[IndexArray, FloatArray]:
    """Grid cells hit by one block of random configurations, and their dexterity.

    Args:
        robot: A serial arm (as :func:`sample_configurations`; its base frame
            is the grid's frame).
        grid: The pose grid.
        block: Sample block index (>= 0): which part of the sample stream.
        samples_per_block: Configurations drawn (>= 1).
        seed: Seed of the map (>= 0).

    Returns:
        ``(cells, manipulability)``: (S,) int64 flat pose indices ``v·O + o``
        of the samples inside the grid's box, in sample order, and (S,)
        float64 Yoshikawa manipulability √det(J Jᵀ) of each (m³ for six
        revolute joints; other units with prismatic joints).

    Raises:
        InputError: As :func:`sample_configurations`.
    """
    q = sample_configurations(robot, block, samples_per_block, seed)
    rotations, positions, manipulability = compute_tool_poses(robot, q)
    voxels = grid.voxel_index(positions)
    inside = voxels >= 0
    orientations = grid.orientation_index(quat_xyzw_from_rotations(rotations[inside]))
    cells = voxels[inside] * grid.orientation_count + orientations
    return cells, manipulability[inside]


def accumulate(
    cells: IndexArray,
    values: FloatArray,
    hit: npt.NDArray[np.generic],
    dexterity: npt.NDArray[np.floating],
) -> None:
    """Fold samples into a map, in place: hit flags and the max manipulability.

    Order-independent (a maximum), so the result is bitwise the same in any
    order of blocks or samples; NaN in ``dexterity`` means no sample yet.

    Args:
        cells: (S,) flat pose indices into ``hit`` and ``dexterity``.
        values: (S,) manipulability of each sample.
        hit: C-contiguous bool or integer array of the map's cells (any
            shape, flat index = cell); set to 1 where hit.
        dexterity: C-contiguous float array of the same size, NaN-initialised;
            each cell becomes the max of itself and its samples.

    Raises:
        InputError: If the arrays are not C-contiguous of one size, or a
            cell is out of range.
    """
    cells = np.asarray(cells, dtype=np.int64)
    values = np.asarray(values, dtype=np.float64)
    if cells.shape != values.shape or cells.ndim != 1:
        raise InputError(
            f"cells and values must be (S,) of one length, got {cells.shape} "
            f"and {values.shape}"
        )
    for name, array in (("hit", hit), ("dexterity", dexterity)):
        if not array.flags.c_contiguous or not array.flags.writeable:
            raise InputError(f"{name} must be a writable C-contiguous array")
    if hit.size != dexterity.size:
        raise InputError(f"hit ({hit.size}) and dexterity ({dexterity.size}) differ")
    if len(cells) and (cells.min() < 0 or cells.max() >= hit.size):
        raise InputError(f"cells must lie in [0, {hit.size})")
    hit.reshape(-1)[cells] = 1
    np.fmax.at(dexterity.reshape(-1), cells, values.astype(dexterity.dtype))


__all__ = [
    "accumulate",
    "sample_block",
    "sample_configurations",
]
