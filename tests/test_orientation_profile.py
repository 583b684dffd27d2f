"""Quaternion orientation planning (Kang 2007, §4): ends, axis, speed, erratum."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from workbench import InfeasibleError, InputError, NonFiniteError, planning
from workbench.planning import compute_relative_axis_angle, orientation
from workbench.poses import rotation_from_axis_angle

ATOL_EXACT = 1e-12
ATOL_FD = 1e-6


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    axis = rng.normal(size=3)
    return rotation_from_axis_angle(axis / np.linalg.norm(axis), rng.uniform(0, np.pi))


def _kang_eq5(q0: float, q1: float, q2: float, q3: float) -> np.ndarray:
    """Kang's eq. (5), rotation matrix of a quaternion, as printed."""
    return np.array(
        [
            [
                q0**2 + q1**2 - q2**2 - q3**2,
                2 * (q1 * q2 - q0 * q3),
                2 * (q1 * q3 + q0 * q2),
            ],
            [
                2 * (q1 * q2 + q0 * q3),
                q0**2 - q1**2 + q2**2 - q3**2,
                2 * (q2 * q3 - q0 * q1),
            ],
            [
                2 * (q1 * q3 - q0 * q2),
                2 * (q2 * q3 + q0 * q1),
                q0**2 - q1**2 - q2**2 + q3**2,
            ],
        ]
    )


def _angles() -> list[float]:
    return [1e-9, 1e-4, 0.3, 1.5, 3.0, math.pi - 1e-6, math.pi - 1e-12, math.pi]


@pytest.mark.parametrize("seed", range(4))
def test_ends_are_exact(seed):
    rng = np.random.default_rng(seed)
    for angle in _angles():
        r1 = _random_rotation(rng)
        axis = rng.normal(size=3)
        r2 = r1 @ rotation_from_axis_angle(axis / np.linalg.norm(axis), angle)
        rot = planning.orientation(r1, r2, 0.8, 2.0)
        r_start, w_start = rot.sample(0.0)
        r_end, w_end = rot.sample(rot.duration)
        np.testing.assert_allclose(r_start, r1, rtol=0, atol=ATOL_EXACT)
        np.testing.assert_allclose(r_end, r2, rtol=0, atol=ATOL_EXACT)
        # and the last sample before the end is on the way to R2 as well
        r_near, _ = rot.sample(rot.duration * (1 - 1e-12))
        np.testing.assert_allclose(r_near, r2, rtol=0, atol=1e-9)
        np.testing.assert_allclose(w_start, 0.0, atol=ATOL_EXACT)
        np.testing.assert_allclose(w_end, 0.0, atol=ATOL_EXACT)
        assert rot.angle <= math.pi


def test_rotation_about_one_fixed_axis_with_trapezoidal_angle(rng):
    r1, r2 = _random_rotation(rng), _random_rotation(rng)
    rot = orientation(r1, r2, 0.5, 1.0)
    axis_base = r1 @ rot.axis
    for t in np.linspace(0.0, rot.duration, 57)[1:-1]:
        r, omega = rot.sample(t)
        e = pin.log3(r1.T @ r)
        phi = np.linalg.norm(e)
        np.testing.assert_allclose(e / phi, rot.axis, rtol=0, atol=1e-9)
        theta, theta_d, _ = rot.profile.sample(t)
        assert phi == pytest.approx(theta, abs=1e-12)
        np.testing.assert_allclose(omega, axis_base * theta_d, rtol=0, atol=1e-12)
    if rot.angle > 0.5**2 / 1.0:  # long enough to cruise: a trapezoid
        assert rot.profile.accelerations == (1.0, 0.0, -1.0)
    else:
        assert rot.profile.accelerations == (1.0, -1.0)


def test_triangular_for_a_small_angle():
    r1 = np.eye(3)
    r2 = rotation_from_axis_angle([0.0, 0.0, 1.0], 0.1)
    rot = orientation(r1, r2, 1.0, 1.0)
    assert rot.profile.accelerations == (1.0, -1.0)
    assert rot.profile.peak_velocity == pytest.approx(math.sqrt(0.1), abs=ATOL_EXACT)


