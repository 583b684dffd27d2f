"""The planner: sphere model, compiled clearances, certified segments, plan()."""

from __future__ import annotations

import dataclasses
import heapq
import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import workbench as wb
from workbench.collision import CollisionChecker
from workbench.collision.scene import Obstacle, Scene
from workbench.errors import InputError
from workbench.motion import (
    SphereChecker,
    get_pair_tables,
    goal_configurations,
    plan,
    spherize,
)
from workbench.motion.pair_tables import SHARE, build_pair_tables
from workbench.motion.planner import ALLOWANCE_MARGIN
from workbench.motion.spheres import mesh_triangles
from workbench.paper_data import ANGELES_PICK_Q_DEG, ANGELES_PLACE_Q_DEG

#: Sphere containment and kernel-vs-numpy agreement [m] (exact arithmetic).
EXACT_TOL = 1e-9
#: FK residual of a pose goal [m, rad].
FK_TOL = 1e-9

PICK, PLACE = np.radians(ANGELES_PICK_Q_DEG), np.radians(ANGELES_PLACE_Q_DEG)


@pytest.fixture(scope="module")
def puma() -> wb.Robot:
    return wb.load_robot("puma560").with_limits(acceleration_limit=np.full(6, 4.0))


@pytest.fixture(scope="module")
def puma_spheres(puma: wb.Robot):
    return spherize(puma)


@pytest.fixture(scope="module")
def ur5_spheres():
    return spherize(wb.load_robot("ur5"))


@pytest.fixture(scope="module")
def ur5_allowance(ur5_spheres):
    """An allowance (L + P,) [m] that lets the UR5's inseparable pairs overlap.

    Its upper arm passes 14 mm from its base in every pose, its wrist links
    a few millimetres from each other: closer than the spheres' excess. The
    planner allows such pairs their overlap at the ends
    (``MotionPlan.allowances``); here they may overlap by a metre.
    """
    robot = ur5_spheres.robot
    checker = SphereChecker(ur5_spheres)
    rng = np.random.default_rng(7)
    allowance = np.zeros(len(checker.links) + len(checker.pairs))
    for _ in range(200):
        values = checker.clearances(
            robot.lower + rng.random(6) * (robot.upper - robot.lower)
        )
        allowance[len(checker.links) :][values[len(checker.links) :] < 0] = 1.0
    return allowance


def _wall(robot: wb.Robot) -> Scene:
    """A 10 cm box on the straight joint path from the pick to the place."""
    middle = robot.fk(0.5 * (PICK + PLACE)).translation
    box = Obstacle("wall", "box", (0.1, 0.1, 0.1), pin.SE3(np.eye(3), middle))
    return Scene("wall", (box,))


def _mixed_scene() -> Scene:
    rotation = pin.utils.rpyToMatrix(0.3, -0.2, 0.7)
    return Scene(
        "mixed",
        (
            Obstacle(
                "box",
                "box",
                (0.3, 0.2, 0.1),
                pin.SE3(rotation, np.array([0.5, 0.2, 0.3])),
            ),
            Obstacle(
                "cyl",
                "cylinder",
                (0.05, 0.4),
                pin.SE3(rotation.T, np.array([-0.3, 0.4, 0.5])),
            ),
            Obstacle(
                "ball",
                "sphere",
                (0.08,),
                pin.SE3(np.eye(3), np.array([0.1, -0.5, 0.6])),
            ),
        ),
    )


def _vertices_in_joint_frame(
    robot: wb.Robot, geometry: pin.GeometryObject
) -> np.ndarray:
    shape = geometry.geometry
    kind = type(shape).__name__
    if kind.startswith("BVHModel"):
        local = np.array(shape.vertices()).reshape(-1, 3)
    elif kind == "Box":
        half = np.array(shape.halfSide)
        local = (
            np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
            * half
        )
    elif kind == "Cylinder":
        angle = np.linspace(0, 2 * math.pi, 64, endpoint=False)
        ring = np.column_stack([np.cos(angle), np.sin(angle)]) * shape.radius
        local = np.concatenate(
            [
                np.column_stack([ring, np.full(64, z)])
                for z in (-shape.halfLength, shape.halfLength)
            ]
        )
    else:
        local = np.zeros((1, 3))
    return local @ geometry.placement.rotation.T + geometry.placement.translation


@pytest.fixture(scope="module")
def mbm_panda_spheres(request):
    urdf = request.path.parent / "data" / "motionbenchmaker" / "panda" / "panda.urdf"
    return spherize(wb.load_robot(str(urdf)))


@pytest.mark.parametrize(
    "fixture", ["puma_spheres", "ur5_spheres", "mbm_panda_spheres"]
)
def test_every_vertex_is_inside_a_sphere_of_its_link(fixture, request) -> None:
    model = request.getfixturevalue(fixture)
    robot = model.robot
    by_link = {link.link: link for link in model.links}
    for geometry in robot.collision_model.geometryObjects:
        link = by_link[robot.model.frames[geometry.parentFrame].name]
        assert link.joint == geometry.parentJoint
        points = _vertices_in_joint_frame(robot, geometry)
        gap = np.linalg.norm(points[:, None] - link.centers[None], axis=2) - link.radii
        assert np.all(gap.min(axis=1) <= EXACT_TOL), geometry.name
        assert link.excess >= 0.0


