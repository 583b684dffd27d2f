"""Kang's fish-cutting program on the simulated fish: limits, events, CLI."""

from __future__ import annotations

import dataclasses
import gc
import json
import math

import numpy as np
import pytest

from workbench import InfeasibleError, InputError, load_robot
from workbench.cli import main
from workbench.collision import CollisionChecker
from workbench.ik import get_solver, get_structure
from workbench.ik.structure import axis_lines
from workbench.tasks import (
    FishCuttingSetup,
    HorizontalCut,
    SimulatedFish,
    VerticalDownCut,
    run_fish_cutting,
)
from workbench.tasks.fish_cutting import summarize_fish_cutting
from workbench.tasks.fish_program import (
    FOLD_MARGIN,
    KANG_BASE_HEIGHT,
    KANG_HOME_ROTATION,
    KANG_HOME_WRIST_CENTER,
    KANG_REACH,
    check_waypoints,
    compute_home_configuration,
    compute_waypoints,
    get_arm_reach,
    get_base_placement,
    get_cell_scale,
    get_shortest_fold,
    get_world_transforms,
)
from workbench.tasks.fish_scene import get_fish_cutting_scene
from workbench.trajectory.csv_io import read_trajectory_csv, record_path

SETUP = FishCuttingSetup()


@pytest.fixture(scope="module")
def run(puma_kang):
    return run_fish_cutting(puma_kang, SimulatedFish(seed=0), SETUP)


def _speed(run) -> np.ndarray:
    return np.linalg.norm(run.velocity, axis=1)


def test_every_servo_command_within_position_and_speed_limits(run, puma_kang):
    q, qd = run.servo.q, run.servo.qd
    assert np.all(q >= puma_kang.lower) and np.all(q <= puma_kang.upper)
    assert np.all(np.abs(qd) <= puma_kang.velocity_limit)
    assert run.max_joint_speed <= puma_kang.velocity_limit.max()


def test_no_joint_jump_between_servo_samples(run, puma_kang):
    dt = np.diff(run.servo.t)
    np.testing.assert_allclose(dt, 1.0 / SETUP.servo_rate, atol=1e-12)
    step = np.abs(np.diff(run.servo.q, axis=0))
    assert np.all(step <= puma_kang.velocity_limit * dt[:, None] * (1 + 1e-9))
    # the servo samples pass through the planning commands
    m = round(SETUP.servo_rate / SETUP.planning_rate)
    np.testing.assert_allclose(run.servo.q[::m], run.q, atol=0)


def test_joint_velocity_commands_agree_with_the_position_commands(run):
    # also where DLS is active (about the rate of the IK positions): no ripple
    central = (run.q[2:] - run.q[:-2]) * (SETUP.planning_rate / 2)
    assert np.abs(run.qd[1:-1] - central).max() < 0.02  # [rad/s]
    np.testing.assert_allclose(run.qd[-1], 0.0, atol=1e-12)  # at rest at home


def test_program_runs_through_and_returns_home(run):
    np.testing.assert_allclose(run.position[-1], run.position[0], atol=1e-12)
    # back at the (wrist-singular) home: theta4 + theta6 is what is defined there
    np.testing.assert_allclose(
        run.q[-1, [0, 1, 2, 4]], run.q[0, [0, 1, 2, 4]], atol=1e-9
    )
    assert run.q[-1, 3] + run.q[-1, 5] == pytest.approx(
        run.q[0, 3] + run.q[0, 5], abs=1e-9
    )
    assert _speed(run)[-1] == 0.0


def test_second_horizontal_cut_hands_over_at_cutting_speed(run):
    """Fig. 7's HorizontalCut(Dh, Ch, 1, 1): vi = vf = 1, so the cut ends moving."""
    primitive = np.array(run.primitive)
    cuts = np.flatnonzero(primitive == "HorizontalCut")
    assert np.all(np.diff(cuts) == 1)  # the two cuts run back to back, never stopping
    speed = _speed(run)
    assert speed[cuts[1:]].min() > 0.0
    end = cuts[-1]
    assert speed[end] == pytest.approx(SETUP.cutting_speed, rel=1e-9)
    point_c = compute_waypoints(SimulatedFish(seed=0), SETUP)["C"]
    step = SETUP.cutting_speed / SETUP.planning_rate
    assert np.linalg.norm(run.position[end, :2] - point_c[:2]) <= step * (1 + 1e-9)
    # the lift that follows brings the horizontal velocity back to zero
    lift = np.flatnonzero(primitive[end + 1 :] != "StraightLine")[0] + end + 1
    np.testing.assert_allclose(run.velocity[lift - 1, :2], 0.0, atol=1e-12)


