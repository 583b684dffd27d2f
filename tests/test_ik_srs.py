"""The closed form of SRS seven-axis arms (``workbench.ik._srs_kernel``) on the iiwa14.

Every branch is checked against Pinocchio's forward kinematics, the arm angle
against its definition (the elbow point turned about SW, the reference arm with
θ3 = 0), the round trip q → (pose, ψ) → q, the batch against the one-pose
kernel, a multi-start numerical IK with the arm-angle constraint, and the
analytic feasible intervals against a dense ψ grid.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from workbench import Robot, load_robot
from workbench.ik import _srs_kernel as kernel
from workbench.ik._redundant_common import (
    ELBOW_SINGULAR,
    NOT_RIGID,
    OK,
    OUT_OF_REACH,
    PARAMETER_SINGULAR,
    SHOULDER_SINGULAR,
    WITHIN_LIMITS,
    WRIST_SINGULAR,
)
from workbench.ik._srs_intervals import compute_feasible_intervals
from workbench.ik.structure import get_structure
from workbench.model.dh import DHJoint, DHTable
from workbench.model.urdf_generator import generate_urdf

#: Joint values recovered by the round trip [rad] (mod 2π).
ATOL_Q = 1e-9
#: FK residual of every returned branch against Pinocchio [m, 1].
ATOL_POSE = 1e-12
#: Arm angle agreement [rad].
ATOL_PSI = 1e-9
#: Interval ends: the limit a joint hits there [rad]; grid points this near an
#: end are not judged.
ATOL_END = 1e-9
#: Limits as the kernel's WITHIN_LIMITS flag widens them [rad].
LIMIT_TOL = 1e-9
#: Rounding of the target pose (ulps of its entries, through Pinocchio's FK
#: and the kernel) that the angles the pose leaves ill-determined amplify by
#: 1 / |sin|: near a singularity a joint is recovered to ATOL_Q +
#: CONDITION_ULPS / |sin| only [rad] (measured: about 6e-14 / |sin|).
CONDITION_ULPS = 1e-13
#: The law of cosines knows |θ4| to about √ulp near the stretched elbow [rad].
STRETCHED_THETA4 = 1e-8


@pytest.fixture(scope="module")
def iiwa() -> Robot:
    return load_robot("iiwa14")


@pytest.fixture(scope="module")
def geometry(iiwa: Robot) -> np.ndarray:
    structure = get_structure(iiwa)
    assert structure.family == "srs"
    model = iiwa.model
    return kernel.pack_geometry(
        structure, model.lowerPositionLimit, model.upperPositionLimit
    )


def _fk(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Pinocchio's (4, 4) pose of the tool frame."""
    return robot.fk(q).homogeneous


def _poses(robot: Robot, qs: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray([_fk(robot, q) for q in qs])


def _psi(geometry: np.ndarray, qs: np.ndarray) -> np.ndarray:
    out = np.empty(len(qs))
    kernel.parameter_of(geometry, np.ascontiguousarray(qs, dtype=float), out)
    return out


def _solve(geometry, pose, psi, previous=None):
    q = np.empty((8, 7))
    flags = np.empty(8, dtype=np.uint8)
    prev = np.empty(0) if previous is None else np.asarray(previous, float)
    status = kernel.solve_pose(geometry, pose, psi, prev, q, flags, True)
    return status, q, flags


def _wrapped(a: np.ndarray) -> np.ndarray:
    return np.abs(np.remainder(a + math.pi, 2.0 * math.pi) - math.pi)


def _distance_to_branches(q_branches: np.ndarray, q: np.ndarray) -> float:
    """Smallest max-abs joint difference (mod 2π) of q to any branch row."""
    return float(np.nanmin(_wrapped(q_branches - q).max(axis=-1)))


def _random_in_limits(iiwa: Robot, rng: np.random.Generator, n: int) -> np.ndarray:
    model = iiwa.model
    return rng.uniform(model.lowerPositionLimit, model.upperPositionLimit, (n, 7))


# --- labels, definition of the arm angle ------------------------------------


def test_branch_labels_and_order() -> None:
    assert len(kernel.BRANCHES) == 8
    assert kernel.BRANCHES[0] == "shoulder-pos/elbow-pos/wrist-pos"
    assert kernel.BRANCHES[5] == "shoulder-neg/elbow-pos/wrist-neg"
    assert kernel.PARAMETER == "arm angle"
    assert kernel.parameter_range(np.empty(0)) == (-math.pi, math.pi)


def test_branch_index_is_the_sign_pattern(iiwa, geometry, rng) -> None:
    for q in _random_in_limits(iiwa, rng, 200):
        _, qs, _ = _solve(geometry, _fk(iiwa, q), rng.uniform(-math.pi, math.pi))
        for b in range(8):
            s = np.sin(qs[b])
            assert (s[1] < 0, s[3] < 0, s[5] < 0) == (
                bool(b >> 2 & 1),
                bool(b >> 1 & 1),
                bool(b & 1),
            )


def _elbow_and_wrist(robot: Robot, q: np.ndarray):
    """Pinocchio's S, E (joint 4 origin) and W (joint 6 origin) [m]."""
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, q)
    return (
        data.oMi[2].translation.copy(),
        data.oMi[4].translation.copy(),
        data.oMi[6].translation.copy(),
    )