def test_every_point_of_every_triangle_is_inside(ur5_spheres) -> None:
    """Points inside the triangles, not only the vertices, are covered."""
    robot = ur5_spheres.robot
    rng = np.random.default_rng(0)
    for geometry in robot.collision_model.geometryObjects:
        shape = geometry.geometry
        if not type(shape).__name__.startswith("BVHModel"):
            continue
        link = next(x for x in ur5_spheres.links if x.joint == geometry.parentJoint)
        vertices = np.array(shape.vertices()).reshape(-1, 3)
        tris = mesh_triangles(shape)
        u = rng.random((len(tris), 2))
        u[u.sum(axis=1) > 1] = 1 - u[u.sum(axis=1) > 1]
        a, b, c = (vertices[tris[:, k]] for k in range(3))
        points = a + u[:, :1] * (b - a) + u[:, 1:] * (c - a)
        points = points @ geometry.placement.rotation.T + geometry.placement.translation
        gap = np.linalg.norm(points[:, None] - link.centers[None], axis=2) - link.radii
        assert np.all(gap.min(axis=1) <= EXACT_TOL), geometry.name


def test_the_spheres_of_closed_meshes_reach_at_most_the_tolerance(
    ur5_spheres,
) -> None:
    """The UR5's meshes are closed: every link's excess is within 2 cm."""
    for link in ur5_spheres.links:
        assert link.excess <= ur5_spheres.tolerance + EXACT_TOL, link.link


def _cube_with_a_hole(half: float) -> tuple[np.ndarray, np.ndarray]:
    """A cube's 12 triangles, one of them left out (a hole)."""
    corners = np.array(
        [[x, y, z] for x in (-half, half) for y in (-half, half) for z in (-half, half)]
    )
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4)]
    faces.append((1, 5, 7, 3))
    tris = [t for a, b, c, d in faces for t in ((a, b, c), (a, c, d))]
    return corners, np.array(tris[:-1])


@pytest.mark.parametrize("holed", [False, True])
def test_a_cube_is_covered_by_few_spheres_even_with_a_hole(holed) -> None:
    """Deep spheres on the medial axis, found by the winding number if holed."""
    from workbench.motion.spheres import _cover_mesh, _surface_samples

    vertices, tris = _cube_with_a_hole(0.05)
    if not holed:
        tris = np.concatenate([tris, [[1, 7, 3]]])
    centers, radii, _ = _cover_mesh(vertices, tris, 0.02)
    points, _ = _surface_samples(vertices, tris, 0.001)
    gap = np.linalg.norm(points[:, None] - centers[None], axis=2) - radii
    assert np.all(gap.min(axis=1) <= EXACT_TOL)
    assert len(radii) <= 40
    assert radii.max() > 0.05  # a sphere about the inside, not only the skin


def _plain_greedy(centers, radii, points, deltas, held):
    """The lazy greedy set cover in plain Python, every sample visited."""
    inside = [
        set(
            np.flatnonzero(
                (radii[i] - deltas >= 0)
                & (
                    np.sum((points - centers[i]) ** 2, axis=1)
                    <= (radii[i] - deltas) ** 2
                )
            ).tolist()
        )
        for i in range(len(centers))
    ]
    free = set(np.flatnonzero(~held).tolist())
    heap = [(-len(inside[i] & free), i) for i in range(len(centers))]
    heap = [item for item in heap if item[0] < 0]
    heapq.heapify(heap)
    chosen = []
    while heap:
        _, i = heapq.heappop(heap)
        count = len(inside[i] & free)
        if count == 0:
            continue
        if heap and -heap[0][0] > count:
            heapq.heappush(heap, (-count, i))
            continue
        chosen.append(i)
        free -= inside[i]
    return chosen, free


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 60), st.integers(1, 400))
def test_the_greedy_cover_equals_a_plain_one(seed, n_centers, n_points) -> None:
    """The compiled cover, which visits only the grid cells a sphere meets,
    picks the same spheres in the same order as one that visits every sample."""
    from workbench.motion._cover_kernel import greedy_cover

    rng = np.random.default_rng(seed)
    points = rng.uniform(-0.1, 0.1, (n_points, 3)) * rng.uniform(0.01, 1.0, 3)
    deltas = rng.uniform(0.0, 0.004, n_points)
    centers = rng.uniform(-0.1, 0.1, (n_centers, 3))
    radii = rng.uniform(0.001, 0.08, n_centers)
    held = rng.random(n_points) < 0.2
    expected, free = _plain_greedy(centers, radii, points, deltas, held)
    out = held.copy()
    chosen = np.zeros(n_centers, dtype=np.int64)
    taken = greedy_cover(
        centers, radii, np.ascontiguousarray(points), deltas, out, chosen
    )
    assert chosen[:taken].tolist() == expected
    assert set(np.flatnonzero(~out).tolist()) == free


def test_surface_samples_are_each_triangles_grid_in_order() -> None:
    """The batched samples equal a triangle-by-triangle grid, point for point."""
    from workbench.motion.spheres import _surface_samples

    rng = np.random.default_rng(3)
    vertices = rng.uniform(-0.05, 0.05, (40, 3))
    triangles = rng.integers(0, 40, (60, 3))
    triangles[0] = (5, 5, 5)  # a degenerate one
    points, deltas = [vertices], [np.zeros(len(vertices))]
    for a, b, c in vertices[triangles]:
        longest = max(math.dist(a, b), math.dist(b, c), math.dist(c, a))
        n = max(1, math.ceil(longest / 0.006))
        for i in range(n + 1):
            for j in range(n + 1 - i):
                points.append([a + i / n * (b - a) + j / n * (c - a)])
                deltas.append([longest / n / math.sqrt(3.0)])
    got_points, got_deltas = _surface_samples(vertices, triangles, 0.006)
    np.testing.assert_allclose(got_points, np.concatenate(points), rtol=0, atol=1e-15)
    np.testing.assert_allclose(got_deltas, np.concatenate(deltas), rtol=1e-14)


