"""Closed-form IK at its edges: reach boundaries, singular wrists and shoulders.

Every pose here is the FK of a configuration, so "out of reach" is always
false: each must be reached, by branches that reproduce it, one of which is
the configuration (up to the one-parameter family of a singular wrist or a
shoulder on the base axis). Configurations come from
``benchmarks/bench_ik_agreement.py`` (stretched and folded elbows, θ5 at 0 and
π, both, the wrist centre on the shoulder-singular surface; each at the edge
and 1e-12 … 1e-4 from it), 10⁴ per family and model through
``analytic_batch``, a subset through ``analytic``. Rounded URDFs (nonzero
joint-origin numbers moved by 1e-9, as a file with nine decimals) and
perturbed ones (zeros moved too: of the family only up to 1e-9) are refined
on their own chain: residuals ≤ 1e-12, and a pose they do not reach is refused
as ``kind="model"``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from benchmarks.bench_ik_agreement import (
    EDGE_FAMILIES,
    edge_configurations,
    fk_residuals,
    rounded_urdf,
)
from workbench import Robot, load_robot
from workbench.ik import (
    WRIST_SINGULAR_TOL,
    UnreachableError,
    analytic,
    analytic_batch,
    get_solver,
    get_structure,
)
from workbench.ik._refine_kernel import (
    EXACT_STRUCTURE_TOL,
    POSITION_TOL,
    ROTATION_TOL,
    refinement_chain,
)
from workbench.ik.structure import KinematicStructure

MODELS = ("puma560", "puma560-kang", "kuka-kr6-r700", "abb-irb2400", "ur5", "ur10")
N_EDGE = 10_000  # configurations per family and model
N_SINGLE = 200  # of them solved one by one too
ATOL_FK = 1e-9  # [m, rad] clean models: a singular wrist's split costs ≤ π·1e-10
ATOL_Q = 1e-6  # [rad] the configuration is among the branches
# At an edge IK is ill-conditioned: a pose rounding error eps moves q by
# ~sqrt(eps) along the fold of an elbow, and that error divided by sin θ5 when
# the wrist is near singular too (observed up to 1.8e-5 rad, tests/test_ik_any_arm
# saw 3.3e-4): all within ATOL_Q_EDGE, nearly all within ATOL_Q.
ATOL_Q_EDGE = 1e-3
FEW = 0.01  # fraction of edge configurations allowed beyond ATOL_Q
ATOL_BATCH = 1e-9  # [rad] analytic_batch against analytic (the atan2's last bits)
N_MODEL = 2_000  # configurations per family of a rounded or perturbed model
TWO_PI = 2.0 * math.pi

_ROBOTS: dict[str, Robot] = {}


def robot_named(name: str) -> Robot:
    """Catalog robots, loaded once per module."""
    if name not in _ROBOTS:
        _ROBOTS[name] = load_robot(name)
    return _ROBOTS[name]


@pytest.fixture(scope="module")
def rounded(tmp_path_factory: pytest.TempPathFactory):
    """Rounded (or, ``zeros=True``, perturbed) copies of catalog URDFs."""
    folder = tmp_path_factory.mktemp("rounded")
    cache: dict[tuple[str, bool], Robot] = {}

    def get(name: str, zeros: bool = False) -> Robot:
        if (name, zeros) not in cache:
            cache[name, zeros] = rounded_urdf(name, Path(folder), zeros=zeros)
        return cache[name, zeros]

    return get


def wrapped(d: np.ndarray) -> np.ndarray:
    return np.remainder(d + np.pi, TWO_PI) - np.pi


def compared_joints(robot: Robot, family: str) -> list[int]:
    """Joints that must match the configuration: all but a singular family's.

    A singular wrist frees θ4 and θ6 (OPW), θ6 and with it frame 3, so θ2, θ3,
    θ4 (UR); a wrist centre on the base axis of an arm without shoulder offset
    frees θ1 and with it θ4, θ5, θ6; the folded PUMA's wrist centre is 0.5 mm
    from axis 2, so θ2 (and the wrist) are known only to rounding / 0.5 mm.
    """
    structure = get_structure(robot)
    if "wrist" in family:
        return [0, 4] if structure.family == "ur" else [0, 1, 2, 4]
    joints = structure.table.joints
    offset = joints[1].d + joints[2].d
    offset += joints[3].d if structure.family == "ur" else 0.0
    if family == "shoulder" and offset == 0.0:
        return [1, 2]
    if family == "folded" and _folds_onto_axis_2(structure):
        return [0, 2]
    return list(range(6))


def _folds_onto_axis_2(structure: KinematicStructure) -> bool:
    """Whether the folded elbow puts the wrist centre within 1 % of axis 2."""
    if structure.family == "ur":
        return False
    joints = structure.table.joints
    forearm = math.hypot(joints[2].a, joints[3].d)
    return abs(abs(joints[1].a) - forearm) < 0.01 * (abs(joints[1].a) + forearm)


def check_edge_family(robot: Robot, family: str, seed: int, fk_tol: float) -> None:
    """Each pose of the family reached, exactly; its configuration is a branch."""
    rng = np.random.default_rng(seed)
    qs = edge_configurations(robot, family, N_EDGE, rng)
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    q_all, valid = analytic_batch(robot, targets)
    unreached = np.flatnonzero(~valid.any(axis=1))
    assert unreached.size == 0, (unreached.size, qs[unreached[:3]])
    rows = np.nonzero(valid)
    residuals = fk_residuals(robot, q_all[rows], targets[rows[0]])
    assert residuals.max() <= fk_tol, residuals.max(axis=0)
    joints = compared_joints(robot, family)
    steps = np.abs(wrapped(q_all - qs[:, None, :]))[..., joints].max(axis=2)
    steps[~valid] = np.inf
    nearest = steps.min(axis=1)
    assert nearest.max() <= ATOL_Q_EDGE, nearest.max()
    assert (nearest > ATOL_Q).mean() <= FEW, (nearest > ATOL_Q).mean()
    for i in range(0, N_EDGE, N_EDGE // N_SINGLE):
        solutions = analytic(robot, targets[i])
        assert [s.index for s in solutions] == list(np.flatnonzero(valid[i]))
        single = np.array([s.q for s in solutions])
        np.testing.assert_allclose(
            wrapped(single - q_all[i][valid[i]]), 0.0, rtol=0, atol=ATOL_BATCH
        )


@pytest.mark.slow
@pytest.mark.parametrize("family", EDGE_FAMILIES)
@pytest.mark.parametrize("name", MODELS)
def test_edge_poses_are_reached(name: str, family: str) -> None:
    """10⁴ configurations per family: 0 false "out of reach", the q among them."""
    robot = robot_named(name)
    check_edge_family(robot, family, EDGE_FAMILIES.index(family), ATOL_FK)


def test_stretched_ur5_with_wrist_nearly_singular() -> None:
    """The reported pose: elbow straight and θ5 = −1e-10 is reached, exactly."""
    robot = robot_named("ur5")
    q = np.array([-1.0, 1.0, 0.0, -1.25, -1e-10, 0.0])
    target = robot.fk(q).homogeneous
    solutions = analytic(robot, target)
    q_all = np.array([s.q for s in solutions])
    residuals = fk_residuals(robot, q_all, [target] * len(q_all))
    assert residuals.max() <= 1e-13
    assert min(abs(wrapped(s.q[[0, 4]] - q[[0, 4]])).max() for s in solutions) <= 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ur5", "ur10"])
def test_ur_frame3_turned_into_reach_costs_no_accuracy(name: str) -> None:
    """θ5 in 1e-10 … 1e-8 (not singular) next to the stretched elbow: ≤ 1e-13."""
    robot = robot_named(name)
    rng = np.random.default_rng(9)
    qs = rng.uniform(robot.lower, robot.upper, size=(N_EDGE, 6))
    qs[:, 2] = rng.choice((-1.0, 1.0), N_EDGE) * 10.0 ** rng.uniform(-12, -4, N_EDGE)
    sign = rng.choice((-1.0, 1.0), N_EDGE)
    qs[:, 4] = sign * 10.0 ** rng.uniform(math.log10(WRIST_SINGULAR_TOL) + 0.1, -8)
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    q_all, valid = analytic_batch(robot, targets)
    assert valid.any(axis=1).all()
    rows = np.nonzero(valid)
    assert fk_residuals(robot, q_all[rows], targets[rows[0]]).max() <= 1e-13


# -- models that are of their family only up to rounding --------------------------

#: Rounded (zeros False) and perturbed (zeros True) models of the tests.
NEAR_MODELS = (("kuka-kr6-r700", False), ("puma560", False), ("ur5", True))

#: Largest fraction of edge poses of a near model that may be refused (as
#: ``kind="model"``): where the idealised arm has a one-parameter family and
#: the model's member is fixed by its 1e-9 deviations, the valley search
#: (``_refine_kernel``) may miss one (measured with bench_ik_agreement.py on
#: 10⁴ poses per family: 2 on the perturbed KUKA with the elbow stretched and
#: the wrist singular, none elsewhere; this bound is a margin for them). All
#: other families: none.
REFUSED = {("ur5", "stretched+wrist"): 0.001}


@pytest.mark.slow
@pytest.mark.parametrize(("name", "zeros"), NEAR_MODELS)
def test_near_model_is_refined_to_1e_12(name: str, zeros: bool, rounded) -> None:
    """Random poses: every branch within 1e-12 m and 1e-12 rad, q among them."""
    robot = rounded(name, zeros)
    structure = get_structure(robot)
    assert structure.residual > 100.0 * POSITION_TOL  # refinement is needed
    assert refinement_chain(robot) is not None
    rng = np.random.default_rng(10)
    qs = rng.uniform(robot.lower, robot.upper, size=(N_EDGE, 6))
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    q_all, valid = analytic_batch(robot, targets)
    assert valid.any(axis=1).all()
    rows = np.nonzero(valid)
    residuals = fk_residuals(robot, q_all[rows], targets[rows[0]])
    assert residuals[:, 0].max() <= POSITION_TOL
    assert residuals[:, 1].max() <= ROTATION_TOL
    steps = np.abs(wrapped(q_all - qs[:, None, :])).max(axis=2)
    steps[~valid] = np.inf
    assert (steps.min(axis=1) > ATOL_Q).mean() <= FEW
    for target, ok in zip(targets[:N_SINGLE], valid, strict=False):
        solutions = analytic(robot, target)
        assert [s.index for s in solutions] == list(np.flatnonzero(ok))
        q = np.array([s.q for s in solutions])
        residuals = fk_residuals(robot, q, [target] * len(q))
        assert residuals[:, 0].max() <= POSITION_TOL
        assert residuals[:, 1].max() <= ROTATION_TOL


@pytest.mark.slow
@pytest.mark.parametrize("family", EDGE_FAMILIES)
@pytest.mark.parametrize(("name", "zeros"), NEAR_MODELS)
def test_near_model_edges(name: str, zeros: bool, family: str, rounded) -> None:
    """Edge poses of near models: reached to 1e-12, or refused as "model".

    Only where :data:`REFUSED` allows, and then with ``kind="model"``; no
    branch is ever returned with a larger residual. (The configuration is not
    compared: next to an edge the pose fixes it only to ~√(1e-9) of the
    model's deviation, more with a singular wrist.)
    """
    robot = rounded(name, zeros)
    rng = np.random.default_rng(20 + EDGE_FAMILIES.index(family))
    qs = edge_configurations(robot, family, N_MODEL, rng)
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    q_all, valid = analytic_batch(robot, targets)
    refused = np.flatnonzero(~valid.any(axis=1))
    assert refused.size <= REFUSED.get((name, family), 0.0) * N_MODEL, refused.size
    rows = np.nonzero(valid)
    residuals = fk_residuals(robot, q_all[rows], targets[rows[0]])
    assert residuals[:, 0].max() <= POSITION_TOL
    assert residuals[:, 1].max() <= ROTATION_TOL
    for i in refused[:5]:  # (one by one, the last bits may differ: reached)
        try:
            q_single = np.array([s.q for s in analytic(robot, targets[i])])
        except UnreachableError as err:
            assert err.kind == "model", err
            continue
        residuals = fk_residuals(robot, q_single, [targets[i]] * len(q_single))
        assert residuals.max() <= POSITION_TOL


def test_near_model_reach_boundary(rounded) -> None:
    """Beyond the model's reach but within the idealised slack: kind "model"."""
    robot = rounded("ur5", True)
    q = np.array([-1.0, 1.0, 0.0, -1.25, 0.7, 0.3])  # elbow stretched
    target = robot.fk(q).homogeneous
    assert len(analytic(robot, target)) >= 1
    # the whole pose moved away from axis 2, in the arm's plane: frame 3 (on
    # axis 4) too, beyond the stretched elbow, within the idealised slack
    model, data = robot.model, robot.model.createData()
    jacobian = pin.computeJointJacobians(model, data, q)
    axis2 = jacobian[3:, 1]
    outward = data.oMi[4].translation - data.oMi[2].translation
    outward -= axis2 * (axis2 @ outward)
    pushed = target.copy()
    step = 5.0 * get_structure(robot).residual
    pushed[:3, 3] += step * outward / np.linalg.norm(outward)
    with pytest.raises(UnreachableError, match="own model") as err:
        analytic(robot, pushed)
    assert err.value.kind == "model"
    _, valid = analytic_batch(robot, pushed[None])
    assert not valid.any()
    far = target.copy()
    far[:3, 3] *= 10.0
    with pytest.raises(UnreachableError, match="reach is") as err:
        analytic(robot, far)
    assert err.value.kind == "reach"


@pytest.mark.parametrize("name", MODELS)
def test_exact_models_are_not_refined(name: str, rounded) -> None:
    """Catalog models, and rounded UR URDFs, fit their family to rounding."""
    for robot in (robot_named(name), rounded("ur5")):
        assert get_structure(robot).residual <= EXACT_STRUCTURE_TOL
        assert refinement_chain(robot) is None
    assert get_solver(robot_named(name)).family.name in ("opw", "ur")