def test_flesh_then_bone_at_every_vertical_cut(run):
    vertical = [e.kind for e in run.events if e.primitive == "VerticalDownCut"]
    assert vertical == ["flesh", "bone"] * SETUP.stations
    assert any(e.primitive == "HorizontalCut" for e in run.events)


def test_flesh_slows_to_cutting_speed_and_bone_stops_the_tool(run):
    speed, dt = _speed(run), 1.0 / SETUP.planning_rate
    a, cut = SETUP.max_acceleration, SETUP.cutting_speed
    vertical = [e for e in run.events if e.primitive == "VerticalDownCut"]
    for flesh, bone in zip(vertical[::2], vertical[1::2], strict=True):
        k_f = round(flesh.t / dt)
        k_b = round(bone.t / dt)
        settle = k_f + math.ceil((SETUP.max_velocity - cut) / a / dt) + 1
        if settle < k_b:
            np.testing.assert_allclose(speed[settle : k_b + 1], cut, atol=1e-12)
        # bone: full deceleration, straight down, to rest v^2 / (2 a) lower, in v / a
        v = speed[k_b]
        n = math.floor(v / a / dt - 1e-9)  # cycles inside the stop
        expected = v - a * dt * np.arange(n + 1)
        np.testing.assert_allclose(speed[k_b : k_b + n + 1], expected, atol=1e-12)
        np.testing.assert_allclose(run.velocity[k_b : k_b + n + 1, :2], 0.0, atol=1e-12)
        assert np.all(run.velocity[k_b : k_b + n + 1, 2] < 0.0)
        lowest = run.position[k_b : k_b + n + 3, 2].min()
        rest = bone.position[2] - v * v / (2 * a)
        assert rest - 1e-12 <= lowest <= rest + a * dt * dt
        assert run.velocity[k_b + n + 2, 2] > 0.0  # then back up to the retreat point


def test_horizontal_cut_steps_up_over_the_bone(run):
    steps = [e for e in run.events if e.primitive == "HorizontalCut"]
    z_cut = run.fish.table_z + run.fish.bone_height
    cutting = np.array([name == "HorizontalCut" for name in run.primitive])
    z = run.position[cutting, 2]
    step = SETUP.cutting_speed / SETUP.planning_rate
    assert z[0] == pytest.approx(z_cut, abs=1e-12)
    assert z[-1] == pytest.approx(z_cut + len(steps) * step, abs=1e-12)
    assert np.all(np.diff(z) >= -1e-15)  # only up
    horizontal = np.linalg.norm(run.velocity[cutting, :2], axis=1)
    assert horizontal.max() == pytest.approx(SETUP.cutting_speed, abs=1e-12)
    for e in steps:
        assert e.position[2] <= run.fish.bone_top(e.position[0], e.position[1])


def test_wrist_continuity_through_singularities(run):
    assert run.wrist_flips == 0
    assert run.wrist_singularity_crossings >= 1  # the cuts pass theta5 = 0
    assert np.abs(np.diff(run.q[:, 3])).max() < 0.05
    assert run.damped.any()


def test_home_is_kangs_q0_and_the_same_pose_on_angeles_model(puma_kang, puma):
    np.testing.assert_allclose(
        compute_home_configuration(puma_kang, SETUP), 0.0, atol=1e-12
    )
    q = compute_home_configuration(puma, SETUP)
    pose = puma.fk(q)
    np.testing.assert_allclose(pose.rotation, KANG_HOME_ROTATION, atol=1e-12)
    lift = np.array([0.0, 0.0, KANG_BASE_HEIGHT])
    np.testing.assert_allclose(
        pose.translation + lift, KANG_HOME_WRIST_CENTER, atol=1e-12
    )


def test_runs_are_deterministic_per_seed():
    a, b, c = SimulatedFish(seed=5), SimulatedFish(seed=5), SimulatedFish(seed=6)
    y = np.linspace(0.2, 0.62, 50)
    np.testing.assert_array_equal(a.sample_profiles(y)[1], b.sample_profiles(y)[1])
    assert not np.allclose(
        a.sample_profiles(y)[1], c.sample_profiles(y)[1], equal_nan=True
    )


