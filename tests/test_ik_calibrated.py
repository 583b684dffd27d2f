"""Calibrated arms: solved through their family, every branch carried to the model.

The models are generated here from the catalog URDFs
(``benchmarks/_calibrated_models.py``): a UR5 and a PUMA 560 with calibration
deltas on every joint origin (seeded uniform 1e-4…1e-3 rad on each ``rpy``
value, 0.1…1 mm on each ``xyz`` value), an iiwa 14 with its joint 2 and 4
origins 0.436 mm off axis (as in ROS-Industrial's URDF) and a calibrated
Panda. For random in-limit configurations: every branch reproduces the pose
to 1e-12 by Pinocchio's FK; the generating configuration is among the branches
to 1e-9 rad, except for at most a fraction :data:`NEAR_SINGULAR_MISSES`, each
within :data:`NEAR_SINGULAR` of a singularity (``least_singular``: of the tool
Jacobian, or of [J; ∇ψ] for an SRS arm at held ψ) and reported by the solve's
``ik.SolveFlag`` byte (a branch vanished, merged, or solutions unlisted); a
100-start numerical search finds a solution outside the branches at no more
than :data:`OUTSIDE_POSES` of its poses, each reported so; and the
bound of :data:`~workbench.ik.structure.CALIBRATION_ANGLE_TOL` and
``CALIBRATION_DISTANCE_TOL`` is where the closed form stops.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from benchmarks._calibrated_models import (
    IIWA_OFF_AXIS,
    calibrated_arm,
    calibrated_urdf,
    fk_residuals,
    least_singular,
    off_axis_iiwa,
    wrapped,
)
from tests._meshes import write_meshes_of
from workbench import Robot, ik, load_robot
from workbench.ik import (
    CALIBRATION_ANGLE_TOL,
    CALIBRATION_DISTANCE_TOL,
    SolveFlag,
    UnsupportedRobotError,
    analytic,
    analytic_batch,
    choose_redundancy,
    get_solver,
    get_structure,
    numeric_batch,
)
from workbench.ik._refine_kernel import refinement_chain

#: ROS-Industrial's description packages, vendored (``tests/data``).
ROS_INDUSTRIAL = Path(__file__).parent / "data" / "ros_industrial"
#: Every branch's FK residual by Pinocchio [m, rad].
ATOL_RESIDUAL = 1e-12
#: The generating configuration is a branch to this [rad, each joint mod 2π].
ATOL_SAME_Q = 1e-9
#: A numerical solution is one of the branches to this [rad]: the numerical
#: search stops at an error of 1e-10, so its joints are that close only.
ATOL_NUMERIC_Q = 1e-6
#: Least singular value of the tool Jacobian [m or rad per rad] below which a
#: configuration counts as near a singularity: there the model's solutions
#: near one of the idealised arm's may be more than its branches, or lie
#: along a valley, and the generating one may be missed.
NEAR_SINGULAR = 0.02
#: The fraction of all configurations that may be missed there.
NEAR_SINGULAR_MISSES = 3e-3
#: Fraction of the searched poses where the numerical search may find a
#: solution outside the branches (each reported by the solve's flags).
OUTSIDE_POSES = 0.02
#: The same for the calibrated Panda at held q7.
PANDA_MISSES = 6e-3
#: How far [rad] outside the idealised arm's feasible intervals the model may
#: still have a branch within its limits (where a joint limit ends an interval,
#: the model's branch is off the idealised one by about the deviation over
#: the Jacobian's least singular value).
FEASIBLE_MARGIN = 0.05
#: Random configurations per arm (the heavy tests) and poses of the search.
SAMPLES = 10_000
SEARCH_POSES = 200
SEARCH_STARTS = 100


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("calibrated")


def _solve_all(robot: Robot, qs: np.ndarray, targets: np.ndarray):
    """Every branch of each target: q (N, B, n), valid (N, B), solve flags (N,)."""
    solver = get_solver(robot)
    value = None if robot.nq == 6 else solver.parameter_of(qs)
    events = np.empty(len(targets), dtype=np.uint8)
    q_all, valid = solver.solve_batch(targets, redundancy=value, solve_flags=events)
    return q_all, valid, events


def _solve_flags(robot: Robot, target: np.ndarray, value: float | None) -> SolveFlag:
    """The solve-level flags of the single solve of ``target``.

    (All three when it raises ``UnreachableError(kind="model")``: no branch
    on the model.)
    """
    solver = get_solver(robot)
    try:
        _, _, events = solver.solve_arrays(target, np.empty(0), redundancy=value)
    except ik.UnreachableError as err:
        assert err.kind == "model"
        return ~SolveFlag(0)
    solutions = solver.solve(target, redundancy=value)  # the same byte, named
    assert solutions.solve_flags == events
    assert isinstance(solutions.solve_flags, SolveFlag)
    return SolveFlag(events)


def _flagged(robot: Robot, target: np.ndarray, value: float | None) -> bool:
    """Whether the single solve of ``target`` reports a lost or merged branch."""
    return bool(_solve_flags(robot, target, value))


def _check_round_trip(
    robot: Robot, qs: np.ndarray, misses: float = NEAR_SINGULAR_MISSES
) -> None:
    """Residuals within 1e-12; the generating q among the branches, or near-singular."""
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    q_all, valid, events = _solve_all(robot, qs, targets)
    rows = np.nonzero(valid)
    residuals = fk_residuals(robot, q_all[rows], targets[rows[0]])
    assert residuals.max() <= ATOL_RESIDUAL, residuals.max()
    gaps = wrapped(q_all - qs[:, None, :]).max(axis=2)
    gaps[~valid] = np.inf
    missed = np.flatnonzero(gaps.min(axis=1) > ATOL_SAME_Q)
    values = None if robot.nq == 6 else get_solver(robot).parameter_of(qs)
    for i in missed:  # near a singularity, and said so by the solve
        sigma = least_singular(robot, qs[i])
        value = None if values is None else float(values[i])
        assert sigma < NEAR_SINGULAR, (i, sigma)
        assert events[i] != 0 and _flagged(robot, targets[i], value), (i, sigma)
    assert len(missed) <= np.ceil(misses * len(qs)), len(missed)


# -- the structure and its deviation -------------------------------------------


@pytest.mark.parametrize(("name", "family"), [("ur5", "ur"), ("puma560", "opw")])
def test_calibrated_arm_is_of_its_family(name: str, family: str, folder) -> None:
    robot = calibrated_urdf(name, folder, seed=0)
    structure = get_structure(robot)
    assert structure.family == family
    deviation = structure.deviation
    assert 1e-4 <= deviation.angle <= CALIBRATION_ANGLE_TOL
    assert 1e-4 <= deviation.distance <= CALIBRATION_DISTANCE_TOL
    assert deviation.calibrated
    assert "rad (" in deviation.describe() and "m (" in deviation.describe()
    assert refinement_chain(robot) is not None
    assert not get_structure(load_robot(name)).deviation.calibrated


def test_off_axis_iiwa_is_srs_with_its_offset(folder) -> None:
    """ROS-Industrial's iiwa 14: 0.436 mm off, SRS, the deviation says where."""
    robot = off_axis_iiwa(folder)
    structure = get_structure(robot)
    assert structure.family == "srs"
    deviation = structure.deviation
    np.testing.assert_allclose(deviation.distance, IIWA_OFF_AXIS, rtol=1e-6, atol=0)
    assert deviation.distance_test in ("1,2,3 meet", "3,4,5 meet")
    assert deviation.angle <= 1e-12
    assert get_solver(robot).parameter == "arm angle"
    assert get_solver(robot).deviation == deviation


