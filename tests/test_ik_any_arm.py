"""Closed-form IK of any OPW or UR-type arm, recognised from its joint axes."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import brentq

from tests.conftest import run_cli as run
from workbench import Robot, load_robot
from workbench.cli import EXIT_BAD_INPUT, EXIT_INFEASIBLE
from workbench.errors import (
    FrameNotFoundError,
    InputError,
    NonFiniteError,
    WorkbenchError,
)
from workbench.ik import (
    BRANCHES,
    STRUCTURE_TOL,
    UR_BRANCHES,
    UnreachableError,
    UnsupportedRobotError,
    _puma_kernel,
    _ur_kernel,
    analytic,
    analytic_batch,
    get_solver,
    get_structure,
    nearest,
)

ATOL_FK = 1e-9  # every branch reproduces the tool pose [m, and rotation entries]
ATOL_SAME_Q = 1e-6  # [rad] the generating q is among the branches
# Next to a singularity IK is ill-conditioned: a pose error eps moves q along
# the null direction of J by ~sqrt(eps) (observed up to 5e-6 rad), more where a
# second singularity is near (observed 3.3e-4 rad at elbow and wrist both near).
ATOL_SAME_Q_SINGULAR = 1e-3
ATOL_INTERPRETED = 1e-12  # [rad] interpreted against compiled kernels (libm, FMA)
DISTINCT = 1e-6  # [rad] branches of a generic pose differ by more than this
N_RANDOM = 10_000
N_SINGULAR = 200
TWO_PI = 2.0 * math.pi

#: Catalog models with a closed form, and their family.
MODELS = {
    "puma560": "opw",
    "puma560-kang": "opw",
    "kuka-kr6-r700": "opw",
    "abb-irb2400": "opw",
    "ur3": "ur",
    "ur5": "ur",
    "ur10": "ur",
}


def plain(robot: Robot, model: pin.Model | None = None, tool: str | None = None):
    """The robot without its DH table: structure read from the joint axes."""
    return Robot(
        f"{robot.name}-axes",
        model or robot.model,
        robot.urdf_path,
        tool or robot.tool_frame,
        package_dirs=[],
    )


@pytest.fixture(scope="module", params=[*MODELS, "puma560-axes", "kuka-axes"])
def arm(request: pytest.FixtureRequest) -> Robot:
    """Every supported model; the ``-axes`` ones have no DH table attached."""
    name = request.param
    if name == "puma560-axes":
        return plain(load_robot("puma560"))
    if name == "kuka-axes":
        return plain(load_robot("kuka-kr6-r700"))
    return load_robot(name)


def wrapped(d: np.ndarray) -> np.ndarray:
    return np.remainder(d + np.pi, TWO_PI) - np.pi


def fk_errors(robot: Robot, qs: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """Max |FK(q) - target| per configuration, Pinocchio's FK."""
    model, data, frame = robot.model, robot.model.createData(), robot.tool_frame_id
    out = np.empty(len(qs))
    for i, (q, target) in enumerate(zip(qs, targets, strict=True)):
        pin.framesForwardKinematics(model, data, q)
        out[i] = np.abs(data.oMf[frame].homogeneous - target).max()
    return out


def check_configurations(robot: Robot, qs: np.ndarray) -> np.ndarray:
    """Every branch of FK(q) reaches it, q is among them; returns (N, 8) q valid."""
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    q_all, valid = analytic_batch(robot, targets)
    assert valid.any(axis=1).all()
    rows = np.nonzero(valid)
    errors = fk_errors(robot, q_all[rows], targets[rows[0]])
    assert errors.max() <= ATOL_FK, errors.max()
    steps = np.abs(wrapped(q_all - qs[:, None, :])).max(axis=2)
    steps[~valid] = np.inf
    assert (steps.min(axis=1) <= ATOL_SAME_Q).all(), steps.min(axis=1).max()
    return q_all, valid