def test_arm_angle_turns_the_elbow_about_sw(iiwa, geometry, rng) -> None:
    """All eight branches of one ψ share one elbow point, at angle ψ about SW."""
    for q in _random_in_limits(iiwa, rng, 50):
        pose = _fk(iiwa, q)
        _, q0, _ = _solve(geometry, pose, 0.0)
        shoulder, elbow0, wrist = _elbow_and_wrist(iiwa, q0[0])
        u = (wrist - shoulder) / np.linalg.norm(wrist - shoulder)
        r0 = elbow0 - shoulder - np.dot(elbow0 - shoulder, u) * u
        for psi in rng.uniform(-math.pi, math.pi, 5):
            _, qs, _ = _solve(geometry, pose, psi)
            for b in range(8):
                _, elbow, _ = _elbow_and_wrist(iiwa, qs[b])
                r = elbow - shoulder - np.dot(elbow - shoulder, u) * u
                angle = math.atan2(np.dot(np.cross(r0, r), u), np.dot(r0, r))
                assert _wrapped(np.array(angle - psi)) <= ATOL_PSI


def test_reference_arm_has_theta3_zero(iiwa, geometry, rng) -> None:
    """At ψ = 0 the elbow-pos arm with θ1 = atan2(SW_y, SW_x) has θ3 = 0 (DH)."""
    for q in _random_in_limits(iiwa, rng, 100):
        _, qs, _ = _solve(geometry, _fk(iiwa, q), 0.0)
        shoulder, _, wrist = _elbow_and_wrist(iiwa, q)
        azimuth = math.atan2(*(wrist - shoulder)[1::-1])
        matches = [
            b
            for b in (0, 1, 4, 5)  # elbow-pos
            if _wrapped(np.array(qs[b, 0] - azimuth)) <= ATOL_Q
        ]
        assert matches
        for b in matches:
            assert _wrapped(np.array(qs[b, 2])) <= ATOL_Q


# --- round trips ----------------------------------------------------------


def _round_trip(iiwa, geometry, qs: np.ndarray) -> tuple[float, float]:
    """Worst q recovery and worst FK residual of solve_batch, all branches."""
    poses = _poses(iiwa, qs)
    psi = _psi(geometry, qs)
    q_out = np.empty((len(qs), 8, 7))
    valid = np.empty((len(qs), 8), dtype=bool)
    kernel.solve_batch(geometry, poses, psi, q_out, valid)
    assert valid.all()
    recovered = max(_distance_to_branches(q_out[i], qs[i]) for i in range(len(qs)))
    residual = 0.0
    for i in range(len(qs)):
        for b in range(8):
            residual = max(residual, np.abs(_fk(iiwa, q_out[i, b]) - poses[i]).max())
    return recovered, residual


@pytest.mark.slow
def test_round_trip_within_limits(iiwa, geometry, rng) -> None:
    qs = _random_in_limits(iiwa, rng, 10_000)
    recovered, residual = _round_trip(iiwa, geometry, qs)
    assert recovered <= ATOL_Q
    assert residual <= ATOL_POSE


@pytest.mark.slow
def test_round_trip_outside_limits(iiwa, geometry, rng) -> None:
    qs = rng.uniform(-3.0 * math.pi, 3.0 * math.pi, (10_000, 7))
    recovered, residual = _round_trip(iiwa, geometry, qs)
    assert recovered <= ATOL_Q
    assert residual <= ATOL_POSE


def _measures(robot: Robot, q: np.ndarray) -> np.ndarray:
    """|sin θ2|, |sin θ4|, |sin θ6|, |SW_xy| / |SW| of q (iiwa: DH θ = q), ascending."""
    shoulder, _, wrist = _elbow_and_wrist(robot, q)
    sw = wrist - shoulder
    sines = np.abs(np.sin(q[[1, 3, 5]]))
    return np.sort([*sines, np.linalg.norm(sw[:2]) / np.linalg.norm(sw)])


