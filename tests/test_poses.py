"""Tests of workbench.poses: round trips, Pinocchio cross-checks, error paths."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from workbench.errors import DimensionError, InputError, NonFiniteError
from workbench.poses import (
    ANGELES7_PRINTED_TOL,
    ANGELES7_TOL,
    RIGIDITY_TOL,
    angeles4_from_rotation,
    angeles7_from_se3,
    as_se3,
    axis_angle_from_rotation,
    parse_target,
    quat_wxyz_from_rotation,
    quat_xyzw_from_rotation,
    rotation_from_angeles4,
    rotation_from_axis_angle,
    rotation_from_quat_wxyz,
    rotation_from_quat_xyzw,
    se3_from_angeles7,
    se3_from_matrix,
)

ATOL_EXACT = 1e-12
# pin.log3 (Pinocchio 4.1) is off by up to ~6e-11 for pi - phi in [1e-3, 1e-2];
# workbench.poses stays at ~1e-15 there (see test_axis_angle_exact_where_log3_is_not).
ATOL_PIN_LOG3 = 1e-10
# Angeles Table II prints the orientation to 2 decimals: half a unit of the last one.
ATOL_PRINTED = 0.005 + 1e-12
# Angeles et al. (1988), Table II, pick pose; positions mm -> m.
ANGELES_PICK = np.array([0.68, -0.49, -0.19, -0.52, -0.09407, 0.12540, -0.47055])
N_RANDOM = 500

# Per test, not a global profile: other test modules keep their own settings.
property_test = settings(deadline=None, max_examples=200, database=None)

unit_axes = (
    st.tuples(*[st.floats(-1.0, 1.0)] * 3)
    .map(np.array)
    .filter(lambda a: np.linalg.norm(a) > 0.1)
    .map(lambda a: a / np.linalg.norm(a))
)
angles = st.one_of(
    st.just(0.0),
    st.floats(-9.0, -3.0).map(lambda k: 10.0**k),  # phi near 0
    st.floats(-300.0, -9.0).map(lambda k: 10.0**k),  # |vect|^2 underflows
    st.floats(-12.0, -3.0).map(lambda k: np.pi - 10.0**k),  # phi near pi
    st.floats(0.0, np.pi, exclude_max=True),
)
positions = st.tuples(*[st.floats(-2.0, 2.0)] * 3).map(np.array)


def _close(actual, desired, atol=ATOL_EXACT):
    np.testing.assert_allclose(actual, desired, rtol=0, atol=atol)


def _canonical_pin_quat_wxyz(rotation):
    """Quaternion from Eigen (independent of workbench), w >= 0, scalar first."""
    xyzw = pin.Quaternion(rotation).coeffs()
    xyzw = -xyzw if xyzw[3] < 0.0 else xyzw
    return np.roll(xyzw, 1)


def _random_rotations(n):
    rng = np.random.default_rng(0)
    quats = rng.normal(size=(n, 4))
    quats /= np.linalg.norm(quats, axis=1, keepdims=True)
    return [pin.Quaternion(*q).toRotationMatrix() for q in quats]  # (w, x, y, z)


# --- definitions on explicit examples -------------------------------------------


def test_angeles7_of_quarter_turn_about_z():
    rotation = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    x = angeles7_from_se3(pin.SE3(rotation, np.array([0.1, -0.2, 0.3])))
    _close(x, [0.0, 0.0, 1.0, 0.0, 0.1, -0.2, 0.3])


def test_angeles7_of_sixty_degrees_about_x():
    c, s = np.cos(np.pi / 3), np.sin(np.pi / 3)
    rotation = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    _close(angeles4_from_rotation(rotation), [s, 0.0, 0.0, c])


def test_angeles7_of_identity():
    _close(angeles7_from_se3(np.eye(4)), [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])


def test_vect_and_trace_definitions_on_random_rotations():
    for rotation in _random_rotations(N_RANDOM):
        r = rotation
        x = angeles4_from_rotation(r)
        vect = 0.5 * np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
        _close(x[:3], vect)
        _close(1.0 + 2.0 * x[3], np.trace(r))


def test_half_turn_has_zero_vect_and_canonical_axis():
    rotation = np.diag([-1.0, 1.0, -1.0])  # pi about y
    _close(angeles4_from_rotation(rotation), [0.0, 0.0, 0.0, -1.0])
    axis, angle = axis_angle_from_rotation(rotation)
    _close(axis, [0.0, 1.0, 0.0])
    _close(angle, np.pi)
    _close(quat_wxyz_from_rotation(rotation), [0.0, 0.0, 1.0, 0.0])


def test_axis_of_identity_is_documented_default():
    axis, angle = axis_angle_from_rotation(np.eye(3))
    _close(axis, [1.0, 0.0, 0.0])
    assert angle == 0.0


# --- round trips (hypothesis) ---------------------------------------------------


@property_test
@given(unit_axes, angles, positions)
def test_se3_angeles7_round_trip(axis, angle, position):
    transform = pin.SE3(pin.exp3(axis * angle), position)
    x = angeles7_from_se3(transform)
    back = se3_from_angeles7(x)
    _close(back.homogeneous, transform.homogeneous)
    _close(angeles7_from_se3(back), x)


@property_test
@given(unit_axes, angles, positions)
def test_angeles7_se3_round_trip(axis, angle, position):
    x = np.concatenate([np.sin(angle) * axis, [np.cos(angle)], position])
    _close(angeles7_from_se3(se3_from_angeles7(x)), x)


@property_test
@given(unit_axes, angles)
def test_angeles4_matches_pinocchio_exp3_and_log3(axis, angle):
    rotation = pin.exp3(axis * angle)
    x = angeles4_from_rotation(rotation)
    _close(x, np.append(np.sin(angle) * axis, np.cos(angle)))
    omega = pin.log3(rotation)
    phi = np.linalg.norm(omega)
    expected_v = np.sin(phi) * omega / phi if phi > 0.0 else np.zeros(3)
    _close(x, np.append(expected_v, np.cos(phi)), atol=ATOL_PIN_LOG3)
    _close(rotation_from_angeles4(x), rotation)


@property_test
@given(unit_axes, angles)
def test_rotation_quat_wxyz_round_trip(axis, angle):
    rotation = pin.exp3(axis * angle)
    q = quat_wxyz_from_rotation(rotation)
    assert q[0] >= 0.0
    _close(q, _canonical_pin_quat_wxyz(rotation))
    _close(rotation_from_quat_wxyz(q), rotation)
    _close(quat_wxyz_from_rotation(rotation_from_quat_wxyz(q)), q)
    _close(rotation_from_quat_wxyz(-q), rotation)


@property_test
@given(unit_axes, angles)
def test_quat_wxyz_rotation_round_trip(axis, angle):
    q = np.append(np.cos(angle / 2.0), np.sin(angle / 2.0) * axis)
    _close(rotation_from_quat_wxyz(q), pin.Quaternion(*q).toRotationMatrix())
    _close(quat_wxyz_from_rotation(rotation_from_quat_wxyz(q)), q)


@property_test
@given(unit_axes, angles)
def test_quat_xyzw_is_reordered_wxyz(axis, angle):
    rotation = pin.exp3(axis * angle)
    q_xyzw = quat_xyzw_from_rotation(rotation)
    _close(q_xyzw, np.roll(quat_wxyz_from_rotation(rotation), -1))
    _close(rotation_from_quat_xyzw(q_xyzw), rotation)
    _close(pin.Quaternion(q_xyzw).toRotationMatrix(), rotation)  # xyzw from array


@property_test
@given(unit_axes, angles)
def test_axis_angle_round_trip(axis, angle):
    rotation = pin.exp3(axis * angle)
    e, phi = axis_angle_from_rotation(rotation)
    assert 0.0 <= phi <= np.pi
    _close(np.linalg.norm(e), 1.0)
    _close(e * phi, axis * angle)  # the axis alone is ill-defined as phi -> 0
    _close(e * phi, pin.log3(rotation), atol=ATOL_PIN_LOG3)
    _close(rotation_from_axis_angle(e, phi), rotation)


@property_test
@given(unit_axes, st.floats(-12.0, -1.0).map(lambda k: np.pi - 10.0**k))
def test_axis_near_pi_is_exact(axis, angle):
    e, phi = axis_angle_from_rotation(pin.exp3(axis * angle))
    _close(e, axis)
    _close(phi, angle)


def test_axis_angle_exact_where_log3_is_not():
    angle = 3.1328125  # pi - 8.8e-3, found by hypothesis
    c, s = np.cos(angle), np.sin(angle)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    e, phi = axis_angle_from_rotation(rotation)
    _close(e, [0.0, 0.0, 1.0])
    _close(phi, angle)
    assert abs(np.linalg.norm(pin.log3(rotation)) - angle) < ATOL_PIN_LOG3


@property_test
@given(unit_axes, st.floats(-4.0 * np.pi, 4.0 * np.pi))
def test_rotation_from_axis_angle_matches_exp3(axis, angle):
    _close(rotation_from_axis_angle(axis, angle), pin.exp3(axis * angle))


@property_test
@given(unit_axes, angles, positions)
def test_se3_matrix_round_trip(axis, angle, position):
    transform = pin.SE3(pin.exp3(axis * angle), position)
    _close(se3_from_matrix(transform.homogeneous).homogeneous, transform.homogeneous)
    copy = as_se3(transform)
    assert copy is not transform
    _close(copy.homogeneous, transform.homogeneous)
    _close(as_se3(transform.homogeneous.tolist()).homogeneous, transform.homogeneous)


def test_round_trips_on_random_rotations():
    for rotation in _random_rotations(N_RANDOM):
        _close(rotation_from_angeles4(angeles4_from_rotation(rotation)), rotation)
        _close(rotation_from_quat_wxyz(quat_wxyz_from_rotation(rotation)), rotation)
        _close(rotation_from_axis_angle(*axis_angle_from_rotation(rotation)), rotation)


# --- Angeles Table II, printed to 2 decimals ------------------------------------


def test_table_ii_pick_projects_to_a_rotation():
    transform = se3_from_angeles7(ANGELES_PICK, tol=ANGELES7_PRINTED_TOL)
    r = transform.rotation
    _close(r.T @ r, np.eye(3))
    _close(np.linalg.det(r), 1.0)
    _close(transform.translation, ANGELES_PICK[4:])
    x = angeles7_from_se3(transform)
    _close(x[:4], ANGELES_PICK[:4] / np.linalg.norm(ANGELES_PICK[:4]))
    _close(x[:4], ANGELES_PICK[:4], atol=ATOL_PRINTED)


def test_table_ii_pick_needs_printed_tolerance():
    with pytest.raises(InputError, match=r"unit norm: \|v\|\^2 \+ c\^2 = 1\.009"):
        se3_from_angeles7(ANGELES_PICK)


def test_printed_tolerance_covers_worst_rounding():
    rng = np.random.default_rng(0)
    for _ in range(N_RANDOM):
        x = rng.normal(size=4)
        x /= np.linalg.norm(x)
        printed = np.round(x, 2)
        if np.any(printed[:3]) or printed[3] >= 0.0:
            rotation_from_angeles4(printed, tol=ANGELES7_PRINTED_TOL)
    worst = np.full(4, 0.5) + 0.005  # every component rounded up by 0.005
    assert abs(worst @ worst - 1.0) < ANGELES7_PRINTED_TOL


# --- error paths ----------------------------------------------------------------


@pytest.mark.parametrize(
    ("func", "value", "error", "fragment"),
    [
        (se3_from_angeles7, np.zeros(6), DimensionError, r"\(7,\), got shape \(6,\)"),
        (se3_from_angeles7, [np.nan, 0, 0, 1, 0, 0, 0], NonFiniteError, "finite"),
        (se3_from_angeles7, [0, 0, 0, 2, 0, 0, 0], InputError, "unit norm"),
        (se3_from_angeles7, [0, 0, 0, -1, 0, 0, 0], InputError, "do not fix"),
        (rotation_from_angeles4, np.zeros(3), DimensionError, r"shape \(4,\)"),
        (rotation_from_angeles4, [0, 0, 0.2, 0.9], InputError, "off by"),
        (se3_from_matrix, np.eye(3), DimensionError, r"shape \(4, 4\)"),
        (se3_from_matrix, np.full((4, 4), np.inf), NonFiniteError, "finite"),
        (se3_from_matrix, "abc", NonFiniteError, "numbers"),
        (se3_from_matrix, np.diag([2.0, 1, 1, 1]), InputError, "not orthonormal"),
        (se3_from_matrix, np.diag([1.0, 1, -1, 1]), InputError, "det = -1"),
        (se3_from_matrix, np.diag([1.0, 1, 1, 2]), InputError, "bottom row"),
        (as_se3, np.diag([-1.0, 1, 1, 1]), InputError, "reflection"),
        (as_se3, np.zeros((4, 4, 1)), DimensionError, r"shape \(4, 4\)"),
        (angeles7_from_se3, np.diag([1.0, 1, 1.1, 1]), InputError, "orthonormal"),
        (angeles4_from_rotation, np.eye(4), DimensionError, r"shape \(3, 3\)"),
        (axis_angle_from_rotation, -np.eye(3), InputError, "det"),
        (quat_wxyz_from_rotation, np.full((3, 3), np.nan), NonFiniteError, "finite"),
        (quat_xyzw_from_rotation, np.zeros((3, 3)), InputError, "orthonormal"),
        (rotation_from_quat_wxyz, [1.0, 0, 0], DimensionError, r"shape \(4,\)"),
        (rotation_from_quat_wxyz, [2.0, 0, 0, 0], InputError, r"\|quat_wxyz\| = 2"),
        (rotation_from_quat_wxyz, np.zeros(4), InputError, "unit norm"),
        (rotation_from_quat_xyzw, [0, 0, 0, np.nan], NonFiniteError, "quat_xyzw"),
        (rotation_from_quat_xyzw, [0, 0, 0, 1.1], InputError, r"\|quat_xyzw\|"),
    ],
)
def test_error_paths(func, value, error, fragment):
    with pytest.raises(error, match=fragment):
        func(value)


def test_as_se3_rejects_non_finite_pin_se3():
    with pytest.raises(NonFiniteError, match="finite"):
        as_se3(pin.SE3(np.full((3, 3), np.nan), np.zeros(3)))


def test_as_se3_rejects_non_rigid_pin_se3():
    with pytest.raises(InputError, match="not orthonormal"):
        as_se3(pin.SE3(2.0 * np.eye(3), np.zeros(3)))


def test_rigidity_tolerance_accepts_seven_decimals_and_rejects_beyond():
    matrix = pin.SE3(pin.exp3(np.array([0.3, -1.2, 0.7])), np.ones(3)).homogeneous
    se3_from_matrix(np.round(matrix, 7))
    perturbed = matrix.copy()
    perturbed[0, 0] += 10.0 * RIGIDITY_TOL
    with pytest.raises(InputError, match="max"):
        se3_from_matrix(perturbed)
    se3_from_matrix(perturbed, tol=100.0 * RIGIDITY_TOL)


def test_axis_angle_errors():
    with pytest.raises(InputError, match=r"\|axis\| = 2"):
        rotation_from_axis_angle([0.0, 0.0, 2.0], 1.0)
    with pytest.raises(DimensionError, match="axis"):
        rotation_from_axis_angle([0.0, 1.0], 1.0)
    with pytest.raises(NonFiniteError, match="angle"):
        rotation_from_axis_angle([0.0, 0.0, 1.0], np.nan)
    with pytest.raises(DimensionError, match="angle"):
        rotation_from_axis_angle([0.0, 0.0, 1.0], [1.0, 2.0])


def test_exact_half_turn_angeles7_cannot_be_converted_back():
    x = angeles7_from_se3(np.diag([1.0, -1.0, -1.0, 1.0]))
    _close(x, [0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="rotation matrix or a quaternion"):
        se3_from_angeles7(x)


def test_default_tolerance_is_tight():
    x = np.array([0.0, 0.0, 0.0, 1.0 + 2.0 * ANGELES7_TOL])
    with pytest.raises(InputError, match="norm"):
        rotation_from_angeles4(x)
    _close(rotation_from_angeles4(x, tol=10.0 * ANGELES7_TOL), np.eye(3))


def test_parse_target_forms_give_one_pose() -> None:
    pose = pin.SE3(pin.exp3(np.array([0.3, -0.5, 0.9])), np.array([0.4, -0.2, 0.6]))
    matrix = parse_target(pose.homogeneous.ravel().tolist(), "matrix")
    assert np.array_equal(matrix.homogeneous, pose.homogeneous)  # kept as given
    typed = [*pose.translation, *quat_wxyz_from_rotation(pose.rotation)]
    quat = parse_target(typed, "xyz_quat_wxyz")
    seven = parse_target(angeles7_from_se3(pose).tolist(), "angeles7")
    for other in (quat, seven):
        np.testing.assert_allclose(
            other.homogeneous, pose.homogeneous, rtol=0, atol=ATOL_EXACT
        )
    mm = [*(1e3 * pose.translation), *quat_wxyz_from_rotation(pose.rotation)]
    np.testing.assert_allclose(
        parse_target(mm, "xyz_quat_wxyz", scale=1e-3).translation,
        pose.translation,
        rtol=0,
        atol=ATOL_EXACT,
    )


@pytest.mark.parametrize(
    ("values", "form", "fragment"),
    [
        ([0.0] * 7, "euler", "target form must be one of angeles7, matrix"),
        ([0.0] * 6, "xyz_quat_wxyz", "has 7 values, got 6"),
        ([2e6, 0, 0, 1, 0, 0, 0], "xyz_quat_wxyz", "too far"),
        ([0, 0, 0, 1.1, 0, 0, 0], "xyz_quat_wxyz", "quat"),
        ([0, 0, 0, float("nan"), 0, 0, 0], "xyz_quat_wxyz", "finite"),
        ([1.0] + [0.0] * 15, "matrix", "bottom row"),
    ],
)
def test_parse_target_refuses_bad_numbers(values, form, fragment) -> None:
    with pytest.raises(InputError, match=fragment):
        parse_target(values, form)