def test_spherize_refuses_a_bad_tolerance(puma) -> None:
    for bad in (0, -1.0, math.nan, math.inf, "1"):
        with pytest.raises(InputError, match="tolerance"):
            spherize(puma, tolerance=bad)  # type: ignore[arg-type]


def _placed_spheres(checker: SphereChecker, q: np.ndarray) -> list[np.ndarray]:
    """Each link's sphere centres (S, 3) [m] in the base frame, in numpy."""
    model = checker.spheres
    robot = model.robot
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, q)
    return [
        x.centers @ data.oMi[x.joint].rotation.T + data.oMi[x.joint].translation
        for x in model.links
    ]


def _numpy_obstacle_clearances(checker: SphereChecker, q: np.ndarray) -> np.ndarray:
    """Every link's spheres against every obstacle (L, O), in numpy (exact formulas)."""
    world = _placed_spheres(checker, q)
    obstacles = checker.scene.obstacles
    out = np.full((len(world), len(obstacles)), np.inf)
    for li, link in enumerate(checker.spheres.links):
        if link.joint == 0:
            continue
        for k, o in enumerate(obstacles):
            local = (world[li] - o.placement.translation) @ o.placement.rotation
            if o.shape == "box":
                e = np.abs(local) - 0.5 * np.array(o.size)
                d = np.linalg.norm(np.maximum(e, 0), axis=1) + np.minimum(
                    e.max(axis=1), 0
                )
            elif o.shape == "cylinder":
                e = np.column_stack(
                    [
                        np.hypot(local[:, 0], local[:, 1]) - o.size[0],
                        np.abs(local[:, 2]) - 0.5 * o.size[1],
                    ]
                )
                d = np.linalg.norm(np.maximum(e, 0), axis=1) + np.minimum(
                    e.max(axis=1), 0
                )
            else:
                d = np.linalg.norm(local, axis=1) - o.size[0]
            out[li, k] = float(np.min(d - link.radii))
    return out + checker.allowance[: len(world), None] + checker.obstacle_allowance


def _numpy_clearances(checker: SphereChecker, q: np.ndarray) -> np.ndarray:
    """Every sphere against every obstacle and pair, in numpy (exact formulas)."""
    model = checker.spheres
    world = _placed_spheres(checker, q)
    by_obstacle = _numpy_obstacle_clearances(checker, q)
    out = list(by_obstacle.min(axis=1, initial=np.inf))
    names = [x.link for x in model.links]
    for a, b in checker.pairs:
        i, j = names.index(a), names.index(b)
        gap = np.linalg.norm(world[i][:, None] - world[j][None], axis=2)
        out.append(
            float(np.min(gap - model.links[i].radii[:, None] - model.links[j].radii))
        )
    return np.array(out) + np.concatenate(
        [np.zeros(len(names)), checker.allowance[len(names) :]]
    )


def _within_limits(robot: wb.Robot, fractions: list[float]) -> np.ndarray:
    """The configuration at ``fractions`` in [-1, 1] of each joint's half range."""
    middle, half = 0.5 * (robot.lower + robot.upper), 0.5 * (robot.upper - robot.lower)
    return middle + np.array(fractions) * half


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6))
def test_compiled_clearances_equal_numpy(ur5_spheres, fractions) -> None:
    robot = ur5_spheres.robot
    q = _within_limits(robot, fractions)
    checker = SphereChecker(ur5_spheres, _mixed_scene())
    expected = _numpy_clearances(checker, q)
    got = checker.clearances(q)
    if np.all(expected > 0):
        np.testing.assert_allclose(got, expected, atol=EXACT_TOL, rtol=0)
        assert checker.is_free(q)
    else:
        assert not checker.is_free(q)
        assert got.min() < 0


@settings(max_examples=25, deadline=None)
@given(
    st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6),
    st.integers(0, 2**32 - 1),
)
def test_each_link_obstacle_clearance_equals_numpy(
    ur5_spheres, fractions, seed
) -> None:
    """``obstacle_clearances`` (L, O): every link's spheres against each obstacle
    alone, its allowances added; their least per link is the link's entry of
    ``clearances``."""
    robot = ur5_spheres.robot
    q = _within_limits(robot, fractions)
    rng = np.random.default_rng(seed)
    plain = SphereChecker(ur5_spheres, _mixed_scene())
    n_links = len(plain.links)
    allowance = np.zeros(n_links + len(plain.pairs))
    allowance[:n_links] = rng.uniform(0.0, 0.01, n_links)
    checker = plain.with_allowance(
        allowance, rng.uniform(0.0, 0.05, plain.obstacle_allowance.shape)
    )
    got = checker.obstacle_clearances(q)
    np.testing.assert_allclose(
        got, _numpy_obstacle_clearances(checker, q), atol=EXACT_TOL, rtol=0
    )
    assert np.isinf(got[[link.joint == 0 for link in ur5_spheres.links]]).all()
    np.testing.assert_allclose(
        checker.clearances(q)[:n_links], got.min(axis=1), atol=EXACT_TOL, rtol=0
    )


