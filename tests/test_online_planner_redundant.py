"""The online planner on seven-axis arms: null-space velocity, redundancy policy."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from workbench.ik import DLS_EPSILON, DLS_LAMBDA_MAX, solve_null_space_velocity

#: Against NumPy's pseudo-inverse (LAPACK SVD), relative to the largest entry.
RTOL_SVD = 1e-12


def _wide_jacobian(seed: int, squash: float) -> np.ndarray:
    """Random 6 × 7 J, singular values >= 0.1 but the smallest times ``squash``."""
    rng = np.random.default_rng(seed)
    u, sigma, vt = np.linalg.svd(rng.normal(size=(6, 7)), full_matrices=False)
    sigma = np.maximum(sigma, 0.1)
    sigma[-1] *= squash
    return (u * sigma) @ vt


@given(seed=st.integers(0, 2**32 - 1))
def test_null_space_velocity_is_the_pseudo_inverse_plus_the_projected_motion(seed):
    jacobian = _wide_jacobian(seed, 1.0)
    rng = np.random.default_rng(seed + 1)
    twist, qd_null = rng.normal(size=6), rng.normal(size=7)
    qd, damped = solve_null_space_velocity(
        jacobian, twist, DLS_EPSILON, DLS_LAMBDA_MAX, qd_null
    )
    pinv = np.linalg.pinv(jacobian)
    expected = pinv @ twist + (np.eye(7) - pinv @ jacobian) @ qd_null
    scale = max(1.0, np.abs(expected).max())
    np.testing.assert_allclose(qd, expected, rtol=0, atol=RTOL_SVD * scale)
    np.testing.assert_allclose(jacobian @ qd, twist, rtol=0, atol=RTOL_SVD * scale)
    assert not damped


@given(seed=st.integers(0, 2**32 - 1), squash=st.sampled_from([1e-3, 1e-8, 1e-16, 0.0]))
def test_null_space_velocity_is_damped_in_the_singular_region(seed, squash):
    jacobian = _wide_jacobian(seed, squash)
    rng = np.random.default_rng(seed + 1)
    twist, qd_null = rng.normal(size=6), rng.normal(size=7)
    qd, damped = solve_null_space_velocity(
        jacobian, twist, DLS_EPSILON, DLS_LAMBDA_MAX, qd_null
    )
    # the DLS inverse of workbench.ik.dls_inverse, written out from LAPACK's SVD
    u, sigma, vt = np.linalg.svd(jacobian, full_matrices=False)
    lambda2 = (1.0 - (sigma[-1] / DLS_EPSILON) ** 2) * DLS_LAMBDA_MAX**2
    dls = (vt.T * (sigma / (sigma**2 + lambda2))) @ u.T
    expected = dls @ twist + (np.eye(7) - dls @ jacobian) @ qd_null
    scale = max(1.0, np.abs(expected).max())
    np.testing.assert_allclose(qd, expected, rtol=0, atol=RTOL_SVD * scale)
    assert damped
