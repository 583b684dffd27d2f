r"""Spheres around a robot's links: the conservative model the planner checks.

:func:`spherize` covers each link's collision geometry (the URDF's
``<collision>`` elements, meshes or primitives) with a few spheres, fixed in
the frame of the link's joint:

* **Meshes.** Every triangle is sampled on a barycentric grid whose edges are
  at most :data:`SAMPLE_SPACING` long, so that every point of the surface lies
  within :math:`\delta = \ell/\sqrt3` of a sample (:math:`\ell` the longest
  grid edge of its triangle: the farthest point of a triangle from its three
  corners is its circumcentre or, for an obtuse one, the middle of its long
  edge, both within :math:`\ell/\sqrt3`). A sphere about a point inside
  the mesh with radius :math:`u + \rho` (:math:`u` its distance to the
  nearest sample) reaches at most :math:`\rho + \delta` beyond the mesh;
  candidates on the ridge of :math:`u` (the medial axis, where such spheres
  are largest) are chosen by greedy set cover until every sample, grown by
  its :math:`\delta`, is inside one, with :math:`\rho` the tolerance less
  the largest :math:`\delta`. What the ridge spheres miss (thin walls,
  flat meshes) gets spheres of radius ``tolerance`` about samples. So
  **every vertex is inside, and so is every point of every triangle**.
* **Boxes** are cut into sub-boxes no longer than :math:`\sqrt2` times their
  shortest edge, each covered by its circumscribed sphere; **cylinders and
  capsules** into slabs along the axis, each covered by the sphere through its
  rims; **spheres** stay themselves. These cover the solid exactly.

A union of spheres that covers a closed surface keeps an obstacle out of the
link along any continuous motion that starts outside (the obstacle would have
to cross the surface first); the planner's motions all start from the start
and goal configurations, which are checked on the exact meshes.

The spheres reach beyond the geometry: the **excess** of a link is the
largest distance from a point of its spheres' surfaces (:data:`EXCESS_SAMPLES`
Fibonacci points each) outside the geometry's convex hull to the nearest
surface sample, an upper bound of how far, at those points, the spheres
reach beyond the geometry; it is within ``tolerance`` for a closed mesh.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.collision.self_filter import get_link_name
from workbench.errors import InputError
from workbench.model.robot import Robot
from workbench.progress import ProgressCallback

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Default excess [m] the spheres of a mesh may have beyond it.
DEFAULT_TOLERANCE = 0.02
#: Longest edge [m] of the sampling grid on a mesh's triangles.
SAMPLE_SPACING = 0.006
#: Spacing [m] of the grid whose ridge points are the candidate centres.
RIDGE_GRID = 0.005
#: Most grid steps along a mesh's longest side (coarser steps beyond).
RIDGE_CELLS = 128
#: A grid point is on the ridge when the depth rises by less than this
#: fraction of the step towards each of its 26 neighbours.
RIDGE_RISE = 0.6
#: Points sampled on each sphere to measure the excess.
EXCESS_SAMPLES = 96


@dataclass(frozen=True, slots=True, eq=False)
class LinkSpheres:
    """The spheres of one link, in the frame of the joint that carries it.

    Attributes:
        link: Link name.
        joint: Pinocchio joint index (0: the fixed base).
        centers: (S, 3) [m], joint frame.
        radii: (S,) [m].
        excess: How far the spheres reach beyond the link's geometry [m]
            (module docstring).
    """

    link: str
    joint: int
    centers: FloatArray
    radii: FloatArray
    excess: float


@dataclass(frozen=True, slots=True, eq=False, weakref_slot=True)
class SphereModel:
    """The spheres of every link with collision geometry.

    Attributes:
        robot: The robot.
        links: One entry per link, in the order of the robot's collision model.
        tolerance: The excess asked of meshes [m].
    """

    robot: Robot
    links: tuple[LinkSpheres, ...]
    tolerance: float

    @property
    def n_spheres(self) -> int:
        """Number of spheres over all links."""
        return sum(len(link.radii) for link in self.links)

    def placed(self, q: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Centres (S, 3) [m] in the base frame and radii (S,) at ``q``."""
        model = self.robot.model
        data = model.createData()
        pin.forwardKinematics(model, data, self.robot.check_configuration(q))
        centers = [
            link.centers @ data.oMi[link.joint].rotation.T
            + data.oMi[link.joint].translation
            for link in self.links
        ]
        return np.concatenate(centers), np.concatenate([x.radii for x in self.links])


