r"""Per-pose measures of a block of the grid for seven-axis arms, in closed form.

A seven-axis arm of the SRS family (KUKA LBR iiwa) or the Franka family (Panda,
FR3) reaches a tool pose along a one-parameter family of configurations per
branch: the arm angle ψ (SRS) or q7 (Franka) [rad]
(:func:`workbench.ik.get_solver`). The map solves every pose in
closed form at a fixed set of :math:`K` values of that parameter,
:func:`redundancy_values`: the centres of :math:`K` equal cells of the
parameter's range (SRS :math:`(-\pi, \pi]`, Franka the limits of joint 7),
through :func:`workbench.ik.analytic_batch`. It is *exact at those values*: a
pose counts as reachable when some branch at one of the :math:`K` values is
within the joint limits (each angle's representative nearest the middle of
its limits, as the six-axis maps); a pose reachable only at values between
them counts as unreachable. The values of :math:`K` are among those of
:math:`3K` (odd multiples nest the cell centres), so a map at :math:`3K`
reaches every pose the one at :math:`K` reaches.

:func:`evaluate_redundant_block` returns, per pose (arrays (B, O)):

* ``reached`` (uint8): branches that reach the pose at some of the values;
* ``branches`` (uint8): branches within the joint limits at some value;
* of the **best candidate** (the in-limit (value, branch) of largest limit
  margin; ties: the first value, then the first branch), NaN where none
  (float32): ``dexterity`` Yoshikawa's :math:`\sqrt{\det(J J^T)}` of the 6 × 7
  tool Jacobian (:func:`workbench.ik.compute_tool_poses`), ``limit_margin``
  [rad] and ``redundancy`` [rad], its parameter value;

and per voxel (B,) float32 ``reachability``, ``dexterity_best`` and
``dexterity_median`` (as the six-axis maps). The shoulder, elbow and wrist
distances of the six-axis maps are factors of det J, which a 6 × 7 Jacobian
has not: a seven-axis map holds none, nor ``near_singular_fraction``.

The function is pure: the same inputs give the same bits on any worker.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.ik import analytic_batch, compute_tool_poses, get_solver
from workbench.model.robot import Robot
from workbench.workspace import _redundant_kernel as kernel
from workbench.workspace._reference import block_poses, summarise_voxels
from workbench.workspace.measures import check_voxel_range

if TYPE_CHECKING:
    from workbench.workspace.grid import PoseGrid

FloatArray = npt.NDArray[np.float64]

#: Default K, the values of the redundancy parameter a map solves each pose at.
DEFAULT_REDUNDANCY_SAMPLES = 16
#: Largest K.
MAX_REDUNDANCY_SAMPLES = 4096
#: Poses per call of the closed form at one value: its work arrays stay small.
CHUNK_POSES = 4096
#: Keys of :func:`evaluate_redundant_block` with one value per pose (B, O).
REDUNDANT_POSE_KEYS = ("reached", "branches", "dexterity", "limit_margin", "redundancy")
#: Keys of :func:`evaluate_redundant_block` with one value per voxel (B,).
REDUNDANT_VOXEL_KEYS = ("reachability", "dexterity_best", "dexterity_median")


def redundancy_values(parameter_range: tuple[float, float], count: int) -> FloatArray:
    """The ``count`` values a map solves at: centres of equal cells of the range.

    Args:
        parameter_range: ``(lo, hi)`` [rad] of the redundancy parameter.
        count: K, 1..:data:`MAX_REDUNDANCY_SAMPLES`.

    Returns:
        (K,) increasing values [rad], ``lo + (k + 1/2)(hi − lo)/K``.

    Raises:
        InputError: If ``count`` is not an integer in range.
    """
    if isinstance(count, bool) or not isinstance(count, int | np.integer):
        raise InputError(f"redundancy samples must be an integer, got {count!r}")
    if not 1 <= count <= MAX_REDUNDANCY_SAMPLES:
        raise InputError(
            f"redundancy samples must be 1..{MAX_REDUNDANCY_SAMPLES}, got {count}"
        )
    lo, hi = (float(v) for v in parameter_range)
    cells = np.arange(int(count), dtype=np.float64) + 0.5
    values: FloatArray = lo + cells * ((hi - lo) / int(count))
    return values


def evaluate_redundant_block(
    robot: Robot, grid: PoseGrid, start: int, stop: int, *, count: int
) -> dict[str, np.ndarray]:
    """Measures of every pose of voxels ``start:stop`` × all orientations.

    Args:
        robot: A seven-axis arm of the SRS or Franka family.
        grid: The pose grid (positions in the robot's base frame).
        start: First voxel of the block, ``0 <= start < stop``.
        stop: One past its last voxel, ``<= V``.
        count: K, the number of parameter values (:func:`redundancy_values`).

    Returns:
        Arrays keyed as in the module docstring: :data:`REDUNDANT_POSE_KEYS`
        (B, O) and :data:`REDUNDANT_VOXEL_KEYS` (B,).

    Raises:
        UnsupportedRobotError: If the robot has no seven-axis closed form.
        InputError: If the voxel range is empty or outside the grid, or
            ``count`` out of range.
    """
    start, stop = check_voxel_range(grid, start, stop)
    solver = get_solver(robot)
    if solver.parameter_range is None:
        raise InputError(f"robot {robot.name!r} is no seven-axis arm")
    values = redundancy_values(solver.parameter_range, count)
    poses = block_poses(grid, start, stop)
    total = len(poses)
    reached = np.zeros(total, dtype=np.uint8)  # bit b: branch b
    usable = np.zeros(total, dtype=np.uint8)
    margin = np.full(total, -np.inf)
    best_q = np.zeros((total, robot.nq))
    best_value = np.full(total, -1, dtype=np.int64)
    joints = _joint_constants(robot)
    for first in range(0, total, CHUNK_POSES):
        chunk = np.ascontiguousarray(poses[first : first + CHUNK_POSES])
        for k, value in enumerate(values):
            q, valid = analytic_batch(robot, chunk, redundancy=float(value))
            kernel.fold_value(
                joints, q, valid, k, first, reached, usable, margin, best_q, best_value
            )
    has = best_value >= 0
    dexterity = np.full(total, np.nan)
    if has.any():
        dexterity[has] = compute_tool_poses(robot, best_q[has])[2]
    shape = (stop - start, grid.orientation_count)
    bits = np.unpackbits(np.stack([reached, usable], axis=1)[..., None], axis=2)
    counts = bits.sum(axis=2, dtype=np.uint8)
    out: dict[str, np.ndarray] = {
        "reached": counts[:, 0].reshape(shape),
        "branches": counts[:, 1].reshape(shape),
        "dexterity": dexterity.astype(np.float32).reshape(shape),
    }
    chosen = values[np.maximum(best_value, 0)]
    for key, field in (("limit_margin", margin), ("redundancy", chosen)):
        out[key] = np.where(has, field, np.nan).astype(np.float32).reshape(shape)
    voxels = summarise_voxels(dexterity.reshape(shape), np.full(shape, np.nan))
    out.update({key: voxels[key] for key in REDUNDANT_VOXEL_KEYS})
    return out


def _joint_constants(robot: Robot) -> FloatArray:
    """(JOINT_ROWS, nq): the six-axis kernel's rows (sign 1 and offset 0, unused)."""
    lower, upper = robot.lower, robot.upper
    bounded = np.isfinite(lower) & np.isfinite(upper)
    mid = 0.5 * (np.where(bounded, lower, 0.0) + np.where(bounded, upper, 0.0))
    ones, zeros = np.ones(robot.nq), np.zeros(robot.nq)
    rows = [ones, zeros, lower, upper, mid, bounded.astype(np.float64)]
    return np.ascontiguousarray(np.stack(rows))


__all__ = [
    "DEFAULT_REDUNDANCY_SAMPLES",
    "MAX_REDUNDANCY_SAMPLES",
    "REDUNDANT_POSE_KEYS",
    "REDUNDANT_VOXEL_KEYS",
    "evaluate_redundant_block",
    "redundancy_values",
]