def test_ros_industrial_iiwa_urdf_itself(tmp_path) -> None:
    """ROS-Industrial's own ``lbr_iiwa_14_r820.urdf`` (vendored in ``tests/data``).

    Its joint 2 and 4 origins are 0.43624 mm off axis (of opposite signs, unlike
    :func:`off_axis_iiwa`'s): SRS, the deviation said, every configuration back.
    """
    root = tmp_path / "src"
    shutil.copytree(ROS_INDUSTRIAL, root)
    folders = {p.name: p for p in root.iterdir() if p.is_dir()}
    urdf = root / "kuka_lbr_iiwa_support" / "urdf" / "lbr_iiwa_14_r820.urdf"
    write_meshes_of(urdf.read_text(), folders)
    robot = load_robot(urdf, tool_frame="tool0")
    solver = get_solver(robot)
    assert solver.family.name == "srs" and solver.deviation is not None
    np.testing.assert_allclose(
        solver.deviation.distance, IIWA_OFF_AXIS, rtol=1e-6, atol=0
    )
    rng = np.random.default_rng(9)
    _check_round_trip(robot, rng.uniform(robot.lower, robot.upper, (500, 7)))


def _moved(robot: Robot, joint: int, placement: pin.SE3) -> Robot:
    model = pin.Model(robot.model)
    model.jointPlacements[joint] = model.jointPlacements[joint] * placement
    return Robot(f"{robot.name}-moved", model, robot.urdf_path, robot.tool_frame,
                 package_dirs=[])  # fmt: skip