def _point_triangle_distances(points: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Distance (P,) [m] of each point to the nearest triangle (T, 3, 3).

    Independent of the kernel's region tests: the projection onto the plane
    where it falls inside (barycentric coordinates), else the nearest of the
    three edges (clamped segment projections).
    """
    p = points[:, None, None, :]  # (P, 1, 1, 3)
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    height = np.einsum("ptk,tk->pt", p[:, :, 0] - a, normal)
    foot = p[:, :, 0] - height[..., None] * normal  # (P, T, 3)
    inside = np.ones(height.shape, dtype=bool)
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ptk,tk->pt", np.cross(v - u, foot - u), normal) >= 0
    starts = np.stack([a, b, c], axis=1)  # (T, 3, 3): edge starts
    ends = np.stack([b, c, a], axis=1)
    edge = ends - starts
    along = np.einsum("ptek,tek->pte", p - starts, edge) / np.einsum(
        "tek,tek->te", edge, edge
    )
    nearest = starts + np.clip(along, 0.0, 1.0)[..., None] * edge
    to_edges = np.linalg.norm(p - nearest, axis=3).min(axis=2)
    return np.where(inside, np.abs(height), to_edges).min(axis=1)


@settings(max_examples=20, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6))
def test_compiled_mesh_clearances_equal_numpy(ur5_spheres, fractions) -> None:
    """A mesh obstacle: the distance to its nearest triangle, minus the radius."""
    robot = ur5_spheres.robot
    q = _within_limits(robot, fractions)
    vertices = np.array(
        [[0.0, 0.0, 0.0], [0.4, 0.0, 0.1], [0.1, 0.3, 0.0], [0.1, 0.1, 0.35]]
    )
    triangles = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]])
    placement = pin.SE3(
        pin.utils.rpyToMatrix(0.4, 0.1, -0.6), np.array([0.3, 0.1, 0.2])
    )
    tetra = Obstacle(
        "tetra",
        "mesh",
        (1.0, 1.0, 1.0),
        placement,
        vertices=vertices,
        triangles=triangles,
    )
    checker = SphereChecker(ur5_spheres, Scene("tetra", (tetra,)))
    got = checker.clearances(q)[: len(checker.links)]
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, q)
    world_tris = vertices[triangles] @ placement.rotation.T + placement.translation
    for li, link in enumerate(ur5_spheres.links):
        if link.joint == 0:
            assert got[li] == math.inf
            continue
        centers = (
            link.centers @ data.oMi[link.joint].rotation.T
            + data.oMi[link.joint].translation
        )
        expected = np.min(_point_triangle_distances(centers, world_tris) - link.radii)
        if expected > 0:
            assert got[li] == pytest.approx(expected, abs=EXACT_TOL)
        else:
            assert got[li] < 0


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6),
    st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6),
)
def test_no_clearance_changes_faster_than_its_levers(
    ur5_spheres, fractions, step
) -> None:
    """|c(q + dq) - c(q)| <= levers @ |dq| for every link and pair (the bound
    the certified segments rest on, pairs' levers from the nearer side)."""
    robot = ur5_spheres.robot
    q = _within_limits(robot, fractions)
    dq = 0.3 * np.array(step)
    checker = SphereChecker(ur5_spheres, _mixed_scene())
    before, after = checker.clearances(q), checker.clearances(q + dq)
    bound = checker.arrays.levers @ np.abs(dq)
    finite = np.isfinite(before)  # inf: a link no obstacle concerns
    change = np.abs(after[finite] - before[finite])
    assert np.all(change <= bound[finite] + EXACT_TOL)


def test_sphere_contacts_include_every_exact_contact(
    ur5_spheres, ur5_allowance
) -> None:
    """Conservative: a configuration free on the spheres is free on the meshes."""
    robot = ur5_spheres.robot
    scene = _mixed_scene()
    spheres = SphereChecker(ur5_spheres, scene, allowance=ur5_allowance)
    exact = CollisionChecker(robot, scene, self_collision=False)
    rng = np.random.default_rng(1)
    free = 0
    for _ in range(300):
        q = robot.lower + rng.random(6) * (robot.upper - robot.lower)
        if spheres.is_free(q):
            free += 1
            assert exact.compute_distances(q).min() > 0
    assert free > 30


def test_a_segment_through_a_thin_wall_is_refused(puma, puma_spheres) -> None:
    """No tunnelling: a 1 mm wall between two free ends is found."""
    q0, q1 = np.zeros(6), np.array([1.2, 0.0, 0.0, 0.0, 0.0, 0.0])
    # A 1 mm sheet across the arc that the wrist sweeps, at its middle.
    middle = puma.fk(0.5 * q1, "wrist_center").translation
    normal = np.cross([0.0, 0.0, 1.0], middle)
    normal /= np.linalg.norm(normal)
    rotation = pin.Quaternion.FromTwoVectors(np.array([1.0, 0, 0]), normal).matrix()
    wall = Obstacle("sheet", "box", (0.001, 0.15, 0.15), pin.SE3(rotation, middle))
    checker = SphereChecker(puma_spheres, Scene("sheet", (wall,)))
    assert checker.is_free(q0) and checker.is_free(q1)
    assert not checker.is_segment_free(q0, q1)
    assert SphereChecker(puma_spheres).is_segment_free(q0, q1)


def test_a_certified_segment_is_free_at_every_sample(
    ur5_spheres, ur5_allowance
) -> None:
    robot = ur5_spheres.robot
    checker = SphereChecker(ur5_spheres, _mixed_scene(), allowance=ur5_allowance)
    rng = np.random.default_rng(2)
    certified = 0
    for _ in range(200):
        qa = robot.lower + rng.random(6) * (robot.upper - robot.lower)
        qb = qa + rng.normal(0, 0.3, 6)
        qb = np.clip(qb, robot.lower, robot.upper)
        if checker.is_segment_free(qa, qb):
            certified += 1
            for s in np.linspace(0, 1, 101):
                assert checker.clearances(qa + s * (qb - qa)).min() >= 0
    assert certified > 10


def test_plan_goes_around_a_wall_and_the_meshes_agree(puma, puma_spheres) -> None:
    scene = _wall(puma)
    exact = CollisionChecker(puma, scene)
    straight = [exact.compute_distances(q).min() for q in np.linspace(PICK, PLACE, 100)]
    assert min(straight) < 0  # the direct motion collides
    result = plan(puma, scene, PICK, PLACE, seed=0, spheres=puma_spheres)
    assert result.solved and result.reason is None
    assert result.clearance is not None and result.clearance.collision_free
    assert result.clearance.lower_bound > 0 and result.min_clearance > 0
    np.testing.assert_array_equal(result.waypoints[0], PICK)
    np.testing.assert_array_equal(result.waypoints[-1], PLACE)
    trajectory = result.trajectory
    assert trajectory is not None
    q, qd, qdd = trajectory.sample(np.array([0.0, trajectory.duration]))
    np.testing.assert_allclose(q, [PICK, PLACE], atol=1e-12)
    assert np.all(qd == 0) and np.all(qdd == 0)
    assert np.all(result.waypoints >= puma.lower) and np.all(
        result.waypoints <= puma.upper
    )
    checker = SphereChecker(puma_spheres, scene)
    for a, b in zip(result.waypoints[:-1], result.waypoints[1:], strict=True):
        assert checker.is_segment_free(a, b)
    assert result.path_length > 0 and result.planning_time > 0


def test_plan_is_deterministic_per_seed(puma, puma_spheres) -> None:
    scene = _wall(puma)
    first = plan(puma, scene, PICK, PLACE, seed=3, spheres=puma_spheres)
    again = plan(puma, scene, PICK, PLACE, seed=3, spheres=puma_spheres)
    np.testing.assert_array_equal(first.waypoints, again.waypoints)
    assert first.iterations == again.iterations


def test_plan_to_a_tool_pose(puma, puma_spheres) -> None:
    target = puma.fk(PLACE)
    result = plan(puma, _wall(puma), PICK, target, seed=0, spheres=puma_spheres)
    assert result.solved
    reached = puma.fk(result.waypoints[-1])
    assert np.linalg.norm(pin.log6(target.actInv(reached)).vector) <= FK_TOL
    goals = goal_configurations(puma, target)
    assert len(goals) >= 2
    for q in goals:
        assert np.linalg.norm(pin.log6(target.actInv(puma.fk(q))).vector) <= FK_TOL


def test_plan_says_why_it_failed(puma, puma_spheres) -> None:
    scene = _wall(puma)
    wall = scene.obstacles[0]
    inside = Scene(
        "on the start",
        (
            Obstacle(
                "block",
                "box",
                (0.2, 0.2, 0.2),
                pin.SE3(np.eye(3), puma.fk(PICK).translation),
            ),
        ),
    )
    assert (
        plan(puma, inside, PICK, PLACE, spheres=puma_spheres).reason
        == "start in collision"
    )
    blocked = Scene(
        "on the goal",
        (
            wall,
            Obstacle(
                "block",
                "box",
                (0.2, 0.2, 0.2),
                pin.SE3(np.eye(3), puma.fk(PLACE).translation),
            ),
        ),
    )
    result = plan(puma, blocked, PICK, PLACE, spheres=puma_spheres)
    assert result.reason == "goal in collision" and not result.solved
    assert result.trajectory is None and result.waypoints.shape == (0, 6)
    far = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.0]))
    assert (
        plan(puma, scene, PICK, far, spheres=puma_spheres).reason == "goal unreachable"
    )