def test_run_makes_no_reference_cycles_and_restores_the_collector(puma_kang):
    """The cycle loop pauses the cyclic GC; that is safe only without cycles.

    The first run sets up what a process does once (lazy imports, compiled
    entry points, caches), which may make cycles of its own: the run checked
    is the second one.
    """
    run_fish_cutting(puma_kang, SimulatedFish(seed=2), SETUP)
    assert gc.isenabled()  # restored
    gc.collect()
    gc.disable()
    try:
        run_fish_cutting(puma_kang, SimulatedFish(seed=2), SETUP)
        assert not gc.isenabled()  # left as it was
        assert gc.collect() == 0  # nothing only the collector could free
    finally:
        gc.enable()


def test_fish_contacts():
    fish = SimulatedFish(seed=1)
    y = 0.4
    bone, flesh = fish.bone_top(0.0, y), fish.flesh_top(0.0, y)
    assert fish.table_z < bone < flesh
    assert fish.get_contact([0.0, y, flesh + 1e-6]) is None
    assert fish.get_contact([0.0, y, flesh - 1e-6]) == "flesh"
    assert fish.get_contact([0.0, y, bone]) == "bone"
    assert fish.get_contact([0.03, y, bone]) == "flesh"  # beside the backbone
    assert fish.get_contact([0.0, 1.0, 0.0]) is None  # off the fish


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"thickness": math.nan}, "thickness must be a finite number"),
        ({"half_width": -0.1}, "half_width must be > 0"),
        ({"tail_y": 0.1}, "must exceed head_y"),
        ({"bone_height": 0.07}, "backbone must lie inside the flesh"),
        ({"bone_variation": -1.0}, "bone_variation must be >= 0"),
    ],
)
def test_bad_fish(kwargs, fragment):
    with pytest.raises(InputError, match=fragment):
        SimulatedFish(**kwargs)


def test_bad_primitive_arguments():
    with pytest.raises(InputError, match="cutting_speed"):
        VerticalDownCut([0, 0, 0], [0, 0, 0], cutting_speed=0.0)
    with pytest.raises(InputError, match="step_height"):
        HorizontalCut([0, 0, 0], cutting_speed=0.1, step_height=math.nan)


def test_unreachable_waypoint_is_rejected_before_running(puma_kang):
    setup = FishCuttingSetup(station_spacing=0.4)
    names = list(compute_waypoints(SimulatedFish(), setup))
    assert "S3" in names
    with pytest.raises(InfeasibleError, match="waypoint S"):
        run_fish_cutting(puma_kang, setup=setup)
    with pytest.raises(InputError, match="max_velocity must be > 0"):
        run_fish_cutting(puma_kang, setup=FishCuttingSetup(max_velocity=-1.0))