def spherize(
    robot: Robot,
    *,
    tolerance: float = DEFAULT_TOLERANCE,
    progress: ProgressCallback | None = None,
) -> SphereModel:
    """Cover every link's collision geometry with spheres (module docstring).

    Args:
        robot: The robot; its collision model is read.
        tolerance: Largest excess [m] of a mesh's spheres, > 0.
        progress: Called as ``progress(done, total)`` after each geometry
            (a mesh of tens of thousands of triangles takes seconds).

    Returns:
        The sphere model.

    Raises:
        InputError: If ``tolerance`` is not a positive number, or the robot
            has no collision geometry or a geometry of a kind that cannot be
            covered (only meshes, boxes, cylinders, capsules and spheres can).
    """
    if not (isinstance(tolerance, int | float) and 0 < tolerance < math.inf):
        raise InputError(
            f"tolerance must be a positive number of metres, got {tolerance!r}"
        )
    objects = list(robot.collision_model.geometryObjects)
    if not objects:
        raise InputError(f"robot {robot.name!r} has no collision geometry")
    grouped: dict[str, list[tuple[FloatArray, FloatArray, float]]] = {}
    joints: dict[str, int] = {}
    for done, geometry in enumerate(objects, start=1):
        link = get_link_name(robot.model, geometry)
        joints[link] = int(geometry.parentJoint)
        grouped.setdefault(link, []).append(_cover(geometry, float(tolerance)))
        if progress is not None:
            progress(done, len(objects))
    links = []
    for link, parts in grouped.items():
        links.append(
            LinkSpheres(
                link,
                joints[link],
                _read_only(np.concatenate([c for c, _, _ in parts])),
                _read_only(np.concatenate([r for _, r, _ in parts])),
                max(e for _, _, e in parts),
            )
        )
    return SphereModel(robot, tuple(links), float(tolerance))


def _read_only(values: FloatArray) -> FloatArray:
    out = np.array(values, dtype=np.float64)
    out.setflags(write=False)
    return out


def _cover(
    geometry: pin.GeometryObject, tolerance: float
) -> tuple[FloatArray, FloatArray, float]:
    """Spheres (centres in the joint frame, radii) and excess of one geometry."""
    shape = geometry.geometry
    kind = type(shape).__name__
    if kind.startswith("BVHModel") or kind == "Convex":
        vertices = np.array(shape.vertices(), dtype=np.float64).reshape(-1, 3)
        triangles = mesh_triangles(shape)
        centers, radii, samples = _cover_mesh(vertices, triangles, tolerance)
    elif kind == "Box":
        half = np.array(shape.halfSide, dtype=np.float64)
        centers, radii = _cover_box(half)
        samples = _box_samples(half)
    elif kind in ("Cylinder", "Capsule"):
        radius, half_length = float(shape.radius), float(shape.halfLength)
        centers, radii = _cover_cylinder(
            radius, half_length, tolerance, kind == "Capsule"
        )
        samples = _cylinder_samples(radius, half_length, kind == "Capsule")
    elif kind == "Sphere":
        centers, radii = np.zeros((1, 3)), np.array([float(shape.radius)])
        samples = _fibonacci(max(EXCESS_SAMPLES, 64)) * float(shape.radius)
    else:
        raise InputError(
            f"collision geometry {geometry.name!r}: a {kind} cannot be covered by "
            "spheres (meshes, boxes, cylinders, capsules and spheres can)"
        )
    excess = _excess(centers, radii, samples)
    placement = geometry.placement
    return (
        centers @ placement.rotation.T + placement.translation,
        radii,
        excess,
    )


def mesh_triangles(shape: object) -> IntArray:
    """Vertex indices (T, 3) of a coal mesh's triangles."""
    count = int(shape.num_tris)  # type: ignore[attr-defined]
    out = np.empty((count, 3), dtype=np.int64)
    for i in range(count):
        tri = shape.tri_indices(i)  # type: ignore[attr-defined]
        out[i] = (tri[0], tri[1], tri[2])
    return out