def test_plan_refuses_bad_arguments(puma, puma_spheres) -> None:
    scene = _wall(puma)
    with pytest.raises(InputError, match="planner"):
        plan(puma, scene, PICK, PLACE, planner="prm")
    with pytest.raises(InputError, match="time_limit"):
        plan(puma, scene, PICK, PLACE, time_limit=0)
    with pytest.raises(InputError, match="iteration_limit"):
        plan(puma, scene, PICK, PLACE, iteration_limit=0)
    with pytest.raises(InputError, match="goal"):
        plan(puma, scene, PICK, np.zeros(5), spheres=puma_spheres)
    with pytest.raises(InputError, match="acceleration"):
        plan(wb.load_robot("puma560"), scene, PICK, PLACE)


def test_an_allowance_lets_an_entry_overlap_that_much_and_no_more(
    puma, puma_spheres
) -> None:
    q = np.zeros(6)
    plain = SphereChecker(puma_spheres)
    centres, radii = puma_spheres.placed(q)
    link3 = plain.links.index("link3")
    first = sum(len(x.radii) for x in puma_spheres.links[:link3])
    # A 2 cm ball whose surface enters link3's first sphere by 5 mm.
    outward = centres[first] / np.linalg.norm(centres[first])
    centre = centres[first] + outward * (radii[first] + 0.02 - 0.005)
    ball = Scene(
        "ball", (Obstacle("ball", "sphere", (0.02,), pin.SE3(np.eye(3), centre)),)
    )
    entries = len(plain.links) + len(plain.pairs)
    allowance = np.zeros(entries)
    overlap = SphereChecker(puma_spheres, ball).clearances(q)[link3]
    assert overlap == pytest.approx(-0.005, abs=EXACT_TOL) or overlap < -0.005
    allowance[link3] = -overlap + 0.001
    assert SphereChecker(puma_spheres, ball, allowance=allowance).is_free(q)
    assert SphereChecker(puma_spheres, ball).with_allowance(allowance).is_free(q)
    allowance[link3] = -overlap - 0.001
    assert not SphereChecker(puma_spheres, ball, allowance=allowance).is_free(q)
    # with_allowance repacks only the allowance: the same arrays as a new checker.
    reused = SphereChecker(puma_spheres, ball).with_allowance(allowance)
    for got, expected in zip(
        reused.arrays,
        SphereChecker(puma_spheres, ball, allowance=allowance).arrays,
        strict=True,
    ):
        np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal(reused.allowance, allowance)
    for bad in (
        np.zeros(entries + 1),
        np.full(entries, -1.0),
        np.full(entries, np.nan),
    ):
        with pytest.raises(InputError, match="allowance"):
            SphereChecker(puma_spheres, ball, allowance=bad)
        with pytest.raises(InputError, match="allowance"):
            plain.with_allowance(bad)