@pytest.mark.parametrize("fraction", [0.95, 1.05])
def test_the_bound_solves_within_and_refuses_beyond(fraction: float) -> None:
    """Axes 2 and 3 of a UR5 turned to 0.95 and 1.05 of the angle bound."""
    robot = load_robot("ur5")
    angle = fraction * CALIBRATION_ANGLE_TOL
    turned = _moved(robot, 3, pin.SE3(pin.exp3(np.array([angle, 0, 0])), np.zeros(3)))
    if fraction > 1.0:
        with pytest.raises(UnsupportedRobotError) as err:
            get_structure(turned)
        message = str(err.value)
        assert re.search(r"axes 2 and 3 are not parallel \(off by 0\.0105", message)
        assert re.search(r"nearest family \(UR\): 0\.01\d* rad \(2∥3\)", message)
        assert "use numerical IK" in message
        return
    structure = get_structure(turned)
    assert structure.family == "ur"
    np.testing.assert_allclose(structure.deviation.angle, angle, rtol=1e-6, atol=0)
    rng = np.random.default_rng(5)
    _check_round_trip(turned, rng.uniform(robot.lower, robot.upper, size=(300, 6)))


@pytest.mark.parametrize("fraction", [0.95, 1.05])
def test_the_distance_bound(fraction: float) -> None:
    """The iiwa's joint 4 moved off axis by 0.95 and 1.05 of the distance bound."""
    robot = load_robot("iiwa14")
    offset = fraction * CALIBRATION_DISTANCE_TOL
    moved = _moved(robot, 4, pin.SE3(np.eye(3), np.array([offset, 0.0, 0.0])))
    if fraction > 1.0:
        with pytest.raises(UnsupportedRobotError) as err:
            get_structure(moved)
        assert "deviation from the nearest family" in str(err.value)
        assert "3,4,5 meet" in str(err.value)
        return
    structure = get_structure(moved)
    assert structure.family == "srs"
    np.testing.assert_allclose(structure.deviation.distance, offset, rtol=1e-6, atol=0)
    rng = np.random.default_rng(6)
    _check_round_trip(moved, rng.uniform(robot.lower, robot.upper, size=(300, 7)))


# -- every configuration comes back ---------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ur5", "puma560", "iiwa14"])
def test_random_configurations_come_back(name: str, folder) -> None:
    robot = calibrated_arm(name, folder)
    rng = np.random.default_rng(1)
    _check_round_trip(robot, rng.uniform(robot.lower, robot.upper, (SAMPLES, robot.nq)))


def test_calibrated_panda_at_held_q7(folder) -> None:
    robot = calibrated_urdf("panda", folder, seed=0)
    assert get_structure(robot).family == "franka"
    rng = np.random.default_rng(2)
    # (the shoulder of a Franka arm, θ2 = 0 with axes 1 and 3 aligned, is a
    # valley its misses come from: 4 of 1000 measured)
    _check_round_trip(
        robot, rng.uniform(robot.lower, robot.upper, (1000, 7)), misses=PANDA_MISSES
    )


@settings(
    max_examples=20,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    seed=st.integers(0, 3),
    name=st.sampled_from(["ur5", "puma560"]),
    unit=st.lists(st.floats(0.0, 1.0), min_size=6, max_size=6),
)
def test_property_round_trip(seed: int, name: str, unit: list[float], folder) -> None:
    """Any calibration seed, any configuration: exact, and back unless near-singular."""
    robot = calibrated_urdf(name, folder, seed=seed)
    q = robot.lower + np.asarray(unit) * (robot.upper - robot.lower)
    target = robot.fk(q).homogeneous
    solutions = analytic(robot, target)
    qs = np.array([s.q for s in solutions])
    assert fk_residuals(robot, qs, np.array([target] * len(qs))).max() <= ATOL_RESIDUAL
    gap = wrapped(qs - q).max(axis=1).min()
    assert gap <= ATOL_SAME_Q or least_singular(robot, q) < NEAR_SINGULAR
    for s in solutions:  # within-limits is the final q's
        inside = bool(
            np.all((robot.lower - 1e-12 <= s.q) & (s.q <= robot.upper + 1e-12))
        )
        assert s.within_limits == inside