def _condition(robot: Robot, q: np.ndarray) -> float:
    """The least of :func:`_measures`: how near q is to a singularity."""
    return float(_measures(robot, q)[0])


def _round_trip_bound(robot: Robot, q: np.ndarray) -> float:
    """How far the branch holding q may be from it [rad]: ulps over the conditions.

    Near one singularity the recovered angles lose ulps / c; where two meet
    (the shoulder and the elbow both within 1e-4 of theirs, the wrist centre
    then near axis 1) they lose ulps / (c1 c2), the product of the two least.
    """
    first, second = (float(c) for c in _measures(robot, q)[:2])
    product = first * second
    return ATOL_Q + CONDITION_ULPS / product if product > 0.0 else math.inf


@settings(max_examples=300)
@given(
    st.lists(st.floats(-math.pi, math.pi, allow_nan=False), min_size=7, max_size=7),
    st.floats(-math.pi, math.pi, allow_nan=False),
)
@example([0.0, 1e-4, 1.0, 1e-4, 0.0, 1.0, 0.0], 0.0)  # shoulder and elbow near theirs
def test_round_trip_property(iiwa, geometry, values, turn) -> None:
    """solve_pose(fk(q), ψ(q)) holds q; at ψ + turn every branch reaches, ψ holds."""
    q = np.array(values)
    pose = _fk(iiwa, q)
    psi = _psi(geometry, q[None])[0]
    status, qs, _ = _solve(geometry, pose, psi)
    assert status == OK
    assert _distance_to_branches(qs, q) <= _round_trip_bound(iiwa, q)
    status, qs, _ = _solve(geometry, pose, psi + turn)
    for b in range(8):
        assert np.abs(_fk(iiwa, qs[b]) - pose).max() <= ATOL_POSE
        if _condition(iiwa, qs[b]) > 1e-6:
            back = _psi(geometry, qs[b][None])[0]
            assert _wrapped(np.array(back - psi - turn)) <= ATOL_PSI


def test_batch_equals_solve_pose(iiwa, geometry, rng) -> None:
    qs = np.concatenate(
        [_random_in_limits(iiwa, rng, 300), rng.uniform(-4, 4, (300, 7))]
    )
    poses = _poses(iiwa, qs)
    values = rng.uniform(-4.0, 4.0, len(qs))
    q_out = np.empty((len(qs), 8, 7))
    valid = np.empty((len(qs), 8), dtype=bool)
    kernel.solve_batch(geometry, poses, values, q_out, valid)
    for i in range(len(qs)):
        status, q_one, _ = _solve(geometry, poses[i], values[i])
        assert status == OK
        np.testing.assert_array_equal(q_out[i], q_one)


def test_nearest_previous(iiwa, geometry, rng) -> None:
    """With q_previous every angle is its representative nearest q_previous."""
    for q in _random_in_limits(iiwa, rng, 200):
        previous = q + rng.choice([-2.0, 0.0, 2.0], 7) * math.pi
        pose = _fk(iiwa, q)
        _, qs, _ = _solve(geometry, pose, _psi(geometry, q[None])[0], previous)
        assert np.all(np.abs(qs - previous) <= math.pi + 1e-12)
        assert np.abs(qs - q - (previous - q)).max(axis=1).min() <= ATOL_Q


# --- singularities -------------------------------------------------------------


SMALL = (1e-6, 1e-7, 1e-9, 1e-12, 0.0)


def _near_singular(rng: np.random.Generator, joint: int, angle: float, n: int):
    qs = rng.uniform(-2.0, 2.0, (n, 7))
    qs[:, joint] = angle * rng.choice([-1.0, 1.0], n)
    return qs


@pytest.mark.parametrize(
    "joint, bit", [(1, SHOULDER_SINGULAR), (3, ELBOW_SINGULAR), (5, WRIST_SINGULAR)]
)
@pytest.mark.parametrize("small", SMALL)
def test_near_singular_round_trip(iiwa, geometry, rng, joint, bit, small) -> None:
    """Every branch reaches the pose; q recovered to its condition; flags."""
    for q in _near_singular(rng, joint, small, 200):
        pose = _fk(iiwa, q)
        psi = _psi(geometry, q[None])[0]
        for previous in (None, q):
            status, qs, flags = _solve(geometry, pose, psi, previous)
            assert status == OK
            for b in range(8):
                assert np.abs(_fk(iiwa, qs[b]) - pose).max() <= ATOL_POSE
                sine = abs(math.sin(qs[b, joint]))
                tol = kernel.ELBOW_SINGULAR_TOL if joint == 3 else kernel.SINGULAR_TOL
                if abs(sine - tol) > 1e-15:
                    assert bool(flags[b] & bit) == (sine <= tol)
            if joint == 3:  # |θ4| to √ulp, the wrist's angles to that / |sin|
                others = np.abs(np.sin(q[[1, 5]])).min()
                bound = ATOL_Q + CONDITION_ULPS / max(small, STRETCHED_THETA4) / others
            elif previous is not None and small <= kernel.SPLIT_TOL:
                bound = ATOL_Q  # θ1 or θ5 taken from q_previous
            else:
                bound = ATOL_Q + CONDITION_ULPS / max(small, 1e-300)
            assert _distance_to_branches(qs, q) <= bound
            if small == 0.0:
                assert np.all(flags & bit)
            elif small >= 1e-6:
                assert not np.any(flags & bit)