def test_an_obstacle_allowance_lets_a_link_overlap_that_obstacle_only(
    puma_spheres,
) -> None:
    """A link's allowance against one obstacle lets it overlap that one and
    no other (the fingers may overlap the can they grasp, not the shelf); the
    link's own allowance counts against every obstacle."""
    q = np.zeros(6)
    plain = SphereChecker(puma_spheres)
    centres, radii = puma_spheres.placed(q)
    link3 = plain.links.index("link3")
    first = sum(len(x.radii) for x in puma_spheres.links[:link3])
    outward = centres[first] / np.linalg.norm(centres[first])
    side = np.cross(outward, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)
    balls = tuple(
        Obstacle(
            name,
            "sphere",
            (0.02,),
            pin.SE3(np.eye(3), centres[first] + d * (radii[first] + 0.015)),
        )
        for name, d in (("can", outward), ("shelf", side))
    )
    scene = Scene("two balls", balls)
    checker = SphereChecker(puma_spheres, scene)
    overlap = checker.obstacle_clearances(q)[link3]
    assert (overlap < -0.004).all()
    by_obstacle = np.zeros((len(plain.links), 2))
    by_obstacle[link3, 0] = -overlap[0] + 0.001
    entries = np.zeros(len(plain.links) + len(plain.pairs))
    can_only = checker.with_allowance(entries, by_obstacle)
    np.testing.assert_allclose(
        can_only.obstacle_clearances(q)[link3], [0.001, overlap[1]], atol=EXACT_TOL
    )
    assert not can_only.is_free(q)
    by_obstacle[link3, 1] = -overlap[1] + 0.001
    assert checker.with_allowance(entries, by_obstacle).is_free(q)
    entries[link3] = -overlap.min() + 0.001  # against every obstacle
    assert SphereChecker(puma_spheres, scene, allowance=entries).is_free(q)
    # an obstacle that allows the link: not checked against it (inf)
    shelf_allows = dataclasses.replace(balls[1], allow=("link3",))
    allowing = SphereChecker(puma_spheres, Scene("allowing", (balls[0], shelf_allows)))
    got = allowing.obstacle_clearances(q)
    assert got[link3, 1] == math.inf and got[link3, 0] == pytest.approx(overlap[0])
    # with_allowance repacks only the allowances: the arrays of a new checker
    for got, expected in zip(
        can_only.arrays,
        SphereChecker(
            puma_spheres,
            scene,
            obstacle_allowance=can_only.obstacle_allowance,
        ).arrays,
        strict=True,
    ):
        np.testing.assert_array_equal(got, expected)
    for bad in (np.zeros((len(plain.links), 3)), np.full((len(plain.links), 2), -1.0)):
        with pytest.raises(InputError, match="links × obstacles"):
            SphereChecker(puma_spheres, scene, obstacle_allowance=bad)
        with pytest.raises(InputError, match="links × obstacles"):
            checker.with_allowance(np.zeros(len(entries)), bad)


