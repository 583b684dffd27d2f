"""SRS singularities (``singularities.redundant``) against Pinocchio's 6 × 7 J."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from workbench import Robot, load_robot
from workbench.errors import InputError
from workbench.singularities import (
    SRS_CONDITION_UNITS,
    SRS_SINGULARITY_KINDS,
    NotSRSArmError,
    compute_srs_conditions,
    compute_srs_degenerate_direction,
    compute_srs_det_jjt,
    get_srs_factorisation,
)

#: det(J Jᵀ) of the factorisation against Pinocchio's, relative (plus the
#: rounding of a vanishing determinant, absolute [m⁶]).
RTOL_DET = 1e-9
ATOL_DET = 1e-15
#: σ_min of J and ‖uᵀ J‖ of the lost direction on a locus.
ATOL_SINGULAR = 1e-12
#: Measured bounds of σ_min / min(distances) (seeded samples; the report's
#: figures): σ_min is never above SIGMA_PER_DISTANCE_MAX times the smallest
#: distance (a small distance makes σ_min small) and never below
#: SIGMA_PER_DISTANCE_MIN times it (a small σ_min needs a small distance).
SIGMA_PER_DISTANCE_MAX = 0.5
SIGMA_PER_DISTANCE_MIN = 1e-5
JACOBIAN_KINDS = SRS_SINGULARITY_KINDS[:4]


@pytest.fixture(scope="module")
def iiwa() -> Robot:
    return load_robot("iiwa14")


def _jacobian(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Pinocchio's 6 × 7 Jacobian of the flange, world-aligned, [linear; angular]."""
    model, data = robot.model, robot.model.createData()
    return pin.computeFrameJacobian(
        model, data, q, robot.tool_frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    )