@pytest.mark.parametrize("seed", range(3))
def test_angular_speed_never_above_limit_and_matches_finite_differences(seed):
    rng = np.random.default_rng(seed)
    r1, r2 = _random_rotation(rng), _random_rotation(rng)
    wmax, amax = 0.7, 1.3
    rot = orientation(r1, r2, wmax, amax)
    h = 1e-6
    speeds = []
    for t in np.linspace(0.0, rot.duration, 301):
        _, omega = rot.sample(t)
        speeds.append(np.linalg.norm(omega))
        r_next, _ = rot.sample(t + h)
        r_prev, _ = rot.sample(t - h)
        fd = pin.log3(r_next @ r_prev.T) / (2 * h)  # base axes
        np.testing.assert_allclose(omega, fd, rtol=0, atol=ATOL_FD)
    assert max(speeds) <= wmax * (1 + 1e-12)
    if rot.angle > wmax**2 / amax:
        assert max(speeds) == pytest.approx(wmax, rel=1e-9)
    alpha = np.linalg.norm(rot.sample_acceleration(rot.duration / 10))
    assert alpha <= amax * (1 + 1e-12)


def test_shortest_path_and_robust_near_pi():
    r1 = np.eye(3)
    for angle in (np.pi + 0.2, 2 * np.pi - 1e-3):  # the other way round is shorter
        r2 = rotation_from_axis_angle([0.0, 1.0, 0.0], angle)
        axis, phi = compute_relative_axis_angle(r1, r2)
        assert phi == pytest.approx(2 * np.pi - angle, abs=1e-12)
        np.testing.assert_allclose(axis, [0.0, -1.0, 0.0], atol=1e-12)
    r2 = rotation_from_axis_angle([1.0, 2.0, 2.0] / np.float64(3.0), np.pi)
    axis, phi = compute_relative_axis_angle(r1, r2)
    assert phi == pytest.approx(np.pi, abs=1e-12)
    np.testing.assert_allclose(axis, [1 / 3, 2 / 3, 2 / 3], atol=1e-12)
    axis, phi = compute_relative_axis_angle(r1, r1)
    assert phi == 0.0
    rot = orientation(r1, r1, 1.0, 1.0)
    assert rot.duration == 0.0
    np.testing.assert_allclose(rot.sample(0.5)[0], r1, atol=0)


def _kang_eq5_inverse(r: np.ndarray) -> np.ndarray:
    """[q0, q1, q2, q3] with eq. (5) giving ``r``, q0 >= 0 (Shoemake, Kang's Ref. 8).

    Written here from eq. (5) itself (largest-pivot form), independent of
    ``workbench.poses``.
    """
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    pivots = [trace, r[0, 0], r[1, 1], r[2, 2]]
    k = int(np.argmax(pivots))
    if k == 0:
        q0 = 0.5 * math.sqrt(1.0 + trace)
        q = [q0, (r[2, 1] - r[1, 2]) / (4 * q0), (r[0, 2] - r[2, 0]) / (4 * q0)]
        q.append((r[1, 0] - r[0, 1]) / (4 * q0))
    else:
        i, j, m = k - 1, k % 3, (k + 1) % 3
        qi = 0.5 * math.sqrt(1.0 + r[i, i] - r[j, j] - r[m, m])
        q = [0.0] * 4
        q[0] = (r[m, j] - r[j, m]) / (4 * qi)
        q[1 + i], q[1 + j] = qi, (r[j, i] + r[i, j]) / (4 * qi)
        q[1 + m] = (r[m, i] + r[i, m]) / (4 * qi)
    q = np.array(q)
    return q if q[0] >= 0 else -q


def test_kang_eq5_is_the_active_matrix_and_eq4_its_passive_axis(rng):
    """Eq. (5) of q = [cos(θ/2), +u sin(θ/2)] is Rot(u, θ), Pinocchio's quaternion."""
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    theta = 1.1
    w, v = math.cos(theta / 2), math.sin(theta / 2) * axis
    plus = _kang_eq5(w, *v)
    np.testing.assert_allclose(plus, rotation_from_axis_angle(axis, theta), atol=1e-15)
    np.testing.assert_allclose(
        plus, pin.Quaternion(w, *v).toRotationMatrix(), atol=1e-15
    )
    # Eq. (4)'s u (minus sign) is the axis of the frame rotation: Rot(u, θ)^T.
    np.testing.assert_allclose(_kang_eq5(w, *(-v)), plus.T, atol=1e-15)