def _surface_samples(
    vertices: FloatArray, triangles: IntArray, spacing: float
) -> tuple[FloatArray, FloatArray]:
    """Grid points on every triangle and each point's coverage radius δ [m].

    The vertices first, then each triangle's grid (n + 1 points along an edge,
    n the least with its longest edge / n <= ``spacing``), triangle by
    triangle; the triangles of one n are computed together.
    """
    corners = vertices[triangles]  # (T, 3, 3)
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    longest = np.maximum.reduce(
        [
            np.sqrt(np.sum((b - a) ** 2, axis=1)),
            np.sqrt(np.sum((c - b) ** 2, axis=1)),
            np.sqrt(np.sum((a - c) ** 2, axis=1)),
        ]
    )
    n = np.maximum(1, np.ceil(longest / spacing)).astype(np.int64)
    count = (n + 1) * (n + 2) // 2  # grid points of each triangle
    first = len(vertices) + np.concatenate([[0], np.cumsum(count)[:-1]])
    total = len(vertices) + int(count.sum())
    points = np.empty((total, 3))
    deltas = np.empty(total)
    points[: len(vertices)] = vertices
    deltas[: len(vertices)] = 0.0
    for size in np.unique(n):
        i, j = np.meshgrid(np.arange(size + 1), np.arange(size + 1), indexing="ij")
        keep = i + j <= size
        u, v = i[keep] / size, j[keep] / size
        chosen = np.flatnonzero(n == size)
        at = (first[chosen][:, None] + np.arange(len(u))).ravel()
        block = (
            a[chosen, None]
            + u[None, :, None] * (b - a)[chosen, None]
            + v[None, :, None] * (c - a)[chosen, None]
        )
        points[at] = block.reshape(-1, 3)
        deltas[at] = np.repeat(longest[chosen] / size / math.sqrt(3.0), len(u))
    return points, deltas


