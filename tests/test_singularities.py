"""Analytic singularities of the PUMA models, numeric measures, directions, paths."""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import random_configurations
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from workbench import InputError, NonFiniteError, Robot, generate_urdf, load_robot
from workbench.model.catalog import get_own_urdf_dir
from workbench.singularities.along_path import find_closest_approaches
from workbench.singularities.conditions import (
    SINGULARITY_KINDS,
    NotPumaTypeError,
    classify_configuration,
    compute_conditions,
    compute_det_j_analytic,
    get_puma_factorisation,
)
from workbench.singularities.directions import compute_degenerate_direction
from workbench.singularities.loci import (
    compute_example_configurations,
    get_elbow_singular_theta3,
    solve_shoulder_theta2,
)
from workbench.singularities.measures import (
    compute_dh_jacobians,
    compute_joint_grid,
    compute_measures,
    compute_singular_values,
    cross_check_det_j,
)
from workbench.trajectory.csv_io import (
    JointTrajectorySamples,
    read_trajectory_csv,
    write_trajectory_csv,
)

REL_DET = 1e-9  # analytic det J vs np.linalg.det(Pinocchio's J), relative
ATOL_EXACT = 1e-12  # two exact computations of the same quantity
ATOL_SINGULAR = 1e-9  # sigma_min and ||u^T J|| on a locus
ATOL_PRINTED_DEG = 5e-4  # Kang prints 87.308 and -92.692: three decimals
ATOL_CROSSING = 1e-6  # [s] linearly interpolated crossing of a sine
N_RANDOM = 3000  # "thousands of random q"
GRID_SECONDS = 3.0  # budget of the analytic 1000 x 1000 det J grid [s]


def _q_on_locus(robot: Robot, kind: str, rng: np.random.Generator) -> np.ndarray:
    """A random configuration exactly on one locus (generic otherwise)."""
    q = rng.uniform(-math.pi, math.pi, 6)
    if kind == "wrist":
        q[4] = 0.0
    elif kind == "elbow":
        q[2] = get_elbow_singular_theta3(robot)[0]
    else:
        q[1] = solve_shoulder_theta2(robot, q[2])[rng.integers(2)]
    return q


# --- factorisation --------------------------------------------------------------


def test_factorisation_signs_come_from_each_table(puma, puma_kang) -> None:
    angeles, kang = get_puma_factorisation(puma), get_puma_factorisation(puma_kang)
    assert (angeles.sigma1, angeles.sigma3, angeles.wrist_sign) == (-1, 1, -1)
    assert (kang.sigma1, kang.sigma3, kang.wrist_sign) == (1, 1, -1)
    assert angeles.constant == pytest.approx(-0.4318 * math.hypot(0.01905, 0.4318))
    assert kang.constant == pytest.approx(0.4318 * math.hypot(0.0203, 0.4318))
    assert "K = -1 · a2" in angeles.describe()["constant"]


def test_det_j_factorisation_matches_pinocchio(any_puma, rng) -> None:
    within = random_configurations(any_puma, rng, N_RANDOM)
    anywhere = rng.uniform(-2 * math.pi, 2 * math.pi, (N_RANDOM, 6))
    for q in (within, anywhere):
        check = cross_check_det_j(any_puma, q)
        assert check.max_relative_error <= REL_DET
        assert np.all(np.abs(check.pinocchio) > 0.0)


def test_shoulder_condition_is_x1_of_wrist_centre(any_puma, rng) -> None:
    for q in random_configurations(any_puma, rng, 100):
        frame1 = any_puma.fk(q, "frame1")
        wrist = any_puma.fk(q).translation
        x1 = frame1.rotation[:, 0] @ (wrist - frame1.translation)
        shoulder = compute_conditions(any_puma, q).shoulder
        np.testing.assert_allclose(shoulder, x1, rtol=0, atol=ATOL_EXACT)


def test_elbow_condition_is_sine_of_forearm_angle(any_puma, rng) -> None:
    """Elbow sine = y2 coordinate of the wrist centre / sqrt(a3² + d4²)."""
    fac = get_puma_factorisation(any_puma)
    for q in random_configurations(any_puma, rng, 100):
        frame2 = any_puma.fk(q, "frame2")
        y2 = frame2.rotation[:, 1] @ (any_puma.fk(q).translation - frame2.translation)
        elbow = compute_conditions(any_puma, q).elbow
        np.testing.assert_allclose(elbow, y2 / fac.forearm, rtol=0, atol=ATOL_EXACT)


