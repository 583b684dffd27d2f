"""The planner's collision checker: a robot's spheres against a scene, compiled.

:class:`SphereChecker` packs a :class:`~workbench.motion.spheres.SphereModel`,
the robot's joints, the checked link pairs (the SRDF's or the project's
self-collision filter, as :class:`~workbench.collision.CollisionChecker`
uses them) and a scene's obstacles into flat arrays for the kernels of
:mod:`workbench.motion._sphere_kernel`, which document the clearance bounds
and the certified segments. Links on the fixed base are checked against the
moving links, not against the scene (as the exact checker does); an
obstacle's ``allow`` list is honoured.
"""

from __future__ import annotations

import copy
import itertools
from typing import NamedTuple

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.collision.scene import Scene
from workbench.collision.self_filter import compute_self_collision_filter
from workbench.errors import InputError
from workbench.model.per_robot import per_robot
from workbench.motion import _sphere_kernel as kernel
from workbench.motion.pair_tables import PairTables, no_tables
from workbench.motion.spheres import LinkSpheres, SphereModel, mesh_triangles

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


class PackedArrays(NamedTuple):
    """The arrays the kernels take after their own arguments (module docstring)."""

    levers: FloatArray
    robot_int: IntArray
    robot_float: FloatArray
    sizes: IntArray
    scene_int: IntArray
    scene_float: FloatArray
    tris: FloatArray


#: The robot's self-collision filter, computed once per robot object.
_filter = per_robot(compute_self_collision_filter)

_KINDS = {"box": kernel.BOX, "cylinder": kernel.CYLINDER, "sphere": kernel.SPHERE}


