"""Compiled greedy set cover of a mesh's surface samples by candidate spheres.

:func:`workbench.motion.spheres.spherize` proposes candidate spheres (centres
on the ridge of the distance to the surface); this module picks a few of them
that together hold every sample they can: the lazy greedy set cover (each
step takes the candidate that holds the most samples not yet held; a
candidate's count only falls as others are taken, so a count recomputed and
still the largest is the step's choice).
"""

from __future__ import annotations

import heapq
import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point, helper

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


@helper(forceinline=True)
def _holds(center: FloatArray, radius: float, point: FloatArray, delta: float) -> bool:
    """The ball of the sample (radius ``delta``) is inside the sphere."""
    reach = radius - delta
    if reach < 0.0:
        return False
    dx = point[0] - center[0]
    dy = point[1] - center[1]
    dz = point[2] - center[2]
    return dx * dx + dy * dy + dz * dz <= reach * reach


#: The samples' grid (:func:`greedy_cover`): cells of this fraction of the
#: mean candidate radius, and at most this many cells in all (coarser then).
CELL_SHARE = 0.25
MAX_CELLS = 1 << 21


@helper()
def _count(
    center: FloatArray,
    radius: float,
    bins: tuple[FloatArray, FloatArray, BoolArray, FloatArray, IntArray, IntArray],
    mark: bool,
) -> int:
    """Samples not yet held that the sphere holds; with ``mark``, hold them.

    ``bins`` is ``(points, deltas, held, grid, dims, start)``: the samples in
    cell order (those of cell c are ``start[c]:start[c + 1]``), the grid's
    corner ``grid[:3]`` and cell size ``grid[3]`` [m] and its cells per axis.
    Only the cells the sphere meets are visited.
    """
    points, deltas, held, grid, dims, start = bins
    size = grid[3]
    reach = radius + 1e-9 * size  # (a cell's bounds and index are rounded)
    lo0 = max(0, math.floor((center[0] - reach - grid[0]) / size))
    lo1 = max(0, math.floor((center[1] - reach - grid[1]) / size))
    lo2 = max(0, math.floor((center[2] - reach - grid[2]) / size))
    hi0 = min(dims[0] - 1, math.floor((center[0] + reach - grid[0]) / size))
    hi1 = min(dims[1] - 1, math.floor((center[1] + reach - grid[1]) / size))
    hi2 = min(dims[2] - 1, math.floor((center[2] + reach - grid[2]) / size))
    count = 0
    for i in range(lo0, hi0 + 1):
        x = grid[0] + i * size
        dx = max(x - center[0], 0.0, center[0] - x - size)
        for j in range(lo1, hi1 + 1):
            y = grid[1] + j * size
            dy = max(y - center[1], 0.0, center[1] - y - size)
            row = (i * dims[1] + j) * dims[2]
            for k in range(lo2, hi2 + 1):
                z = grid[2] + k * size
                dz = max(z - center[2], 0.0, center[2] - z - size)
                if dx * dx + dy * dy + dz * dz > reach * reach:
                    continue  # the cell is outside the sphere
                for s in range(start[row + k], start[row + k + 1]):
                    if not held[s] and _holds(center, radius, points[s], deltas[s]):
                        count += 1
                        if mark:
                            held[s] = True
    return count


