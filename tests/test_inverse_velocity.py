"""The planner's joint-velocity step: exact block inverse and Jacobi-SVD DLS."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from workbench.ik import DLS_EPSILON, DLS_LAMBDA_MAX, dls_inverse
from workbench.planning._inverse_velocity import (
    _orthogonalise_rows,
    damped_solve,
    solve_velocity,
)

RTOL_SVD = 1e-12
"""Against LAPACK's SVD (gesdd), whose own rounding reaches ~3e-13 here
(the Jacobi result is closer to a 40-digit reference than gesdd's)."""

SHAPES = [(6, 6), (7, 6), (6, 7)]


def _jacobian(seed: int, shape: tuple[int, int], squash: float) -> np.ndarray:
    """Random J with its smallest singular value scaled by ``squash``."""
    rng = np.random.default_rng(seed)
    u, sigma, vt = np.linalg.svd(rng.normal(size=shape), full_matrices=False)
    sigma[-1] *= squash
    return (u * sigma) @ vt


@given(
    seed=st.integers(0, 2**32 - 1),
    shape=st.sampled_from(SHAPES),
    squash=st.sampled_from([1.0, 0.1, 1e-3, 1e-8, 1e-16, 0.0]),
)
def test_damped_solve_is_the_dls_about_the_reference(seed, shape, squash):
    jacobian = _jacobian(seed, shape, squash)
    rng = np.random.default_rng(seed + 1)
    twist, reference = rng.normal(size=shape[0]), rng.normal(size=shape[1])
    qd = np.empty(shape[1])
    damped_solve(jacobian, twist, DLS_EPSILON, DLS_LAMBDA_MAX, reference, qd)
    expected = reference + dls_inverse(jacobian) @ (twist - jacobian @ reference)
    scale = max(1.0, np.abs(expected).max())
    np.testing.assert_allclose(qd, expected, rtol=0, atol=RTOL_SVD * scale)


@given(seed=st.integers(0, 2**32 - 1), shape=st.sampled_from(SHAPES))
def test_jacobi_rows_give_the_singular_values_and_the_matrix(seed, shape):
    jacobian = _jacobian(seed, shape, 1e-6)
    x = jacobian.copy() if shape[1] > shape[0] else jacobian.T.copy()
    original = x.copy()
    y = np.eye(x.shape[0])
    norms2 = _orthogonalise_rows(x, y)
    gram = x @ x.T
    np.testing.assert_allclose(norms2, np.einsum("ij,ij->i", x, x), rtol=1e-15, atol=0)
    sigma = np.sqrt(np.diag(gram))
    off_diagonal = gram - np.diag(np.diag(gram))
    assert np.abs(off_diagonal).max() <= 1e-14 * sigma.max() ** 2
    np.testing.assert_allclose(y @ y.T, np.eye(len(y)), rtol=0, atol=1e-14)
    np.testing.assert_allclose(y.T @ x, original, rtol=0, atol=1e-14)
    np.testing.assert_allclose(
        np.sort(sigma)[::-1],
        np.linalg.svd(jacobian, compute_uv=False),
        rtol=0,
        atol=1e-14 * sigma.max(),
    )


def test_damping_law_on_a_diagonal_jacobian():
    sigma = np.array([2.0, 1.0, 0.5, 0.2, 0.04, 0.01])  # sigma_min < epsilon
    twist = np.arange(1.0, 7.0)
    qd = np.empty(6)
    damped_solve(np.diag(sigma), twist, 0.05, 0.05, np.zeros(6), qd)
    lambda2 = (1.0 - (0.01 / 0.05) ** 2) * 0.05**2
    np.testing.assert_allclose(
        qd, sigma * twist / (sigma**2 + lambda2), rtol=1e-15, atol=0
    )


def test_solve_velocity_uses_the_block_inverse_outside_the_singular_region():
    rng = np.random.default_rng(7)
    jacobian = rng.normal(size=(6, 6)) + 3.0 * np.eye(6)
    jacobian[:3, 3:] = 0.0  # the spherical-wrist structure
    twist = rng.normal(size=6)
    qd, damped = solve_velocity(jacobian, twist, DLS_EPSILON, DLS_LAMBDA_MAX)
    assert not damped
    np.testing.assert_allclose(jacobian @ qd, twist, rtol=0, atol=1e-13)

    singular = jacobian.copy()
    singular[3:, 5] = singular[3:, 4]  # two wrist axes aligned: sigma_min = 0
    qd, damped = solve_velocity(singular, twist, DLS_EPSILON, DLS_LAMBDA_MAX)
    assert damped
    np.testing.assert_allclose(
        qd, dls_inverse(singular) @ twist, rtol=0, atol=RTOL_SVD * 10
    )
    reference = np.full(6, 0.3)
    qd, _ = solve_velocity(
        singular, twist, DLS_EPSILON, DLS_LAMBDA_MAX, lambda: reference
    )
    expected = reference + dls_inverse(singular) @ (twist - singular @ reference)
    np.testing.assert_allclose(qd, expected, rtol=0, atol=RTOL_SVD * 10)


@pytest.mark.parametrize("lambda_max", [0.0, 0.05])
def test_zero_jacobian_gives_the_reference(lambda_max):
    qd = np.empty(6)
    reference = np.arange(6.0)
    damped_solve(np.zeros((6, 6)), np.ones(6), 0.05, lambda_max, reference, qd)
    np.testing.assert_array_equal(qd, reference)
