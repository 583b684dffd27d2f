"""Collision geometry, self-collision filter, distances, clearance along paths."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import coal
import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.conftest import random_configurations
from workbench import InputError, load_robot, paper_data
from workbench.collision import (
    CollisionChecker,
    Obstacle,
    Scene,
    check_path,
    compute_self_collision_filter,
    get_angeles_scene,
)
from workbench.collision.along_path import DISTANCE_TOL
from workbench.collision.self_filter import CONTACT_TOL
from workbench.trajectory import pick_and_place

ATOL_COAL = 1e-9  # [m] agreement with coal's own distance (GJK to 1e-12)
ATOL_EPA = 1e-6  # [m] penetration depths (coal's EPA tolerance)
Q_PICK = np.deg2rad(paper_data.ANGELES_PICK_Q_DEG)
Q_PLACE = np.deg2rad(paper_data.ANGELES_PLACE_Q_DEG)


@pytest.fixture(scope="module")
def angeles_checker(puma) -> CollisionChecker:
    return CollisionChecker(puma, get_angeles_scene(puma))


def _table3_path(robot, samples: int = 1000):
    traj = pick_and_place(robot, Q_PICK, Q_PLACE, paper_data.ANGELES_DURATION)
    t = np.linspace(0.0, traj.duration, samples)
    return traj, t, traj.sample(t)[0]


def test_puma_collision_geometry_mirrors_the_moving_visuals(any_puma) -> None:
    visual = [g for g in any_puma.visual_model.geometryObjects if g.parentJoint != 0]
    collision = list(any_puma.collision_model.geometryObjects)
    assert len(collision) == len(visual) > 0
    for v, c in zip(visual, collision, strict=True):
        assert v.parentJoint == c.parentJoint
        assert type(v.geometry) is type(c.geometry)
        np.testing.assert_allclose(
            v.placement.homogeneous, c.placement.homogeneous, rtol=0, atol=0
        )


@pytest.mark.parametrize("name", ["puma560", "puma560-kang", "ur5", "panda"])
def test_filter_excludes_neighbours_and_zero_pose_contacts(name) -> None:
    robot = load_robot(name)
    found = compute_self_collision_filter(robot)
    assert found == compute_self_collision_filter(robot)  # deterministic
    model, geometry = robot.model, robot.collision_model
    joint_of = {
        model.frames[g.parentFrame].name: g.parentJoint
        for g in geometry.geometryObjects
    }
    for d in found.disabled:
        a, b = joint_of[d.link_a], joint_of[d.link_b]
        if d.reason == "Rigid":
            assert a == b
        elif d.reason == "Adjacent":
            assert model.parents[a] == b or model.parents[b] == a
        else:
            assert d.reason == "Default"
    # every consecutive pair of moving links with geometry is excluded
    for link_a, ja in joint_of.items():
        for link_b, jb in joint_of.items():
            if link_a != link_b and model.parents[jb] == ja:
                assert found.is_disabled(link_a, link_b)
    # the checked pairs are apart at the zero pose, the "Default" ones touch
    checker = CollisionChecker(robot)
    zero = checker.compute_distances(pin.neutral(model))
    assert np.all(zero > CONTACT_TOL)
    srdf = ET.fromstring(found.to_srdf())
    rows = srdf.findall("disable_collisions")
    assert len(rows) == len(found.disabled)
    assert {r.get("reason") for r in rows} <= {"Rigid", "Adjacent", "Default"}


def test_puma_filter_lists_the_housings_that_overlap(puma) -> None:
    found = compute_self_collision_filter(puma)
    reasons = {(d.link_a, d.link_b): d.reason for d in found.disabled}
    assert reasons[("link1", "link2")] == "Adjacent"
    assert reasons[("link6", "wrist_center")] == "Rigid"
    assert reasons[("link4", "link6")] == "Default"
    assert ("link2", "link4") in found.get_checked_pairs()


def test_pick_pose_puts_the_upper_arm_through_the_pedestal(angeles_checker) -> None:
    d = angeles_checker.compute_distances(Q_PICK)
    by_pair: dict[tuple[str, str], float] = {}
    for pair, value in zip(angeles_checker.body_pairs, d, strict=True):
        by_pair[pair] = min(by_pair.get(pair, np.inf), value)
    assert by_pair[("link2", "pedestal")] == pytest.approx(-0.02957, abs=1e-4)
    assert by_pair[("link4", "pedestal")] > 0.04  # the forearm passes by it
    colliding = {pair for pair, value in by_pair.items() if value <= 0.0}
    assert colliding == {("link2", "pedestal")}
    assert ("link1", "pedestal") not in by_pair  # allowed: it stands on it


def _dh_link_poses(robot, q) -> dict[int, pin.SE3]:
    """Joint frames from the numpy DH product (no Pinocchio kinematics)."""
    frames = robot.dh_table.frame_transforms(q)
    poses = {0: pin.SE3.Identity()}
    for i, joint in enumerate(robot.dh_table.joints, 1):
        rz = pin.SE3(
            pin.rpy.rpyToMatrix(0, 0, q[i - 1] + joint.theta_offset), np.zeros(3)
        )
        poses[i] = pin.SE3(frames[i - 1]) * rz
    return poses


def test_distances_agree_with_coal_reference(puma, angeles_checker, rng) -> None:
    geometry = angeles_checker.geometry_model
    compared = 0
    for q in random_configurations(puma, rng, 40):
        ours = angeles_checker.compute_distances(q)
        poses = _dh_link_poses(puma, q)
        for k, pair in enumerate(angeles_checker.pairs):
            transforms = []
            for index in (pair.geometry_a, pair.geometry_b):
                g = geometry.geometryObjects[index]
                placed = poses[g.parentJoint] * g.placement
                transforms.append(coal.Transform3s(placed.rotation, placed.translation))
            request, result = coal.DistanceRequest(), coal.DistanceResult()
            request.gjk_tolerance = 1e-12
            a = geometry.geometryObjects[pair.geometry_a].geometry
            b = geometry.geometryObjects[pair.geometry_b].geometry
            reference = coal.distance(
                a, transforms[0], b, transforms[1], request, result
            )
            tol = ATOL_COAL if reference > 0.0 else ATOL_EPA
            assert ours[k] == pytest.approx(reference, abs=tol), pair
            compared += reference > 0.0
    assert compared > 1000


def test_free_path_reports_its_clearance(puma) -> None:
    checker = CollisionChecker(puma)  # self-collision only: the path is free
    _, t, q = _table3_path(puma)
    report = check_path(checker, t, q)
    brute = np.array([checker.compute_distances(qk) for qk in q])
    assert report.contacts == () and report.collision_free
    assert report.describe_first_contact() is None
    assert report.min_clearance == pytest.approx(brute.min(), abs=ATOL_COAL)
    k = int(np.flatnonzero(t == report.t)[0])  # where it says: a minimum (ties)
    at = [d for d, pair in zip(brute[k], checker.body_pairs, strict=True)
          if pair == (report.body_a, report.body_b)]  # fmt: skip
    assert min(at) == pytest.approx(brute.min(), abs=ATOL_COAL)
    assert 0.0 < report.lower_bound <= report.min_clearance
    assert report.evaluations < brute.size  # the bound skipped far pairs


def test_paper_path_contacts_with_pedestal_and_table(puma, angeles_checker) -> None:
    traj, t, q = _table3_path(puma)
    speed = traj.get_extrema(1)
    report = check_path(
        angeles_checker,
        t,
        q,
        sample=lambda s: traj.sample(s)[0],
        max_joint_speed=np.maximum(np.abs(speed.minimum), np.abs(speed.maximum)),
    )
    first = report.first_contact
    assert (first.body_a, first.body_b, first.t_start) == ("link2", "pedestal", 0.0)
    assert first.distance == pytest.approx(-0.02957, abs=1e-4)
    message = report.describe_first_contact()
    assert message.startswith("collision of link2 with pedestal from t = 0 s")
    assert message.endswith(f"(and {len(report.contacts) - 1} more contact(s))")
    bodies = {(c.body_a, c.body_b) for c in report.contacts}
    assert ("link6", "pick_table") in bodies
    brute = np.array([angeles_checker.compute_distances(qk) for qk in q])
    assert report.min_clearance == pytest.approx(brute.min(), abs=ATOL_EPA)
    inside = brute <= 0.0  # every contact sample lies in a reported interval
    for k, p in zip(*np.nonzero(inside), strict=True):
        pair = angeles_checker.body_pairs[p]
        assert any(
            (c.body_a, c.body_b) == pair and c.t_start <= t[k] <= c.t_end
            for c in report.contacts
        )


def test_spline_bound_with_accelerations_holds(puma) -> None:
    checker = CollisionChecker(puma)  # free: the bound must be positive and hold
    traj, t, q = _table3_path(puma, samples=101)
    peaks = [traj.get_extrema(order) for order in (1, 2)]
    speed, acceleration = (np.maximum(-e.minimum, e.maximum) for e in peaks)
    report = check_path(
        checker,
        t,
        q,
        sample=lambda s: traj.sample(s)[0],
        max_joint_speed=speed,
        max_joint_acceleration=acceleration,
    )
    loose = check_path(
        checker, t, q, sample=lambda s: traj.sample(s)[0], max_joint_speed=speed
    )
    dense = traj.sample(np.linspace(0.0, traj.duration, 4001))[0]
    brute = min(checker.compute_distances(qk).min() for qk in dense)
    assert report.collision_free and loose.collision_free
    assert report.lower_bound <= brute + DISTANCE_TOL
    assert loose.lower_bound <= brute + DISTANCE_TOL
    assert report.refinements < loose.refinements  # the tighter travel bound
    with pytest.raises(InputError, match=">= 0"):
        check_path(checker, t, q, sample=lambda s: q[0], max_joint_speed=speed,
                   max_joint_acceleration=-acceleration)  # fmt: skip


def _thin_plate_setup(robot):
    """A 2 mm plate that the wrist sweeps through between two samples."""
    q0 = np.array([0.0, -0.6, 2.4, 0.0, 0.5, 0.0])
    q1 = q0 + np.array([0.8, 0.0, 0.0, 0.0, 0.0, 0.0])
    mid = robot.fk(0.5 * (q0 + q1)).translation
    angle = float(np.arctan2(mid[1], mid[0]))
    plate = Obstacle(
        "plate",
        "box",
        (0.12, 0.002, 0.12),  # thin across the sweep (tangential direction)
        pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, angle), mid),
    )
    return q0, q1, CollisionChecker(robot, Scene("plate", (plate,)))


def test_obstacle_thinner_than_the_step_is_caught(puma) -> None:
    q0, q1, checker = _thin_plate_setup(puma)
    scene_pairs = [k for k, p in enumerate(checker.pairs) if p.kind == "scene"]
    ends = np.array([checker.compute_distances(q) for q in (q0, q1)])[:, scene_pairs]
    assert np.all(ends > 0.05)  # both samples are far from the plate
    report = check_path(checker, [0.0, 1.0], [q0, q1])
    assert not report.collision_free
    assert report.first_contact.body_b == "plate"
    assert 0.0 < report.first_contact.t < 1.0
    assert report.refinements > 0


@pytest.mark.slow
@given(seed=st.integers(0, 10_000))
def test_lower_bound_holds_between_samples(puma, seed) -> None:
    rng = np.random.default_rng(seed)
    q0, q1, checker = _thin_plate_setup(puma)
    offset = rng.uniform(-0.3, 0.3, (4, puma.nq))
    q = np.vstack([q0, q0 + offset[0], q1 + offset[1], q1 + offset[2]])
    t = np.array([0.0, 0.4, 0.9, 1.3])
    report = check_path(checker, t, q)
    dense = np.linspace(0.0, 1.3, 400)
    path = np.array([np.interp(dense, t, column) for column in q.T]).T
    brute = np.array([checker.compute_distances(qk) for qk in path])
    assert brute.min() >= report.lower_bound - DISTANCE_TOL
    if brute.min() <= 0.0:
        assert not report.collision_free


def test_stride_bound_covers_the_full_polyline(puma) -> None:
    q0, q1, checker = _thin_plate_setup(puma)
    t = np.linspace(0.0, 1.0, 41)
    q = q0 + t[:, None] * (q1 - q0)
    report = check_path(checker, t, q, stride=20)  # distances at 3 samples only
    assert report.samples == 3 and report.first_contact.body_b == "plate"


def test_single_configuration(puma, angeles_checker) -> None:
    report = check_path(angeles_checker, [0.0], [Q_PICK])
    assert report.first_contact.body_b == "pedestal"
    assert report.lower_bound == report.min_clearance


def test_bad_inputs(puma, angeles_checker) -> None:
    with pytest.raises(InputError, match="strictly increasing"):
        check_path(angeles_checker, [0.0, 0.0], [Q_PICK, Q_PLACE])
    with pytest.raises(InputError, match="max_joint_speed"):
        check_path(
            angeles_checker, [0.0, 1.0], [Q_PICK, Q_PLACE], sample=lambda s: Q_PICK
        )
    with pytest.raises(InputError, match="stride"):
        check_path(angeles_checker, [0.0, 1.0], [Q_PICK, Q_PLACE], stride=0)
    with pytest.raises(InputError, match="shape"):
        check_path(angeles_checker, [0.0, 1.0], [Q_PICK])
    with pytest.raises(InputError, match="finite"):
        check_path(angeles_checker, [0.0, np.nan], [Q_PICK, Q_PLACE])
    nothing = CollisionChecker(puma, self_collision=False)
    with pytest.raises(InputError, match="no pairs"):
        check_path(nothing, [0.0], [Q_PICK])


def test_checker_errors(puma) -> None:
    box = Obstacle("link2", "box", (0.1, 0.1, 0.1), pin.SE3.Identity())
    with pytest.raises(InputError, match="name of a robot link"):
        CollisionChecker(puma, Scene("s", (box,)))
    ball = Obstacle("ball", "sphere", (0.1,), pin.SE3.Identity(), ("nope",))
    with pytest.raises(InputError, match=r"unknown link.*nope"):
        CollisionChecker(puma, Scene("s", (ball,)))
    with pytest.raises(InputError, match="no DH table"):
        get_angeles_scene(load_robot("ur5"))


def test_robot_without_collision_geometry(tmp_path) -> None:
    text = (load_robot("puma560").urdf_path).read_text()
    while "<collision>" in text:  # the same arm with its visual geometry only
        start = text.index("<collision>")
        text = text[:start] + text[text.index("</collision>") + 12 :]
    path = tmp_path / "bare.urdf"
    path.write_text(text)
    bare = load_robot(path)
    with pytest.raises(InputError, match="no collision geometry"):
        CollisionChecker(bare)


def test_ur5_meshes_are_checked(rng) -> None:
    ur5 = load_robot("ur5")
    table = Obstacle(
        "table", "box", (1.0, 1.0, 0.02), pin.SE3(np.eye(3), np.array([0, 0, -0.02]))
    )
    checker = CollisionChecker(ur5, Scene("floor", (table,)))
    down = np.array([0.0, -0.3, 2.6, 0.0, 0.0, 0.0])  # forearm folded to the floor
    up = np.array([0.0, -1.57, 0.0, -1.57, 0.0, 0.0])
    report = check_path(checker, [0.0, 2.0], [up, down])
    assert "table" in {c.body_b for c in report.contacts}
    assert check_path(checker, [0.0], [up]).collision_free


def _at(x: float, y: float, z: float) -> pin.SE3:
    return pin.SE3(np.eye(3), np.array([x, y, z]))


#: Agreement [m] of two penetration depths coal computes from different warm starts.
PENETRATION_TOL = 1e-6


def _ur5_on_a_table():
    """The UR5 (meshes) over a table top and beside a post (boxes, a cylinder)."""
    ur5 = load_robot("ur5")
    scene = Scene(
        "table",
        (
            Obstacle("table", "box", (1.2, 1.2, 0.02), _at(0.0, 0.0, -0.02)),
            Obstacle("post", "cylinder", (0.05, 0.8), _at(0.45, 0.2, 0.4)),
        ),
    )
    return ur5, CollisionChecker(ur5, scene)


@pytest.fixture(scope="module")
def ur5_table():
    return _ur5_on_a_table()


@given(seed=st.integers(0, 10_000))
def test_hull_bounds_never_exceed_the_mesh_distances(ur5_table, seed) -> None:
    ur5, checker = ur5_table
    for q in random_configurations(ur5, np.random.default_rng(seed), 3):
        exact = checker.compute_distances(q)
        lower = checker.compute_lower_bounds(q)
        assert np.all(lower <= exact + DISTANCE_TOL)
        k, least = checker.compute_least_distance(q)
        # the least exact distance, and a pair in contact when one is
        tol = DISTANCE_TOL if exact.min() > 0.0 else PENETRATION_TOL
        assert least == pytest.approx(exact.min(), abs=tol)
        assert exact[k] == pytest.approx(least, abs=tol)
        assert (least <= 0.0) == (exact.min() <= 0.0)


def test_path_clearance_is_the_least_over_every_pair_at_every_sample(
    ur5_table,
) -> None:
    ur5, checker = ur5_table
    rng = np.random.default_rng(7)
    up = np.array([0.0, -1.57, 0.0, -1.57, 0.0, 0.0])
    side = np.array([1.5, -1.2, 0.8, -1.57, 1.0, 0.0])  # 13 mm from the post
    for q0, q1 in [(up, side), *(random_configurations(ur5, rng, 2) for _ in range(2))]:
        t = np.linspace(0.0, 1.0, 65)
        q = q0 + t[:, None] * (q1 - q0)
        report = check_path(checker, t, q)
        brute = np.array([checker.compute_distances(qk) for qk in q])
        # a penetration depth (EPA) depends on coal's warm start to ~1e-8
        tol = DISTANCE_TOL if brute.min() > 0.0 else PENETRATION_TOL
        # the least over the samples, or less between them (a refinement)
        assert report.min_clearance <= brute.min() + tol
        if report.t in t:
            assert report.min_clearance == pytest.approx(brute.min(), abs=tol)
        assert report.lower_bound <= report.min_clearance + DISTANCE_TOL
        pairs = checker.body_pairs
        touching = {pairs[p] for p in np.flatnonzero(brute.min(axis=0) <= 0)}
        assert {(c.body_a, c.body_b) for c in report.contacts} >= touching
        if touching:
            assert not report.collision_free


def test_a_flat_mesh_bounds_itself(ur5_table) -> None:
    """Qhull cannot wrap a flat mesh: it stays a mesh (coal's Qhull call on it
    would end the process), and the bounds still hold."""
    ur5, _ = ur5_table
    sheet = Obstacle(
        "sheet",
        "mesh",
        (1.0, 1.0, 1.0),
        _at(0.4, 0.0, 0.3),
        vertices=np.array([[0, 0, 0], [0.3, 0, 0], [0, 0.3, 0], [0.3, 0.3, 0.0]]),
        triangles=np.array([[0, 1, 2], [1, 3, 2]]),
    )
    checker = CollisionChecker(ur5, Scene("sheet", (sheet,)))
    q = np.array([0.0, -1.57, 0.0, -1.57, 0.0, 0.0])
    exact = checker.compute_distances(q)
    lower = checker.compute_lower_bounds(q)
    assert np.all(lower <= exact + DISTANCE_TOL)
    assert check_path(checker, [0.0, 1.0], [q, q + 0.2]).min_clearance > 0.0