def _wrist_on_axis_1(rng: np.random.Generator, n: int, offset: float) -> np.ndarray:
    """Configurations with W on axis 1 (θ2 from θ4, θ3 = 0), θ2 moved by offset."""
    qs = rng.uniform(-2.0, 2.0, (n, 7))
    qs[:, 2] = 0.0
    qs[:, 3] = rng.uniform(0.2, 2.0, n) * rng.choice([-1.0, 1.0], n)
    # iiwa: SW in frame 2 = (−s4 d5, 0, d3 + c4 d5); vertical when θ2 turns it up
    vx, vz = -np.sin(qs[:, 3]) * 0.40, 0.42 + np.cos(qs[:, 3]) * 0.40
    qs[:, 1] = np.arctan2(-vx, vz) + offset
    return qs


@pytest.mark.parametrize("offset", SMALL)
def test_wrist_near_axis_1(iiwa, geometry, rng, offset) -> None:
    """The algorithmic singularity: ψ finite, flagged on the axis, branches reach."""
    for q in _wrist_on_axis_1(rng, 100, offset):
        pose = _fk(iiwa, q)
        shoulder, _, wrist = _elbow_and_wrist(iiwa, q)
        rho = np.linalg.norm((wrist - shoulder)[:2])
        psi = _psi(geometry, q[None])[0]
        assert math.isfinite(psi)
        status, qs, flags = _solve(geometry, pose, psi)
        assert status == OK
        for b in range(8):
            assert np.abs(_fk(iiwa, qs[b]) - pose).max() <= ATOL_POSE
        # ψ's reference turns with atan2(SW_y, SW_x): known to ulp / ρ only
        assert _distance_to_branches(qs, q) <= ATOL_Q + CONDITION_ULPS / max(
            rho, 1e-300
        )
        on_axis = rho <= kernel.SINGULAR_TOL * np.linalg.norm(wrist - shoulder)
        assert np.all(flags & PARAMETER_SINGULAR) == on_axis or rho < 1e-15


def test_exactly_on_axis_1_takes_theta1_zero(geometry) -> None:
    """On axis 1 the reference takes θ1° = 0: ψ(q) = θ1 for the stretched-up-…"""
    q = np.array([0.7, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0])
    q[1] = math.atan2(math.sin(0.5) * 0.40, 0.42 + math.cos(0.5) * 0.40)
    psi_a = _psi(geometry, q[None])[0]
    q_turned = q.copy()
    q_turned[0] += 0.3
    psi_b = _psi(geometry, q_turned[None])[0]
    # turning joint 1 turns the arm about SW (= axis 1) by the same angle
    assert _wrapped(np.array(psi_b - psi_a - 0.3)) <= ATOL_PSI


# --- multi-start numerical IK with the arm-angle constraint ---------------------


def _numeric_solutions(iiwa, geometry, pose, psi, rng, starts=50):
    """Gauss-Newton on [log6(T⁻¹ FK(q)); ψ(q) − ψ*] from random starts."""
    model, data = iiwa.model, iiwa.model.createData()
    frame = iiwa.tool_frame_id
    target = pin.SE3(pose[:3, :3], pose[:3, 3])
    found = []
    for q in rng.uniform(-math.pi, math.pi, (starts, 7)):
        for _ in range(60):
            pin.framesForwardKinematics(model, data, q)
            err6 = pin.log6(target.actInv(data.oMf[frame])).vector
            jac = pin.Jlog6(target.actInv(data.oMf[frame])) @ pin.computeFrameJacobian(
                model, data, q, frame, pin.ReferenceFrame.LOCAL
            )
            h = 1e-6
            plus = q + h * np.eye(7)
            minus = q - h * np.eye(7)
            grad = (_psi(geometry, plus) - _psi(geometry, minus)) / (2 * h)
            grad = np.remainder(grad * 2 * h + math.pi, 2 * math.pi) - math.pi
            grad /= 2 * h
            dpsi = np.remainder(_psi(geometry, q[None])[0] - psi + math.pi, 2 * math.pi)
            residual = np.concatenate([err6, [dpsi - math.pi]])
            if np.abs(residual).max() < 1e-13:
                break
            step = np.linalg.lstsq(np.vstack([jac, grad]), -residual, rcond=None)[0]
            norm = np.linalg.norm(step)
            q = q + (step if norm < 0.5 else step * 0.5 / norm)
        else:
            continue
        found.append(q.copy())
    return found