def test_conditions_are_vectorised(puma_kang, rng) -> None:
    q = rng.uniform(-3, 3, (4, 5, 6))
    batch = compute_conditions(puma_kang, q)
    assert batch.shoulder.shape == (4, 5)
    single = compute_conditions(puma_kang, q[2, 3])
    np.testing.assert_allclose(batch.elbow[2, 3], single.elbow, rtol=0, atol=0)


def test_models_agree_under_the_joint_mapping(puma, puma_kang, rng) -> None:
    """Kang = Angeles with θ2 + π, −θ5 (urdf/README.md), once a3 is the same."""
    rows = list(puma_kang.dh_table.joints)
    rows[2] = dataclasses.replace(rows[2], a=puma.dh_table.joints[2].a)
    kang = dataclasses.replace(puma_kang.dh_table, joints=tuple(rows))
    q = random_configurations(puma, rng, 200)
    q_kang = q + np.array([0.0, math.pi, 0.0, 0.0, 0.0, 0.0])
    q_kang[:, 4] *= -1.0
    a, k = compute_conditions(puma, q), compute_conditions(kang, q_kang)
    np.testing.assert_allclose(k.shoulder, -a.shoulder, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(k.elbow, a.elbow, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(k.wrist, -a.wrist, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(
        compute_det_j_analytic(kang, q_kang),
        -compute_det_j_analytic(puma, q),
        rtol=0,
        atol=ATOL_EXACT,
    )


def _kang_printed_jacobian(q: np.ndarray, a2, a3, d3, d4) -> np.ndarray:
    """Kang (2007), Section 3, J(q) as printed (columns 4-6 in its second block)."""
    c1, s1 = np.cos(q[0]), np.sin(q[0])
    s2, s3 = np.sin(q[1]), np.sin(q[2])
    c2, c3 = np.cos(q[1]), np.cos(q[2])
    c4, s4, c5, s5 = np.cos(q[3]), np.sin(q[3]), np.cos(q[4]), np.sin(q[4])
    c23, s23 = np.cos(q[1] + q[2]), np.sin(q[1] + q[2])
    reach = a2 * c2 + a3 * c23 + d4 * s23
    height = a2 * s2 + a3 * s23 - d4 * c23
    k, m = a3 * c3 + d4 * s3, a3 * s3 - d4 * c3
    return np.array(
        [
            [-s1 * reach + d3 * c1, -c1 * height, -c1 * s2 * k - c1 * c2 * m, 0, 0, 0],
            [c1 * reach + d3 * s1, -s1 * height, -s1 * s2 * k - s1 * c2 * m, 0, 0, 0],
            [0, reach, c2 * k - s2 * m, 0, 0, 0],
            [0, s1, s1, c1 * s23, c1 * c23 * s4 - s1 * c4,
             -c1 * c23 * c4 * s5 - s1 * s4 * s5 + c1 * s23 * c5],
            [0, -c1, -c1, s1 * s23, s1 * c23 * s4 + c1 * c4,
             -s1 * c23 * c4 * s5 + c1 * s4 * s5 + s1 * s23 * c5],
            [1, 0, 0, -c23, s23 * s4, -s23 * c4 * s5 - c23 * c5],
        ]
    )  # fmt: skip


def test_kang_printed_jacobian_matches_pinocchio(puma_kang, rng) -> None:
    """No erratum here: the printed J(q) is Pinocchio's (docs/errata-...)."""
    j = puma_kang.dh_table.joints
    for q in rng.uniform(-math.pi, math.pi, (200, 6)):
        printed = _kang_printed_jacobian(q, j[1].a, j[2].a, j[2].d, j[3].d)
        np.testing.assert_allclose(
            printed, puma_kang.jacobian(q), rtol=0, atol=ATOL_EXACT
        )


# --- elbow angles, loci, classification -----------------------------------------


def test_kang_elbow_angles_are_the_printed_ones(puma_kang) -> None:
    np.testing.assert_allclose(
        np.degrees(get_elbow_singular_theta3(puma_kang)),
        [87.308, -92.692],
        rtol=0,
        atol=ATOL_PRINTED_DEG,
    )


def test_angeles_elbow_angles_follow_from_its_a3(puma) -> None:
    extended = math.degrees(math.atan2(0.4318, 0.01905))  # 87.474°
    np.testing.assert_allclose(
        np.degrees(get_elbow_singular_theta3(puma)),
        [extended, extended - 180.0],
        rtol=0,
        atol=ATOL_EXACT,
    )


def test_elbow_angles_are_singular_and_in_range(any_puma, rng) -> None:
    theta3 = get_elbow_singular_theta3(any_puma)
    assert np.all((theta3 > -math.pi) & (theta3 <= math.pi))
    for value in theta3:
        q = rng.uniform(-3, 3, 6)
        q[2] = value
        assert abs(compute_conditions(any_puma, q).elbow) <= ATOL_EXACT
        assert compute_measures(any_puma, q).sigma_min <= ATOL_SINGULAR


def test_shoulder_locus_solutions(any_puma, rng) -> None:
    theta3 = rng.uniform(-3, 3, 50)
    theta2 = solve_shoulder_theta2(any_puma, theta3)
    q = np.zeros((50, 2, 6))
    q[..., 1], q[..., 2] = theta2, theta3[:, None]
    shoulder = compute_conditions(any_puma, q).shoulder
    np.testing.assert_allclose(shoulder, 0.0, rtol=0, atol=ATOL_EXACT)


def test_example_configurations_lie_on_their_locus(any_puma) -> None:
    examples = compute_example_configurations(any_puma)
    assert set(examples) == {
        "elbow, extended",
        "elbow, retracted",
        "shoulder, elbow down",
        "shoulder, elbow up",
        "wrist",
    }
    for name, q in examples.items():
        kind = name.split(",")[0]
        value = compute_conditions(any_puma, q).as_dict()[kind]
        assert abs(value) <= ATOL_EXACT, name
        assert compute_measures(any_puma, q).sigma_min <= ATOL_SINGULAR, name
        assert kind in classify_configuration(any_puma, q)
        within = np.all((q >= any_puma.lower) & (q <= any_puma.upper))
        assert within == (name != "elbow, retracted"), name


def test_classification(puma_kang) -> None:
    assert classify_configuration(puma_kang, np.zeros(6)) == ("wrist",)  # home
    generic = np.radians([10.0, 20.0, -30.0, 40.0, 50.0, 60.0])
    assert classify_configuration(puma_kang, generic) == ()
    near = generic.copy()
    near[4] = math.radians(0.5)
    assert classify_configuration(puma_kang, near) == ("wrist",)
    assert classify_configuration(puma_kang, near, wrist_tol=1e-3) == ()


# --- degenerate directions --------------------------------------------------------


@pytest.mark.parametrize("kind", SINGULARITY_KINDS)
def test_degenerate_direction_annihilates_jacobian(any_puma, rng, kind) -> None:
    for _ in range(20):
        q = _q_on_locus(any_puma, kind, rng)
        d = compute_degenerate_direction(any_puma, q, kind)
        jac = any_puma.jacobian(q)
        assert d.sigma_min <= ATOL_SINGULAR
        assert np.linalg.norm(d.direction @ jac) <= ATOL_SINGULAR
        assert d.residual <= ATOL_SINGULAR
        assert np.linalg.norm(jac @ d.self_motion) <= ATOL_SINGULAR
        np.testing.assert_allclose(np.linalg.norm(d.direction), 1.0, atol=ATOL_EXACT)


def test_shoulder_direction_is_kang_z1(any_puma, rng) -> None:
    for _ in range(20):
        q = _q_on_locus(any_puma, "shoulder", rng)
        d = compute_degenerate_direction(any_puma, q, "shoulder")
        assert d.paper_axis == "z1"
        assert d.angle_to_paper_deg <= 1e-6
        np.testing.assert_allclose(d.direction[3:], 0.0, atol=ATOL_EXACT)


def test_elbow_direction_points_from_shoulder_to_wrist(any_puma, rng) -> None:
    for _ in range(20):
        q = _q_on_locus(any_puma, "elbow", rng)
        d = compute_degenerate_direction(any_puma, q, "elbow")
        radial = any_puma.fk(q).translation - any_puma.fk(q, "frame1").translation
        np.testing.assert_allclose(
            d.direction[:3], radial / np.linalg.norm(radial), rtol=0, atol=ATOL_EXACT
        )


def _robot_from_table(table, tmp_path: Path) -> Robot:
    path = tmp_path / f"{table.name}.urdf"
    path.write_text(generate_urdf(table), encoding="utf-8")
    loaded = load_robot(path, tool_frame=table.tool_frame)
    return Robot(
        table.name,
        loaded.model,
        path,
        table.tool_frame,
        package_dirs=[],
        dh_table=table,
    )


def test_kang_x1_holds_only_without_shoulder_offset(puma_kang, tmp_path) -> None:
    """Erratum: the elbow's degenerate direction is x1 only if d2 + d3 = 0, θ2 = 0."""
    q = np.zeros(6)
    q[2], q[4] = get_elbow_singular_theta3(puma_kang)[0], 1.0
    with_offset = compute_degenerate_direction(puma_kang, q, "elbow")
    reach = 0.4318 + math.hypot(0.0203, 0.4318)
    assert with_offset.angle_to_paper_deg == pytest.approx(
        math.degrees(math.atan2(0.1254, reach)), abs=1e-9
    )  # 8.26°
    rows = list(puma_kang.dh_table.joints)
    rows[2] = dataclasses.replace(rows[2], d=0.0)
    table = dataclasses.replace(
        puma_kang.dh_table, name="kang-no-offset", joints=tuple(rows)
    )
    no_offset = compute_degenerate_direction(
        _robot_from_table(table, tmp_path), q, "elbow"
    )
    assert no_offset.angle_to_paper_deg <= 1e-6
    assert no_offset.residual <= ATOL_SINGULAR


def test_wrist_direction_is_about_x4(any_puma, rng) -> None:
    for _ in range(10):
        q = _q_on_locus(any_puma, "wrist", rng)
        d = compute_degenerate_direction(any_puma, q, "wrist")
        x4 = any_puma.fk(q, "frame4").rotation[:, 0]
        angular = d.direction[3:] / np.linalg.norm(d.direction[3:])
        assert abs(abs(angular @ x4) - 1.0) <= ATOL_EXACT
        assert d.paper_axis is None


def test_direction_errors(puma, rng) -> None:
    with pytest.raises(InputError, match="unknown singularity kind 'knee'"):
        compute_degenerate_direction(puma, np.zeros(6), "knee")
    with pytest.raises(NotPumaTypeError, match="no closed-form IK"):
        compute_degenerate_direction(load_robot("generic6r"), np.zeros(6), "wrist")


# --- numeric measures and grids ---------------------------------------------------


def test_measures_match_their_definitions(any_puma, rng) -> None:
    q = random_configurations(any_puma, rng, 20)
    m = compute_measures(any_puma, q)
    for i, qi in enumerate(q):
        jac = any_puma.jacobian(qi)
        sv = np.linalg.svd(jac, compute_uv=False)
        np.testing.assert_allclose(m.singular_values[i], sv, rtol=0, atol=ATOL_EXACT)
        np.testing.assert_allclose(
            m.manipulability[i], math.sqrt(np.linalg.det(jac @ jac.T)), rtol=1e-9
        )
        assert m.condition_number[i] == pytest.approx(sv[0] / sv[-1], rel=1e-12)
    single = compute_measures(any_puma, q[0])
    assert np.ndim(single.sigma_min) == 0
    assert single.det_j == pytest.approx(m.det_j[0], rel=1e-12)


def test_measures_of_a_redundant_arm_have_no_determinant() -> None:
    panda = load_robot("panda")
    m = compute_measures(panda, np.zeros(panda.nq) + 0.3)
    assert m.det_j is None
    assert m.singular_values.shape == (6,)


def test_condition_number_is_inf_when_exactly_singular(puma) -> None:
    from workbench.singularities.measures import compute_measures_from_jacobians

    jac = np.eye(6)
    jac[5, 5] = 0.0
    assert compute_measures_from_jacobians(jac).condition_number == np.inf


@settings(max_examples=200)
@given(
    matrix=st.integers(1, 9).flatmap(
        lambda n: arrays(
            np.float64,
            (6, n),
            elements=st.floats(-10.0, 10.0, allow_nan=False, allow_subnormal=False),
        )
    ),
    rank_drop=st.booleans(),
)
def test_compiled_singular_values_match_lapack(matrix, rank_drop) -> None:
    """Jacobi SVD against np.linalg.svd: 6 × n, n < 6, = 6 or > 6, rank-deficient."""
    if rank_drop and matrix.shape[1] > 1:
        matrix[:, -1] = 0.5 * matrix[:, 0]  # two dependent columns: sigma_min = 0
    expected = np.linalg.svd(matrix, compute_uv=False)
    got = compute_singular_values(matrix)
    scale = max(1.0, float(expected[0]))
    np.testing.assert_allclose(got, expected, rtol=0, atol=ATOL_EXACT * scale)
    batch = compute_singular_values(np.stack([matrix, 2.0 * matrix]))
    np.testing.assert_array_equal(batch[0], got)  # one matrix, whatever the batch
    np.testing.assert_allclose(batch[1], 2.0 * got, rtol=0, atol=ATOL_EXACT * scale)


def test_compiled_singular_values_do_not_depend_on_the_batch(rng) -> None:
    """Matrices swept side by side get the bits each gets alone (any lane, any N)."""
    jacobians = rng.normal(size=(37, 6, 6))
    jacobians[5, :, 2] = jacobians[5, :, 4]  # a singular one among them
    batch = compute_singular_values(jacobians)
    alone = np.stack([compute_singular_values(j) for j in jacobians])
    np.testing.assert_array_equal(batch, alone)
    np.testing.assert_array_equal(compute_singular_values(jacobians[3:20]), batch[3:20])


def test_compiled_sigma_min_vanishes_on_the_loci(any_puma, rng) -> None:
    """On each locus, sigma_min of the singular Jacobian is at rounding level."""
    for kind in ("shoulder", "elbow", "wrist"):
        q = np.stack([_q_on_locus(any_puma, kind, rng) for _ in range(20)])
        sigma = compute_singular_values(np.stack([any_puma.jacobian(qi) for qi in q]))
        assert sigma[:, -1].max() <= ATOL_SINGULAR, kind


def test_compiled_singular_values_refuse_other_shapes() -> None:
    with pytest.raises(InputError, match=r"\(\.\.\., 6, nv\)"):
        compute_singular_values(np.zeros((5, 6)))
    with pytest.raises(InputError, match="got \\(6, 0\\)"):
        compute_singular_values(np.zeros((6, 0)))


def test_batched_dh_jacobian_matches_pinocchio(any_puma, rng) -> None:
    q = random_configurations(any_puma, rng, 50)
    batched = compute_dh_jacobians(any_puma.dh_table, q)
    for qi, jac in zip(q, batched, strict=True):
        np.testing.assert_allclose(jac, any_puma.jacobian(qi), rtol=0, atol=ATOL_EXACT)


def test_det_grid_1000_squared_is_fast_and_matches_pinocchio(puma_kang) -> None:
    calls = []
    axis = np.linspace(-math.pi, math.pi, 1000)
    q_fixed = np.array([0.3, 0.0, 0.0, 0.2, 1.0, -0.4])
    start = time.perf_counter()
    grid = compute_joint_grid(
        puma_kang, axis, axis, q_fixed=q_fixed, progress=lambda d, n: calls.append(d)
    )
    assert time.perf_counter() - start <= GRID_SECONDS
    assert grid.method == "analytic"
    assert grid.values["det_j"].shape == (1000, 1000)
    assert calls[-1] == 1000 * 1000
    sub = grid.configurations()[::97, ::89].reshape(-1, 6)
    pin_det = [np.linalg.det(puma_kang.jacobian(q)) for q in sub]
    np.testing.assert_allclose(
        grid.values["det_j"][::97, ::89].ravel(), pin_det, rtol=0, atol=ATOL_EXACT
    )


def test_svd_grid_matches_pinocchio(puma, rng) -> None:
    axis = np.linspace(-3, 3, 7)
    grid = compute_joint_grid(
        puma, axis, axis[:5], q_fixed=np.full(6, 0.4), quantity="svd"
    )
    assert grid.method == "compiled"
    q = grid.configurations().reshape(-1, 6)
    expected = compute_measures(puma, q).sigma_min.reshape(5, 7)
    np.testing.assert_allclose(
        grid.values["sigma_min"], expected, rtol=0, atol=ATOL_EXACT
    )


def test_grid_of_a_robot_without_dh_table_uses_pinocchio(tmp_path) -> None:
    ur5 = load_robot("ur5")  # a closed-form family: det J from its factors
    axis = np.linspace(-1, 1, 4)
    grid = compute_joint_grid(ur5, axis, axis, q_fixed=np.full(6, 0.5))
    assert grid.method == "analytic"
    generic = load_robot("generic6r")  # no family: SVD of compiled Jacobians
    grid = compute_joint_grid(generic, axis, axis, q_fixed=np.full(6, 0.5))
    assert grid.method == "compiled"
    from workbench import Robot

    plain = Robot("plain", generic.model, generic.urdf_path, "flange", package_dirs=[])
    grid = compute_joint_grid(plain, axis, axis, q_fixed=np.full(6, 0.5))
    assert grid.method == "compiled"
    assert set(grid.values) >= {"det_j", "sigma_min"}
    # A mimic joint on the way to the tool: no compiled chain, one Pinocchio
    # call per point, the same numbers.
    text = (get_own_urdf_dir() / "puma560.urdf").read_text()
    end = text.index("</joint>", text.index('<joint name="joint6"'))
    path = tmp_path / "mimic.urdf"
    path.write_text(text[:end] + '<mimic joint="joint4"/>' + text[end:])
    mimic = load_robot(path)
    grid = compute_joint_grid(
        mimic, axis, axis, q_fixed=np.full(5, 0.5), quantity="svd"
    )
    assert grid.method == "pinocchio"
    q = grid.configurations().reshape(-1, 5)
    expected = [np.linalg.svd(mimic.jacobian(qi), compute_uv=False)[-1] for qi in q]
    np.testing.assert_allclose(
        grid.values["sigma_min"].ravel(), expected, rtol=0, atol=ATOL_EXACT
    )


def test_grid_errors(puma) -> None:
    axis = np.zeros(3)
    with pytest.raises(InputError, match="quantity must be"):
        compute_joint_grid(puma, axis, axis, q_fixed=np.zeros(6), quantity="x")
    with pytest.raises(InputError, match="two indices"):
        compute_joint_grid(puma, axis, axis, q_fixed=np.zeros(6), joints=(1, 1))
    with pytest.raises(NonFiniteError):
        compute_joint_grid(puma, [np.nan], axis, q_fixed=np.zeros(6))


# --- input errors -------------------------------------------------------------


def test_not_puma_type_errors(puma) -> None:
    with pytest.raises(NotPumaTypeError, match="axes 2 and 3 are not parallel"):
        compute_conditions(load_robot("generic6r"), np.zeros(6))
    rows = list(puma.dh_table.joints)
    rows[3] = dataclasses.replace(rows[3], a=0.1)
    table = dataclasses.replace(puma.dh_table, joints=tuple(rows))
    with pytest.raises(NotPumaTypeError, match="a4 = 0"):
        get_puma_factorisation(table)
    assert issubclass(NotPumaTypeError, InputError)


def test_configuration_errors(puma) -> None:
    with pytest.raises(InputError, match=r"shape \(\.\.\., 6\)"):
        compute_conditions(puma, np.zeros(5))
    with pytest.raises(NonFiniteError):
        compute_conditions(puma, [0, 0, np.nan, 0, 0, 0])
    with pytest.raises(InputError, match="6 values expected, 3 given"):
        compute_measures(puma, np.zeros(3))


# --- along a trajectory -----------------------------------------------------------


def test_closest_approach_and_crossing(puma_kang, tmp_path) -> None:
    t = np.linspace(0.0, 2.0, 201)  # [s]
    q = np.tile(np.radians([10.0, 30.0, 20.0, 0.0, 0.0, 0.0]), (t.size, 1))
    q[:, 4] = np.radians(np.linspace(30.0, -10.0, t.size))  # θ5 = 0 at t = 1.5 s
    q[:, 2] = np.radians(np.linspace(20.0, 60.0, t.size))  # elbow approaches 87°
    path = tmp_path / "path.csv"
    zeros = np.zeros_like(q)
    write_trajectory_csv(path, JointTrajectorySamples(t, q, zeros, zeros))
    samples = read_trajectory_csv(path, puma_kang.nq)
    approaches = find_closest_approaches(puma_kang, samples.t, samples.q)
    assert set(approaches) == {"shoulder", "elbow", "wrist", "sigma_min"}
    wrist = approaches["wrist"]
    assert wrist.crossed
    assert wrist.crossings[0] == pytest.approx(1.5, abs=ATOL_CROSSING)
    elbow = approaches["elbow"]
    assert not elbow.crossed and elbow.index == t.size - 1 and elbow.t == 2.0
    expected = compute_conditions(puma_kang, q[-1]).elbow
    assert elbow.distance == pytest.approx(float(expected), abs=ATOL_EXACT)
    assert approaches["sigma_min"].t == pytest.approx(1.5, abs=0.011)


def test_closest_approach_of_any_robot_and_errors() -> None:
    ur5 = load_robot("generic6r")
    t = np.linspace(0, 1, 5)
    approaches = find_closest_approaches(ur5, t, np.full((5, 6), 0.5))
    assert set(approaches) == {"sigma_min"}
    with pytest.raises(InputError, match="increase"):
        find_closest_approaches(ur5, t[::-1], np.zeros((5, 6)))
    with pytest.raises(InputError):
        find_closest_approaches(ur5, t, np.zeros((4, 6)))
