"""Screening of a region of base candidates against a workspace map.

The candidates of a region are a lattice: yaws × x × y at one base height
(:class:`CandidateLattice`). For each yaw, every task pose is looked up at
its nearest map orientation (once per pose and yaw) and, per candidate, at
its nearest voxel (the compiled loop of
:mod:`workbench.workspace._placement_kernel`). The map is read once into the
layout that loop wants: (orientation, layer, x, y) planes of only the
orientations and heights the task visits.

Two passes: the first drops a candidate at its first missed task pose (task
poses farthest from the task's centre first, as they drop most), which is
all that is needed when some candidates reach every pose; the second, run
only when the first leaves too few, counts every candidate's missed poses.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.singularities.conditions import ELBOW_TOL, SHOULDER_TOL, WRIST_TOL
from workbench.validation import as_finite_array, check_positive
from workbench.workspace._placement_kernel import gather_planes, screen_candidates
from workbench.workspace.grid import PoseGrid
from workbench.workspace.measures import get_core_count
from workbench.workspace.orientations import (
    quat_multiply_xyzw,
    quat_xyzw_from_rotations,
)

FloatArray = npt.NDArray[np.float64]
IndexArray = npt.NDArray[np.int64]
Progress = Callable[[int, int], None]

#: Most candidates of one region (yaws × positions).
MAX_CANDIDATES = 50_000_000
#: Decimals [m, rad] the lattice's coordinates are rounded to (no 1e-16 m
#: where a coordinate is a multiple of the step).
_LATTICE_DECIMALS = 12
#: Slack [in steps] of the lattice's extent: a region whose width is a
#: multiple of the step up to rounding includes its far edge.
_EDGE_SLACK = 1e-9


@dataclass(frozen=True)
class CandidateLattice:
    """The candidate bases of a region: yaws × xs × ys at one height.

    Attributes:
        xs: (A,) base x [m], world frame.
        ys: (B,) base y [m].
        yaws: (Y,) base yaw about the world z axis [rad].
        height: Base z [m].
    """

    xs: FloatArray
    ys: FloatArray
    yaws: FloatArray
    height: float

    @staticmethod
    def make(
        region: Sequence[float], height: float, yaw_step: float, resolution: float
    ) -> CandidateLattice:
        """The lattice from ``(xmin, ymin)`` by ``resolution``, yaws by ``yaw_step``.

        Raises:
            InputError: On a region with max below min, a non-positive step,
                a non-finite height, or more than :data:`MAX_CANDIDATES`.
        """
        box = as_finite_array(np.asarray(region, dtype=np.float64), (4,), "region")
        xmin, xmax, ymin, ymax = (float(v) for v in box)
        if xmax < xmin or ymax < ymin:
            raise InputError(
                f"region (xmin, xmax, ymin, ymax) has max below min: "
                f"{xmin:g}, {xmax:g}, {ymin:g}, {ymax:g}"
            )
        check_positive(resolution, "resolution", strict=True)
        check_positive(yaw_step, "yaw_step", strict=True)
        if not math.isfinite(height):
            raise InputError(f"height must be finite, got {height}")
        step = float(resolution)
        nx = math.floor((xmax - xmin) / step + _EDGE_SLACK) + 1
        ny = math.floor((ymax - ymin) / step + _EDGE_SLACK) + 1
        nyaw = max(1, math.ceil(2.0 * math.pi / float(yaw_step) - _EDGE_SLACK))
        if nx * ny * nyaw > MAX_CANDIDATES:
            raise InputError(
                f"{nx:.3g} × {ny:.3g} × {nyaw:.3g} candidates (x, y, yaw), at most "
                f"{MAX_CANDIDATES}: raise the resolution or the yaw step"
            )
        return CandidateLattice(
            xs=np.round(
                xmin + step * np.arange(nx, dtype=np.float64), _LATTICE_DECIMALS
            ),
            ys=np.round(
                ymin + step * np.arange(ny, dtype=np.float64), _LATTICE_DECIMALS
            ),
            yaws=float(yaw_step) * np.arange(nyaw, dtype=np.float64),
            height=float(height),
        )

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(Y, A, B)``."""
        return (len(self.yaws), len(self.xs), len(self.ys))

    def rows(self, flat: IndexArray) -> FloatArray:
        """(C, 4) rows ``x, y, z, yaw`` of flat candidate indices (C order)."""
        k, a, b = np.unravel_index(flat, self.shape)
        height = np.full(len(k), self.height)
        return np.column_stack([self.xs[a], self.ys[b], height, self.yaws[k]])


