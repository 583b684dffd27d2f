"""The joint-space singularity map against Pinocchio and the analytic factors.

sigma_min against ``np.linalg.svd`` of Pinocchio's Jacobian, det J against the
factorisation K s e w and against ``np.linalg.det``, and |det J| = prod sigma_i,
on OPW, UR-type, generic 6R and 7-axis arms; the map is the same bits on one
thread or two, and its random and grid configurations are the ones documented.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from workbench import InputError, Robot, load_robot
from workbench.singularities.conditions import (
    WRIST_TOL,
    compute_conditions,
    get_factorisation,
)
from workbench.workspace.joint_space import (
    CHUNK,
    DEFAULT_SAMPLES,
    MAX_CONFIGURATIONS,
    compute_joint_space_map,
)
from workbench.workspace.measures import singularity_margin

ATOL_EXACT = 1e-12
"""Two exact computations of the same quantity (singular values: Jacobi vs LAPACK)."""

REL_DET = 1e-9
"""det J: analytic factors vs LAPACK's determinant of Pinocchio's Jacobian, and
|det J| vs prod sigma_i, relative."""

ATOL_SINGULAR = 1e-9
"""sigma_min at a configuration exactly on a singular locus."""

CHECKED = 300  # configurations compared with Pinocchio one by one


@pytest.fixture(scope="module", params=("puma560", "ur5", "generic6r", "panda"))
def arm(request: pytest.FixtureRequest):
    return load_robot(request.param)


def test_sigma_min_matches_lapack_on_pinocchios_jacobian(arm) -> None:
    m = compute_joint_space_map(arm, samples=CHECKED, seed=3)
    assert m.q.shape == (CHECKED, arm.nq) and m.count == CHECKED
    assert np.all((m.q >= arm.lower) & (m.q <= arm.upper))
    expected = np.array([np.linalg.svd(arm.jacobian(q), compute_uv=False) for q in m.q])
    np.testing.assert_allclose(m.sigma_min, expected[:, -1], rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(
        m.manipulability, np.prod(expected, axis=1), rtol=REL_DET, atol=0
    )


def test_det_j_is_the_product_of_the_factors_and_of_the_singular_values(arm) -> None:
    m = compute_joint_space_map(arm, samples=CHECKED, seed=4)
    if arm.nv != 6:
        assert m.det_j is None and m.shoulder is None
        assert m.near_singular_fraction() is None
        return
    assert m.det_j is not None
    lapack = np.array([np.linalg.det(arm.jacobian(q)) for q in m.q])
    np.testing.assert_allclose(m.det_j, lapack, rtol=REL_DET, atol=0)
    np.testing.assert_allclose(np.abs(m.det_j), m.manipulability, rtol=REL_DET, atol=0)
    if arm.name == "generic6r":  # no closed-form family: no factors
        assert m.shoulder is None and m.singularity_margin is None
        return
    assert m.shoulder is not None and m.elbow is not None and m.wrist is not None
    c = compute_conditions(arm, m.q)
    np.testing.assert_array_equal(m.shoulder, c.shoulder)
    np.testing.assert_array_equal(m.elbow, c.elbow)
    np.testing.assert_array_equal(m.wrist, c.wrist)
    constant = get_factorisation(arm).constant
    np.testing.assert_array_equal(m.det_j, constant * c.shoulder * c.elbow * c.wrist)
    margin = singularity_margin(c.shoulder, c.elbow, c.wrist)
    np.testing.assert_array_equal(m.singularity_margin, margin)
    assert m.near_singular_fraction() == pytest.approx(np.mean(margin < 1.0))


def test_the_map_is_the_same_on_one_thread_or_two() -> None:
    ur5 = load_robot("ur5")
    count = 2 * CHUNK + 1000  # three chunks, the last one short
    calls: list[tuple[int, int]] = []
    one = compute_joint_space_map(ur5, samples=count, seed=7, workers=1)
    two = compute_joint_space_map(
        ur5, samples=count, seed=7, workers=2, progress=lambda *c: calls.append(c)
    )
    assert (one.workers, two.workers) == (1, 2)
    for name in ("q", "sigma_min", "manipulability", "det_j", "singularity_margin"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name))
    assert sorted(calls)[-1] == (count, count) and len(calls) == 3
    # Chunk c draws from default_rng([seed, c]): the documented stream.
    first = np.random.default_rng([7, 0]).uniform(ur5.lower, ur5.upper, (CHUNK, 6))
    np.testing.assert_array_equal(one.q[:CHUNK], first)
    other = compute_joint_space_map(ur5, samples=100, seed=8)
    assert not np.array_equal(other.q, one.q[:100])
    assert (one.sampling, one.seed, one.points_per_joint) == ("random", 7, None)


def test_a_grid_holds_the_limits_and_the_wrist_locus() -> None:
    puma = load_robot("puma560")
    m = compute_joint_space_map(puma, points_per_joint=3)
    assert m.count == 3**6
    axes = [
        np.linspace(lo, hi, 3) for lo, hi in zip(puma.lower, puma.upper, strict=True)
    ]
    expected = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 6)
    np.testing.assert_array_equal(m.q, expected)  # last joint fastest
    assert (m.sampling, m.seed, m.points_per_joint) == ("grid", None, 3)
    assert m.wrist is not None and m.singularity_margin is not None
    on_wrist_locus = np.abs(m.wrist) < WRIST_TOL  # q5 = 0, the middle of its range
    assert on_wrist_locus.sum() == 3**5
    assert m.sigma_min[on_wrist_locus].max() <= ATOL_SINGULAR
    assert np.all(m.singularity_margin[on_wrist_locus] < 1.0)
    assert m.sigma_min[~on_wrist_locus].min() > ATOL_SINGULAR


def test_defaults_and_bad_input() -> None:
    ur5 = load_robot("ur5")
    assert DEFAULT_SAMPLES == 1_000_000 and MAX_CONFIGURATIONS == 20_000_000
    with pytest.raises(InputError, match="not both"):
        compute_joint_space_map(ur5, samples=10, points_per_joint=2)
    with pytest.raises(InputError, match="samples must be a positive integer"):
        compute_joint_space_map(ur5, samples=0)
    with pytest.raises(InputError, match="points_per_joint must be a positive"):
        compute_joint_space_map(ur5, points_per_joint=2.5)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="workers must be a positive integer"):
        compute_joint_space_map(ur5, samples=10, workers=0)
    with pytest.raises(InputError, match="seed must be a non-negative integer"):
        compute_joint_space_map(ur5, samples=10, seed=-1)
    with pytest.raises(InputError, match="more than 20,000,000 in one map"):
        compute_joint_space_map(ur5, points_per_joint=17)  # 24 million
    kinova = load_robot("kinova")  # continuous joints: (cos, sin) coordinates
    with pytest.raises(InputError, match="one coordinate per joint"):
        compute_joint_space_map(kinova, samples=10)
    model = pin.Model(ur5.model)
    model.lowerPositionLimit, model.upperPositionLimit = np.full((2, 6), np.inf) * [
        [-1.0],
        [1.0],
    ]
    unlimited = Robot(
        "unlimited", model, ur5.urdf_path, ur5.tool_frame, package_dirs=[]
    )
    with pytest.raises(InputError, match="finite limits"):
        compute_joint_space_map(unlimited, samples=10)
