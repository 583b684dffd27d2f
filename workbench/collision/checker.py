r"""Distances between a robot's links and between the links and a scene (coal).

:class:`CollisionChecker` puts the robot's collision geometry (the URDF's
``<collision>`` elements: primitives for the PUMA models, meshes for UR5 or
Panda) and a scene's obstacles into one ``pinocchio.GeometryModel`` and keeps
two families of pairs: link–link pairs that the self-collision filter does
not exclude, and moving link–obstacle pairs that the obstacle does not
``allow``. Distances are coal's, through ``pinocchio.computeDistances``.

For the checks along paths it also gives each pair :math:`p` its *lever arms*
:math:`L_{p,i}` [m/rad]: an upper bound on how far any point of either body
can move per radian of joint :math:`i`. A point :math:`x` of a body carried
by joint :math:`j` moves at :math:`\sum_{i \preceq j} \dot q_i\, \omega_i
\times (x - o_i)`, and :math:`|x - o_i| \le \sum_{k \in (i, j]} |{}^{\lambda(k)}
p_k| + r_g` (the joint offsets along the chain, plus the radius of the body's
bounding box about its joint), so the distance of the pair changes by at most
:math:`\sum_i L_{p,i} |\Delta q_i|` when joint :math:`i` travels
:math:`|\Delta q_i|`.

:meth:`CollisionChecker.compute_lower_bounds` gives each pair a cheap lower
bound of its distance: that of the convex hulls of its meshes (a mesh lies in
its hull, so nothing of it is nearer than the hull; primitives stay
themselves). A hull of a few hundred vertices costs coal a few µs where a
mesh of 40 000 triangles near a large box costs milliseconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.collision.scene import Scene
from workbench.collision.self_filter import (
    SelfCollisionFilter,
    compute_self_collision_filter,
    get_link_name,
)
from workbench.errors import InputError
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]

_SCENE_PREFIX = "scene/"
#: GJK tolerance [m] of every distance request (coal's default is 1e-6).
GJK_TOLERANCE = 1e-10


@dataclass(frozen=True, slots=True)
class PairInfo:
    """One checked pair of geometry objects.

    Attributes:
        body_a, body_b: Robot link names or obstacle names.
        geometry_a, geometry_b: Indices in :attr:`CollisionChecker.geometry_model`.
        kind: ``"self"`` or ``"scene"``.
    """

    body_a: str
    body_b: str
    geometry_a: int
    geometry_b: int
    kind: str


class CollisionChecker:
    """Self- and scene-collision distances of one robot.

    Args:
        robot: The robot (revolute joints for the checks along paths).
        scene: Static obstacles in the base frame; default none.
        self_collision: Also check link–link pairs.

    Attributes:
        robot, scene: As given.
        filter: The self-collision filter used.
        geometry_model, geometry_data: Pinocchio's geometry model and data.
        pairs: The checked pairs, in the order of :meth:`compute_distances`.
        levers: Lever arms, shape (P, nv) [m/rad].

    Raises:
        InputError: If an obstacle has a link's name, an ``allow`` entry is
            not a link of the robot, or the robot has no collision geometry.
        SceneFileError: If an obstacle's mesh cannot be read.
    """

    def __init__(
        self, robot: Robot, scene: Scene | None = None, *, self_collision: bool = True
    ):
        self.robot = robot
        self.scene = scene or Scene("empty")
        model = robot.model
        geometry = pin.GeometryModel(robot.collision_model)
        robot_objects = list(geometry.geometryObjects)
        if not robot_objects:
            raise InputError(f"robot {robot.name!r} has no collision geometry")
        self.filter: SelfCollisionFilter = compute_self_collision_filter(robot)
        links = [get_link_name(model, g) for g in robot_objects]
        obstacle_ids = self._add_obstacles(geometry, set(links))
        pairs: list[PairInfo] = []
        if self_collision:
            for i, j in _index_pairs(len(robot_objects)):
                a, b = links[i], links[j]
                if a != b and not self.filter.is_disabled(a, b):
                    pairs.append(PairInfo(a, b, i, j, "self"))
        for obstacle, k in zip(self.scene.obstacles, obstacle_ids, strict=True):
            for i, g in enumerate(robot_objects):
                if g.parentJoint != 0 and links[i] not in obstacle.allow:
                    pairs.append(PairInfo(links[i], obstacle.name, i, k, "scene"))
        for pair in pairs:
            geometry.addCollisionPair(
                pin.CollisionPair(pair.geometry_a, pair.geometry_b)
            )
        self.geometry_model = geometry
        self.geometry_data = pin.GeometryData(geometry)
        for request in self.geometry_data.distanceRequests:
            request.gjk_tolerance = GJK_TOLERANCE
        self.data = model.createData()
        self.pairs = tuple(pairs)
        self.levers = self._compute_levers()
        self._hulls: tuple[pin.GeometryModel, pin.GeometryData] | None = None

    def _add_obstacles(self, geometry: pin.GeometryModel, links: set[str]) -> list[int]:
        ids = []
        all_links = {f.name for f in self.robot.model.frames}
        for obstacle in self.scene.obstacles:
            if obstacle.name in links:
                raise InputError(
                    f"obstacle {obstacle.name!r} has the name of a robot link"
                )
            unknown = sorted(set(obstacle.allow) - all_links)
            if unknown:
                raise InputError(
                    f"obstacle {obstacle.name!r}: 'allow' names unknown link(s) "
                    f"{', '.join(unknown)}; links with geometry: "
                    f"{', '.join(sorted(links))}"
                )
            g = pin.GeometryObject(
                _SCENE_PREFIX + obstacle.name,
                0,
                0,
                obstacle.placement,
                obstacle.build_geometry(),
            )
            g.meshColor = np.array(obstacle.color)
            ids.append(geometry.addGeometryObject(g))
        return ids

    def _compute_levers(self) -> FloatArray:
        model = self.robot.model
        for joint_model in list(model.joints)[1:]:
            if not joint_model.shortname().startswith("JointModelR"):
                raise InputError(
                    f"collision checks along paths need revolute joints, "
                    f"got {joint_model.shortname()}"
                )
        objects = self.geometry_model.geometryObjects
        radius = np.array([_bounding_radius(g) for g in objects])
        offsets = np.array(
            [np.linalg.norm(p.translation) for p in model.jointPlacements]
        )
        arms = np.zeros((len(objects), model.nv))  # [geometry, joint] lever [m/rad]
        for g, obj in enumerate(objects):
            joint, chain = int(obj.parentJoint), 0.0
            while joint > 0:
                arms[g, model.joints[joint].idx_v] = chain + radius[g]
                chain += offsets[joint]
                joint = int(model.parents[joint])
        levers = np.array([arms[p.geometry_a] + arms[p.geometry_b] for p in self.pairs])
        return levers.reshape(len(self.pairs), model.nv)

    @property
    def body_pairs(self) -> list[tuple[str, str]]:
        """``(body_a, body_b)`` of every checked pair, in order."""
        return [(p.body_a, p.body_b) for p in self.pairs]

    def compute_distances(
        self, q: npt.ArrayLike, active: npt.NDArray[np.bool_] | None = None
    ) -> FloatArray:
        """Signed distances of the checked pairs at ``q``.

        Args:
            q: Configuration (nq,) [rad].
            active: Optional mask (P,): compute only these pairs (NaN for
                the others).

        Returns:
            Shape (P,) [m]; <= 0 means contact (minus the penetration depth).
        """
        q = self.robot.check_configuration(q)
        if active is None:
            return self.compute_raw_distances(q)
        mask = np.asarray(active, dtype=bool)
        if mask.shape != (len(self.pairs),):
            raise InputError(f"active must have shape ({len(self.pairs)},)")
        self.set_active(mask)
        try:
            out = self.compute_raw_distances(q)
        finally:
            self.set_active(None)
        out[~mask] = np.nan
        return out

    def set_active(self, active: npt.NDArray[np.bool_] | None) -> None:
        """Compute only the pairs of the mask (P,) from now on; None: all pairs."""
        data = self.geometry_data
        for k in range(len(self.pairs)):
            if active is None or active[k]:
                data.activateCollisionPair(k)
            else:
                data.deactivateCollisionPair(k)

    def compute_raw_distances(self, q: FloatArray) -> FloatArray:
        """Distances (P,) [m] of the active pairs at a checked ``q``, no validation.

        Inactive pairs keep their last value: mask them yourself.
        """
        pin.computeDistances(
            self.robot.model, self.data, self.geometry_model, self.geometry_data, q
        )
        return np.array([r.min_distance for r in self.geometry_data.distanceResults])

    def compute_lower_bounds(self, q: FloatArray) -> FloatArray:
        """Lower bounds (P,) [m] of every pair's distance at a checked ``q``.

        The distances of the pairs with each mesh replaced by its convex hull
        (module docstring), built on the first call; equal to
        :meth:`compute_raw_distances` for pairs of primitives. Not affected by
        :meth:`set_active`.
        """
        model, data = self._hull_pair()
        pin.computeDistances(self.robot.model, self.data, model, data, q)
        return np.array([r.min_distance for r in data.distanceResults])

    def compute_pair_lower_bound(self, q: FloatArray, k: int) -> float:
        """Pair ``k``'s hull bound [m] alone at a checked ``q``, no validation."""
        model, data = self._hull_pair()
        pin.updateGeometryPlacements(self.robot.model, self.data, model, data, q)
        return float(pin.computeDistance(model, data, int(k)).min_distance)

    def _hull_pair(self) -> tuple[pin.GeometryModel, pin.GeometryData]:
        """The hull model and its data (:func:`_hull_model`), built on first use."""
        if self._hulls is None:
            self._hulls = _hull_model(self.geometry_model)
        return self._hulls

    def compute_least_distance(self, q: npt.ArrayLike) -> tuple[int, float]:
        """The pair nearest to contact at ``q`` and its exact distance [m].

        Exact distances are computed only for the pairs whose hull bound
        (:meth:`compute_lower_bounds`) is at most the least exact distance
        found, or 0, so the least is exact and a pair in contact is found
        (the deepest, when several touch). ``(-1, inf)`` without pairs.
        Leaves every pair active.
        """
        q = self.robot.check_configuration(q)
        if not self.pairs:
            return -1, math.inf
        exact = self._measure_where_least(q[None], self.compute_lower_bounds(q)[None])
        k = int(np.nanargmin(exact[0]))
        return k, float(exact[0, k])

    def _measure_where_least(self, qs: FloatArray, lower: FloatArray) -> FloatArray:
        """Exact distances (S, P) [m] where a bound may be the least, NaN elsewhere.

        ``lower`` (S, P) holds the hull bounds of the pairs at the checked
        configurations ``qs`` (S, nq). A pair at a configuration is measured
        when its bound is at most the least exact distance found over all of
        them, or 0, in rounds until none is: the least exact distance, and
        every contact, are then among the measured ones. Leaves every pair
        active (also :mod:`~workbench.collision.along_path`'s coarse samples).
        """
        exact = np.full(lower.shape, np.nan)
        s, k = np.unravel_index(np.argmin(lower), lower.shape)
        exact[s, k] = self.compute_pair_distance(qs[s], int(k))
        try:
            while True:
                reach = max(float(np.nanmin(exact)), 0.0) + 10.0 * GJK_TOLERANCE
                need = (lower <= reach) & np.isnan(exact)
                if not need.any():
                    return exact
                for s in np.flatnonzero(need.any(axis=1)):
                    self.set_active(need[s])
                    exact[s, need[s]] = self.compute_raw_distances(qs[s])[need[s]]
        finally:
            self.set_active(None)

    def compute_pair_distance(self, q: FloatArray, k: int) -> float:
        """Distance [m] of pair ``k`` alone at a checked ``q``, no validation."""
        pin.updateGeometryPlacements(
            self.robot.model, self.data, self.geometry_model, self.geometry_data, q
        )
        return float(
            pin.computeDistance(
                self.geometry_model, self.geometry_data, int(k)
            ).min_distance
        )

    def compute_closest_points(self, k: int) -> tuple[FloatArray, FloatArray]:
        """Nearest points (3,) [m], base frame, of pair ``k`` at the last computed q."""
        result = self.geometry_data.distanceResults[k]
        return np.array(result.getNearestPoint1()), np.array(result.getNearestPoint2())

    def compute_placements(self, q: npt.ArrayLike) -> list[pin.SE3]:
        """Pose of every geometry object in the base frame at ``q``."""
        q = self.robot.check_configuration(q)
        pin.updateGeometryPlacements(
            self.robot.model, self.data, self.geometry_model, self.geometry_data, q
        )
        return [pin.SE3(m) for m in self.geometry_data.oMg]