class Screening:
    """The screening of one task over one lattice (see the module docstring).

    Args:
        grid: The map's pose grid.
        read: ``read(name)`` gives the map's per-pose array ``name`` (V, O).
        task: (N, 4, 4) task poses in the world frame [m].
        lattice: The candidates.
        distances: The map holds the singularity distances ``shoulder``,
            ``elbow``, ``wrist``; without them (a seven-axis map) the margin
            is 0 at every pose and the ranking falls to the dexterity.
    """

    def __init__(
        self,
        grid: PoseGrid,
        read: Callable[[str], npt.NDArray[np.generic]],
        task: FloatArray,
        lattice: CandidateLattice,
        distances: bool = True,
    ):
        self.lattice = lattice
        centre = task[:, :3, 3].mean(axis=0)
        order = np.argsort(-np.linalg.norm(task[:, :3, 3] - centre, axis=1))
        task = task[order]
        iz = np.rint(
            (task[:, 2, 3] - lattice.height - grid.origin[2]) / grid.resolution
        ).astype(np.int64)
        inside = (iz >= 0) & (iz < grid.shape[2])
        layers = np.unique(iz[inside])
        task_layer = np.where(inside, np.searchsorted(layers, iz), -1)
        yaws = lattice.yaws
        self.cos_sin = np.column_stack([np.cos(yaws), np.sin(yaws)])
        c, s = self.cos_sin[:, 0:1], self.cos_sin[:, 1:2]
        px, py = task[None, :, 0, 3], task[None, :, 1, 3]
        self.task_xy = np.stack([c * px + s * py, -s * px + c * py], axis=-1)
        half = -0.5 * yaws
        turn = np.column_stack([np.zeros((len(yaws), 2)), np.sin(half), np.cos(half)])
        in_base = quat_multiply_xyzw(
            turn[:, None, :], quat_xyzw_from_rotations(task[:, :3, :3])
        )
        nearest = grid.orientation_index(in_base.reshape(-1, 4))
        used, compact = np.unique(nearest, return_inverse=True)
        self.orientation = compact.reshape(len(yaws), -1).astype(np.int64)
        self.task_layer = task_layer.astype(np.int64)
        rows = layers if len(layers) else np.zeros(1, dtype=np.int64)
        shape = (len(used), len(rows), grid.shape[0], grid.shape[1])
        self.dexterity = np.empty(shape, dtype=np.float32)
        self.margin = np.empty(shape, dtype=np.float32)

        names = ("dexterity", "shoulder", "elbow", "wrist")
        loaded = [
            np.ascontiguousarray(read(name), dtype=np.float32).reshape(-1)
            for name in (names if distances else names[:1])
        ]
        dexterity, shoulder, elbow, wrist = loaded if distances else loaded * 4
        inverse = 1.0 / np.array([SHOULDER_TOL, ELBOW_TOL, WRIST_TOL])
        if not distances:  # margin |dexterity| · 0 = 0 at every reached pose
            inverse = np.zeros(3)
        gather_planes(
            dexterity,
            shoulder,
            elbow,
            wrist,
            np.asarray(grid.shape, dtype=np.int64),
            int(grid.orientation_count),
            rows.astype(np.int64),
            used.astype(np.int64),
            inverse,
            self.dexterity,
            self.margin,
        )
        self.origin = np.asarray(grid.origin[:2], dtype=np.float64)
        self.resolution = float(grid.resolution)

    def rank(self, *, prune: bool, progress: Progress | None = None) -> IndexArray:
        """Flat candidate indices, best screened first.

        Key: missed poses, then worst margin >= 1 first, then the worst
        dexterity and the worst margin, larger first. With ``prune``, only
        the candidates that miss no pose are ranked (the rest follow, in no
        useful order, with a missed count of 1). Sets :attr:`reached` (the
        candidates that miss no pose) and the aggregates :attr:`missed`,
        :attr:`worst_dexterity`, :attr:`worst_margin`, each (Y, A·B).
        """
        lattice = self.lattice
        count_yaw, count_x, count_y = lattice.shape
        missed = np.empty((count_yaw, count_x * count_y), dtype=np.int32)
        worst_dexterity = np.empty(missed.shape, dtype=np.float32)
        worst_margin = np.empty(missed.shape, dtype=np.float32)
        arguments = (
            self.dexterity, self.margin, self.origin, self.resolution,
            self.task_xy, self.task_layer, self.orientation, self.cos_sin,
            lattice.xs, lattice.ys,
        )  # fmt: skip
        outputs = (missed, worst_dexterity, worst_margin)
        done = [0]

        def run(k: int) -> int:
            reached = screen_candidates(*arguments, k, prune, *outputs)
            done[0] += 1
            if progress is not None:
                progress(done[0], count_yaw)
            return int(reached)

        with ThreadPoolExecutor(get_core_count()) as pool:
            self.reached = sum(pool.map(run, range(count_yaw)))
        self.missed, self.worst_dexterity = missed, worst_dexterity
        self.worst_margin = worst_margin
        finite = np.isfinite(worst_margin)
        margin_key = np.where(finite, worst_margin, -np.inf).reshape(-1)
        dexterity_key = np.where(finite, worst_dexterity, -np.inf).reshape(-1)
        keys = (-margin_key, -dexterity_key, margin_key < 1.0, missed.reshape(-1))
        return np.lexsort(keys)


__all__ = [
    "MAX_CANDIDATES",
    "CandidateLattice",
    "Screening",
]