@entry_point(outputs=("held", "chosen"), contiguous=("points",))
def greedy_cover(
    centers: FloatArray,
    radii: FloatArray,
    points: FloatArray,
    deltas: FloatArray,
    held: BoolArray,
    chosen: IntArray,
) -> int:
    """Pick candidate spheres until none holds a sample not yet held.

    The samples are binned on a grid (cells of :data:`CELL_SHARE` of the mean
    candidate radius, :data:`MAX_CELLS` at most), so that a candidate's count
    visits only the samples of the cells it meets.

    Args:
        centers: (C, 3) [m] candidate centres.
        radii: (C,) [m] candidate radii.
        points: (P, 3) [m] surface samples.
        deltas: (P,) [m] each sample's coverage radius: a sample is held
            when its ball is inside a sphere.
        held: (P,) in: samples already held; out: also those the chosen hold.
        chosen: (C,) out: indices of the chosen candidates, in order.

    Returns:
        The number of candidates chosen (the first entries of ``chosen``).
    """
    n_points = points.shape[0]
    grid = np.zeros(4)
    dims = np.ones(3, dtype=np.int64)
    if n_points > 0:
        extent = np.empty(3)
        for k in range(3):
            grid[k] = points[:, k].min()
            extent[k] = points[:, k].max() - grid[k]
        size = CELL_SHARE * radii.mean() if centers.shape[0] > 0 else 1.0
        size = max(size, 1e-9)
        while (extent[0] / size + 1) * (extent[1] / size + 1) * (
            extent[2] / size + 1
        ) > MAX_CELLS:
            size *= 1.25
        grid[3] = size
        for k in range(3):
            dims[k] = math.floor(extent[k] / size) + 1
    cell = np.empty(n_points, dtype=np.int64)
    for s in range(n_points):
        i = min(dims[0] - 1, math.floor((points[s, 0] - grid[0]) / grid[3]))
        j = min(dims[1] - 1, math.floor((points[s, 1] - grid[1]) / grid[3]))
        k = min(dims[2] - 1, math.floor((points[s, 2] - grid[2]) / grid[3]))
        cell[s] = (i * dims[1] + j) * dims[2] + k
    start = np.zeros(dims[0] * dims[1] * dims[2] + 1, dtype=np.int64)
    for s in range(n_points):
        start[cell[s] + 1] += 1
    for c in range(len(start) - 1):
        start[c + 1] += start[c]
    order = np.empty(n_points, dtype=np.int64)
    fill = start[:-1].copy()
    for s in range(n_points):
        order[fill[cell[s]]] = s
        fill[cell[s]] += 1
    sorted_points = np.empty((n_points, 3))
    sorted_deltas = np.empty(n_points)
    sorted_held = np.empty(n_points, dtype=np.bool_)
    for n in range(n_points):
        sorted_points[n] = points[order[n]]
        sorted_deltas[n] = deltas[order[n]]
        sorted_held[n] = held[order[n]]
    bins = (sorted_points, sorted_deltas, sorted_held, grid, dims, start)
    heap = [(0, 0) for _ in range(0)]
    for i in range(centers.shape[0]):
        count = _count(centers[i], radii[i], bins, False)
        if count > 0:
            heap.append((-count, i))
    heapq.heapify(heap)
    taken = 0
    while len(heap) > 0:
        _, i = heapq.heappop(heap)
        count = _count(centers[i], radii[i], bins, False)
        if count == 0:
            continue
        if len(heap) > 0 and -heap[0][0] > count:
            heapq.heappush(heap, (-count, i))
            continue
        chosen[taken] = i
        taken += 1
        _count(centers[i], radii[i], bins, True)
    for n in range(n_points):
        held[order[n]] = sorted_held[n]
    return taken


@entry_point(outputs=("out",), contiguous=("points", "corners"))
def winding_numbers(points: FloatArray, corners: FloatArray, out: FloatArray) -> None:
    """Generalised winding number of a triangle soup at points.

    Args:
        points: (P, 3) [m].
        corners: (T, 3, 3) [m] the triangles' corners.
        out: (P,) out: |sum of the triangles' solid angles| / 4 pi (1 inside
            a closed surface, 0 outside, about 1/2 on it).
    """
    for p in range(points.shape[0]):
        total = 0.0
        for t in range(corners.shape[0]):
            a = corners[t, 0] - points[p]
            b = corners[t, 1] - points[p]
            c = corners[t, 2] - points[p]
            la = np.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
            lb = np.sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2])
            lc = np.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
            det = (
                a[0] * (b[1] * c[2] - b[2] * c[1])
                - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0])
            )
            ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
            bc = b[0] * c[0] + b[1] * c[1] + b[2] * c[2]
            ca = c[0] * a[0] + c[1] * a[1] + c[2] * a[2]
            total += np.arctan2(det, la * lb * lc + ab * lc + bc * la + ca * lb)
        out[p] = abs(total) / (2.0 * np.pi)