class SphereChecker:
    """Clearance and certified segments of a sphere model in a scene.

    Args:
        spheres: The robot's sphere model (:func:`~workbench.motion.spherize`).
        scene: Static obstacles in the base frame; default none.
        allowance: Per clearance entry (L + P,) [m], >= 0: how far the
            spheres of that entry may overlap (a link's: every obstacle);
            default none.
        obstacle_allowance: Per link and obstacle (L, O) [m], >= 0, added to
            the link's allowance against that obstacle alone
            (:func:`~workbench.motion.plan` allows each link–obstacle pair and
            each link pair the overlap it has at the start or a goal where
            the exact meshes are apart, and no more); default none.
        pair_tables: Clearance tables of the pairs whose spheres overlap
            over their one or two relative joints
            (:func:`~workbench.motion.pair_tables.build_pair_tables`,
            aligned with :attr:`pairs`): such a pair's clearance is its
            table's at the nearest node plus its allowance; default none.

    Attributes:
        spheres, scene, pair_tables: As given (``pair_tables``: none for
            every pair when not given).
        allowance: (L + P,) [m], read-only.
        obstacle_allowance: (L, O) [m], read-only.
        links: Link names, in the order of the clearance entries.
        pairs: Checked link pairs ``(link_a, link_b)``, after the links.

    Raises:
        InputError: If the robot has a joint other than a revolute one with
            one coordinate, an obstacle's ``allow`` names no link, an
            allowance is not of its shape or not finite and >= 0, or
            ``pair_tables`` are for another number of pairs.
    """

    def __init__(
        self,
        spheres: SphereModel,
        scene: Scene | None = None,
        *,
        allowance: npt.ArrayLike | None = None,
        obstacle_allowance: npt.ArrayLike | None = None,
        pair_tables: PairTables | None = None,
    ) -> None:
        self.spheres = spheres
        self.scene = scene or Scene("empty")
        self.links = tuple(link.link for link in spheres.links)
        self.pairs = _pairs(spheres)
        self.pair_tables = pair_tables or no_tables(len(self.pairs))
        if len(self.pair_tables.start) != len(self.pairs):
            raise InputError(
                f"pair_tables hold {len(self.pair_tables.start)} pairs; this "
                f"checker has {len(self.pairs)}"
            )
        n_entries = len(self.links) + len(self.pairs)
        self.allowance = _check_allowance(
            np.zeros(n_entries) if allowance is None else allowance, (n_entries,)
        )
        shape = (len(self.links), len(self.scene.obstacles))
        self.obstacle_allowance = _check_allowance(
            np.zeros(shape) if obstacle_allowance is None else obstacle_allowance,
            shape,
        )
        (
            self._robot_int,
            self._robot_float,
            self._levers,
            sizes,
            self._allowance_at,
            self._obstacle_allowance_at,
            self._allowed_at,
        ) = _pack_robot(
            spheres,
            self.scene,
            self.allowance,
            self.obstacle_allowance,
            self.pair_tables,
        )
        self._scene_int, self._scene_float, self._tris = _pack_scene(self.scene)
        self._sizes = np.array(sizes, dtype=np.int64)
        self._store = np.zeros((kernel.MAX_EVALUATIONS, len(self._levers)))

    def with_allowance(
        self, allowance: npt.ArrayLike, obstacle_allowance: npt.ArrayLike | None = None
    ) -> SphereChecker:
        """This checker with other allowances (L + P,), (L, O) [m], packed once.

        Raises:
            InputError: If an allowance is not of its shape, finite and >= 0.
        """
        allowed = _check_allowance(allowance, self.allowance.shape)
        by_obstacle = _check_allowance(
            np.zeros(self.obstacle_allowance.shape)
            if obstacle_allowance is None
            else obstacle_allowance,
            self.obstacle_allowance.shape,
        )
        out = copy.copy(self)
        out.allowance, out.obstacle_allowance = allowed, by_obstacle
        out._robot_float = self._robot_float.copy()
        out._robot_float[self._allowance_at] = allowed
        out._robot_float[self._obstacle_allowance_at] = _per_obstacle(
            allowed, by_obstacle
        ).ravel()
        out._store = np.zeros_like(self._store)
        return out

    @property
    def arrays(self) -> PackedArrays:
        """The packed arrays the kernels take after their own arguments."""
        return PackedArrays(
            self._levers,
            self._robot_int,
            self._robot_float,
            self._sizes,
            self._scene_int,
            self._scene_float,
            self._tris,
        )

    def clearances(self, q: npt.ArrayLike) -> FloatArray:
        """Clearance of every link to the scene and of every pair [m] at ``q``.

        Returns:
            (L + P,): links (:attr:`links`) then pairs (:attr:`pairs`); a
            negative entry is a contact; inf for a link that no obstacle
            concerns.
        """
        q = self.spheres.robot.check_configuration(q)
        out = np.full(len(self._levers), np.inf)
        kernel.clearances(q, *self.arrays[1:], False, out)
        return out

    def obstacle_clearances(self, q: npt.ArrayLike) -> FloatArray:
        """Clearance of every link to every obstacle [m] at ``q``.

        One evaluation per obstacle, the others left out (as an obstacle's
        ``allow`` leaves a link out): for the ends of a motion, not its
        inside.

        Returns:
            (L, O): links (:attr:`links`) by the scene's obstacles, each with
            its allowances; inf where a link is not checked against an
            obstacle (on the fixed base, or in the obstacle's ``allow``).
        """
        q = self.spheres.robot.check_configuration(q)
        out = np.full(self.obstacle_allowance.shape, np.inf)
        n_links, n_obstacles = len(self.links), len(self.scene.obstacles)
        robot_int = self._robot_int.copy()
        allowed = robot_int[self._allowed_at].reshape(n_links, max(1, n_obstacles))
        given = allowed.copy()
        entries = np.empty(len(self._levers))
        for o in range(n_obstacles):
            allowed[:] = 1
            allowed[:, o] = given[:, o]
            kernel.clearances(q, robot_int, *self.arrays[2:], False, entries)
            out[:, o] = entries[:n_links]
        return out

    def is_free(self, q: npt.ArrayLike) -> bool:
        """Whether no sphere touches an obstacle or a checked link at ``q``."""
        q = self.spheres.robot.check_configuration(q)
        out = np.empty(len(self._levers))
        return bool(kernel.clearances(q, *self.arrays[1:], True, out))

    def is_segment_free(self, qa: npt.ArrayLike, qb: npt.ArrayLike) -> bool:
        """Whether the straight joint segment is proven free, ends included."""
        robot = self.spheres.robot
        a, b = robot.check_configuration(qa), robot.check_configuration(qb)
        return bool(kernel.motion_free(a, b, *self.arrays, self._store))