# -- single poses, flags --------------------------------------------------------


def test_single_poses_agree_with_the_batch_and_report_lost_branches(folder) -> None:
    """``analytic`` gives the batch's branches; a lost branch sets its flag."""
    robot = calibrated_urdf("ur5", folder, seed=0)
    solver = get_solver(robot)
    rng = np.random.default_rng(3)
    qs = rng.uniform(robot.lower, robot.upper, size=(2000, 6))
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    events = np.empty(len(qs), dtype=np.uint8)
    q_all, valid = solver.solve_batch(targets, solve_flags=events)
    chain = solver._refine
    try:  # the idealised arm's branches: the same solver, not carried
        solver._refine = None
        _, ideal_valid = solver.solve_batch(targets)
    finally:
        solver._refine = chain
    lost = np.flatnonzero(valid.sum(axis=1) < ideal_valid.sum(axis=1))
    assert lost.size > 0  # near the folds of the model some branches vanish
    for i in [*range(50), *lost[:20]]:
        solutions = analytic(robot, targets[i])
        assert [s.index for s in solutions] == list(np.flatnonzero(valid[i]))
        np.testing.assert_allclose(
            np.array([s.q for s in solutions]), q_all[i][valid[i]], rtol=0, atol=1e-9
        )
        single = _solve_flags(robot, targets[i], None)
        assert single == events[i]
        if i in lost:
            assert single & (SolveFlag.BRANCH_VANISHED | SolveFlag.BRANCHES_MERGED)
    np.testing.assert_array_equal(
        q_all, analytic_batch(robot, targets)[0]
    )  # the default return is unchanged
    clean = load_robot("ur5")
    assert _solve_flags(clean, clean.fk(qs[0]).homogeneous, None) == 0
    clean_events = np.ones(len(qs), dtype=np.uint8)
    get_solver(clean).solve_batch(targets, solve_flags=clean_events)
    assert not clean_events.any()


def test_a_pose_just_past_the_ideal_reach_is_flagged(folder) -> None:
    """The idealised Franka arm refuses a pose the calibrated model reaches: said.

    Configuration 4214 of 10⁴ random ones (seed 1) of the calibrated Panda puts
    the wrist point 0.18 mm past the idealised arm's stretched elbow at its q7:
    the kernel finds no start, the single solve raises ``kind="model"`` (the
    model may reach it) and the batch sets ``SOLUTIONS_UNLISTED``.
    """
    robot = calibrated_urdf("panda", folder, seed=0)
    solver = get_solver(robot)
    rng = np.random.default_rng(1)
    q = rng.uniform(robot.lower, robot.upper, (10_000, 7))[4214]
    target = robot.fk(q).homogeneous
    value = float(solver.parameter_of(q))
    with pytest.raises(ik.UnreachableError, match="may reach it") as err:
        solver.solve(target, redundancy=value)
    assert err.value.kind == "model"
    distance, high = err.value.distance, err.value.bounds[1]
    assert 0.0 < distance - high <= solver._slack  # past the reach, within the slack
    events = np.empty(1, dtype=np.uint8)
    _, valid = solver.solve_batch(target[None], redundancy=value, solve_flags=events)
    assert not valid.any() and events[0] == SolveFlag.SOLUTIONS_UNLISTED
    far = target.copy()
    far[:3, 3] *= 3.0  # far out of every reach: refused as before
    with pytest.raises(ik.UnreachableError) as err:
        solver.solve(far, redundancy=value)
    assert err.value.kind == "reach"
    get_solver(robot).solve_batch(far[None], redundancy=value, solve_flags=events)
    assert events[0] == 0