@pytest.mark.slow
def test_multi_start_numerical_ik_agrees(iiwa, geometry, rng) -> None:
    found_total, distinct = 0, 0
    for q in _random_in_limits(iiwa, rng, 200):
        pose = _fk(iiwa, q)
        psi = rng.uniform(-math.pi, math.pi)
        _, qs, _ = _solve(geometry, pose, psi)
        solutions = _numeric_solutions(iiwa, geometry, pose, psi, rng, starts=50)
        labels = set()
        for s in solutions:
            d = _wrapped(qs - s).max(axis=1)
            assert d.min() <= ATOL_Q
            labels.add(int(d.argmin()))
        found_total += len(solutions)
        distinct += len(labels)
    assert found_total >= 200 * 45  # measured: 9 916 of 10 000 starts converge
    assert distinct >= 200 * 7  # and find 7.99 of the 8 branches per pose


# --- flags, bad input, diagnose, track -------------------------------------


def test_within_limits_flag(iiwa, geometry, rng) -> None:
    model = iiwa.model
    low, high = model.lowerPositionLimit, model.upperPositionLimit
    for q in rng.uniform(-3.2, 3.2, (300, 7)):
        _, qs, flags = _solve(geometry, _fk(iiwa, q), rng.uniform(-3, 3))
        inside = np.all((qs >= low - LIMIT_TOL) & (qs <= high + LIMIT_TOL), axis=1)
        np.testing.assert_array_equal((flags & WITHIN_LIMITS) != 0, inside)


def test_not_rigid_and_out_of_reach(iiwa, geometry) -> None:
    pose = _fk(iiwa, np.zeros(7))
    bad = pose.copy()
    bad[0, 0] = 2.0
    status, qs, flags = _solve(geometry, bad, 0.0)
    assert status == NOT_RIGID
    assert np.isnan(qs).all() and not flags.any()
    assert kernel.diagnose(geometry, bad, 0.0)[0] == NOT_RIGID
    far = pose.copy()
    far[:3, 3] = [2.0, 0.0, 0.5]
    status, qs, flags = _solve(geometry, far, 0.0)
    assert status == OUT_OF_REACH
    assert np.isnan(qs).all() and not flags.any()
    code, distance, low, high = kernel.diagnose(geometry, far, 1.0)
    assert code == OUT_OF_REACH
    wrist = far[:3, 3] - 0.126 * far[:3, 2] - np.array([0.0, 0.0, 0.36])
    assert distance == pytest.approx(np.linalg.norm(wrist), abs=1e-15)
    assert (low, high) == pytest.approx((0.02, 0.82), abs=1e-15)
    q_out = np.empty((1, 8, 7))
    valid = np.empty((1, 8), dtype=bool)
    kernel.solve_batch(geometry, far[None], np.zeros(1), q_out, valid)
    assert np.isnan(q_out).all() and not valid.any()
    assert compute_feasible_intervals(geometry, far) == [[] for _ in range(8)]


def test_stretched_elbow_is_reached(iiwa, geometry) -> None:
    """A pose at the stretched arm, rounded outward, is clipped, not refused."""
    q = np.array([0.3, 0.5, -0.2, 0.0, 0.4, 0.6, 0.1])
    status, _, flags = _solve(geometry, _fk(iiwa, q), 0.0)
    assert status == OK
    assert np.all(flags & ELBOW_SINGULAR)
    assert kernel.diagnose(geometry, _fk(iiwa, q), 0.0)[0] == OK