def _check_allowance(allowance: npt.ArrayLike, shape: tuple[int, ...]) -> FloatArray:
    try:
        allowed = np.array(allowance, dtype=np.float64)
    except (TypeError, ValueError):
        allowed = np.full(1, np.nan)
    if (
        allowed.shape != shape
        or not np.all(np.isfinite(allowed))
        or np.any(allowed < 0)
    ):
        what = (
            f"{shape[0]} finite values >= 0 [m] (links, then pairs)"
            if len(shape) == 1
            else f"({shape[0]}, {shape[1]}) finite values >= 0 [m] (links × obstacles)"
        )
        raise InputError(f"allowance must be {what}, got shape {allowed.shape}")
    allowed.setflags(write=False)
    return allowed


def _per_obstacle(allowance: FloatArray, obstacle_allowance: FloatArray) -> FloatArray:
    """Each link's allowance against each obstacle (L, max(1, O)) [m], packed."""
    n_links = len(obstacle_allowance)
    out = np.repeat(allowance[:n_links, None], max(1, obstacle_allowance.shape[1]), 1)
    out[:, : obstacle_allowance.shape[1]] += obstacle_allowance
    return out


def _pairs(spheres: SphereModel) -> tuple[tuple[str, str], ...]:
    robot = spheres.robot
    checked = _filter(robot)
    names = [link.link for link in spheres.links]
    return tuple(
        (a, b)
        for i, a in enumerate(names)
        for b in names[i + 1 :]
        if not checked.is_disabled(a, b)
        and not (
            spheres.links[i].joint == 0 and spheres.links[names.index(b)].joint == 0
        )
    )