def _hull_model(
    geometry: pin.GeometryModel,
) -> tuple[pin.GeometryModel, pin.GeometryData]:
    """``geometry`` with every mesh replaced by its convex hull, same pairs.

    A mesh that Qhull cannot wrap (flat, or fewer than four points) stays
    itself: SciPy's Qhull is asked first, with coal's options, because coal's
    own call does not return from such a mesh (the process ends).
    """
    from scipy.spatial import ConvexHull, QhullError

    hulls = pin.GeometryModel()
    for g in geometry.geometryObjects:
        shape = g.geometry
        if hasattr(shape, "num_tris"):  # a coal BVH mesh
            if shape.convex is None:
                try:
                    ConvexHull(np.asarray(shape.vertices()), qhull_options="Qt")
                except (QhullError, ValueError):
                    pass
                else:
                    shape.buildConvexHull(True, "Qt")
            shape = shape.convex or shape
        hulls.addGeometryObject(
            pin.GeometryObject(g.name, g.parentJoint, g.parentFrame, g.placement, shape)
        )
    for pair in geometry.collisionPairs:
        hulls.addCollisionPair(pin.CollisionPair(pair.first, pair.second))
    data = pin.GeometryData(hulls)
    for request in data.distanceRequests:
        request.gjk_tolerance = GJK_TOLERANCE
    return hulls, data


def _index_pairs(n: int) -> list[tuple[int, int]]:
    return [(i, j) for i in range(n) for j in range(i + 1, n)]


def _bounding_radius(geometry: pin.GeometryObject) -> float:
    """Largest distance [m] from the parent joint's origin to the geometry."""
    shape = geometry.geometry
    shape.computeLocalAABB()
    box = shape.aabb_local
    lo, hi = np.array(box.min_), np.array(box.max_)
    corners = np.array(
        [
            [x, y, z]
            for x in (lo[0], hi[0])
            for y in (lo[1], hi[1])
            for z in (lo[2], hi[2])
        ]
    )
    placed = corners @ geometry.placement.rotation.T + geometry.placement.translation
    return float(np.max(np.linalg.norm(placed, axis=1)))


__all__ = ["CollisionChecker", "PairInfo"]