def test_track_keeps_the_branch(iiwa, geometry, rng) -> None:
    for q in _random_in_limits(iiwa, rng, 100):
        pose = _fk(iiwa, q)
        psi = _psi(geometry, q[None])[0]
        _, qs, flags = _solve(geometry, pose, psi)
        b = int(_wrapped(qs - q).max(axis=1).argmin())
        q_out = np.empty(7)
        status, index, within = kernel.track(
            geometry, pose, psi, q + 1e-4, b, 1e-2, q_out
        )
        assert (status, index) == (OK, b)
        np.testing.assert_allclose(q_out, q, rtol=0, atol=ATOL_Q)
        assert within == bool(flags[b] & WITHIN_LIMITS)
        other = (b + 1) % 8
        status, index, _ = kernel.track(geometry, pose, psi, q, other, 1e-6, q_out)
        assert index == b  # too far from `other`: the nearest of all
    status, index, within = kernel.track(
        geometry, np.eye(4) * 2.0, 0.0, np.zeros(7), 0, 1.0, np.empty(7)
    )
    assert (status, index, within) == (NOT_RIGID, -1, False)


# --- feasible intervals ------------------------------------------------------


def _grid_within(iiwa, geometry, pose, grid):
    n = grid.size
    q = np.empty((n, 8, 7))
    valid = np.empty((n, 8), dtype=bool)
    poses = np.ascontiguousarray(np.broadcast_to(pose, (n, 4, 4)))
    kernel.solve_batch(geometry, poses, grid, q, valid)
    model = iiwa.model
    inside = (q >= model.lowerPositionLimit) & (q <= model.upperPositionLimit)
    return valid & inside.all(axis=2), q


@pytest.mark.slow
def test_feasible_intervals_against_a_dense_grid(iiwa, geometry, rng) -> None:
    grid = np.linspace(-math.pi, math.pi, 100_001)
    model = iiwa.model
    low, high = model.lowerPositionLimit, model.upperPositionLimit
    counted = 0
    for q in _random_in_limits(iiwa, rng, 40):
        pose = _fk(iiwa, q)
        intervals = compute_feasible_intervals(geometry, pose)
        within, _ = _grid_within(iiwa, geometry, pose, grid)
        assert any(
            lo - ATOL_END <= _psi(geometry, q[None])[0] <= hi + ATOL_END
            for branch in intervals
            for lo, hi in branch
        )
        for b, branch in enumerate(intervals):
            member = np.zeros(grid.size, dtype=bool)
            near_end = np.zeros(grid.size, dtype=bool)
            for lo, hi in branch:
                assert -math.pi <= lo <= hi <= math.pi
                member |= (grid >= lo) & (grid <= hi)
                for end in (lo, hi):
                    near_end |= np.abs(grid - end) <= ATOL_END
                    if abs(end) == math.pi:
                        continue
                    _, qs, _ = _solve(geometry, pose, end)
                    hit = np.minimum(np.abs(qs[b] - low), np.abs(qs[b] - high))
                    assert hit.min() <= ATOL_END
                    counted += 1
            assert all(a[1] < c[0] for a, c in itertools.pairwise(branch))
            np.testing.assert_array_equal(
                member[~near_end], within[~near_end, b], err_msg=f"branch {b}"
            )
    assert counted > 100


@pytest.mark.slow
def test_feasible_interval_of_a_joint_with_a_stationary_point(iiwa, geometry) -> None:
    """θ1(ψ) that turns back: two limit hits of one joint, both found."""
    rng = np.random.default_rng(7)
    grid = np.linspace(-math.pi, math.pi, 20_001)
    checked = 0
    for q in _random_in_limits(iiwa, rng, 100):
        pose = _fk(iiwa, q)
        within, qs = _grid_within(iiwa, geometry, pose, grid)
        slope = np.diff(np.unwrap(qs[:, 0, 0]))
        if not (slope.max() > 0.0 > slope.min()):
            continue  # monotonic θ1(ψ)
        intervals = compute_feasible_intervals(geometry, pose)
        member = np.zeros(grid.size, dtype=bool)
        for lo, hi in intervals[0]:
            member |= (grid >= lo - ATOL_END) & (grid <= hi + ATOL_END)
        np.testing.assert_array_equal(member | ~within[:, 0], np.ones(grid.size, bool))
        checked += 1
    assert checked >= 10


# --- other DH sign conventions and lengths ---------------------------------------

#: α signs of joints 1..6: this project's iiwa14 table (Faria et al. 2018), the
#: KUKA LWR4 table of Enayati's implementation of Shimizu's method, and
#: Shimizu's own (PA10-like) table.
SIGN_TABLES = {
    "faria": (-1, 1, 1, -1, -1, 1),
    "lwr4": (1, -1, -1, 1, 1, -1),
    "shimizu": (-1, 1, -1, 1, -1, 1),
}


