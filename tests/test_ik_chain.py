"""The compiled chain of the numerical IK against Pinocchio, its reference.

Forward kinematics, LOCAL Jacobian and SE(3) log error of ``_chain_kernel``
equal Pinocchio's to 1e-12 at 10,000 random configurations per robot, for
the robots of the project and for arms with prismatic, unaligned-axis and
continuous joints.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from workbench import DimensionError, InputError, NonFiniteError, Robot, load_robot
from workbench.ik import _chain_kernel as kernel
from workbench.ik import compute_jacobians_local, numeric
from workbench.ik._chain import FULL_POSE, compiled_entry, get_chain

ATOL_EXACT = 1e-12
"""The same quantity computed twice, by Pinocchio and by the compiled chain."""

ATOL_IK = 1e-9
"""Pose error accepted from the solver [m] and [rad]."""

CONFIGURATIONS_PER_ROBOT = 10_000

ROBOT_NAMES = ("puma560", "puma560-kang", "ur5", "panda")


def modified_ur5(folder: Path, kind: str) -> Robot:
    """UR5 variants: 'mixed' (a prismatic elbow, an unaligned wrist axis) or
    'continuous' (a continuous shoulder pan joint, nq = 7, nv = 6)."""
    ur5 = load_robot("ur5")
    text = ur5.description
    if kind == "continuous":
        text = text.replace(
            'name="shoulder_pan_joint" type="revolute"',
            'name="shoulder_pan_joint" type="continuous"',
        )
    else:
        text = text.replace(
            'name="elbow_joint" type="revolute"', 'name="elbow_joint" type="prismatic"'
        )
        head, tail = text.split('name="wrist_2_joint"', 1)
        tail = tail.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0.6 0.8"/>', 1)
        text = head + 'name="wrist_2_joint"' + tail
    path = folder / f"ur5_{kind}.urdf"
    path.write_text(text, encoding="utf-8")
    return load_robot(path, tool_frame=ur5.tool_frame)


@pytest.fixture(scope="module", params=(*ROBOT_NAMES, "mixed", "continuous"))
def robot(request: pytest.FixtureRequest, tmp_path_factory) -> Robot:
    if request.param in ROBOT_NAMES:
        return load_robot(request.param)
    return modified_ur5(tmp_path_factory.mktemp("urdf"), request.param)


def test_modified_models_have_the_joint_kinds_under_test(tmp_path) -> None:
    mixed = modified_ur5(tmp_path, "mixed")
    kinds = [joint.shortname() for joint in mixed.model.joints[1:]]
    assert "JointModelPY" in kinds
    assert "JointModelRevoluteUnaligned" in kinds
    continuous = modified_ur5(tmp_path, "continuous")
    assert (continuous.nq, continuous.nv) == (7, 6)


def test_fk_and_jacobian_equal_pinocchio(robot: Robot) -> None:
    """10,000 random configurations: the pose and LOCAL Jacobian to 1e-12."""
    chain = get_chain(robot)
    rng = np.random.default_rng(0)
    values = chain.low + chain.span * rng.random((CONFIGURATIONS_PER_ROBOT, chain.n))
    configurations = chain.to_configuration(values, chain.mid)
    model, data, frame_id = robot.model, robot.model.createData(), robot.tool_frame_id
    jac = np.empty((6, chain.n))
    worst_pose = worst_jacobian = 0.0
    for value, q in zip(values, configurations, strict=True):
        pose = kernel.chain_kinematics(chain.packed, value, jac)
        pin.computeJointJacobians(model, data, q)
        expected = pin.updateFramePlacement(model, data, frame_id).homogeneous
        expected_jac = pin.getFrameJacobian(
            model, data, frame_id, pin.ReferenceFrame.LOCAL
        )
        worst_pose = max(worst_pose, np.max(np.abs(pose - expected)))
        worst_jacobian = max(worst_jacobian, np.max(np.abs(jac - expected_jac)))
    assert worst_pose <= ATOL_EXACT
    assert worst_jacobian <= ATOL_EXACT


def test_batch_jacobians_equal_pinocchios_local_jacobian(robot: Robot) -> None:
    """compute_jacobians_local: Robot.jacobian_local of each configuration (N, 6, nv).

    Including the continuous joint's (cos, sin) coordinates (nq = 7, nv = 6)
    and the Panda's fingers, off the path to the tool (zero columns).
    """
    chain = get_chain(robot)
    rng = np.random.default_rng(4)
    values = chain.low + chain.span * rng.random((200, chain.n))
    q = chain.to_configuration(values, chain.mid)
    batch = compute_jacobians_local(robot, q)
    assert batch.shape == (200, 6, robot.nv)
    expected = np.stack([robot.jacobian_local(qi) for qi in q])
    np.testing.assert_allclose(batch, expected, rtol=0, atol=ATOL_EXACT)
    assert compute_jacobians_local(robot, q[:0]).shape == (0, 6, robot.nv)


def test_batch_jacobians_refuse_bad_input(tmp_path) -> None:
    ur5 = load_robot("ur5")
    with pytest.raises(DimensionError, match="q"):
        compute_jacobians_local(ur5, np.zeros((3, 5)))
    with pytest.raises(DimensionError, match="q"):
        compute_jacobians_local(ur5, np.zeros(6))
    with pytest.raises(NonFiniteError, match="q must be finite"):
        compute_jacobians_local(ur5, np.full((2, 6), np.nan))
    text = ur5.description
    end = text.index("</joint>", text.index('name="wrist_3_joint"'))
    path = tmp_path / "mimic.urdf"
    path.write_text(text[:end] + '<mimic joint="wrist_1_joint"/>' + text[end:])
    mimic = load_robot(path, tool_frame=ur5.tool_frame)
    with pytest.raises(InputError, match="mimic joints"):
        compute_jacobians_local(mimic, np.zeros((1, mimic.nq)))


def test_chain_coordinates_round_trip(robot: Robot) -> None:
    chain = get_chain(robot)
    rng = np.random.default_rng(1)
    values = chain.low + chain.span * rng.random((100, chain.n))
    q = chain.to_configuration(values, chain.mid)
    back = chain.to_chain(q)
    np.testing.assert_allclose(back, values, rtol=0, atol=ATOL_EXACT)


@pytest.mark.parametrize("angle", [0.0, 1e-9, 1e-5, 0.3, 2.0, np.pi - 1e-3, np.pi])
def test_error_is_pinocchios_log6(angle: float) -> None:
    """e = log6(T^-1 M) at rotation angles from 0 to pi (the special cases)."""
    rng = np.random.default_rng(2)
    for _ in range(50):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        offset = pin.SE3(pin.exp3(angle * axis), rng.uniform(-1.0, 1.0, 3))
        target = pin.SE3.Random()
        tool = target * offset
        frames = np.zeros((1, 12))
        frames[0, :9] = tool.rotation.ravel()
        frames[0, 9:] = tool.translation
        e = np.empty(6)
        position = kernel._error(target.homogeneous, frames, e)
        expected = pin.log6(target.actInv(tool)).vector
        if angle == np.pi:  # w and -w are both logarithms: compare exp6(e)
            np.testing.assert_allclose(
                pin.exp6(e).homogeneous,
                target.actInv(tool).homogeneous,
                rtol=0,
                atol=ATOL_EXACT,
            )
        else:  # log3 near pi is ill-conditioned, in Pinocchio as here
            atol = ATOL_EXACT if angle < 3.0 else 1e-7
            np.testing.assert_allclose(e, expected, rtol=0, atol=atol)
        assert position == pytest.approx(np.linalg.norm(offset.translation), abs=1e-12)


def test_numeric_solves_mixed_joint_arm(tmp_path) -> None:
    """Prismatic and unaligned revolute joints: FK targets are reached."""
    robot = modified_ur5(tmp_path, "mixed")
    rng = np.random.default_rng(3)
    for _ in range(20):
        target = robot.fk(rng.uniform(robot.lower, robot.upper))
        result = numeric(robot, target, rng=rng)
        assert result.success
        pose = robot.fk(result.q)
        assert np.linalg.norm(pose.translation - target.translation) <= ATOL_IK
        assert np.linalg.norm(pin.log3(pose.rotation.T @ target.rotation)) <= ATOL_IK
        assert np.all(result.q >= robot.lower)
        assert np.all(result.q <= robot.upper)


def test_unsupported_joint_raises(puma: Robot) -> None:
    """A free-flyer root joint is not a revolute or prismatic joint."""
    model = pin.buildModelFromUrdf(str(puma.urdf_path), pin.JointModelFreeFlyer())
    robot = Robot("floating", model, puma.urdf_path, puma.tool_frame, package_dirs=[])
    with pytest.raises(InputError, match="supports revolute, continuous and prismatic"):
        numeric(robot, robot.fk(pin.neutral(model)))


def test_joints_off_the_tool_path_keep_their_reference(tmp_path) -> None:
    """A tree: the tool on an intermediate link; later joints keep q0's values."""
    ur5 = load_robot("ur5")
    robot = load_robot(ur5.urdf_path, tool_frame="forearm_link")
    rng = np.random.default_rng(4)
    q0 = rng.uniform(robot.lower, robot.upper)
    target = robot.fk(rng.uniform(robot.lower, robot.upper))
    result = numeric(robot, target, q0, rng=rng)
    assert result.success
    chain = get_chain(robot)
    off = np.setdiff1d(np.arange(robot.nq), chain.idx_q)
    assert off.size > 0
    np.testing.assert_array_equal(result.q[off], q0[off])