def test_kang_eq4_eq5_path_reaches_r2_and_equals_the_workbench(rng):
    """Through eq. (5) and eq. (4) alike, R -> q -> R(t) reaches R2 in every case.

    §4: q from R = R1^T R2 by eq. (5); u and θ12 from q by eq. (4); θ(t) by the
    trapezoid; R(t) = R1 · eq5(eq4(u, θ(t))). The same passive pair both ways is
    consistent; it traces the workbench's R1 Rot(u_active, θ(t)) exactly.
    """
    pairs = [(_random_rotation(rng), _random_rotation(rng)) for _ in range(200)]
    near_pi = rotation_from_axis_angle([0.0, 0.6, 0.8], math.pi - 1e-9)
    pairs += [(np.eye(3), near_pi), (near_pi, np.eye(3))]
    for r1, r2 in pairs:
        q = _kang_eq5_inverse(r1.T @ r2)
        np.testing.assert_allclose(_kang_eq5(*q), r1.T @ r2, atol=ATOL_EXACT)
        half = math.atan2(np.linalg.norm(q[1:]), q[0])
        u_kang = -q[1:] / math.sin(half)  # eq. (4): q_vec = -u sin(θ/2)
        profile = orientation(r1, r2, 0.8, 2.0)
        for t in np.linspace(0.0, profile.duration, 7):
            theta = profile.profile.sample(t)[0]
            kang_t = r1 @ _kang_eq5(
                math.cos(theta / 2), *(-u_kang * math.sin(theta / 2))
            )
            np.testing.assert_allclose(kang_t, profile.sample(t)[0], atol=ATOL_EXACT)
        np.testing.assert_allclose(kang_t, r2, atol=ATOL_EXACT)
        # Only a mix fails: eq. (4)'s u in the active Rodrigues formula.
        if 1e-3 < 2 * half < math.pi - 1e-3:
            mixed = r1 @ rotation_from_axis_angle(u_kang, 2 * half)
            assert np.abs(mixed - r2).max() > 1e-3


def test_vi_vf_flags_pass_through():
    r2 = rotation_from_axis_angle([0.0, 0.0, 1.0], 1.0)
    rot = orientation(np.eye(3), r2, 0.5, 1.0, initial_velocity=0.5, final_velocity=0.5)
    assert rot.duration == pytest.approx(2.0, abs=ATOL_EXACT)
    np.testing.assert_allclose(rot.sample(0.0)[1], [0.0, 0.0, 0.5], atol=ATOL_EXACT)


@pytest.mark.parametrize(
    ("args", "error", "fragment"),
    [
        ((np.eye(3), np.eye(3), 0.0, 1.0), InputError, "max_velocity must be > 0"),
        ((np.eye(3), np.eye(3), 1.0, -1.0), InputError, "max_acceleration must be > 0"),
        ((np.eye(3), np.eye(3), math.nan, 1.0), NonFiniteError, "max_velocity"),
        ((np.full((3, 3), np.nan), np.eye(3), 1.0, 1.0), NonFiniteError, "finite"),
        ((2 * np.eye(3), np.eye(3), 1.0, 1.0), InputError, "not a rotation"),
        ((np.eye(3), -np.eye(3), 1.0, 1.0), InputError, "not a rotation"),
        ((np.eye(2), np.eye(3), 1.0, 1.0), InputError, "shape"),
    ],
)
def test_bad_input(args, error, fragment):
    with pytest.raises(error, match=fragment):
        orientation(*args)


def test_infeasible_end_speed():
    r2 = rotation_from_axis_angle([0.0, 0.0, 1.0], 0.01)
    with pytest.raises(InfeasibleError, match="too short to accelerate"):
        orientation(np.eye(3), r2, 1.0, 1.0, final_velocity=1.0)