def _pack_robot(
    spheres: SphereModel,
    scene: Scene,
    allowance: FloatArray,
    obstacle_allowance: FloatArray,
    tables: PairTables,
) -> tuple[IntArray, FloatArray, FloatArray, list[int], slice, slice, slice]:
    robot = spheres.robot
    model = robot.model
    if model.nq != model.nv:
        raise InputError(
            "motion planning needs revolute joints with one coordinate each; "
            f"{robot.name!r} has nq = {model.nq}, nv = {model.nv}"
        )
    axes = np.zeros((model.njoints, 3))
    for j in range(1, model.njoints):
        name = model.joints[j].shortname()
        if name in ("JointModelRX", "JointModelRY", "JointModelRZ"):
            axes[j, "XYZ".index(name[-1])] = 1.0
        elif name == "JointModelRevoluteUnaligned":
            axes[j] = np.asarray(model.joints[j].extract().axis)
        else:
            raise InputError(
                f"motion planning needs revolute joints; joint "
                f"{model.names[j]!r} is a {name}"
            )
    links = spheres.links
    names = [link.link for link in links]
    all_links = {f.name for f in model.frames}
    allowed = np.zeros((len(links), max(1, len(scene.obstacles))), dtype=np.int64)
    for o, obstacle in enumerate(scene.obstacles):
        unknown = sorted(set(obstacle.allow) - all_links)
        if unknown:
            raise InputError(
                f"obstacle {obstacle.name!r}: 'allow' names unknown link(s) "
                f"{', '.join(unknown)}"
            )
        for name in obstacle.allow:
            if name in names:
                allowed[names.index(name), o] = 1
    pairs = _pairs(spheres)
    start = model.njoints * 2 + len(links) * 2 + len(pairs) * 2
    allowed_at = slice(start, start + allowed.size)
    pa = np.array([names.index(a) for a, _ in pairs], dtype=np.int64)
    pb = np.array([names.index(b) for _, b in pairs], dtype=np.int64)
    # Each link's spheres in groups of at most GROUP_SIZE near ones, each group
    # with its bounding sphere: the kernel skips a group that cannot come nearer.
    orders, group_first, group_center, group_radius = [], [0], [], []
    link_groups = [0]
    for link in links:
        order, groups = _groups(link.centers)
        orders.append(order)
        for group in groups:
            center, radius = _bounding_sphere(
                link.centers[order[group]], link.radii[order[group]]
            )
            group_center.append(center)
            group_radius.append(radius)
            group_first.append(group_first[-1] + len(group))
        link_groups.append(link_groups[-1] + len(groups))
    bound_center, bound_radius = [], []
    for link in links:
        center, radius = _bounding_sphere(link.centers, link.radii)
        bound_center.append(center)
        bound_radius.append(radius)
    parents = np.array(model.parents, dtype=np.int64)
    parents[0] = -1
    jq = np.array([max(model.joints[j].idx_q, 0) for j in range(model.njoints)])
    robot_int = np.concatenate(
        [
            parents,
            jq,
            np.array([link.joint for link in links], dtype=np.int64),
            pa,
            pb,
            np.array([link.joint != 0 for link in links], dtype=np.int64),
            allowed.ravel(),
            np.array(link_groups, dtype=np.int64),
            np.array(group_first, dtype=np.int64),
            tables.start,
            tables.joint.ravel(),
            tables.cells.ravel(),
            tables.periodic.ravel(),
        ]
    ).astype(np.int64)
    rotations = np.array([p.rotation for p in model.jointPlacements])
    positions = np.array([p.translation for p in model.jointPlacements])
    before_allowance = [
        rotations.ravel(),
        positions.ravel(),
        axes.ravel(),
        np.array(bound_center).ravel(),
        np.array(bound_radius),
        np.concatenate(
            [link.centers[o] for link, o in zip(links, orders, strict=True)]
        ).ravel(),
        np.concatenate([link.radii[o] for link, o in zip(links, orders, strict=True)]),
    ]
    start = sum(part.size for part in before_allowance)
    allowance_at = slice(start, start + len(allowance))
    robot_float = np.concatenate(
        [
            *before_allowance,
            allowance,
            np.array(group_center).ravel(),
            np.array(group_radius),
            tables.lower.ravel(),
            tables.step.ravel(),
            tables.values,
        ]
    )
    per_obstacle = _per_obstacle(allowance, obstacle_allowance).ravel()
    obstacle_allowance_at = slice(
        len(robot_float), len(robot_float) + per_obstacle.size
    )
    robot_float = np.concatenate([robot_float, per_obstacle])
    # A pair with a table is judged by its meshes' distance: its geometry's
    # speed bounds how fast that changes.
    levers = _levers(
        model, links, bound_center, axes, positions, pa, pb, tables.start >= 0
    )
    sizes = [
        model.njoints,
        len(links),
        group_first[-1],
        len(pairs),
        len(scene.obstacles),
        model.nv,
        len(group_radius),
        len(tables.values),
    ]
    return (
        robot_int,
        robot_float,
        np.ascontiguousarray(levers),
        sizes,
        allowance_at,
        obstacle_allowance_at,
        allowed_at,
    )