def _jacobian_at(robot: Robot, q: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Pinocchio's Jacobian with the linear rows moved to ``point`` (v + ω × r)."""
    jac = _jacobian(robot, q).copy()
    r = point - robot.fk(q).translation
    jac[:3] -= np.cross(r, jac[3:].T).T
    return jac


def _on_locus(rng: np.random.Generator, kind: str, n: int) -> np.ndarray:
    q = rng.uniform(-math.pi, math.pi, (n, 7))
    zero_or_pi = rng.choice([0.0, math.pi], n)
    quarter = rng.choice([-math.pi / 2, math.pi / 2], n)
    if kind == "elbow":
        q[:, 3] = zero_or_pi
    elif kind == "shoulder":
        q[:, 1], q[:, 2] = zero_or_pi, quarter
    elif kind == "wrist":
        q[:, 5], q[:, 4] = zero_or_pi, quarter
    else:
        q[:, 1], q[:, 5] = zero_or_pi, rng.choice([0.0, math.pi], n)
    return q


def _smallest_distance(robot: Robot, qs: np.ndarray) -> np.ndarray:
    c = compute_srs_conditions(robot, qs)
    return np.minimum.reduce([np.abs(c.elbow), c.shoulder, c.wrist, c.shoulder_wrist])


@pytest.mark.slow
def test_det_jjt_factorisation(iiwa, rng) -> None:
    qs = rng.uniform(-math.pi, math.pi, (10_000, 7))
    analytic = compute_srs_det_jjt(iiwa, qs)
    for q, value in zip(qs, analytic, strict=True):
        jac = _jacobian(iiwa, q)
        exact = np.linalg.det(jac @ jac.T)
        assert abs(value - exact) <= RTOL_DET * abs(exact) + ATOL_DET
        # Cauchy–Binet: the sum of the seven squared 6 × 6 minors
        minors = [np.linalg.det(np.delete(jac, k, axis=1)) for k in range(7)]
        assert abs(sum(m * m for m in minors) - exact) <= RTOL_DET * exact + ATOL_DET


@pytest.mark.slow
@pytest.mark.parametrize("kind", JACOBIAN_KINDS)
def test_rank_loss_and_lost_direction_on_each_locus(iiwa, rng, kind) -> None:
    worst_sigma, worst_residual = 0.0, 0.0
    for q in _on_locus(rng, kind, 300):
        assert getattr(compute_srs_conditions(iiwa, q), kind) <= 1e-15
        lost = compute_srs_degenerate_direction(iiwa, q, kind)
        jac = _jacobian_at(iiwa, q, lost.reference_point)
        u, sigma, _ = np.linalg.svd(jac)
        worst_sigma = max(worst_sigma, sigma[-1])
        worst_residual = max(worst_residual, np.linalg.norm(lost.direction @ jac))
        assert np.linalg.norm(lost.direction) == pytest.approx(1.0, abs=1e-15)
        if sigma[-2] > 1e-6:  # a one-dimensional left null space: the same line
            assert abs(u[:, -1] @ lost.direction) >= 1.0 - 1e-9
    assert worst_sigma <= ATOL_SINGULAR
    assert worst_residual <= ATOL_SINGULAR


def test_reference_point_is_the_wrist_centre(iiwa, rng) -> None:
    for q in rng.uniform(-3.0, 3.0, (50, 7)):
        pose = iiwa.fk(q)
        wrist = pose.translation - 0.126 * pose.rotation[:, 2]
        lost = compute_srs_degenerate_direction(iiwa, q, "elbow")
        np.testing.assert_allclose(lost.reference_point, wrist, rtol=0, atol=1e-15)


def test_small_sigma_iff_small_distance(iiwa, rng) -> None:
    """σ_min / min(distances) stays within measured bounds, at random and near loci."""
    samples = [rng.uniform(-math.pi, math.pi, (10_000, 7))]
    for kind in JACOBIAN_KINDS:
        near = _on_locus(rng, kind, 2_000)
        scale = 10.0 ** rng.uniform(-9.0, -1.0, (2_000, 1))
        samples.append(near + scale * rng.normal(size=(2_000, 7)))
    qs = np.concatenate(samples)
    sigma = np.array(
        [np.linalg.svd(_jacobian(iiwa, q), compute_uv=False)[-1] for q in qs]
    )
    ratio = sigma / _smallest_distance(iiwa, qs)
    assert ratio.max() <= SIGMA_PER_DISTANCE_MAX
    assert ratio.min() >= SIGMA_PER_DISTANCE_MIN


def test_arm_angle_distance(iiwa, rng) -> None:
    """|SW_xy| / |SW| from Pinocchio's S and W; zero with W on axis 1."""
    model, data = iiwa.model, iiwa.model.createData()
    for q in rng.uniform(-3.0, 3.0, (200, 7)):
        pin.forwardKinematics(model, data, q)
        sw = data.oMi[6].translation - data.oMi[2].translation
        expected = np.linalg.norm(sw[:2]) / np.linalg.norm(sw)
        value = compute_srs_conditions(iiwa, q).arm_angle
        assert value == pytest.approx(expected, abs=1e-14)
    q = np.array([0.4, 0.0, 0.0, 0.8, 0.0, 0.0, 0.0])  # θ3 = 0: SW in the x2 z2 plane
    q[1] = math.atan2(math.sin(0.8) * 0.40, 0.42 + math.cos(0.8) * 0.40)
    assert compute_srs_conditions(iiwa, q).arm_angle <= 1e-15
    sigma = np.linalg.svd(_jacobian(iiwa, q), compute_uv=False)[-1]
    assert sigma > 1e-3  # the algorithmic singularity keeps J's rank


def test_conditions_shapes_and_units(iiwa) -> None:
    qs = np.zeros((2, 3, 7))
    c = compute_srs_conditions(iiwa, qs)
    for value in c.as_dict().values():
        assert value.shape == (2, 3)
    assert set(c.as_dict()) == set(SRS_SINGULARITY_KINDS) == set(SRS_CONDITION_UNITS)
    assert compute_srs_det_jjt(iiwa, qs).shape == (2, 3)
    fac = get_srs_factorisation(iiwa)
    assert (fac.d3, fac.d5) == pytest.approx((0.42, 0.40), abs=1e-12)


def test_errors(iiwa) -> None:
    with pytest.raises(NotSRSArmError, match="not an SRS"):
        compute_srs_conditions(load_robot("puma560"), np.zeros(6))
    with pytest.raises(InputError, match=r"shape \(\.\.\., 7\)"):
        compute_srs_conditions(iiwa, np.zeros(6))
    with pytest.raises(InputError, match="finite"):
        compute_srs_det_jjt(iiwa, np.full(7, np.nan))
    with pytest.raises(InputError, match="loses no twist"):
        compute_srs_degenerate_direction(iiwa, np.zeros(7), "arm_angle")
    with pytest.raises(InputError, match=r"shape \(7,\)"):
        compute_srs_degenerate_direction(iiwa, np.zeros((2, 7)), "elbow")