def _srs_robot(tmp_path, signs, lengths=(0.31, 0.40, 0.39, 0.078)) -> Robot:
    """An SRS arm generated from a DH table with these α signs and d1, d3, d5, d7."""
    d1, d3, d5, d7 = lengths
    ds = (d1, 0.0, d3, 0.0, d5, 0.0, d7)
    alphas = (*(s * math.pi / 2 for s in signs), 0.0)
    table = DHTable(
        name="srs_test",
        joints=tuple(
            DHJoint(alpha=a, a=0.0, d=d, lower=-2.9, upper=2.9)
            for a, d in zip(alphas, ds, strict=True)
        ),
        tool_frame="flange",
    )
    path = tmp_path / "srs_test.urdf"
    path.write_text(generate_urdf(table))
    return load_robot(path, tool_frame="flange")


@pytest.mark.parametrize("convention", sorted(SIGN_TABLES))
def test_other_sign_conventions_and_lengths(tmp_path, rng, convention) -> None:
    """The kernel takes every sign and length from the fitted chain."""
    robot = _srs_robot(tmp_path, SIGN_TABLES[convention])
    structure = get_structure(robot)
    assert structure.family == "srs"
    model = robot.model
    geometry = kernel.pack_geometry(
        structure, model.lowerPositionLimit, model.upperPositionLimit
    )
    qs = rng.uniform(-math.pi, math.pi, (1_000, 7))
    recovered, residual = _round_trip(robot, geometry, qs)
    assert recovered <= ATOL_Q
    assert residual <= ATOL_POSE
    for q in qs[:20]:  # all branches of one ψ share the elbow, turned by ψ
        pose = _fk(robot, q)
        _, q0, _ = _solve(geometry, pose, 0.0)
        _, q1, _ = _solve(geometry, pose, 1.0)
        shoulder, e0, wrist = _elbow_and_wrist(robot, q0[0])
        u = (wrist - shoulder) / np.linalg.norm(wrist - shoulder)
        r0 = e0 - shoulder - np.dot(e0 - shoulder, u) * u
        for b in range(8):
            _, e1, _ = _elbow_and_wrist(robot, q1[b])
            r1 = e1 - shoulder - np.dot(e1 - shoulder, u) * u
            angle = math.atan2(np.dot(np.cross(r0, r1), u), np.dot(r0, r1))
            assert abs(angle - 1.0) <= ATOL_PSI


def _lwr4_printed_angles(frames: np.ndarray) -> np.ndarray:
    """θ1..θ7 by the formulas of the LWR4 implementation of Shimizu's method.

    Enayati's ``LWR4_Kinematics::IK`` (Nearlab, 2016), configuration 0, with
    R03 and R47 the frames' true rotations and θ4 by the law of cosines.
    """
    r03 = frames[3][:3, :3]
    r47 = frames[4][:3, :3].T @ frames[7][:3, :3]
    sw = frames[5][:3, 3] - frames[1][:3, 3]
    d3, d5 = (
        np.linalg.norm(frames[3][:3, 3] - frames[1][:3, 3]),
        np.linalg.norm(frames[5][:3, 3] - frames[3][:3, 3]),
    )
    return np.array(
        [
            math.atan2(r03[1, 1], r03[0, 1]),
            math.acos(-r03[2, 1]),
            math.atan2(-r03[2, 2], r03[2, 0]),
            math.acos((sw @ sw - d3 * d3 - d5 * d5) / (2.0 * d3 * d5)),
            math.atan2(-r47[1, 2], -r47[0, 2]),
            math.acos(r47[2, 2]),
            math.atan2(-r47[2, 1], r47[2, 0]),
        ]
    )


def test_lwr4_formulas_hold_on_their_table_only(rng) -> None:
    """Erratum: the LWR4 table's formulas give π − θ2, π − θ3, θ5 + π, θ7 + π here."""
    faria = DHTable.from_json("urdf/iiwa14.dh.json")
    lwr4 = DHTable(
        name="lwr4",
        joints=tuple(DHJoint(alpha=-j.alpha, a=0.0, d=j.d) for j in faria.joints),
    )
    for q in rng.uniform(-3.0, 3.0, (500, 7)):
        q[[1, 3, 5]] = np.abs(q[[1, 3, 5]])  # configuration 0: θ2, θ4, θ6 > 0
        own = _lwr4_printed_angles(lwr4.frame_transforms(q))
        assert _wrapped(own - q).max() <= ATOL_Q
        printed = _lwr4_printed_angles(faria.frame_transforms(q))
        pi = math.pi
        expected = q + np.array([0.0, 0.0, 0.0, 0.0, pi, 0.0, pi])
        expected[1], expected[2] = pi - q[1], pi - q[2]
        assert _wrapped(printed - expected).max() <= ATOL_Q