def _levers(
    model: pin.Model,
    links: tuple[LinkSpheres, ...],
    bound_center: list[FloatArray],
    axes: FloatArray,
    positions: FloatArray,
    pa: IntArray,
    pb: IntArray,
    padded: npt.NDArray[np.bool_],
) -> FloatArray:
    """Lever arms (L + P, nv) [m/rad] of the links, then of the checked pairs.

    Entry (e, i) bounds how fast a clearance of entry e changes when joint i
    turns: the speed of the sphere centres, the kernels' motion bound. For
    the pairs marked in ``padded`` (P,), of every point of their spheres (the
    levers of each link grown by its largest radius), so of the links'
    geometry, which they hold.
    """
    # Lever arm of link l about joint i [m/rad]: a bound on the distance of
    # its sphere centres (and bounding centre) from the axis of joint i, in
    # any configuration: from its own joint's axis exactly; from an ancestor's,
    # the distance of the next joint's origin from that axis plus the chain
    # of offsets below (d(x, axis) <= d(o, axis) + |x - o|).
    offsets = np.linalg.norm(positions, axis=1)
    link_points = [
        np.vstack([link.centers, bound_center[li]]) for li, link in enumerate(links)
    ]
    link_levers = np.zeros((len(links), model.nv))
    for li, link in enumerate(links):
        if link.joint == 0:
            continue
        points = link_points[li]
        joint = link.joint
        link_levers[li, model.joints[joint].idx_v] = np.max(
            np.linalg.norm(np.cross(points, axes[joint]), axis=1)
        )
        chain = float(np.max(np.linalg.norm(points, axis=1)))
        child, joint = joint, int(model.parents[joint])
        while joint > 0:
            off_axis = float(np.linalg.norm(np.cross(positions[child], axes[joint])))
            link_levers[li, model.joints[joint].idx_v] = off_axis + chain
            chain += offsets[child]
            child, joint = joint, int(model.parents[joint])
    # A pair's distance changes only through the joints that move one link
    # relative to the other: those on one side of their common ancestor (a
    # joint both hang on moves them together).
    carried = np.zeros((len(links), model.nv), dtype=bool)
    for li, link in enumerate(links):
        joint = link.joint
        while joint > 0:
            carried[li, model.joints[joint].idx_v] = True
            joint = int(model.parents[joint])
    apart = carried[pa] ^ carried[pb]
    grow = np.array([float(link.radii.max(initial=0.0)) for link in links])
    # Such a joint turns one link about its axis relative to the other, which
    # is the other turning the opposite way: its points' distance from that
    # axis bounds the change too, and the smaller of the two counts.
    far = np.full((len(links), model.nv), np.inf)
    for li, link in enumerate(links):
        for j in range(1, model.njoints):
            v = model.joints[j].idx_v
            if not carried[li, v]:
                far[li, v] = _lever_from_the_other_side(
                    model, link.joint, link_points[li], j, axes, offsets
                )
    still = np.where(carried[pa], pb[:, None], pa[:, None])  # (P, nv)
    columns = np.arange(model.nv)
    pair_levers = np.minimum(link_levers[pa] + link_levers[pb], far[still, columns])
    grown = link_levers + grow[:, None] * carried
    pair_grown = np.minimum(grown[pa] + grown[pb], far[still, columns] + grow[still])
    pair_levers = np.where(
        apart, np.where(padded[:, None], pair_grown, pair_levers), 0.0
    )
    return np.concatenate([link_levers, pair_levers.reshape(-1, model.nv)])


def _lever_from_the_other_side(
    model: pin.Model,
    own: int,
    points: FloatArray,
    joint: int,
    axes: FloatArray,
    offsets: FloatArray,
) -> float:
    """How far [m/rad] a link's centres can be from a joint's axis not carrying it.

    A bound on the distance of ``points`` (N, 3) [m] (the sphere centres and
    bounding centre of a link on joint ``own``, in its frame) from the axis of
    ``joint``, in any configuration: exact when the joint hangs on ``own``
    (its axis fixed in the link's frame), else their distance from the joint
    origin plus the chain of offsets between the two joint origins.
    """
    if int(model.parents[joint]) == own:
        placement = model.jointPlacements[joint]
        axis = placement.rotation @ axes[joint]
        return float(
            np.max(
                np.linalg.norm(np.cross(points - placement.translation, axis), axis=1)
            )
        )
    chain = {}
    length, j = 0.0, own
    while True:
        chain[j] = length
        if j == 0:
            break
        length += offsets[j]
        j = int(model.parents[j])
    length, j = 0.0, joint
    while j not in chain:
        length += offsets[j]
        j = int(model.parents[j])
    return float(np.max(np.linalg.norm(points, axis=1))) + chain[j] + length


