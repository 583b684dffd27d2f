"""Seven-axis arms whose URDF rounds its numbers to 4 decimals: exact closed form.

example-robot-data's xArm7 writes π/2 as ``1.5708`` (3.67e-6 rad off) and its
axes 1, 2, 3 meet only to 1.08e-6 m: of the Franka pattern within
``STRUCTURE_TOL`` = 1e-5, not 1e-6. The iiwa14 (SRS) and panda (Franka) URDFs
rounded the same way (``bench_ik_agreement.rounded_urdf(decimals=4)``) are
the same case for both families. On such models every branch of the closed
form is refined on the model's own chain, the redundancy parameter held: each
configuration comes back from its pose and its parameter to 1e-9, every branch
reproduces the pose to 1e-12 by Pinocchio's FK, the batch gives what single
poses give, and a structure broken by 2e-2 (beyond the calibration bound) is
still refused.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from benchmarks.bench_ik_agreement import rounded_urdf
from tests.conftest import run_cli
from workbench import Robot, ik, load_robot
from workbench.ik import UnsupportedRobotError
from workbench.ik._refine_kernel import refinement_chain
from workbench.ik._refine_redundant_kernel import TWIN_TOL
from workbench.ik.structure import STRUCTURE_TOL

#: The configuration is among the branches [rad, each joint mod 2π].
ATOL_SAME_Q = 1e-9
#: FK residual of every branch against Pinocchio [m, rad].
ATOL_RESIDUAL = 1e-12
#: Batch against single poses [rad]: the same Newton steps from the same start.
ATOL_BATCH = 1e-12
#: Random configurations per model.
SAMPLES = 2000
#: A broken structure [rad].
BROKEN = 2e-2

#: The models, and their families.
FAMILIES = {"xarm7": "franka", "iiwa14": "srs", "panda": "franka"}


def _load(name: str, folder: Path) -> Robot:
    """xarm7 as shipped, or the iiwa14 / panda URDF rounded to 4 decimals."""
    if name == "xarm7":
        return load_robot(name)
    return rounded_urdf(name, folder, decimals=4)


@pytest.fixture(scope="module", params=list(FAMILIES))
def robot(request, tmp_path_factory) -> Robot:
    return _load(request.param, tmp_path_factory.mktemp("rounded"))


def _wrapped(a: np.ndarray) -> np.ndarray:
    return np.abs(np.angle(np.exp(1j * a)))


def _residual(robot: Robot, q: np.ndarray, target: pin.SE3) -> tuple[float, float]:
    """Position [m] and rotation [rad] residual of ``q`` by Pinocchio's FK."""
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    pose = data.oMf[robot.tool_frame_id]
    position = float(np.linalg.norm(pose.translation - target.translation))
    rotation = float(np.linalg.norm(pin.log3(target.rotation.T @ pose.rotation)))
    return position, rotation


def test_xarm7_is_franka_within_the_tolerance() -> None:
    robot = load_robot("xarm7")
    structure = ik.get_structure(robot)
    assert structure.family == "franka"
    deviation = structure.deviation
    assert 1e-6 < max(deviation.angle, deviation.distance) <= STRUCTURE_TOL
    assert refinement_chain(robot) is not None
    assert ik.get_solver(robot).parameter == "q7"


@pytest.mark.parametrize("name", ["iiwa14", "panda"])
def test_exact_models_are_not_refined(name: str) -> None:
    assert refinement_chain(load_robot(name)) is None


def test_rounded_models_keep_their_family(robot: Robot) -> None:
    name = next(k for k in FAMILIES if k in robot.name)
    structure = ik.get_structure(robot)
    assert structure.family == FAMILIES[name]
    deviation = structure.deviation
    assert 1e-6 < max(deviation.angle, deviation.distance) <= STRUCTURE_TOL
    assert structure.residual > 1e-7  # the model is not the idealised chain


def _round_trip(robot: Robot, q: np.ndarray) -> None:
    target = robot.fk(q)
    value = ik.get_solver(robot).parameter_of(q)
    solutions = ik.analytic(robot, target, redundancy=value)
    assert min(_wrapped(s.q - q).max() for s in solutions) <= ATOL_SAME_Q
    for s in solutions:
        position, rotation = _residual(robot, np.asarray(s.q), target)
        assert position <= ATOL_RESIDUAL and rotation <= ATOL_RESIDUAL, s.branch
        if ik.get_structure(robot).family == "franka":
            assert s.q[6] == value  # q7 held
        else:  # the arm angle held, on the idealised chain
            assert abs(ik.get_solver(robot).parameter_of(s.q) - value) <= ATOL_RESIDUAL


@pytest.mark.slow
def test_round_trip_of_random_configurations(robot: Robot) -> None:
    """analytic(fk(q), redundancy=solver.parameter_of(q)) holds q, each branch exact."""
    rng = np.random.default_rng(2026)
    for q in rng.uniform(robot.lower, robot.upper, size=(SAMPLES, 7)):
        _round_trip(robot, q)