def test_numeric_calls_the_kernels_compiled_code_with_its_types() -> None:
    """Chain.run skips Numba's dispatcher only for arguments of its one signature."""
    chain = get_chain(load_robot("ur5"))
    packed, q_ref, features, starts = chain.run_inputs
    states = chain.fresh_state.reshape(1, -1).copy()
    args = (packed, np.eye(4), q_ref, states, 0, 0.0, 0, False, features, starts, True,
            FULL_POSE, kernel.PART_POSE)  # fmt: skip
    chain.run(*args)  # the first call compiles (or loads) the kernel
    if len(getattr(kernel.run, "signatures", ())) != 1:  # e.g. NUMBA_DISABLE_JIT
        pytest.skip("kernel.run has not exactly one compiled signature")
    assert chain.run is not kernel.run
    assert compiled_entry(kernel.run, args) is chain.run
    wrong = (
        (packed, np.eye(4, dtype=np.float32), *args[2:]),  # dtype
        (packed, np.asfortranarray(np.eye(4)), *args[2:]),  # layout
        (packed, np.eye(4)[None], *args[2:]),  # dimensions
        args[:-1],  # count
        (*args[:6], 0.5, *args[7:]),  # a float for an int
    )
    for bad in wrong:
        assert compiled_entry(kernel.run, bad) is kernel.run


def test_a_robot_keeps_its_chain_until_its_model_changes() -> None:
    robot = load_robot("ur5")
    chain = get_chain(robot)
    assert get_chain(robot) is chain
    assert chain.robot() is robot
    robot.upper = robot.upper - 0.1  # replaced limits: a new chain
    rebuilt = get_chain(robot)
    assert rebuilt is not chain
    assert get_chain(robot) is rebuilt