def _cover_mesh(
    vertices: FloatArray, triangles: IntArray, tolerance: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Spheres on the ridge of the depth, chosen by greedy set cover.

    A sphere about a point ``c`` inside the mesh with radius
    ``u(c) + reach`` (``u`` the distance to the nearest surface sample)
    reaches at most ``reach`` plus the samples' δ beyond the geometry (the
    ball of radius ``u`` is inside it); moving ``c`` up the gradient of ``u``
    grows the sphere by as much as it moves, so only centres on the ridge of
    ``u`` (the medial axis) are worth proposing. The candidates are the
    points of a :data:`RIDGE_GRID` grid inside the mesh (the cells that the
    sampled surface's cells enclose or, for a mesh with holes, a generalised
    winding number > 1/2) at which the grid's distance transform rises by
    less than :data:`RIDGE_RISE` of the step towards every neighbour; the
    greedy set cover (:func:`workbench.motion._cover_kernel.greedy_cover`)
    picks from them until every sample they can hold is held. The samples
    left (thin walls, flat meshes) get spheres of radius ``tolerance`` about
    samples, chosen the same way; whatever a small tolerance still leaves is
    split at the median along its principal axis until each group's sphere
    has a radius of at most ``tolerance / 2``.
    """
    from scipy import ndimage
    from scipy.spatial import cKDTree

    from workbench.motion._cover_kernel import greedy_cover, winding_numbers

    if len(vertices) == 0 or len(triangles) == 0:
        raise InputError("a collision mesh has no triangles")
    points, deltas = _surface_samples(vertices, triangles, SAMPLE_SPACING)
    reach = max(tolerance - float(deltas.max()), tolerance / 2.0)
    lo, hi = points.min(axis=0), points.max(axis=0)
    step = max(RIDGE_GRID, float(np.max(hi - lo)) / RIDGE_CELLS)
    lo = lo - step
    shape = tuple(int(n) for n in np.ceil((hi - lo) / step).astype(int) + 2)
    # The surface's cells, closed by one dilation (samples are closer than
    # two steps), and the cells they enclose.
    wall = np.zeros(shape, dtype=bool)
    cell = np.rint((points - lo) / step).astype(np.int64)
    wall[cell[:, 0], cell[:, 1], cell[:, 2]] = True
    wall = ndimage.binary_dilation(wall, np.ones((3, 3, 3), dtype=bool))
    inside = ndimage.binary_fill_holes(wall) & ~wall
    holed = not inside.any()
    corners = np.ascontiguousarray(vertices[triangles])
    if holed:
        # A hole: the generalised winding number decides, on every other
        # grid point (the candidates need not follow the surface closely).
        coarse = np.argwhere(np.ones(tuple((n + 1) // 2 for n in shape), bool))
        winding = np.zeros(len(coarse))
        winding_numbers(
            np.ascontiguousarray(lo + 2.0 * step * coarse.astype(np.float64)),
            corners,
            winding,
        )
        solid = (winding > 0.5).reshape(tuple((n + 1) // 2 for n in shape))
        inside = (
            ~wall
            & solid.repeat(2, 0)
            .repeat(2, 1)
            .repeat(2, 2)[: shape[0], : shape[1], : shape[2]]
        )
    depth = ndimage.distance_transform_edt(inside)
    ridge = inside.copy()
    padded = np.pad(depth, 1)
    for offset in np.ndindex(3, 3, 3):
        d = np.array(offset) - 1
        if not d.any():
            continue
        neighbour = padded[
            1 + d[0] : 1 + d[0] + shape[0],
            1 + d[1] : 1 + d[1] + shape[1],
            1 + d[2] : 1 + d[2] + shape[2],
        ]
        ridge &= neighbour - depth < RIDGE_RISE * float(np.linalg.norm(d))
    centers = lo + step * np.argwhere(ridge).astype(np.float64)
    if holed and len(centers):  # each candidate itself inside
        winding = np.zeros(len(centers))
        winding_numbers(
            np.ascontiguousarray(centers),
            corners,
            winding,
        )
        centers = centers[winding > 0.5]
    tree = cKDTree(points)
    held = np.zeros(len(points), dtype=bool)
    if len(centers):
        gap, _ = tree.query(centers)
        radii = gap + reach
        chosen = np.zeros(len(centers), dtype=np.int64)
        taken = greedy_cover(
            np.ascontiguousarray(centers), radii, points, deltas, held, chosen
        )
        centers, radii = centers[chosen[:taken]], radii[chosen[:taken]]
    else:
        centers, radii = np.zeros((0, 3)), np.zeros(0)
    # Samples no ridge sphere holds (thin walls, flat meshes): spheres of
    # radius ``tolerance`` about samples (they reach at most that far from
    # the surface), one candidate per grid cell, chosen the same way.
    left = np.flatnonzero(~held)
    _, first = np.unique(cell[left], axis=0, return_index=True)
    around = np.ascontiguousarray(points[left[first]])
    chosen = np.zeros(len(around), dtype=np.int64)
    taken = greedy_cover(
        around, np.full(len(around), tolerance), points, deltas, held, chosen
    )
    extra = _split_cover(points[~held], deltas[~held], tolerance / 2.0)
    return (
        np.concatenate([centers, around[chosen[:taken]], extra[0]]),
        np.concatenate([radii, np.full(taken, tolerance), extra[1]]),
        points,
    )


def _split_cover(
    points: FloatArray, deltas: FloatArray, largest: float
) -> tuple[FloatArray, FloatArray]:
    """Spheres of radius <= ``largest`` (or about one sample) holding samples.

    A group's sphere is about its bounding box's centre; a group whose sphere
    is too large is split at the median along its principal axis.
    """
    centers, radii = [], []
    groups = [np.arange(len(points))] if len(points) else []
    while groups:
        group = groups.pop()
        members = points[group]
        center = 0.5 * (members.min(axis=0) + members.max(axis=0))
        radius = float(np.max(np.linalg.norm(members - center, axis=1) + deltas[group]))
        if radius <= largest or len(group) == 1:
            centers.append(center)
            radii.append(radius)
            continue
        offsets = members - members.mean(axis=0)
        along = offsets @ np.linalg.svd(offsets, full_matrices=False)[2][0]
        low = along <= np.median(along)
        if low.all():
            low = np.arange(len(group)) < len(group) // 2
        groups += [group[low], group[~low]]
    return np.array(centers).reshape(-1, 3), np.array(radii)


class _OutsideHull:
    """Excess of one sphere over a geometry given by its surface samples."""

    def __init__(self, samples: FloatArray, tree: object) -> None:
        from scipy.spatial import ConvexHull, QhullError

        self.tree = tree
        self.directions = _fibonacci(EXCESS_SAMPLES)
        try:
            self.planes: FloatArray | None = ConvexHull(samples).equations
        except QhullError:  # flat geometry: every sphere point counts
            self.planes = None

    def excess(self, center: FloatArray, radius: float) -> float:
        surface = center + radius * self.directions
        if self.planes is not None:
            distance = surface @ self.planes[:, :3].T + self.planes[:, 3]
            surface = surface[np.max(distance, axis=1) > 0]
        if len(surface) == 0:
            return 0.0
        gap, _ = self.tree.query(surface)  # type: ignore[attr-defined]
        return float(np.max(gap))


def _cover_box(half: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Sub-boxes no longer than sqrt(2) x the shortest edge, circumscribed."""
    shortest = max(float(half.min()), 1e-6)
    counts = np.maximum(1, np.ceil(half / (math.sqrt(2.0) * shortest)).astype(int))
    sub = half / counts
    axes = [(-half[i] + sub[i] * (2 * np.arange(counts[i]) + 1)) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return grid, np.full(len(grid), float(np.linalg.norm(sub)))


def _cover_cylinder(
    radius: float, half_length: float, tolerance: float, capsule: bool
) -> tuple[FloatArray, FloatArray]:
    """Axis slabs; the sphere through a slab's rims covers it."""
    # A slab of height h needs sqrt(r^2 + h^2/4) - r <= tolerance.
    slab = 2.0 * math.sqrt(max((radius + tolerance) ** 2 - radius**2, 1e-12))
    count = max(1, math.ceil(2.0 * half_length / slab))
    height = 2.0 * half_length / count
    z = -half_length + height * (np.arange(count) + 0.5)
    centers = np.column_stack([np.zeros(count), np.zeros(count), z])
    radii = np.full(count, math.hypot(radius, height / 2.0))
    if capsule:
        ends = np.array([[0.0, 0.0, -half_length], [0.0, 0.0, half_length]])
        centers = np.concatenate([centers, ends])
        radii = np.concatenate([radii, [radius, radius]])
    return centers, radii


def _box_samples(half: FloatArray) -> FloatArray:
    step = SAMPLE_SPACING
    faces = []
    for axis in range(3):
        others = [i for i in range(3) if i != axis]
        a = np.linspace(
            -half[others[0]],
            half[others[0]],
            max(2, math.ceil(2 * half[others[0]] / step) + 1),
        )
        b = np.linspace(
            -half[others[1]],
            half[others[1]],
            max(2, math.ceil(2 * half[others[1]] / step) + 1),
        )
        u, v = np.meshgrid(a, b, indexing="ij")
        for sign in (-1.0, 1.0):
            face = np.empty((u.size, 3))
            face[:, axis] = sign * half[axis]
            face[:, others[0]], face[:, others[1]] = u.ravel(), v.ravel()
            faces.append(face)
    return np.concatenate(faces)


def _cylinder_samples(radius: float, half_length: float, capsule: bool) -> FloatArray:
    step = SAMPLE_SPACING
    angles = np.linspace(
        0.0, 2 * math.pi, max(8, math.ceil(2 * math.pi * radius / step)), endpoint=False
    )
    z = np.linspace(
        -half_length, half_length, max(2, math.ceil(2 * half_length / step) + 1)
    )
    a, h = np.meshgrid(angles, z, indexing="ij")
    side = np.column_stack(
        [radius * np.cos(a).ravel(), radius * np.sin(a).ravel(), h.ravel()]
    )
    if capsule:
        cap = _fibonacci(max(64, math.ceil(4 * math.pi * radius**2 / step**2))) * radius
        ends = [
            cap[cap[:, 2] >= 0] + [0, 0, half_length],
            cap[cap[:, 2] <= 0] - [0, 0, half_length],
        ]
    else:
        rings = np.linspace(0.0, radius, max(2, math.ceil(radius / step) + 1))
        r, t = np.meshgrid(rings, angles, indexing="ij")
        disk = np.column_stack([(r * np.cos(t)).ravel(), (r * np.sin(t)).ravel()])
        ends = [
            np.column_stack([disk, np.full(len(disk), s * half_length)])
            for s in (-1, 1)
        ]
    return np.concatenate([side, *ends])


def _fibonacci(count: int) -> FloatArray:
    """``count`` nearly uniform unit vectors (Fibonacci sphere)."""
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    phi = math.pi * (3.0 - math.sqrt(5.0)) * i
    r = np.sqrt(1.0 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def _excess(centers: FloatArray, radii: FloatArray, samples: FloatArray) -> float:
    """Upper bound [m] of how far the spheres reach beyond the samples' hull."""
    from scipy.spatial import cKDTree

    outside = _OutsideHull(samples, cKDTree(samples))
    return max(outside.excess(c, float(r)) for c, r in zip(centers, radii, strict=True))


__all__ = [
    "DEFAULT_TOLERANCE",
    "RIDGE_GRID",
    "SAMPLE_SPACING",
    "LinkSpheres",
    "SphereModel",
    "spherize",
]