def test_reference_with_the_branch_theta4_is_turned_by_pi(iiwa, geometry, rng) -> None:
    """Convention: a reference arm built with θ4 < 0 puts E0 at ψ = π of ours.

    Shimizu's reference arm (θ3 = 0) taken with the elbow-neg branch's own θ4
    mirrors E0 across SW: its arm angles are ours + π on the elbow-neg
    branches. Ours uses θ4 = +|θ4| for every branch, as implementations that
    apply the elbow flip (θ3 + π, −θ4, θ5 + π) after solving do.
    """
    geo = geometry.view(np.recarray)[0]
    for q in _random_in_limits(iiwa, rng, 100):
        shoulder, _, wrist = _elbow_and_wrist(iiwa, q)
        sw = tuple(wrist - shoulder)
        c4 = kernel._elbow_cosine(geo, float(np.dot(sw, sw)))
        s4 = math.sqrt(1.0 - c4 * c4)
        u = np.array(sw) / np.linalg.norm(sw)
        elbows = []
        for sine in (s4, -s4):
            _, col1, _, _ = kernel._reference(geo, sw, c4, sine)
            z2 = geo.sigma[2] * np.array(col1)
            elbows.append(z2 - np.dot(z2, u) * u)
        angle = math.atan2(np.cross(elbows[0], elbows[1]) @ u, elbows[0] @ elbows[1])
        assert abs(abs(angle) - math.pi) <= ATOL_PSI


def _random_rigid(rng: np.random.Generator) -> np.ndarray:
    quat = rng.normal(size=4)
    pose = np.eye(4)
    pose[:3, :3] = pin.Quaternion(*(quat / np.linalg.norm(quat))).matrix()
    pose[:3, 3] = rng.uniform(-0.5, 0.5, 3)
    return pose


def test_base_tool_joint_signs_and_offsets(iiwa, rng) -> None:
    """A chain base · DH(s q + θ0) · tool with all four non-trivial."""
    fitted = get_structure(iiwa)
    offsets = rng.uniform(-math.pi, math.pi, 7)
    table = DHTable(
        name="srs_offsets",
        joints=tuple(
            dataclasses.replace(j, theta_offset=float(o))
            for j, o in zip(fitted.table.joints, offsets, strict=True)
        ),
    )
    signs = tuple(float(s) for s in rng.choice([-1.0, 1.0], 7))
    base, tool = _random_rigid(rng), _random_rigid(rng)
    structure = dataclasses.replace(
        fitted, table=table, joint_sign=signs, base=base, tool=tool
    )
    low, high = np.full(7, -2.5), np.full(7, 2.5)
    geometry = kernel.pack_geometry(structure, low, high)

    def fk(q: np.ndarray) -> np.ndarray:
        return base @ table.forward_kinematics(np.asarray(signs) * q) @ tool

    for q in rng.uniform(-2.5, 2.5, (300, 7)):
        pose = fk(q)
        psi = _psi(geometry, q[None])[0]
        status, qs, flags = _solve(geometry, pose, psi)
        assert status == OK
        assert _distance_to_branches(qs, q) <= ATOL_Q
        for b in range(8):
            assert np.abs(fk(qs[b]) - pose).max() <= ATOL_POSE
            inside = bool(
                np.all((qs[b] >= low - LIMIT_TOL) & (qs[b] <= high + LIMIT_TOL))
            )
            assert bool(flags[b] & WITHIN_LIMITS) == inside
            back = _psi(geometry, qs[b][None])[0]
            assert _wrapped(np.array(back - psi)) <= ATOL_PSI
    grid = np.linspace(-math.pi, math.pi, 20_001)
    for q in rng.uniform(-2.5, 2.5, (10, 7)):
        pose = fk(q)
        n = grid.size
        q_grid = np.empty((n, 8, 7))
        valid = np.empty((n, 8), dtype=bool)
        poses = np.ascontiguousarray(np.broadcast_to(pose, (n, 4, 4)))
        kernel.solve_batch(geometry, poses, grid, q_grid, valid)
        within = valid & np.all((q_grid >= low) & (q_grid <= high), axis=2)
        for b, branch in enumerate(compute_feasible_intervals(geometry, pose)):
            member = np.zeros(n, dtype=bool)
            near_end = np.zeros(n, dtype=bool)
            for lo, hi in branch:
                member |= (grid >= lo) & (grid <= hi)
                near_end |= (np.abs(grid - lo) <= ATOL_END) | (
                    np.abs(grid - hi) <= ATOL_END
                )
            np.testing.assert_array_equal(member[~near_end], within[~near_end, b])