#: Most spheres of one group of a link (the kernel's middle level).
GROUP_SIZE = 8


def _groups(centers: FloatArray) -> tuple[IntArray, list[IntArray]]:
    """An order of the spheres and its groups (ranges) of <= GROUP_SIZE.

    Groups are split at the median along their principal axis, so that each
    holds near spheres.
    """
    pending, done = [np.arange(len(centers))], []
    while pending:
        group = pending.pop()
        if len(group) <= GROUP_SIZE:
            done.append(group)
            continue
        offsets = centers[group] - centers[group].mean(axis=0)
        along = offsets @ np.linalg.svd(offsets, full_matrices=False)[2][0]
        order = group[np.argsort(along, kind="stable")]
        pending += [order[len(order) // 2 :], order[: len(order) // 2]]
    order = np.concatenate(done) if done else np.zeros(0, dtype=np.int64)
    starts = np.cumsum([0] + [len(g) for g in done])
    return order, [np.arange(a, b) for a, b in itertools.pairwise(starts)]


def _bounding_sphere(
    centers: FloatArray, radii: FloatArray
) -> tuple[FloatArray, float]:
    """A sphere (centre (3,) [m], radius [m]) holding the given spheres."""
    lo = (centers - radii[:, None]).min(axis=0)
    hi = (centers + radii[:, None]).max(axis=0)
    center = 0.5 * (lo + hi)
    return center, float(np.max(np.linalg.norm(centers - center, axis=1) + radii))


def _pack_scene(scene: Scene) -> tuple[IntArray, FloatArray, FloatArray]:
    kinds, rotations, positions, sizes, first, tris = [], [], [], [], [0], []
    for obstacle in scene.obstacles:
        placement: pin.SE3 = obstacle.placement
        rotations.append(placement.rotation)
        positions.append(placement.translation)
        if obstacle.shape == "box":
            size = 0.5 * np.array(obstacle.size)
        elif obstacle.shape == "cylinder":
            size = np.array([obstacle.size[0], 0.5 * obstacle.size[1], 0.0])
        elif obstacle.shape == "sphere":
            size = np.array([obstacle.size[0], 0.0, 0.0])
        else:
            geometry = obstacle.build_geometry()
            vertices = np.array(geometry.vertices(), dtype=np.float64).reshape(-1, 3)
            triangles = mesh_triangles(geometry)
            corners = vertices[triangles]
            # Triangles in the obstacle frame; the kernel expresses p there.
            center = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
            radius = float(np.max(np.linalg.norm(vertices - center, axis=1)))
            positions[-1] = placement.translation + placement.rotation @ center
            tris.append(corners - center)
            size = np.array([radius, 0.0, 0.0])
        kinds.append(_KINDS.get(obstacle.shape, kernel.MESH))
        sizes.append(size)
        first.append(first[-1] + (len(tris[-1]) if obstacle.shape == "mesh" else 0))
    n = len(kinds)
    scene_int = np.concatenate(
        [np.array(kinds, dtype=np.int64), np.array(first, dtype=np.int64)]
    )
    scene_float = (
        np.concatenate(
            [
                np.array(rotations).reshape(-1),
                np.array(positions).reshape(-1),
                np.array(sizes).reshape(-1),
            ]
        )
        if n
        else np.zeros(0)
    )
    soup: FloatArray = (
        np.concatenate(tris).astype(np.float64) if tris else np.zeros((0, 3, 3))
    )
    return scene_int, scene_float, np.ascontiguousarray(soup)


__all__ = ["PackedArrays", "SphereChecker"]
