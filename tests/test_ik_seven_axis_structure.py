"""Seven-axis families read from the joint axes: SRS (iiwa14), Franka (panda)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from workbench import Robot, load_robot
from workbench.errors import InputError
from workbench.ik import UnsupportedRobotError, get_solver, get_structure
from workbench.ik.structure import compute_structure
from workbench.model.dh import DHTable

#: FK of the fitted chain against Pinocchio's [m, rad]: both are exact products
#: of the same rigid transforms.
ATOL_EXACT = 1e-12
URDF = Path(__file__).resolve().parents[1] / "urdf"
HALF_PI = math.pi / 2.0


def _variant(robot: Robot, joint: int, placement: pin.SE3) -> Robot:
    """The robot (no DH table) with joint ``joint`` (1-based) put at ``placement``."""
    model = pin.Model(robot.model)
    model.jointPlacements[joint] = placement
    return Robot(f"{robot.name}-variant", model, robot.urdf_path, robot.tool_frame,
                 package_dirs=[])  # fmt: skip


def _fitted_fk(structure, q: np.ndarray) -> np.ndarray:
    theta = q * np.asarray(structure.joint_sign)
    return structure.base @ structure.table.forward_kinematics(theta) @ structure.tool


def test_iiwa14_is_srs_with_its_published_table() -> None:
    structure = get_structure(load_robot("iiwa14"))
    published = DHTable.from_json(URDF / "iiwa14.dh.json")
    assert structure.family == "srs"
    assert structure.joint_sign == (1.0,) * 7
    assert structure.table.nq == 7
    for fitted, row in zip(structure.table.joints, published.joints, strict=True):
        got = (fitted.alpha, fitted.a, fitted.d, fitted.theta_offset)
        want = (row.alpha, row.a, row.d, row.theta_offset)
        np.testing.assert_allclose(got, want, rtol=0, atol=ATOL_EXACT)
        assert fitted.alpha in (HALF_PI, -HALF_PI, 0.0) and fitted.a == 0.0
    for k in (1, 3, 5):  # S, E, W: exact zeros
        assert structure.table.joints[k].d == 0.0
    np.testing.assert_allclose(structure.base, np.eye(4), rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(structure.tool, np.eye(4), rtol=0, atol=ATOL_EXACT)
    assert structure.residual <= ATOL_EXACT


def test_panda_is_franka_to_its_hand_tcp() -> None:
    robot = load_robot("panda")
    structure = get_structure(robot)
    assert robot.tool_frame == "panda_hand_tcp"
    assert structure.family == "franka"
    assert structure.residual <= ATOL_EXACT
    rows = structure.table.joints
    assert [abs(r.alpha) for r in rows] == [HALF_PI] * 6 + [0.0]
    assert [r.a == 0.0 for r in rows] == [True, True, False, False, True, False, True]
    assert rows[1].d == 0.0  # axes 1, 2, 3 meet: the spherical shoulder
    # the Panda's lengths [m]: shoulder, upper arm, elbow offsets, forearm,
    # wrist offset, flange + hand to the TCP
    lengths = (rows[0].d, rows[2].d, rows[2].a, rows[3].a, rows[4].d, rows[5].a)
    np.testing.assert_allclose(
        np.abs(lengths), [0.333, 0.316, 0.0825, 0.0825, 0.384, 0.088], atol=1e-15
    )
    np.testing.assert_allclose(rows[6].d, 0.107 + 0.1034, rtol=0, atol=1e-15)


@pytest.mark.parametrize("name", ["iiwa14", "panda"])
def test_fitted_chain_is_the_model(name: str) -> None:
    """FK(q) = base · DH(θ) · tool, θ = s q + θ0, against Pinocchio at random q."""
    robot = load_robot(name)
    structure = get_structure(robot)
    rng = np.random.default_rng(11)
    for q in rng.uniform(-2 * np.pi, 2 * np.pi, size=(200, 7)):
        np.testing.assert_allclose(
            _fitted_fk(structure, q), robot.fk(q).homogeneous, rtol=0, atol=ATOL_EXACT
        )


def test_perturbed_iiwa_is_refused_naming_each_test() -> None:
    robot = load_robot("iiwa14")
    moved = robot.model.jointPlacements[4] * pin.SE3(np.eye(3), np.array([1e-2, 0, 0]))
    with pytest.raises(UnsupportedRobotError) as err:
        compute_structure(_variant(robot, 4, moved))
    message = str(err.value)
    assert "not SRS (spherical shoulder, elbow and wrist)" in message
    assert re.search(r"axes 3, 4, 5 do not meet in one point \(off by 0\.01\d* m\)",
                     message)  # fmt: skip
    # the iiwa's axes pass Franka's angle tests; its zero offsets do not
    assert "not Franka" in message and "wrist offset (a6) is zero" in message
    assert "not OPW" not in message and "use numerical IK" in message
    turned = robot.model.jointPlacements[6] * pin.SE3(pin.exp3(np.array([2e-2, 0, 0])),
                                                      np.zeros(3))  # fmt: skip
    with pytest.raises(UnsupportedRobotError) as err:
        compute_structure(_variant(robot, 6, turned))
    assert re.search(r"axes 5 and 6 are not perpendicular \(off by 0\.02\d* rad\)",
                     str(err.value))  # fmt: skip


def test_franka_without_elbow_offset_is_refused() -> None:
    robot = load_robot("panda")
    placement = pin.SE3(robot.model.jointPlacements[4])
    placement.translation = np.zeros(3)  # a3 = 0: axes 3 and 4 meet
    with pytest.raises(UnsupportedRobotError) as err:
        compute_structure(_variant(robot, 4, placement))
    message = str(err.value)
    assert "an elbow offset (a3, a4) or the wrist offset (a6) is zero" in message
    assert "axes 3, 4, 5 do not meet in one point" in message


def test_seven_axis_arms_have_the_one_solver_type() -> None:
    for name in ("iiwa14", "panda"):
        solver = get_solver(load_robot(name))
        assert solver.nq == 7 and solver.parameter is not None
        with pytest.raises(InputError, match="give redundancy="):
            solver.solve(np.eye(4))


@pytest.mark.parametrize("name", ["iiwa14", "panda"])
def test_urdf_rounding_passes(name: str) -> None:
    """An axis 1.8e-9 rad off (π/2 written 1.570796325) keeps the family."""
    robot = load_robot(name)
    turn = pin.SE3(pin.exp3(np.array([1.8e-9, 0.0, 0.0])), np.zeros(3))
    rounded = _variant(robot, 4, robot.model.jointPlacements[4] * turn)
    structure = compute_structure(rounded)
    assert structure.family == get_structure(robot).family
    assert 1e-9 <= structure.deviation.angle <= 2e-9
    assert structure.residual <= 1e-8  # the idealised chain vs the rounded model