def test_a_tight_end_gets_the_tools_certified_retreats_as_branches(
    puma, puma_spheres
) -> None:
    """Where a link holding an allowance ends in the scene's spheres, the
    tool's straight retreats along its frame's axes (the longest of
    ESCAPE_DISTANCES certified free each way) seed that end's tree."""
    from workbench.motion import _sphere_kernel as kernel
    from workbench.motion import planner as planner_module

    q = np.radians([20.0, -30.0, 40.0, 10.0, 30.0, 0.0])
    centres, radii = puma_spheres.placed(q)
    link6 = [x.link for x in puma_spheres.links].index("link6")
    first = sum(len(x.radii) for x in puma_spheres.links[:link6])
    own = slice(first, first + len(puma_spheres.links[link6].radii))
    tip = first + int(np.argmax(np.linalg.norm(centres[own] - centres[first], axis=1)))
    outward = centres[tip] - puma.fk(q).translation
    outward /= np.linalg.norm(outward)
    centre = centres[tip] + outward * (radii[tip] + 0.02 - 0.005)
    ball = Scene(
        "ball", (Obstacle("can", "sphere", (0.02,), pin.SE3(np.eye(3), centre)),)
    )
    plain = SphereChecker(puma_spheres, ball)
    overlap = plain.obstacle_clearances(q)[link6, 0]
    assert overlap < 0.0
    store = np.zeros((kernel.MAX_EVALUATIONS, len(plain.arrays[0])))
    assert planner_module._escapes(plain, puma, q, store) == []  # no allowance
    by_obstacle = np.zeros(plain.obstacle_allowance.shape)
    by_obstacle[link6, 0] = -overlap + ALLOWANCE_MARGIN
    tight = plain.with_allowance(np.zeros(len(plain.allowance)), by_obstacle)
    escapes = planner_module._escapes(tight, puma, q, store)
    assert 1 <= len(escapes) <= 6
    jacobian = puma.jacobian_local(q)
    moves = set()
    for escape in escapes:
        assert tight.is_segment_free(q, escape)
        assert np.all(escape >= puma.lower) and np.all(escape <= puma.upper)
        # a straight tool move to first order: J dq = (v, 0), v along one axis
        twist = jacobian @ (escape - q)
        axis = int(np.argmax(np.abs(twist[:3])))
        expected = np.zeros(6)
        expected[axis] = twist[axis]
        np.testing.assert_allclose(twist, expected, rtol=0, atol=EXACT_TOL)
        assert (
            min(abs(abs(twist[axis]) - d) for d in planner_module.ESCAPE_DISTANCES)
            < EXACT_TOL
        )
        moves.add((axis, np.sign(twist[axis])))
    assert len(moves) == len(escapes)  # one per axis and way


def test_a_trajectory_the_judge_refuses_is_planned_again_on_narrow_margins(
    monkeypatch, ur5_spheres
) -> None:
    """With verify, the inseparable pairs first get their tables and the other
    allowances half the exact clearance at the ends; a trajectory the exact
    check refuses is planned again without tables, on 1 mm margins."""
    from pathlib import Path

    from workbench.motion import planner as planner_module
    from workbench.motion.problems import find_problems

    ur5 = ur5_spheres.robot.with_limits(acceleration_limit=np.full(6, 10.0))
    data = Path(__file__).parent / "data" / "motionbenchmaker" / "ur5"
    problem = find_problems(data, scenarios=["box"])[0]
    start, goal = problem.read_request(ur5)
    plain = SphereChecker(ur5_spheres, problem.scene)
    lowest = np.minimum(plain.clearances(start), plain.clearances(goal))
    n_links = len(plain.links)
    overlap = {
        plain.pairs[k - n_links]: -lowest[k]
        for k in np.flatnonzero(lowest < 0)
        if k >= n_links
    }
    assert overlap  # the base and the upper arm's spheres overlap at the ends
    by_obstacle = np.minimum(
        plain.obstacle_clearances(start), plain.obstacle_clearances(goal)
    )
    for li, o in zip(*np.nonzero(by_obstacle < 0), strict=True):
        overlap[plain.links[li], problem.scene.obstacles[o].name] = -by_obstacle[li, o]

    def margins(result) -> dict:
        return {(a, b): m - overlap[(a, b)] for a, b, m in result.allowances}

    tabled = set(get_pair_tables(ur5_spheres).pairs)
    assert ("base_link", "upper_arm_link") in tabled
    wide = plan(ur5, problem.scene, start, goal, spheres=ur5_spheres, time_limit=5)
    assert wide.solved
    # the tables' pairs overlap no more at the ends than they are allowed to
    assert not tabled & {(a, b) for a, b, _ in wide.allowances}
    assert all(m >= ALLOWANCE_MARGIN - EXACT_TOL for m in margins(wide).values())

    verdicts = []
    real = planner_module.verify_trajectory

    def refuse_first(exact, trajectory):
        report = real(exact, trajectory)
        verdicts.append(report)
        if len(verdicts) == 1:
            return dataclasses.replace(report, lower_bound=-1.0)  # not proven
        return report

    monkeypatch.setattr(planner_module, "verify_trajectory", refuse_first)
    again = plan(ur5, problem.scene, start, goal, spheres=ur5_spheres, time_limit=5)
    assert len(verdicts) == 2 and again.solved and again.clearance is verdicts[1]
    np.testing.assert_allclose(
        list(margins(again).values()), ALLOWANCE_MARGIN, atol=EXACT_TOL
    )
    narrow = plan(
        ur5, problem.scene, start, goal, spheres=ur5_spheres, time_limit=5, verify=False
    )
    assert margins(narrow) == pytest.approx(margins(again))


@pytest.fixture(scope="module")
def ur5_tables(ur5_spheres):
    return get_pair_tables(ur5_spheres)


def _table_value(tables, k: int, q: np.ndarray) -> float:
    """Pair k's table value at q, the nearest node's, in plain Python (NaN: none)."""
    if tables.start[k] < 0:
        return math.nan
    index = 0
    for i in range(2):
        j = tables.joint[k, i]
        if j < 0:
            break
        n = tables.cells[k, i]
        cell = math.floor((q[j] - tables.lower[k, i]) / tables.step[k, i])
        cell = cell % n if tables.periodic[k, i] else min(max(cell, 0), n - 1)
        index = index * n + cell
    return float(tables.values[tables.start[k] + index])