def test_family_is_recognised(arm) -> None:
    family = MODELS.get(arm.name, "opw")
    assert get_solver(arm).branches == (UR_BRANCHES if family == "ur" else BRANCHES)
    structure = get_structure(arm)
    assert structure.family == family
    assert max(structure.deviation.angle, structure.deviation.distance) <= STRUCTURE_TOL
    assert structure.residual <= 1e-12


@pytest.mark.slow
def test_random_configurations(arm) -> None:
    """10,000 configurations within limits: every branch, q among them, 8 distinct."""
    rng = np.random.default_rng(1)
    qs = rng.uniform(arm.lower, arm.upper, size=(N_RANDOM, 6))
    q_all, valid = check_configurations(arm, qs)
    full = valid.all(axis=1)
    assert full.mean() > 0.5  # most poses: all eight branches reach
    gaps = np.abs(wrapped(q_all[full, :, None, :] - q_all[full, None, :, :]))
    gaps = gaps.max(axis=3) + np.eye(8) * 10.0
    generic = gaps.min(axis=(1, 2)) > DISTINCT
    assert generic.mean() > 0.99  # the rest sit next to a singularity


@pytest.mark.parametrize(
    "name", ["puma560", "puma560-kang", "kuka-kr6-r700", "abb-irb2400"]
)
def test_axes_and_dh_table_agree(name: str) -> None:
    """The structure read from the axes gives the DH table's branches and labels."""
    robot = load_robot(name)
    from_axes = plain(robot)
    rng = np.random.default_rng(8)
    for q in rng.uniform(robot.lower, robot.upper, size=(200, 6)):
        target = robot.fk(q)
        with_table, axes = analytic(robot, target), analytic(from_axes, target)
        assert [s.branch for s in axes] == [s.branch for s in with_table]
        np.testing.assert_allclose(
            [s.q for s in axes], [s.q for s in with_table], rtol=0, atol=1e-9
        )


def test_batch_equals_single(arm) -> None:
    rng = np.random.default_rng(2)
    qs = rng.uniform(arm.lower, arm.upper, size=(100, 6))
    targets = np.array([arm.fk(q).homogeneous for q in qs])
    q_all, valid = analytic_batch(arm, targets)
    for target, batch, ok in zip(targets, q_all, valid, strict=True):
        solutions = analytic(arm, target)
        assert [s.index for s in solutions] == list(np.nonzero(ok)[0])
        single = np.array([s.q for s in solutions])
        np.testing.assert_allclose(batch[ok], single, rtol=0, atol=1e-9)