@pytest.mark.slow
def test_cli_json_csv_and_html(tmp_path, capsys, run):
    path, page = tmp_path / "fish.csv", tmp_path / "fish.html"
    assert main(["fishcut", "--csv", str(path), "--html", str(page), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    for key in (
        "robot", "cycles", "servo_rate_hz", "planning_rate_hz", "events",
        "latency_us", "max_joint_speed", "wrist_flips",
    ):  # fmt: skip
        assert key in result
    assert result["robot"] == "puma560-kang"
    assert result["cycles"] == len(run.t) - 1
    assert set(result["latency_us"]) == {"median", "p99"}
    assert [e["kind"] for e in result["events"]] == [e.kind for e in run.events]
    assert result["wrist_flips"] == 0
    samples = read_trajectory_csv(path, nq=6)
    np.testing.assert_allclose(samples.q, run.servo.q, atol=0)
    assert "<html" in page.read_text(encoding="utf-8")[:200]
    assert sorted(tmp_path.iterdir()) == sorted([path, record_path(path), page])


@pytest.mark.parametrize(
    ("args", "code", "fragment"),
    [
        (["--max-velocity", "0.6"], 3, "velocity"),  # fails mid-run
        (["--robot", "generic6r"], 2, "closed-form IK"),
        (["--servo-rate", "150"], 2, "integer multiple"),
        (["--max-velocity", "nan"], 2, "--max-velocity: not a finite number"),
        (["--robot", "nope"], 2, "unknown robot"),
    ],
)
def test_cli_bad_input_writes_nothing(tmp_path, capsys, args, code, fragment):
    path = tmp_path / "fish.csv"
    assert main(["fishcut", "--csv", str(path), *args]) == code
    err = capsys.readouterr().err
    assert fragment in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []  # no partial CSV, no temporary file


def test_cli_rejects_missing_folder(tmp_path, capsys):
    assert main(["fishcut", "--csv", str(tmp_path / "no" / "x.csv")]) == 2
    assert "does not exist" in capsys.readouterr().err


#: Cell scale of each arm from its data-sheet lengths [m], independent of the
#: fitted DH table: reach to the wrist point over Kang's PUMA, to 0.01.
ARM_SCALES = {
    "ur3": (0.24365 + 0.21325 + 0.08535, 0.63),  # a2 + a3 + d5
    "ur5": (0.425 + 0.39225 + 0.09465, 1.06),
    "ur10": (0.612 + 0.5723 + 0.1157, 1.5),
    "kuka-kr6-r700": (0.315 + math.hypot(0.035, 0.365), 0.79),  # a2 + |(a3, d4)|
    "abb-irb2400": (0.705 + math.hypot(0.135, 0.755), 1.7),
}


@pytest.fixture(scope="module")
def ur3_run():
    """The default run on the UR3: Kang's cell scaled by 0.63."""
    return run_fish_cutting(load_robot("ur3"))


def test_cell_scale_is_one_for_both_pumas(puma_kang, puma):
    for robot in (puma_kang, puma):
        assert get_cell_scale(robot) == 1.0
        base = get_base_placement(robot, SETUP)
        assert np.array_equal(base.rotation, np.eye(3))
        assert np.array_equal(base.translation, [0.0, 0.0, KANG_BASE_HEIGHT])
    assert SETUP.scale == 1.0 and SETUP.scaled(1.0) == SETUP
    assert KANG_REACH == pytest.approx(0.8641, abs=1e-4)  # a2 + hypot(a3, d4)


@pytest.mark.parametrize("name", sorted(ARM_SCALES))
def test_cell_scale_is_the_reach_ratio_of_the_data_sheet(name):
    reach, expected = ARM_SCALES[name]
    assert round(reach / KANG_REACH, 2) == expected
    assert get_cell_scale(load_robot(name)) == expected


def test_scaled_setup_scales_lengths_and_linear_limits_only():
    big = SETUP.scaled(2.5)
    assert big.scale == 2.5
    for name in (
        "tool_length", "max_velocity", "max_acceleration", "station_spacing",
        "clearance",
    ):  # fmt: skip
        assert getattr(big, name) == pytest.approx(2.5 * getattr(SETUP, name))
    for name in (
        "max_angular_velocity", "max_angular_acceleration", "cutting_speed_ratio",
        "planning_rate", "servo_rate", "stations", "max_cycles",
    ):  # fmt: skip
        assert getattr(big, name) == getattr(SETUP, name)
    for setup in (SETUP, big, SETUP.scaled(0.5)):  # the arcs' radius stays >= v² / a
        assert (
            setup.station_spacing >= 2 * setup.max_velocity**2 / setup.max_acceleration
        )
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(InputError, match="scale"):
            SETUP.scaled(bad)
        with pytest.raises(InputError, match="scale"):
            SimulatedFish().scaled(bad)
    with pytest.raises(InputError, match="setup scale"):
        FishCuttingSetup(scale=0.0)


def test_scaled_fish_is_the_fish_scaled():
    fish, big = SimulatedFish(seed=3), SimulatedFish(seed=3).scaled(1.7)
    for y in np.linspace(0.18, 0.6, 15):
        for x in (-0.03, 0.0, 0.004):
            assert big.flesh_top(1.7 * x, 1.7 * y) == pytest.approx(
                1.7 * fish.flesh_top(x, y), abs=1e-12
            )
            assert big.bone_top(1.7 * x, 1.7 * y) == pytest.approx(
                1.7 * fish.bone_top(x, y), abs=1e-12
            )


@pytest.mark.parametrize("name", sorted(ARM_SCALES))
def test_every_arm_reaches_the_scaled_cell_within_its_limits(name):
    robot = load_robot(name)
    setup = FishCuttingSetup().scaled(get_cell_scale(robot))
    fish = SimulatedFish().scaled(setup.scale)
    q_home = compute_home_configuration(robot, setup)
    assert np.all((q_home >= robot.lower) & (q_home <= robot.upper))
    check_waypoints(robot, fish, setup, q_home)  # raises on any miss
    tip, base = get_world_transforms(robot, setup)
    home = base * robot.fk(q_home)  # Kang's H scaled, orientation kept
    np.testing.assert_allclose(home.rotation, KANG_HOME_ROTATION, atol=1e-12)
    np.testing.assert_allclose(
        home.translation, setup.scale * KANG_HOME_WRIST_CENTER, atol=1e-12
    )
    # the shoulder where the scaled PUMA's is: axis 1 the world z axis, axis 2
    # horizontal at s * KANG_BASE_HEIGHT, a1 from axis 1 (the KUKA's, ABB's offset)
    w, p = axis_lines(robot)  # joint axes at q = 0, base frame
    w1, w2 = base.rotation @ w[0], base.rotation @ w[1]
    p1, p2 = base.act(p[0]), base.act(p[1])
    np.testing.assert_allclose(abs(w1[2]), 1.0, atol=1e-12)
    np.testing.assert_allclose(p1[:2], 0.0, atol=1e-12)
    assert w2[2] == pytest.approx(0.0, abs=1e-12)
    assert p2[2] == pytest.approx(setup.scale * KANG_BASE_HEIGHT, abs=1e-12)
    a1 = abs(p2[0] * w2[1] - p2[1] * w2[0]) / np.linalg.norm(w2[:2])
    assert a1 == pytest.approx(abs(get_structure(robot).table.joints[0].a), abs=1e-12)
    assert tip.translation[2] == pytest.approx(0.05 * setup.scale)


@pytest.mark.slow
def test_ur3_run_is_the_puma_run_scaled(ur3_run, run):
    """Same program, same time line, same events; every length times s = 0.63."""
    ur3, s = load_robot("ur3"), ur3_run.setup.scale
    assert s == 0.63 and ur3_run.fish.table_z == pytest.approx(s * run.fish.table_z)
    assert np.array_equal(ur3_run.t, run.t)
    assert ur3_run.primitive == run.primitive
    np.testing.assert_allclose(ur3_run.position / s, run.position, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ur3_run.velocity / s, run.velocity, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ur3_run.rotation, run.rotation, rtol=0, atol=1e-9)
    assert [(e.t, e.kind, e.primitive) for e in ur3_run.events] == [
        (e.t, e.kind, e.primitive) for e in run.events
    ]
    # the joint commands track that path, within the UR3's limits, no wrist flip
    tip, base = get_world_transforms(ur3, ur3_run.setup)
    for k in range(0, len(ur3_run.t), 7):
        pose = base * ur3.fk(ur3_run.q[k]) * tip
        np.testing.assert_allclose(pose.translation, ur3_run.position[k], atol=1e-9)
        np.testing.assert_allclose(pose.rotation, ur3_run.rotation[k], atol=1e-9)
    assert ur3_run.wrist_flips == 0 and np.abs(np.diff(ur3_run.q[:, 3])).max() < 0.05
    assert np.all((ur3_run.servo.q >= ur3.lower) & (ur3_run.servo.q <= ur3.upper))
    assert ur3_run.max_joint_speed <= ur3.velocity_limit.min()
    np.testing.assert_allclose(ur3_run.position[-1], ur3_run.position[0], atol=1e-12)


@pytest.mark.slow
def test_ur3_clears_the_scaled_table_and_fish(ur3_run):
    """The UR3 in its cell: table and fish (no pedestal), only the knife cuts."""
    ur3 = load_robot("ur3")
    scene = get_fish_cutting_scene(ur3, ur3_run.fish, ur3_run.setup)
    names = [o.name for o in scene.obstacles]
    assert names == ["cutting_table", "fish"]
    assert scene.obstacles[1].allow == ("wrist_2_link", "wrist_3_link", "ee_link")
    _, base = get_world_transforms(ur3, ur3_run.setup)
    table = base * scene.obstacles[0].placement  # back in the world frame
    top = table.translation[2] + scene.obstacles[0].size[2] / 2
    assert top == pytest.approx(0.63 * SimulatedFish().table_z, abs=1e-12)
    checker = CollisionChecker(ur3, scene, self_collision=False)
    distances = [checker.compute_distances(q) for q in ur3_run.q[::10]]
    assert np.min(distances) > 0.02  # [m]


def test_cli_runs_any_closed_form_arm_in_its_scaled_cell(capsys, run) -> None:
    from tests.conftest import run_cli

    code, out, _ = run_cli(
        capsys, "fishcut", "--robot", "ur3", "--json", "--no-collision"
    )
    result = json.loads(out)
    assert code == 0 and result["robot"] == "ur3" and result["scale"] == 0.63
    assert result["wrist_flips"] == 0 and result["cycles"] == len(run.t) - 1
    assert [e["kind"] for e in result["events"]][:2] == ["flesh", "bone"]
    code, out, _ = run_cli(capsys, "fishcut", "--json", "--no-collision")
    assert code == 0 and json.loads(out)["scale"] == 1.0


# -- seven-axis arms -----------------------------------------------------------------
SEVEN_AXIS_SCALES = {
    # reach hypot(a3, d3) + hypot(a4, d5) over KANG_REACH
    "panda": (math.hypot(0.0825, 0.316) + math.hypot(0.0825, 0.384), 0.83),
    # its elbow (±120°) folds too little for Kang's start pose at its reach 0.82 m
    "iiwa14": (0.42 + 0.40, 1.09),
}
#: Pinocchio axis lines meet (S, W) to rounding [m].
ATOL_LINES = 1e-9


def _axis_point(robot, q, joint: int):
    """A point (3,) [m] and the direction (3,) of joint ``joint`` (1-based) at q."""
    pin = pytest.importorskip("pinocchio")
    jacobian = pin.computeJointJacobians(robot.model, robot.data, q)
    v, w = jacobian[:3, joint - 1], jacobian[3:, joint - 1]  # WORLD: v = p × w
    return np.cross(w, v) / (w @ w), w / np.linalg.norm(w)


def _meet(robot, q, i: int, j: int) -> np.ndarray:
    """The point where axes i and j meet (the midpoint of their shortest link)."""
    p1, d1 = _axis_point(robot, q, i)
    p2, d2 = _axis_point(robot, q, j)
    a = np.array([[d1 @ d1, -d1 @ d2], [d1 @ d2, -d2 @ d2]])
    s, t = np.linalg.solve(a, [(p2 - p1) @ d1, (p2 - p1) @ d2])
    x1, x2 = p1 + s * d1, p2 + t * d2
    assert np.linalg.norm(x1 - x2) <= ATOL_LINES
    return 0.5 * (x1 + x2)


@pytest.fixture(scope="module", params=sorted(SEVEN_AXIS_SCALES))
def seven_axis_run(request):
    robot = load_robot(request.param)
    return robot, run_fish_cutting(robot)


@pytest.mark.slow
def test_seven_axis_cell_scale(seven_axis_run):
    robot, result = seven_axis_run
    reach, scale = SEVEN_AXIS_SCALES[robot.name]
    assert get_arm_reach(robot) == pytest.approx(reach, abs=1e-12)
    assert get_cell_scale(robot) == scale == result.setup.scale


@pytest.mark.slow
def test_shortest_fold_against_pinocchio(seven_axis_run):
    robot, _ = seven_axis_run
    q = np.zeros(7)
    lo, hi = robot.lower[3] + FOLD_MARGIN, robot.upper[3] - FOLD_MARGIN
    distances = []
    for q4 in np.linspace(lo, hi, 4001):
        q[3] = q4
        distances.append(np.linalg.norm(_meet(robot, q, 5, 6) - _meet(robot, q, 1, 2)))
    # sampled: within the sampling's error of the exact minimum, never below
    fold = get_shortest_fold(robot)
    assert fold <= min(distances) + 1e-12
    assert fold >= min(distances) - 1e-6


def test_seven_axis_shoulder_and_wrist_where_the_scaled_pumas_are(seven_axis_run):
    """With the tool down, W − S is Kang's wrist centre − shoulder, scaled.

    Exactly for the SRS arm; the Franka's wrist point is its flange offset
    a6 = 0.088 m aside of axis 7, so there only the height is exact.
    """
    robot, result = seven_axis_run
    _, base = get_world_transforms(robot, result.setup)
    q_home = result.q[0]
    shoulder = base.act(_meet(robot, q_home, 1, 2))
    wrist = base.act(_meet(robot, q_home, 5, 6))
    s = result.setup.scale
    np.testing.assert_allclose(shoulder[:2], 0.0, rtol=0, atol=1e-9)
    expected = s * (KANG_HOME_WRIST_CENTER - np.array([0.0, 0.0, KANG_BASE_HEIGHT]))
    offset = abs(get_structure(robot).table.joints[5].a)  # a6: 0 (SRS), 0.088 m
    aside = np.linalg.norm((wrist - shoulder - expected)[:2])
    assert aside == pytest.approx(offset, abs=1e-9)
    assert wrist[2] - shoulder[2] == pytest.approx(expected[2], abs=1e-9)


def test_seven_axis_run_is_continuous_within_limits_without_flips(seven_axis_run):
    robot, result = seven_axis_run
    q = result.q
    assert len(result.t) - 1 == 2869 and result.branch_flips == 0
    assert np.all((q >= robot.lower) & (q <= robot.upper))
    assert result.min_limit_margin > 0.0
    step = np.abs(np.diff(q, axis=0))
    assert np.all(step <= robot.velocity_limit / SETUP.planning_rate)
    servo = result.servo
    assert np.all(np.abs(servo.qd) <= robot.velocity_limit)
    assert np.all((servo.q >= robot.lower) & (servo.q <= robot.upper))


def test_seven_axis_trace_and_summary(seven_axis_run):
    robot, result = seven_axis_run
    solver = get_solver(robot)
    trace = solver.parameter_of(result.q)
    wrapped = np.remainder(trace - result.redundancy + np.pi, 2 * np.pi) - np.pi
    np.testing.assert_allclose(wrapped, 0.0, rtol=0, atol=1e-9)
    summary = summarize_fish_cutting(result, robot.name)
    trace_summary = summary["redundancy"]
    assert set(trace_summary) == {
        "parameter", "policy", "start", "end", "min", "max", "travel", "max_rate",
        "moving_cycles", "branch", "branch_changes", "min_limit_margin",
    }  # fmt: skip
    assert trace_summary["parameter"] == solver.parameter
    assert trace_summary["policy"] == "keep"
    assert trace_summary["start"] == result.redundancy[0]
    assert trace_summary["min"] <= trace_summary["start"] <= trace_summary["max"]
    assert trace_summary["min_limit_margin"] == result.min_limit_margin
    assert summary["branch_flips"] == 0 and summary["cycles"] == 2869


def test_six_axis_summary_has_no_redundancy(run):
    summary = summarize_fish_cutting(run, "puma560-kang")
    assert summary["redundancy"] is None and summary["branch_flips"] == 0
    assert np.isnan(run.redundancy).all() and run.redundancy_parameter is None


@pytest.mark.slow
def test_seven_axis_policy_options():
    panda = load_robot("panda")
    setup = dataclasses.replace(
        FishCuttingSetup().scaled(get_cell_scale(panda)), max_cycles=50
    )
    with pytest.raises(InfeasibleError, match="did not finish within 50 cycles"):
        run_fish_cutting(panda, setup=setup, redundancy="limit_margin")
    with pytest.raises(InputError, match="no redundancy"):
        run_fish_cutting(load_robot("puma560-kang"), redundancy="keep")


@pytest.mark.slow
def test_cli_seven_axis_arms_and_the_policy_option(capsys) -> None:
    from tests.conftest import run_cli

    code, out, _ = run_cli(
        capsys, "fishcut", "--robot", "iiwa14", "--json", "--no-collision"
    )
    result = json.loads(out)
    assert code == 0 and result["scale"] == 1.09 and result["branch_flips"] == 0
    assert result["redundancy"]["parameter"] == "arm angle"
    assert result["redundancy"]["policy"] == "keep"
    code, out, _ = run_cli(
        capsys, "fishcut", "--robot", "panda", "--redundancy-policy",
        "limit_margin", "--no-collision",
    )  # fmt: skip
    assert code == 0 and "redundancy q7 (limit_margin)" in out
    assert "branch flips 0" in out
    code, _, err = run_cli(
        capsys, "fishcut", "--robot", "ur5", "--redundancy-policy", "keep"
    )
    assert code == 2 and "ur5: a six-axis arm has no redundancy" in err


def test_seven_axis_cell_too_small_is_refused_before_running():
    iiwa = load_robot("iiwa14")
    setup = FishCuttingSetup().scaled(0.95)  # its reach ratio: A too near the shoulder
    with pytest.raises(InfeasibleError, match="no branch reaches Kang's home pose H"):
        run_fish_cutting(iiwa, setup=setup)
    home = compute_home_configuration(iiwa, FishCuttingSetup().scaled(1.09))
    with pytest.raises(InfeasibleError, match=r"waypoint S0 .* no IK solution"):
        check_waypoints(iiwa, SimulatedFish().scaled(0.95), setup, home)