@pytest.mark.slow  # the UR5's tables again: 2 s
def test_the_table_build_counts_every_node(ur5_spheres, ur5_tables) -> None:
    """``progress(done, total)`` after each node of the tables, to the end, where
    ``total`` is every tabled joint group's node count; the tables are the same."""
    calls: list[tuple[int, int]] = []
    tables = build_pair_tables(
        SphereChecker(ur5_spheres),
        CollisionChecker(ur5_spheres.robot, None),
        progress=lambda done, total: calls.append((done, total)),
    )
    nodes = {}
    for k in np.flatnonzero(tables.start >= 0):
        used = tables.joint[k] >= 0
        nodes[tuple(tables.joint[k][used])] = int(np.prod(tables.cells[k][used]))
    total = sum(nodes.values())
    assert total > 100
    assert calls == [(done, total) for done in range(1, total + 1)]
    assert tables.pairs == ur5_tables.pairs
    for mine, cached in zip(tables[:-1], ur5_tables[:-1], strict=True):
        np.testing.assert_array_equal(mine, cached)


def test_a_first_plan_counts_its_sphere_cover_once_per_robot() -> None:
    """``plan(progress=...)`` hears ``("sphere cover", done, total)`` per
    geometry while the robot's spheres are built, and nothing once they are
    (the PUMA's pairs need no table: no ``"pair tables"`` stage)."""
    robot = wb.load_robot("puma560").with_limits(acceleration_limit=np.full(6, 4.0))
    calls: list[tuple[str, int, int]] = []

    def heard(stage: str, done: int, total: int) -> None:
        calls.append((stage, done, total))

    first = plan(robot, None, PICK, PLACE, progress=heard, verify=True)
    n = len(robot.collision_model.geometryObjects)
    assert first.solved
    assert calls == [("sphere cover", done, n) for done in range(1, n + 1)]
    calls.clear()
    again = plan(robot, None, PICK, PLACE, progress=heard)
    assert calls == []
    np.testing.assert_array_equal(again.waypoints, first.waypoints)


def test_the_inseparable_pairs_get_tables_of_half_their_exact_distance(
    ur5_spheres, ur5_tables
) -> None:
    """The UR5's pairs whose spheres overlap almost everywhere while the meshes
    are apart get tables; at a node the pair's clearance is then its spheres'
    or half the meshes' distance (a bound of it), whichever is more, and its
    spheres' where the meshes touch."""
    robot = ur5_spheres.robot
    assert {("base_link", "upper_arm_link"), ("forearm_link", "wrist_2_link")} <= set(
        ur5_tables.pairs
    )
    plain = SphereChecker(ur5_spheres)
    tabled = SphereChecker(ur5_spheres, pair_tables=ur5_tables)
    exact = CollisionChecker(robot, None)
    rng = np.random.default_rng(3)
    n_links = len(plain.links)
    for pair in ur5_tables.pairs:
        k = plain.pairs.index(pair)
        measured = [
            i for i, p in enumerate(exact.pairs) if {p.body_a, p.body_b} == set(pair)
        ]
        width = int(np.sum(ur5_tables.joint[k] >= 0))
        joints = ur5_tables.joint[k, :width]
        lower, step = ur5_tables.lower[k, :width], ur5_tables.step[k, :width]
        for _ in range(6):
            cells = rng.integers(0, ur5_tables.cells[k, :width])
            q = np.clip(np.zeros(robot.nq), robot.lower, robot.upper)
            q[joints] = lower + (cells + 0.5) * step  # a node
            d = min(exact.compute_pair_distance(q, i) for i in measured)
            g = plain.clearances(q)[n_links + k]
            c = tabled.clearances(q)[n_links + k]
            assert g - EXACT_TOL <= c <= max(g, SHARE * d) + EXACT_TOL
            if d <= 0.0:
                assert c == pytest.approx(g, abs=EXACT_TOL)
    # most of the sampled configurations were refused by these pairs, now few
    qs = rng.uniform(robot.lower, robot.upper, size=(100, robot.nq))
    base_arm = n_links + plain.pairs.index(("base_link", "upper_arm_link"))
    before = np.mean([plain.clearances(q)[base_arm] < 0.0 for q in qs])
    after = np.mean([tabled.clearances(q)[base_arm] < 0.0 for q in qs])
    assert before > 0.9 and after < 0.1


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6))
def test_a_tables_value_is_that_of_the_nearest_node(
    ur5_spheres, ur5_tables, fractions
) -> None:
    """A pair with a table takes its value at the node nearest q (wrapped on
    joints of a full turn), plus its allowance; the others, and a pair at a
    node where its meshes touch (NaN), keep their spheres' clearance."""
    q = _within_limits(ur5_spheres.robot, fractions)
    plain = SphereChecker(ur5_spheres).clearances(q)
    allowance = np.full(len(plain), 0.002)
    tabled = SphereChecker(
        ur5_spheres, allowance=allowance, pair_tables=ur5_tables
    ).clearances(q)
    n_links = len(ur5_spheres.links)
    np.testing.assert_allclose(tabled[:n_links], plain[:n_links] + 0.002, atol=1e-12)
    for k in range(len(plain) - n_links):
        value = _table_value(ur5_tables, k, q)
        expected = plain[n_links + k] if math.isnan(value) else value
        assert tabled[n_links + k] == pytest.approx(expected + 0.002, abs=1e-12)


def test_pair_tables_must_fit_the_checker(puma_spheres, ur5_tables) -> None:
    with pytest.raises(InputError, match="pair_tables"):
        SphereChecker(puma_spheres, pair_tables=ur5_tables)