@pytest.mark.slow
def test_vectorised_batch_stage_equals_angle_arguments(arm) -> None:
    """The batch's vectorised first stage gives angle_arguments' values, bitwise.

    On random poses, wrist-singular ones (exactly and 1e-12 off: the scalar
    fallback), shoulder-singular ones, and unreachable ones (out of reach, in
    the cylinder of the shoulder offset); angle_arguments runs as Python, whose
    float arithmetic is the compiled code's (no library call on these paths).
    """
    rng = np.random.default_rng(7)
    qs = list(rng.uniform(arm.lower, arm.upper, size=(200, 6)))
    qs += [_dh_angle_config(arm, rng, 4, theta) for theta in (0.0, 1e-12, -1e-12)]
    qs += [q for q in (_shoulder_config(arm, rng) for _ in range(3)) if q is not None]
    targets = np.array([arm.fk(q).homogeneous for q in qs])
    targets = np.concatenate([targets, targets[:2], targets[:2]])
    targets[-4:-2, :3, 3] *= 10.0  # out of reach
    targets[-2:, :2, 3] *= 1e-3  # near the base axis
    closed_form = get_solver(arm)
    solver = _ur_kernel if closed_form.family.name == "ur" else _puma_kernel
    geometry = closed_form.geometry
    n, slots = len(targets), solver.N_ANGLES
    y, x = np.full((n, slots), np.nan), np.full((n, slots), np.nan)
    status, exact = np.empty(n, np.int8), np.empty(n, np.int64)
    odd = np.empty(n, np.uint8)
    flat = (targets.reshape(-1), y.reshape(-1), x.reshape(-1))
    flagged = solver.batch_arguments(geometry, *flat, status, exact, odd, True)
    assert flagged == np.count_nonzero(odd) >= 3
    assert solver.batch_fallback(geometry, targets, y, x, status, exact, odd) < 0
    geo = np.asarray(geometry).view(np.recarray)[0]
    scalar = solver.angle_arguments.py_func
    for i, target in enumerate(targets):
        ys, xs = np.full(slots, np.nan), np.full(slots, np.nan)
        code, mask = scalar(geo, target, np.empty(0), ys, xs, np.empty((4, 4)))
        assert status[i] == code, i
        if code != solver.OK:
            continue
        assert exact[i] == mask, i
        used = [slot for slot in range(slots) if not mask >> slot & 1]
        np.testing.assert_array_equal(y[i], ys, err_msg=f"pose {i}")
        np.testing.assert_array_equal(x[i, used], xs[used], err_msg=f"pose {i}")
    assert (status == solver.OK).sum() >= 200
    assert (status[-4:-2] == solver.OUT_OF_REACH).all()
    if get_structure(arm).family == "ur":  # offset D: a cylinder of no reach
        assert (status[-2:] == solver.IN_CYLINDER).all()
    # and the batch assembly then gives assemble's joint values
    angles = np.arctan2(y, np.where(np.isnan(x), 1.0, x))
    q, valid = np.empty((n, 8, 6)), np.empty((n, 8), bool)
    solver.batch_assemble(geometry, angles, y, status, exact, q, valid)
    for i in np.flatnonzero(status == solver.OK):
        mask = int(exact[i])
        exact_slots = [bool(mask >> slot & 1) for slot in range(slots)]
        single, none = np.empty((8, 6)), np.empty(0, bool)
        theta = np.where(exact_slots, y[i], angles[i])
        solver.assemble.py_func(geo, theta, np.empty(0), single, none, mask)
        np.testing.assert_array_equal(q[i], single, err_msg=f"pose {i}")
        np.testing.assert_array_equal(valid[i], ~np.isnan(single[:, 0]))
    assert (
        np.isnan(q[status != solver.OK]).all() and not valid[status != solver.OK].any()
    )


def _dh_angle_config(arm: Robot, rng, joint: int, theta: float) -> np.ndarray:
    """Random q within limits with DH angle ``theta`` at ``joint``."""
    structure = get_structure(arm)
    sign = structure.joint_sign[joint]
    offset = structure.table.joints[joint].theta_offset
    q = rng.uniform(arm.lower, arm.upper)
    value = sign * (theta - offset)
    for turns in (0, 1, -1, 2, -2):
        candidate = value + turns * TWO_PI
        if arm.lower[joint] <= candidate <= arm.upper[joint]:
            q[joint] = candidate
            return q
    q[joint] = wrapped(value)
    return q


def _elbow_theta3(arm: Robot) -> list[float]:
    """DH θ3 of the stretched and folded elbow."""
    joints = get_structure(arm).table.joints
    if get_structure(arm).family == "ur":
        return [0.0, math.pi]
    beta = math.atan2(-math.copysign(1.0, joints[2].alpha) * joints[3].d, joints[2].a)
    return [-beta, math.pi - beta]


