"""Degenerate directions and loci of every OPW and UR-type model, against Pinocchio."""

from __future__ import annotations

import math

import numpy as np
import pytest

from workbench import InputError, Robot, load_robot
from workbench.singularities.conditions import (
    SINGULARITY_KINDS,
    NotPumaTypeError,
    classify_configuration,
    compute_conditions,
    get_factorisation,
)
from workbench.singularities.directions import (
    compute_degenerate_direction,
    compute_joint_axes,
    compute_wrist_point,
)
from workbench.singularities.loci import (
    compute_example_configurations,
    get_elbow_singular_theta3,
    solve_shoulder_theta2,
)

MODELS = (
    "puma560",
    "puma560-kang",
    "kuka-kr6-r700",
    "abb-irb2400",
    "ur3",
    "ur5",
    "ur10",
)
N_ON_LOCUS = 6  # random configurations per model and kind
ATOL_NULL = 1e-9  # ||u^T J||, ||J v||, sigma_min on a locus (J entries are O(1) m)
ATOL_EXACT = 1e-12  # the same quantity computed twice; lines meeting [m]
ATOL_SVD = 1e-7  # u against the SVD's left singular vector, up to sign
SEPARATED = 1e-3  # second smallest singular value above which that vector is unique


@pytest.fixture(scope="module", params=MODELS)
def arm(request: pytest.FixtureRequest) -> Robot:
    return load_robot(request.param)


def _on_locus(arm: Robot, kind: str, rng: np.random.Generator) -> np.ndarray:
    """A random configuration exactly on one locus (joint limits ignored)."""
    fac = get_factorisation(arm)
    q = rng.uniform(-math.pi, math.pi, 6)
    if kind == "wrist":
        theta5 = rng.choice([0.0, math.pi])
        q[4] = fac.joint_sign[4] * (theta5 - fac.theta_offset[4])
    elif kind == "elbow":
        q[2] = get_elbow_singular_theta3(arm)[rng.integers(2)]
    else:
        roots = solve_shoulder_theta2(arm, q[2], q[3])
        while np.isnan(
            roots[0]
        ):  # ABB: near the retracted elbow the plane is out of reach
            q[2] = rng.uniform(-math.pi, math.pi)
            roots = solve_shoulder_theta2(arm, q[2], q[3])
        q[1] = roots[rng.integers(2)]
    return q


