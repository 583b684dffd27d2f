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


@helper()
def _count(
    center: FloatArray,
    radius: float,
    points: FloatArray,
    deltas: FloatArray,
    held: BoolArray,
) -> int:
    count = 0
    for s in range(points.shape[0]):
        if not held[s] and _holds(center, radius, points[s], deltas[s]):
            count += 1
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
    heap = [(0, 0) for _ in range(0)]
    for i in range(centers.shape[0]):
        count = _count(centers[i], radii[i], points, deltas, held)
        if count > 0:
            heap.append((-count, i))
    heapq.heapify(heap)
    taken = 0
    while len(heap) > 0:
        _, i = heapq.heappop(heap)
        count = _count(centers[i], radii[i], points, deltas, held)
        if count == 0:
            continue
        if len(heap) > 0 and -heap[0][0] > count:
            heapq.heappush(heap, (-count, i))
            continue
        chosen[taken] = i
        taken += 1
        for s in range(points.shape[0]):
            if not held[s] and _holds(centers[i], radii[i], points[s], deltas[s]):
                held[s] = True
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