def _shoulder_config(arm: Robot, rng) -> np.ndarray | None:
    """q within limits with the wrist point on the shoulder-singular surface."""
    structure = get_structure(arm)
    table, signs = structure.table, np.asarray(structure.joint_sign)
    q = rng.uniform(arm.lower, arm.upper)
    which = 4 if structure.family == "ur" else 3  # the wrist point: origin of frame

    def x1(q2: float) -> float:
        q[1] = q2
        frames = table.frame_transforms(q * signs)
        point = frames[which + 1][:3, 3]
        return float(frames[1][:3, 0] @ (point - frames[1][:3, 3])) + table.joints[0].a

    grid = np.linspace(arm.lower[1], arm.upper[1], 60)
    values = [x1(g) for g in grid]
    for a, b, fa, fb in zip(grid, grid[1:], values, values[1:], strict=False):
        if fa * fb < 0.0:
            q[1] = brentq(x1, a, b, xtol=1e-15)
            return q
    return None


@pytest.mark.slow
def test_near_every_singularity(arm) -> None:
    """Wrist, elbow and shoulder singular (and 1e-12..1e-6 off): every branch."""
    rng = np.random.default_rng(3)
    configurations = []
    for delta in (0.0, 1e-12, 1e-8, 1e-6):
        for base in (0.0, math.pi):
            configurations += [
                _dh_angle_config(arm, rng, 4, base + delta) for _ in range(N_SINGULAR)
            ]
        for theta3 in _elbow_theta3(arm):
            configurations += [
                _dh_angle_config(arm, rng, 2, theta3 + delta)
                for _ in range(N_SINGULAR // 4)
            ]
    shoulder = [_shoulder_config(arm, rng) for _ in range(N_SINGULAR // 4)]
    shoulder = [q for q in shoulder if q is not None]
    assert len(shoulder) >= 10
    for q in configurations + shoulder:
        target = arm.fk(q).homogeneous
        solutions = analytic(arm, target)
        errors = fk_errors(arm, [s.q for s in solutions], [target] * len(solutions))
        assert errors.max() <= ATOL_FK
        steps = [np.abs(wrapped(s.q - q)).max() for s in solutions]
        if min(steps) > ATOL_SAME_Q_SINGULAR:  # q is another family member
            assert any(s.wrist_singular or s.shoulder_singular for s in solutions)


def test_wrist_singularity_is_flagged(arm) -> None:
    rng = np.random.default_rng(4)
    q = _dh_angle_config(arm, rng, 4, 0.0)
    solutions = analytic(arm, arm.fk(q))
    assert any(s.wrist_singular for s in solutions)


def test_continuity_no_wrist_flip(arm) -> None:
    """A path through the wrist singularity: nearest() never jumps by π or 2π."""
    rng = np.random.default_rng(5)
    structure = get_structure(arm)
    sign, offset = structure.joint_sign[2], structure.table.joints[2].theta_offset
    while True:  # away from the elbow singularity all along
        start = _dh_angle_config(arm, rng, 4, 0.0)
        inward = np.where(start > (arm.lower + arm.upper) / 2.0, -0.2, 0.2)
        path = start + np.linspace(0.0, 1.0, 301)[:, None] * inward
        path[:, 4] = start[4] + np.linspace(0.3, -0.3, 301)  # through sin θ5 = 0
        theta3 = sign * path[:, 2] + offset
        if all(
            np.abs(np.sin(theta3 - folded)).min() > 0.3 for folded in _elbow_theta3(arm)
        ):
            break
    q_prev = path[0]
    for q in path[1:]:
        best = nearest(analytic(arm, arm.fk(q), q_previous=q_prev), q_prev)
        assert np.abs(best.q - q_prev).max() < 0.05
        q_prev = best.q
    np.testing.assert_allclose(q_prev, path[-1], rtol=0, atol=ATOL_SAME_Q)


# -- structure recognition ------------------------------------------------------------


def _rotated(robot: Robot, joint: int, angle: float) -> Robot:
    """The robot with joint ``joint`` (1-based) placement turned about x."""
    model = pin.Model(robot.model)
    turn = pin.SE3(pin.exp3(np.array([angle, 0.3 * angle, 0.0])), np.zeros(3))
    model.jointPlacements[joint] = model.jointPlacements[joint] * turn
    return plain(robot, model)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["puma560", "ur5", "abb-irb2400"])
def test_urdf_rounding_passes_and_2e2_is_refused(name: str) -> None:
    robot = load_robot(name)
    rounded = _rotated(robot, 3, 1.8e-9)  # alpha written 1.570796325
    structure = get_structure(rounded)
    assert structure.family == MODELS[name]
    assert max(structure.deviation.angle, structure.deviation.distance) <= 2e-9
    rng = np.random.default_rng(6)
    for q in rng.uniform(robot.lower, robot.upper, size=(50, 6)):
        target = rounded.fk(q).homogeneous
        qs = [s.q for s in analytic(rounded, target)]
        errors = fk_errors(rounded, qs, [target] * len(qs))
        assert errors.max() <= 1e-8  # the model itself is 1.8e-9 rad off
    with pytest.raises(UnsupportedRobotError, match=r"axes 2 and 3 are not") as err:
        get_structure(_rotated(robot, 3, 2e-2))
    assert re.search(r"not parallel \(off by 0\.02\d* rad\)", str(err.value))


def test_no_family_is_refused_naming_the_axes() -> None:
    robot = load_robot("generic6r")
    for candidate in (robot, plain(robot)):
        with pytest.raises(UnsupportedRobotError) as err:
            analytic(candidate, np.eye(4))
        message = str(err.value)
        assert "not OPW" in message and "not UR" in message
        assert "axes 2 and 3 are not parallel (off by 0.524 rad)" in message
        assert "axes 5 and 6 do not meet (off by 0.03 m)" in message
    with pytest.raises(UnsupportedRobotError, match="9 joint variables"):
        get_structure(load_robot("kinova"))


# -- any tool frame -------------------------------------------------------------------


def _with_tcp(robot: Robot, placement: pin.SE3) -> Robot:
    model = pin.Model(robot.model)
    parent = model.frames[robot.tool_frame_id]
    model.addFrame(
        pin.Frame("tcp", 6, parent.placement * placement, pin.FrameType.OP_FRAME)
    )
    return plain(robot, model, "tcp")


@pytest.mark.parametrize("name", ["puma560", "ur5", "kuka-kr6-r700"])
def test_any_tool_frame(name: str) -> None:
    """A gripper TCP (offset and turned) and another URDF frame: target = tool."""
    rng = np.random.default_rng(7)
    robot = load_robot(name)
    tcp = pin.SE3(pin.exp3(np.array([0.4, -0.2, 1.1])), np.array([0.02, -0.03, 0.15]))
    other = {"puma560": "frame6", "ur5": "ee_link", "kuka-kr6-r700": "link6"}[name]
    for tooled in (_with_tcp(robot, tcp), load_robot(name, tool_frame=other)):
        qs = rng.uniform(robot.lower, robot.upper, size=(500, 6))
        check_configurations(tooled, qs)


# -- errors and the command line -----------------------------------------------------


def test_bad_input_and_unreachable() -> None:
    robot = load_robot("ur5")
    bad = np.eye(4)
    bad[0, 0] = 2.0
    with pytest.raises(InputError, match=r"rigid|orthonormal"):
        analytic(robot, bad)
    with pytest.raises(InputError, match="rigid"):
        analytic_batch(robot, bad[None])
    with pytest.raises(NonFiniteError):
        analytic(robot, np.full((4, 4), np.nan))
    with pytest.raises(FrameNotFoundError, match="nope"):
        load_robot("ur5", tool_frame="nope")
    far = np.eye(4)
    far[0, 3] = 3.0
    with pytest.raises(UnreachableError, match="out of reach") as err:
        analytic(robot, far)
    assert err.value.kind == "reach"
    near = np.eye(4)
    near[2, 3] = 0.3  # wrist point on the base axis: inside the cylinder |D|
    with pytest.raises(UnreachableError, match="cylinder"):
        analytic(robot, near)
    q, valid = analytic_batch(robot, far[None])
    assert not valid.any() and np.isnan(q).all()


def test_cli_solver_is_named(capsys) -> None:
    robot = load_robot("ur5")
    q = np.array([0.3, -1.2, 1.4, -0.5, 1.1, 0.7])
    numbers = [repr(x) for x in robot.fk(q).homogeneous.ravel().tolist()]
    code, out, _ = run(
        capsys, "ik", "--robot", "ur5", "--matrix", *numbers, "--all", "--json"
    )
    result = json.loads(out)
    assert code == 0 and result["solver"] == "closed-form"
    assert [row["branch"] for row in result["solutions"]] == list(UR_BRANCHES)
    assert max(row["residual"] for row in result["solutions"]) <= ATOL_FK
    generic = load_robot("generic6r")
    numbers = [repr(x) for x in generic.fk(q).homogeneous.ravel().tolist()]
    code, out, _ = run(
        capsys, "ik", "--robot", "generic6r", "--matrix", *numbers, "--all", "--json"
    )
    result = json.loads(out)
    assert code == 0 and result["solver"] == "numeric"
    assert "axes 2 and 3 are not parallel" in result["solver_note"]
    assert [row["branch"] for row in result["solutions"]] == ["numeric"]
    code, _, err = run(
        capsys, "ik", "--robot", "generic6r", "--matrix", *numbers, "--all"
    )
    assert code == 0 and "no closed form" in err
    code, _, err = run(
        capsys, "ik", "--robot", "ur5", "--tool-frame", "nope", "--matrix", *numbers
    )
    assert code == EXIT_BAD_INPUT and "nope" in err
    far = np.eye(4)
    far[0, 3] = 3.0
    code, _, err = run(
        capsys, "ik", "--robot", "ur5", "--matrix", *map(repr, far.ravel().tolist())
    )
    assert code == EXIT_INFEASIBLE and "out of reach" in err


# -- analytic singularities ------------------------------------------------------------


def test_det_j_is_the_product_of_the_factors(arm) -> None:
    """det J = K · shoulder · elbow · wrist to 1e-9 relative, Pinocchio's J."""
    from workbench.singularities.conditions import (
        compute_det_j_analytic,
        get_factorisation,
    )

    rng = np.random.default_rng(9)
    qs = rng.uniform(arm.lower, arm.upper, size=(N_RANDOM // 10, 6))
    analytic_det = compute_det_j_analytic(arm, qs)
    pinocchio_det = np.array([np.linalg.det(arm.jacobian(q)) for q in qs])
    scale = abs(get_factorisation(arm).constant) * max(abs(arm.fk(qs[0]).translation))
    np.testing.assert_allclose(
        analytic_det, pinocchio_det, rtol=1e-9, atol=1e-12 * scale
    )


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ur5", "kuka-kr6-r700"])
def test_round_trip_property(name: str) -> None:
    """Hypothesis: q -> FK -> every branch reaches the pose, q among them."""
    from hypothesis import given, settings
    from hypothesis import strategies as st

    robot = load_robot(name)
    unit = st.floats(0.0, 1.0, allow_nan=False)

    @settings(max_examples=300)
    @given(st.lists(unit, min_size=6, max_size=6))
    def round_trip(u: list[float]) -> None:
        q = robot.lower + np.asarray(u) * (robot.upper - robot.lower)
        target = robot.fk(q).homogeneous
        solutions = analytic(robot, target)
        qs = [s.q for s in solutions]
        assert fk_errors(robot, qs, [target] * len(qs)).max() <= ATOL_FK
        steps = [np.abs(wrapped(x - q)).max() for x in qs]
        assert min(steps) <= ATOL_SAME_Q_SINGULAR or any(
            s.wrist_singular or s.shoulder_singular for s in solutions
        )

    round_trip()


# -- the interpreted kernels (one-shot commands) ---------------------------------------


def solution_rows(robot: Robot, targets: np.ndarray) -> np.ndarray:
    """One row per branch found: target, branch index, q, and the three flags."""
    return np.array(
        [
            [i, s.index, *s.q, s.within_limits, s.wrist_singular, s.shoulder_singular]
            for i, target in enumerate(targets)
            for s in analytic(robot, target)
        ]
    )


def model_named(name: str) -> Robot:
    """A catalog model; with the suffix ``-axes``, without its DH table."""
    base = name.removesuffix("-axes")
    return load_robot(base) if base == name else plain(load_robot(base))


def error_lines(robot: Robot) -> list[str]:
    """``"<error class> <message>"`` of a pose out of reach and of a non-rigid one."""
    lines = []
    for kind, pose in (("reach", np.eye(4)), ("rigid", 2.0 * np.eye(4))):
        pose[0, 3] = 3.0 if kind == "reach" else 0.0
        with pytest.raises(WorkbenchError) as error:
            analytic(robot, pose)
        lines.append(f"{type(error.value).__name__} {error.value}")
    return lines


_INTERPRETED_SCRIPT = """
import sys
import numpy as np
from workbench import _compiled
from workbench.ik import _puma_kernel, _ur_kernel
from tests.test_ik_any_arm import error_lines, model_named, solution_rows

data = np.load(sys.argv[1])
with _compiled.interpreted():
    results = {name: solution_rows(model_named(name), data[name]) for name in data}
    print("\\n".join(error_lines(model_named("ur5"))))
compiled = _puma_kernel.solve_pose.signatures + _ur_kernel.solve_pose.signatures
assert not compiled, compiled  # nothing was compiled: the Python source ran
np.savez(sys.argv[2], **results)
"""


@pytest.mark.slow
@pytest.mark.subprocess
def test_interpreted_kernels_equal_the_compiled_ones(tmp_path) -> None:
    """``_compiled.interpreted`` (``workbench ik``) gives the compiled answers.

    Random and singular configurations of each family, with and without a DH
    table, in a fresh process where nothing is compiled; the errors are the same.
    """
    rng = np.random.default_rng(11)
    targets, robots = {}, {}
    for name in ("puma560", "puma560-kang", "kuka-kr6-r700-axes", "ur5"):
        robot = model_named(name)
        qs = [rng.uniform(robot.lower, robot.upper) for _ in range(12)]
        qs += [_dh_angle_config(robot, rng, 4, 0.0) for _ in range(4)]  # wrist
        qs += [_dh_angle_config(robot, rng, 2, t) for t in _elbow_theta3(robot)]
        qs += [q for q in (_shoulder_config(robot, rng),) if q is not None]
        targets[name] = np.array([robot.fk(q).homogeneous for q in qs])
        robots[name] = robot
    np.savez(tmp_path / "targets.npz", **targets)
    script = tmp_path / "interpreted.py"
    script.write_text(_INTERPRETED_SCRIPT)
    arguments = [str(script), str(tmp_path / "targets.npz"), str(tmp_path / "q")]
    done = subprocess.run(
        [sys.executable, *arguments],
        capture_output=True,
        text=True,
        check=False,
        cwd=Path(__file__).parents[1],
    )
    assert done.returncode == 0, done.stderr
    results = np.load(tmp_path / "q.npz")
    for name, robot in robots.items():
        rows = solution_rows(robot, targets[name])
        assert results[name].shape == rows.shape
        np.testing.assert_array_equal(results[name][:, :2], rows[:, :2])  # labels
        np.testing.assert_array_equal(results[name][:, -3:], rows[:, -3:])  # flags
        np.testing.assert_allclose(results[name], rows, rtol=0, atol=ATOL_INTERPRETED)
    assert done.stdout.splitlines() == error_lines(robots["ur5"])
