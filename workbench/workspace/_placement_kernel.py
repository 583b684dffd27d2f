"""Compiled screening of base placements: one map lookup per task pose and candidate.

For a yaw ψ of the base, the task orientations in the base frame are fixed
(one nearest-orientation index per task pose, found before the call) and the
task positions move with the candidate's translation only: the position of
task pose ``i`` in the base frame of candidate ``(x, y, h, ψ)`` is
``Rz(−ψ) (p_i − (x, y, h))``, i.e. ``(c p_x + s p_y − c x − s y,
−s p_x + c p_y + s x − c y, p_z − h)`` with ``c, s = cos ψ, sin ψ``. Its
voxel is the nearest grid point (ties round up), an O(1) index; the map's
entry at (voxel, orientation) says whether a usable branch reaches the
pose there, with what dexterity and singularity margin.

Loop order: yaw, task pose, candidate row, candidate column, so the map
entries a task pose visits (one orientation column, the voxels under the
candidate region) stay in the caches across the candidates, and the
per-candidate aggregates of one yaw (a few tens of kB) as well. Yaws are
independent: callers split them between threads (the kernel releases the GIL).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point

FloatArray = npt.NDArray[np.float64]

TAU = 2.0 * math.pi


@entry_point(
    outputs=("missed", "worst_dexterity", "worst_margin"),
    contiguous=("dexterity", "margin"),
)
def screen_candidates(
    dexterity: npt.NDArray[np.float32],
    margin: npt.NDArray[np.float32],
    origin: FloatArray,
    resolution: float,
    task_xy: FloatArray,
    task_layer: npt.NDArray[np.int64],
    orientation: npt.NDArray[np.int64],
    yaw_cos_sin: FloatArray,
    xs: FloatArray,
    ys: FloatArray,
    yaw: int,
    prune: bool,
    missed: npt.NDArray[np.int32],
    worst_dexterity: npt.NDArray[np.float32],
    worst_margin: npt.NDArray[np.float32],
) -> int:
    """Aggregate the map over the task for every candidate of one yaw.

    Args:
        dexterity: (O, L, nx, ny) the map's dexterity |det J| [m³] of the best
            usable branch at orientation ``o``, layer ``l`` (one of the task's
            heights), voxel ``(ix, iy)``; NaN where no branch is usable. One
            (o, l) plane is what a task pose visits at one yaw.
        margin: (O, L, nx, ny) singularity margin [1] of that branch.
        origin: (2,) x, y of the centre of voxel (0, 0) [m], base frame.
        resolution: Voxel edge [m].
        task_xy: (Y, N, 2) ``Rz(−ψ) p_xy`` of every task pose at every yaw [m],
            in the order the poses are screened.
        task_layer: (N,) layer of every task pose (−1: outside the grid).
        orientation: (Y, N) index into ``dexterity``'s first axis of the
            nearest map orientation of every task pose at every yaw.
        yaw_cos_sin: (Y, 2) ``cos ψ, sin ψ``.
        xs: (A,) candidate x [m], world frame.
        ys: (B,) candidate y [m], world frame.
        yaw: The yaw index to compute.
        prune: Drop a candidate at its first missed pose: its count stays 1
            (at least one missed) and its worst values partial; the others
            are exact. Far cheaper when few candidates reach every pose.
        missed: (Y, A·B) output: task poses without a usable branch.
        worst_dexterity: (Y, A·B) output: smallest dexterity over the reached
            task poses [m³] (inf when none is reached).
        worst_margin: (Y, A·B) output: smallest margin over them (inf: none).

    Returns:
        The candidates of this yaw that missed no pose.
    """
    nx, ny, count_y = dexterity.shape[2], dexterity.shape[3], ys.shape[0]
    scale = 1.0 / resolution
    c, s = yaw_cos_sin[yaw, 0] * scale, yaw_cos_sin[yaw, 1] * scale
    total = xs.shape[0] * count_y
    alive = np.arange(total)
    for j in range(total):
        missed[yaw, j] = 0
        worst_dexterity[yaw, j] = np.inf
        worst_margin[yaw, j] = np.inf
    n_alive = total
    for i in range(task_layer.shape[0]):
        layer = task_layer[i]
        dex = dexterity[orientation[yaw, i], max(layer, 0)]
        mar = margin[orientation[yaw, i], max(layer, 0)]
        tx = (task_xy[yaw, i, 0] - origin[0]) * scale + 0.5
        ty = (task_xy[yaw, i, 1] - origin[1]) * scale + 0.5
        kept = 0
        for j in range(n_alive):
            candidate = alive[j]
            x, y = xs[candidate // count_y], ys[candidate % count_y]
            ix = math.floor(tx - c * x - s * y)
            iy = math.floor(ty + s * x - c * y)
            d = np.float32(np.nan)
            if (layer >= 0) & (ix >= 0) & (ix < nx) & (iy >= 0) & (iy < ny):
                d = dex[ix, iy]
            if d == d:
                worst_dexterity[yaw, candidate] = min(
                    worst_dexterity[yaw, candidate], d
                )
                worst_margin[yaw, candidate] = min(
                    worst_margin[yaw, candidate], mar[ix, iy]
                )
                alive[kept] = candidate
                kept += 1
            else:
                missed[yaw, candidate] += 1
                if not prune:
                    alive[kept] = candidate
                    kept += 1
        n_alive = kept
    reached = 0
    for j in range(total):
        reached += missed[yaw, j] == 0
    return reached


@entry_point(
    outputs=("dexterity_planes", "margin_planes"),
    contiguous=("dexterity", "shoulder", "elbow", "wrist"),
)
def gather_planes(
    dexterity: npt.NDArray[np.float32],
    shoulder: npt.NDArray[np.float32],
    elbow: npt.NDArray[np.float32],
    wrist: npt.NDArray[np.float32],
    grid_shape: npt.NDArray[np.int64],
    orientation_count: int,
    layers: npt.NDArray[np.int64],
    used: npt.NDArray[np.int64],
    inverse_tolerances: FloatArray,
    dexterity_planes: npt.NDArray[np.float32],
    margin_planes: npt.NDArray[np.float32],
) -> None:
    """The (orientation, layer) planes :func:`screen_candidates` reads, in one pass.

    Args:
        dexterity: (V·O,) the map's dexterity [m³], pose ``v·O + o``.
        shoulder: (V·O,) the best branch's |s| [m].
        elbow: (V·O,) its |e| [1].
        wrist: (V·O,) its |w| [1].
        grid_shape: (3,) ``(nx, ny, nz)``.
        orientation_count: O.
        layers: (L,) the z layers to gather.
        used: (U,) the orientations to gather.
        inverse_tolerances: (3,) ``1 / SHOULDER_TOL, 1 / ELBOW_TOL, 1 / WRIST_TOL``.
        dexterity_planes: (U, L, nx, ny) output: ``dexterity`` of orientation
            ``used[u]`` at voxel ``(ix, iy, layers[l])``.
        margin_planes: (U, L, nx, ny) output: the singularity margin
            ``min(|s|/SHOULDER_TOL, |e|/ELBOW_TOL, |w|/WRIST_TOL)`` there.
    """
    nx, ny, nz = grid_shape[0], grid_shape[1], grid_shape[2]
    ks = np.float32(inverse_tolerances[0])
    ke = np.float32(inverse_tolerances[1])
    kw = np.float32(inverse_tolerances[2])
    for ix in range(nx):
        for iy in range(ny):
            for lk in range(layers.shape[0]):
                row = ((ix * ny + iy) * nz + layers[lk]) * orientation_count
                for u in range(used.shape[0]):
                    k = row + used[u]
                    dexterity_planes[u, lk, ix, iy] = dexterity[k]
                    m = min(abs(shoulder[k]) * ks, abs(elbow[k]) * ke)
                    margin_planes[u, lk, ix, iy] = min(m, abs(wrist[k]) * kw)


@entry_point(outputs=("parent",))
def chain_parents(
    q: FloatArray,
    usable: npt.NDArray[np.bool_],
    dexterity: FloatArray,
    wraps: npt.NDArray[np.bool_],
    step_max: float,
    parent: npt.NDArray[np.int64],
) -> tuple[float, int]:
    """The max–min chain of solutions along a path (``placement_check.follow_path``).

    Args:
        q: (K, S, n) the S solutions [rad] of each of the K samples.
        usable: (K, S) the solutions a chain may use.
        dexterity: (K, S) their dexterity (larger is better).
        wraps: (n,) joints whose step is taken modulo 2π.
        step_max: Largest step of a joint between consecutive samples [rad].
        parent: (K, S) output: the solution at sample k − 1 that the best chain
            ending at solution s of sample k comes from.

    Returns:
        ``(worst dexterity of the best chain, its solution at the last sample)``;
        the worst dexterity is −inf when no chain follows the path.
    """
    count, width, joints = q.shape[0], q.shape[1], q.shape[2]
    value = np.empty(width)
    reach = np.empty(width)
    for s in range(width):
        value[s] = dexterity[0, s] if usable[0, s] else -np.inf
        parent[0, s] = 0
    for k in range(1, count):
        for t in range(width):
            best, origin = -np.inf, 0
            if usable[k, t]:
                for f in range(width):
                    if value[f] == -np.inf:
                        continue
                    joins = True
                    for j in range(joints):
                        step = q[k, t, j] - q[k - 1, f, j]
                        if wraps[j]:
                            step -= TAU * np.round(step / TAU)
                        if not abs(step) <= step_max:  # NaN: no step
                            joins = False
                            break
                    if joins:
                        v = min(value[f], dexterity[k, t])
                        if v > best:
                            best, origin = v, f
            reach[t] = best
            parent[k, t] = origin
        for t in range(width):
            value[t] = reach[t]
    last = 0
    for s in range(width):
        if value[s] > value[last]:
            last = s
    return value[last], last


__all__ = ["chain_parents", "gather_planes", "screen_candidates"]