@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(0.0, 1.0), min_size=7, max_size=7))
def test_round_trip_property_xarm7(fractions: list[float]) -> None:
    robot = load_robot("xarm7")
    q = robot.lower + np.asarray(fractions) * (robot.upper - robot.lower)
    _round_trip(robot, q)


@pytest.mark.slow
def test_batch_equals_single_poses(robot: Robot) -> None:
    rng = np.random.default_rng(7)
    qs = rng.uniform(robot.lower, robot.upper, size=(300, 7))
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    values = ik.get_solver(robot).parameter_of(qs)
    q_batch, valid = ik.analytic_batch(robot, targets, redundancy=values)
    for i in range(len(qs)):
        try:
            single = ik.analytic(robot, targets[i], redundancy=float(values[i]))
        except ik.UnreachableError:
            single = []
        assert [s.index for s in single] == list(np.flatnonzero(valid[i]))
        for s in single:
            assert _wrapped(q_batch[i, s.index] - s.q).max() <= ATOL_BATCH
        assert np.isnan(q_batch[i][~valid[i]]).all()


def test_track_follows_a_motion_exactly() -> None:
    """track / try_track on the model: exact, continuous, None out of reach."""
    robot = load_robot("xarm7")
    solver = ik.get_solver(robot)
    start = np.array([0.3, -0.4, 0.2, 0.9, 0.1, 1.2, 0.4])
    end = start + np.array([0.2, 0.3, -0.1, 0.2, 0.3, -0.2, 0.0])
    first = ik.analytic(robot, robot.fk(start), redundancy=float(start[6]))
    branch = min(first, key=lambda s: _wrapped(s.q - start).max()).index
    previous = start
    for t in np.linspace(0.0, 1.0, 51):
        q_true = start + t * (end - start)
        pose = robot.fk(q_true).homogeneous
        q, index, _ = solver.track(
            pose, previous, branch, 0.01, redundancy=float(q_true[6])
        )
        assert index == branch
        assert _wrapped(q - q_true).max() <= ATOL_SAME_Q
        tried = solver.try_track(
            pose, previous, branch, 0.01, redundancy=float(q_true[6])
        )
        assert tried is not None and np.array_equal(tried[0], q)
        previous = q
    far = np.eye(4)
    far[:3, 3] = (5.0, 0.0, 0.0)
    assert solver.try_track(far, previous, branch, 0.01, redundancy=0.0) is None
    with pytest.raises(ik.UnreachableError):
        solver.track(far, previous, branch, 0.01, redundancy=0.0)


def test_fold_twins_are_both_found() -> None:
    """Wrist twins that start at the idealised arm's edge reach both solutions.

    The configuration (xarm7, q5 near −π/2 with q4 at its elbow) puts the
    idealised arm just past its wrist edge for this q7: both wrist branches
    start at the edge and the model's two solutions lie on either side.
    """
    robot = load_robot("xarm7")
    rng = np.random.default_rng(5)  # (found among random draws: q5 = −1.529 rad)
    q = rng.uniform(robot.lower, robot.upper, size=(2000, 7))[570]
    solutions = ik.analytic(robot, robot.fk(q), redundancy=float(q[6]))
    assert any(s.wrist_singular for s in solutions)
    assert min(_wrapped(s.q - q).max() for s in solutions) <= ATOL_SAME_Q
    twins = [s for s in solutions if s.wrist_singular]
    distinct = {tuple(np.round(s.q, 6)) for s in twins}
    assert len(distinct) == len(twins)  # no two branches on one solution
    assert all(
        _wrapped(a.q - b.q).max() > TWIN_TOL
        for a in twins
        for b in twins
        if a.index < b.index
    )


def test_broken_structure_is_refused() -> None:
    """The xArm7 with joint 4 turned by 2e-2 rad: no closed form, every test named."""
    robot = load_robot("xarm7")
    model = pin.Model(robot.model)
    turn = pin.SE3(pin.exp3(np.array([BROKEN, 0.0, 0.0])), np.zeros(3))
    model.jointPlacements[4] = model.jointPlacements[4] * turn
    broken = Robot("xarm7-broken", model, robot.urdf_path, robot.tool_frame,
                   package_dirs=[])  # fmt: skip
    with pytest.raises(UnsupportedRobotError, match=r"bound 0\.01 rad, 0\.005 m"):
        ik.get_structure(broken)
    with pytest.raises(UnsupportedRobotError):
        ik.get_solver(broken)


def test_cli_ik_solves_the_xarm7_in_closed_form(capsys) -> None:
    code, out, err = run_cli(
        capsys, "ik", "--robot", "xarm7", "--xyz-quat-wxyz",
        "0.3", "0.1", "0.4", "0", "1", "0", "0",
    )  # fmt: skip
    assert code == 0, err
    assert "closed-form (FRANKA family, seven axes)" in out
    residuals = [float(part.split()[0]) for part in out.split("residual ")[1:]]
    assert residuals and max(residuals) <= ATOL_RESIDUAL