# -- no solution outside the branches -------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ur5", "puma560", "iiwa14"])
def test_numerical_search_finds_no_other_solution(name: str, folder) -> None:
    """100 random starts of ``numeric_batch`` at 200 poses: every solution a branch.

    Seven axes: each numerical solution is compared with the branches at its
    own value of the redundancy parameter.
    """
    robot = calibrated_arm(name, folder)
    rng = np.random.default_rng(4)
    qs = rng.uniform(robot.lower, robot.upper, size=(SEARCH_POSES, robot.nq))
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    starts = rng.uniform(
        robot.lower, robot.upper, (SEARCH_POSES * SEARCH_STARTS, robot.nq)
    )
    repeated = np.repeat(targets, SEARCH_STARTS, axis=0)
    found = numeric_batch(robot, repeated, starts, rng=7)
    ok = np.flatnonzero(found.success)
    assert ok.size > 0.5 * len(repeated)
    q_num = found.q[ok]
    solver = get_solver(robot)
    if robot.nq == 6:
        q_all, valid = analytic_batch(robot, targets)
        q_all, valid = q_all[ok // SEARCH_STARTS], valid[ok // SEARCH_STARTS]
    else:
        values = solver.parameter_of(q_num)
        q_all, valid = solver.solve_batch(repeated[ok], redundancy=values)
    gaps = wrapped(q_all - q_num[:, None, :]).max(axis=2)
    gaps[~valid] = np.inf
    outside = np.flatnonzero(gaps.min(axis=1) > ATOL_NUMERIC_Q)
    for i in outside:  # a solution the branches miss: the solve reports it
        value = None if robot.nq == 6 else float(solver.parameter_of(q_num[i]))
        assert _flagged(robot, repeated[ok[i]], value), (i, gaps.min(axis=1)[i])
    poses = np.unique(ok[outside] // SEARCH_STARTS)
    assert poses.size <= OUTSIDE_POSES * SEARCH_POSES, poses


# -- seven axes: the redundancy tools -------------------------------------------


@pytest.mark.parametrize("name", ["iiwa14", "panda"])
def test_feasible_intervals_and_choice_keep_working(name: str, folder) -> None:
    """Feasible intervals and ``choose_redundancy`` on a calibrated seven-axis arm.

    The intervals are the idealised arm's, its reach tests widened by the
    model's deviation: they hold every value where the model has a branch
    within its limits (a superset, sampled here on a grid of the parameter).
    The choice is a configuration of the model within its limits, exact to
    1e-12, at the parameter it names.
    """
    robot = (
        off_axis_iiwa(folder)
        if name == "iiwa14"
        else calibrated_urdf("panda", folder, seed=0)
    )
    solver = get_solver(robot)
    lo, hi = solver.parameter_range
    grid = np.linspace(lo, hi, 41)[1:-1]
    rng = np.random.default_rng(8)
    inside, worst = 0, 0.0
    for q in rng.uniform(0.8 * robot.lower, 0.8 * robot.upper, size=(10, 7)):
        target = robot.fk(q).homogeneous
        feasible = solver.feasible(target)
        for value in grid:
            try:
                solutions = solver.solve(target, redundancy=float(value))
            except ik.UnreachableError:
                continue
            for s in solutions:
                if s.within_limits:
                    inside += 1
                    ranges = feasible.union
                    gap = min(max(a - value, value - b, 0.0) for a, b in ranges)
                    worst = max(worst, gap)
        choice = choose_redundancy(robot, target)
        chosen = choice.solution
        assert chosen.within_limits
        assert fk_residuals(robot, chosen.q[None], target[None]).max() <= ATOL_RESIDUAL
        gap = wrapped(np.asarray(solver.parameter_of(chosen.q) - choice.value))
        assert gap <= 1e-9
    assert inside > 50
    assert worst <= FEASIBLE_MARGIN, worst


# -- the command line ------------------------------------------------------------


def test_cli_ik_shows_the_deviation(capsys, folder) -> None:
    from tests.conftest import run_cli

    robot = calibrated_urdf("ur5", folder, seed=0)
    pose = ("--xyz-quat-wxyz", "0.3", "0.1", "0.4", "0", "1", "0", "0")
    share = Path(load_robot("ur5").urdf_path).parents[3]  # example-robot-data
    args = ("ik", "--robot", str(robot.urdf_path), "--tool-frame", "tool0",
            "--package-dir", f"example-robot-data={share}", *pose)  # fmt: skip
    code, out, err = run_cli(capsys, *args)
    assert code == 0, err
    assert "calibrated arm: structure deviation 0.0017 rad (3∥4)" in out
    code, out, err = run_cli(capsys, *args, "--json")
    assert code == 0, err
    found = json.loads(out)["structure_deviation"]
    deviation = get_structure(robot).deviation
    assert found == {
        "angle": deviation.angle,
        "angle_test": deviation.angle_test,
        "distance": deviation.distance,
        "distance_test": deviation.distance_test,
    }
    code, out, _ = run_cli(capsys, "ik", "--robot", "ur5", *pose, "--json")
    assert code == 0 and "structure_deviation" not in json.loads(out)