def _shifted_jacobian(arm: Robot, q: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Pinocchio's tool Jacobian with its linear rows moved to ``point``."""
    jac = arm.jacobian(q).copy()
    jac[:3] += np.cross(jac[3:].T, point - arm.fk(q).translation).T
    return jac


def _line_distance(p1, z1, p2, z2) -> float:
    c = np.cross(z1, z2)
    return abs(float((p2 - p1) @ c)) / float(np.linalg.norm(c))


@pytest.mark.parametrize("kind", SINGULARITY_KINDS)
def test_direction_is_the_left_null_vector_of_pinocchios_jacobian(arm, kind) -> None:
    rng = np.random.default_rng(7)
    compared = 0
    for _ in range(N_ON_LOCUS):
        q = _on_locus(arm, kind, rng)
        assert abs(compute_conditions(arm, q).as_dict()[kind]) <= ATOL_EXACT
        d = compute_degenerate_direction(arm, q, kind)
        jac = _shifted_jacobian(arm, q, d.reference_point)
        tool_jac = arm.jacobian(q)
        assert np.linalg.norm(d.direction) == pytest.approx(1.0, abs=ATOL_EXACT)
        assert np.linalg.norm(d.tool_direction) == pytest.approx(1.0, abs=ATOL_EXACT)
        assert np.linalg.norm(d.direction @ jac) <= ATOL_NULL
        assert np.linalg.norm(d.tool_direction @ tool_jac) <= ATOL_NULL
        assert max(d.residual, d.tool_residual) <= ATOL_NULL
        assert np.linalg.norm(tool_jac @ d.self_motion) <= ATOL_NULL
        sv = np.linalg.svd(jac, compute_uv=False)
        assert sv[-1] <= ATOL_NULL
        if sv[-2] > SEPARATED:  # a one-dimensional left null space
            left = np.linalg.svd(jac)[0][:, -1]
            error = min(
                np.linalg.norm(left - d.direction), np.linalg.norm(left + d.direction)
            )
            assert error <= ATOL_SVD
            np.testing.assert_allclose(d.svd_direction, d.direction, atol=ATOL_SVD)
            compared += 1
    assert compared >= N_ON_LOCUS // 2


def test_reference_point_is_where_the_wrist_axes_meet(arm) -> None:
    rng = np.random.default_rng(8)
    family = get_factorisation(arm).family
    meeting = (3, 4, 5) if family == "opw" else (4, 5)
    for q in rng.uniform(-math.pi, math.pi, (5, 6)):
        z, o = compute_joint_axes(arm, q)
        point = compute_wrist_point(arm, q)
        for i in meeting:
            off_axis = np.cross(point - o[i], z[i])
            assert np.linalg.norm(off_axis) <= ATOL_EXACT
    if arm.name.startswith("puma"):  # the tool frame is the wrist centre
        np.testing.assert_allclose(point, arm.fk(q).translation, atol=ATOL_EXACT)


def test_geometric_meaning(arm) -> None:
    """Shoulder: u = [z2; 0]. OPW elbow: a force line meeting axes 1, 2, 3.

    Wrist: the moment part is along ±(z4 × z5), normal to axes 4, 5 and 6.
    """
    rng = np.random.default_rng(9)
    family = get_factorisation(arm).family
    for _ in range(4):
        q = _on_locus(arm, "shoulder", rng)
        z, _ = compute_joint_axes(arm, q)
        d = compute_degenerate_direction(arm, q, "shoulder")
        np.testing.assert_allclose(d.direction, [*z[1], 0, 0, 0], atol=ATOL_EXACT)
        q = _on_locus(arm, "wrist", rng)
        z, _ = compute_joint_axes(arm, q)
        moment = compute_degenerate_direction(arm, q, "wrist").direction[3:]
        assert np.linalg.norm(np.cross(moment, np.cross(z[3], z[4]))) <= ATOL_EXACT
        assert abs(moment @ z[5]) <= ATOL_EXACT
        if family == "opw":
            q = _on_locus(arm, "elbow", rng)
            z, o = compute_joint_axes(arm, q)
            d = compute_degenerate_direction(arm, q, "elbow")
            np.testing.assert_allclose(d.direction[3:], 0.0, atol=ATOL_EXACT)
            for i in range(3):
                gap = _line_distance(d.reference_point, d.direction[:3], o[i], z[i])
                assert gap <= 1e-9


@pytest.mark.parametrize("kind", SINGULARITY_KINDS)
def test_off_the_locus_the_residual_grows_linearly(arm, kind) -> None:
    """Reported, not raised: ‖uᵀJ‖ = |shoulder| for the shoulder, ∝ the sine else."""
    rng = np.random.default_rng(10)
    q = _on_locus(arm, kind, rng)
    joint = {"shoulder": 1, "elbow": 2, "wrist": 4}[kind]
    ratios = []
    for step in (1e-3, 1e-5):
        near = q.copy()
        near[joint] += step
        d = compute_degenerate_direction(arm, near, kind)
        assert d.condition == pytest.approx(
            float(compute_conditions(arm, near).as_dict()[kind]), abs=0
        )
        assert d.residual > 0.0
        if kind == "shoulder":
            assert d.residual == pytest.approx(abs(d.condition), rel=1e-9)
        ratios.append(d.residual / abs(d.condition))
    assert ratios[0] == pytest.approx(ratios[1], rel=1e-2)


def test_examples_lie_on_their_locus_for_any_arm(arm) -> None:
    examples = compute_example_configurations(arm)
    assert set(examples) == {
        "shoulder, elbow up",
        "shoulder, elbow down",
        "elbow, extended",
        "elbow, retracted",
        "wrist",
    }
    for name, q in examples.items():
        kind = name.split(",")[0]
        assert abs(compute_conditions(arm, q).as_dict()[kind]) <= ATOL_EXACT, name
        assert kind in classify_configuration(arm, q), name
        d = compute_degenerate_direction(arm, q, kind)
        assert max(d.sigma_min, d.residual, d.tool_residual) <= ATOL_NULL, name
    elbow = {"elbow, extended", "elbow, retracted"}
    if not arm.name.startswith("puma"):  # PUMA: the retracted elbow is nearly shoulder
        for name in set(examples) - elbow:
            assert len(classify_configuration(arm, examples[name])) == 1, name


def test_loci_of_any_arm(arm) -> None:
    rng = np.random.default_rng(11)
    q = rng.uniform(-math.pi, math.pi, (50, 2, 6))
    q[..., 1] = solve_shoulder_theta2(arm, q[:, 0, 2], q[:, 0, 3])
    q[:, 1, 2:4] = q[:, 0, 2:4]
    reachable = ~np.isnan(q[..., 1])
    assert reachable.mean() > 0.8
    shoulder = compute_conditions(arm, q[reachable]).shoulder
    np.testing.assert_allclose(shoulder, 0.0, atol=ATOL_EXACT)
    q = rng.uniform(-math.pi, math.pi, (2, 6))
    q[:, 2] = get_elbow_singular_theta3(arm)
    np.testing.assert_allclose(compute_conditions(arm, q).elbow, 0.0, atol=ATOL_EXACT)
    ur = get_factorisation(arm).family == "ur"
    reach = []  # distance from axis 2 of the wrist centre (UR: of axis 4)
    for qi in q:
        z, o = compute_joint_axes(arm, qi)
        point = o[3] if ur else compute_wrist_point(arm, qi)
        reach.append(np.linalg.norm(np.cross(point - o[1], z[1])))
    assert reach[0] > reach[1]  # extended, retracted


def test_shoulder_roots_are_nan_where_the_plane_is_out_of_reach() -> None:
    """Retracted elbow: the wrist centre is |a2 − L3| from axis 2, a1 from the plane."""
    for name, reachable in (("kuka-kr6-r700", True), ("abb-irb2400", False)):
        arm = load_robot(name)
        fac = get_factorisation(arm)
        assert (abs(fac.a2 - fac.forearm) >= fac.a1) == reachable
        roots = solve_shoulder_theta2(arm, get_elbow_singular_theta3(arm)[1])
        assert np.all(np.isfinite(roots)) == reachable
        assert np.all(np.isnan(roots)) != reachable


def test_direction_errors() -> None:
    with pytest.raises(NotPumaTypeError, match="no closed-form IK"):
        compute_degenerate_direction(load_robot("generic6r"), np.zeros(6), "wrist")
    with pytest.raises(InputError, match="unknown singularity kind"):
        compute_degenerate_direction(load_robot("ur5"), np.zeros(6), "knee")
