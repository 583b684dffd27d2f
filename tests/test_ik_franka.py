"""Closed form of Franka-type arms for a given q7 and its feasible q7 intervals."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from workbench import Robot, load_robot
from workbench._compiled import interpreted
from workbench.ik import _franka_kernel as kernel
from workbench.ik import get_structure
from workbench.ik._franka_intervals import END_TOL, compute_feasible_intervals
from workbench.ik._redundant_common import (
    ELBOW_SINGULAR,
    NOT_RIGID,
    OK,
    OUT_OF_REACH,
    SHOULDER_SINGULAR,
    WITHIN_LIMITS,
    WRIST_SINGULAR,
)
from workbench.ik.batch_poses import compute_tool_poses
from workbench.ik.structure import KinematicStructure
from workbench.model.dh import DHJoint, DHTable

#: A branch reaches its pose: FK residual [m, rotation entries] vs Pinocchio.
ATOL_FK = 1e-12
#: The solutions contain the configuration that made the pose [rad].
ATOL_Q = 1e-9
#: At a singularity itself two branches meet in a double root, known to
#: about √(rounding) only [rad]: the elbow's cos θ4 comes from squared lengths
#: with a rounding up to ~1e-12, so θ4 to √(2e-12) ≈ 1.4e-6 (1.7e-6 seen with
#: Pinocchio 4.1's forward kinematics of the target pose).
ATOL_DOUBLE_ROOT = 3e-6
#: Distances [rad] from a singularity at which the branches are tested.
NEAR = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6)
#: Near a singularity the branches that meet there are known to about
#: CONDITION / distance [rad] (a double root: rounding over its separation),
#: ATOL_Q from 1e-4 rad away.
CONDITION = 1e-13
#: Interval ends: a limit hit or a reach boundary to this [rad or unitless].
ATOL_END = 1e-9
SEED = 0
TAU = 2.0 * math.pi


@pytest.fixture(scope="module")
def panda() -> Robot:
    return load_robot("panda")


@pytest.fixture(scope="module")
def geometry(panda: Robot) -> np.ndarray:
    return kernel.pack_geometry(get_structure(panda), panda.lower, panda.upper)


def _angle_gap(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a − b| taken mod 2π, elementwise [rad]."""
    return np.abs(np.remainder(a - b + math.pi, TAU) - math.pi)


def _gap_to_branches(q_branches: np.ndarray, q: np.ndarray) -> float:
    """Distance [rad] (max over joints, mod 2π) from q to the nearest branch."""
    return float(np.nanmin(_angle_gap(q_branches, q).max(axis=-1)))


def _poses(robot: Robot, q: np.ndarray) -> np.ndarray:
    rotations, positions, _ = compute_tool_poses(robot, q)
    poses = np.zeros((len(q), 4, 4))
    poses[:, :3, :3], poses[:, :3, 3], poses[:, 3, 3] = rotations, positions, 1.0
    return poses


def _solve(geometry: np.ndarray, pose: np.ndarray, value: float, prev=None):
    q = np.empty((kernel.B, 7))
    flags = np.empty(kernel.B, dtype=np.uint8)
    previous = np.empty(0) if prev is None else np.asarray(prev, dtype=float)
    status = kernel.solve_pose(geometry, pose, value, previous, q, flags, True)
    return status, q, flags


def _batch(geometry: np.ndarray, poses: np.ndarray, values: np.ndarray):
    n = len(poses)
    q = np.empty((n, kernel.B, 7))
    valid = np.empty((n, kernel.B), dtype=np.bool_)
    kernel.solve_batch(geometry, np.ascontiguousarray(poses), values, q, valid)
    return q, valid


def _check_residuals(robot: Robot, pose: np.ndarray, q: np.ndarray) -> None:
    for row in q:
        if not np.isnan(row[0]):
            got = np.asarray(robot.fk(row))
            np.testing.assert_allclose(got, pose, rtol=0, atol=ATOL_FK)


def test_interface() -> None:
    assert kernel.PARAMETER == "q7"
    assert len(kernel.BRANCHES) == kernel.B == 8
    assert len(set(kernel.BRANCHES)) == 8
    assert kernel.BRANCHES[0] == "elbow-neg/wrist-neg/shoulder-neg"
    assert kernel.BRANCHES[5] == "elbow-pos/wrist-neg/shoulder-pos"


def test_parameter_range_is_q7_limits(panda: Robot, geometry: np.ndarray) -> None:
    assert kernel.parameter_range(geometry) == (panda.lower[6], panda.upper[6])


@pytest.mark.parametrize("inside", [True, False], ids=["in-limits", "any-angles"])
def test_round_trip_batch(panda: Robot, geometry: np.ndarray, inside: bool) -> None:
    rng = np.random.default_rng(SEED)
    n = 10_000
    if inside:
        q = rng.uniform(panda.lower, panda.upper, size=(n, 7))
    else:
        q = rng.uniform(-math.pi, math.pi, size=(n, 7)) * 1.5
    poses = _poses(panda, q)
    q_all, valid = _batch(geometry, poses, q[:, 6])
    assert np.array_equal(valid, ~np.isnan(q_all[:, :, 0]))
    gaps = np.nanmin(_angle_gap(q_all, q[:, None, :]).max(axis=2), axis=1)
    assert gaps.max() <= ATOL_Q
    assert np.all(q_all[valid][:, 6] == np.repeat(q[:, 6], valid.sum(axis=1)))
    # every reached branch reaches its pose (compiled chain, all of them) ...
    reached = q_all[valid]
    again = _poses(panda, reached)
    want = np.repeat(poses, valid.sum(axis=1), axis=0)
    np.testing.assert_allclose(again, want, rtol=0, atol=ATOL_FK)
    # ... and, for a subset, against Pinocchio itself; batch == pose, bitwise
    for i in range(0, n, 50):
        status, q_one, flags = _solve(geometry, poses[i], q[i, 6])
        assert status == OK
        np.testing.assert_array_equal(q_one, q_all[i])
        _check_residuals(panda, poses[i], q_one)
        within = [bool(f & WITHIN_LIMITS) for f in flags]
        lower, upper = panda.lower - 1e-9, panda.upper + 1e-9
        expected = [bool(np.all((lower <= row) & (row <= upper))) for row in q_one]
        assert within == expected


@pytest.mark.slow
@given(
    st.lists(
        st.floats(min_value=0.0, max_value=1.0, allow_nan=False),
        min_size=7,
        max_size=7,
    )
)
def test_round_trip_property(fractions: list[float]) -> None:
    robot = load_robot("panda")
    geometry = kernel.pack_geometry(get_structure(robot), robot.lower, robot.upper)
    q = robot.lower + np.asarray(fractions) * (robot.upper - robot.lower)
    pose = np.asarray(robot.fk(q))
    status, q_all, _ = _solve(geometry, pose, q[6])
    assert status == OK
    assert _gap_to_branches(q_all, q) <= ATOL_Q
    _check_residuals(robot, pose, q_all)


def _singular_angles(geometry: np.ndarray) -> dict[str, tuple[int, tuple[float, ...]]]:
    """Joint index and DH angles of each singularity of the closed form."""
    geo = geometry[0]
    phi = math.atan2(geo["sphi"], geo["cphi"])
    return {
        "shoulder": (1, (0.0, math.pi)),  # sin θ2 = 0
        "elbow": (3, (-phi, math.pi - phi)),  # sin(θ4 + φ) = 0
        "wrist": (4, (0.5 * math.pi, -0.5 * math.pi)),  # cos θ5 = 0
    }


def _well_conditioned(geometry: np.ndarray, q: np.ndarray, skip: int) -> bool:
    """q is 0.1 away (sines) from every singularity but ``skip``'s.

    Also axis 5 0.1 · L24 away from S (|κ|), unless the elbow is tested: κ
    depends on θ4 only (folded, the Panda's axis 5 passes near S).
    """
    geo = geometry[0]
    theta = geo["joint_sign"] * q + geo["theta_offset"]
    phi = math.atan2(geo["sphi"], geo["cphi"])
    sg = geo["sigma"]
    c4, s4 = math.cos(theta[3]), math.sin(theta[3])
    kappa = geo["a4"] + geo["a3"] * c4 + sg[2] * geo["d3"] * s4  # axis 5 off S
    checks = {
        1: abs(math.sin(theta[1])),
        3: abs(math.sin(theta[3] + phi)),
        4: abs(math.cos(theta[4])),
        5: abs(kappa) / math.sqrt(geo["l24s"]),
    }
    skipped = (skip, 5) if skip == 3 else (skip,)
    return all(v > 0.1 for j, v in checks.items() if j not in skipped)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["shoulder", "elbow", "wrist"])
def test_near_singularities(panda: Robot, geometry: np.ndarray, name: str) -> None:
    joint, thetas = _singular_angles(geometry)[name]
    geo = geometry[0]
    flag = {"shoulder": SHOULDER_SINGULAR, "elbow": ELBOW_SINGULAR}.get(
        name, WRIST_SINGULAR
    )
    rng = np.random.default_rng(SEED)
    done = 0
    while done < 120:
        q = rng.uniform(-math.pi, math.pi, 7)
        theta = thetas[done % 2]
        q[joint] = geo["joint_sign"][joint] * (theta - geo["theta_offset"][joint])
        if not _well_conditioned(geometry, q, joint):
            continue
        done += 1
        for distance in (0.0, *NEAR):
            q_near = q.copy()
            q_near[joint] += distance * (1 if done % 4 < 2 else -1)
            pose = np.asarray(panda.fk(q_near))
            # at the singularity θ1 (shoulder) is free: q_previous picks it
            prev = q_near if distance == 0.0 else None
            status, q_all, flags = _solve(geometry, pose, q_near[6], prev)
            assert status == OK
            _check_residuals(panda, pose, q_all)
            gap = _gap_to_branches(q_all, q_near)
            if distance == 0.0:
                assert gap <= ATOL_DOUBLE_ROOT
                nearest = int(np.nanargmin(_angle_gap(q_all, q_near).max(axis=1)))
                assert flags[nearest] & flag
            else:
                assert gap <= max(ATOL_Q, CONDITION / distance), (distance, gap)


def _random_franka(rng: np.random.Generator) -> KinematicStructure:
    """A Franka-pattern arm with random lengths, signs, offsets, base and tool."""

    def sign() -> float:
        return float(rng.choice([-1.0, 1.0]))

    def length(low: float, high: float) -> float:
        return sign() * float(rng.uniform(low, high))

    half = 0.5 * math.pi
    rows = [
        (sign() * half, 0.0, length(0.1, 0.5)),
        (sign() * half, 0.0, 0.0),
        (sign() * half, length(0.03, 0.2), length(0.2, 0.6)),
        (sign() * half, length(0.03, 0.2), length(0.0, 0.1)),
        (sign() * half, 0.0, length(0.2, 0.6)),
        (sign() * half, length(0.03, 0.2), length(0.0, 0.1)),
        (float(rng.uniform(-math.pi, math.pi)), length(0.0, 0.1), length(0.0, 0.3)),
    ]
    offsets = rng.uniform(-math.pi, math.pi, 7)
    table = DHTable(
        "franka-like",
        tuple(
            DHJoint(alpha=al, a=a, d=d, theta_offset=float(o))
            for (al, a, d), o in zip(rows, offsets, strict=True)
        ),
    )

    def transform() -> np.ndarray:
        m = np.eye(4)
        m[:3, :3] = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        if np.linalg.det(m[:3, :3]) < 0:
            m[:3, 0] *= -1.0
        m[:3, 3] = rng.uniform(-0.5, 0.5, 3)
        return m

    signs = tuple(sign() for _ in range(7))
    return KinematicStructure("franka", table, signs, transform(), transform(), 0, 0)


def _fitted_fk(structure: KinematicStructure, q: np.ndarray) -> np.ndarray:
    theta = np.asarray(structure.joint_sign) * q
    return structure.base @ structure.table.forward_kinematics(theta) @ structure.tool


def test_any_franka_pattern() -> None:
    """Any lengths, signs, offsets of the pattern: FK by the DH table itself."""
    rng = np.random.default_rng(SEED)
    lower, upper = np.full(7, -math.pi), np.full(7, math.pi)
    for _ in range(30):
        structure = _random_franka(rng)
        geometry = kernel.pack_geometry(structure, lower, upper)
        for _ in range(30):
            q = rng.uniform(-math.pi, math.pi, 7)
            pose = _fitted_fk(structure, q)
            status, q_all, _ = _solve(geometry, pose, q[6])
            assert status == OK
            assert _gap_to_branches(q_all, q) <= ATOL_Q
            for row in q_all[~np.isnan(q_all[:, 0])]:
                got = _fitted_fk(structure, row)
                np.testing.assert_allclose(got, pose, rtol=0, atol=ATOL_FK)


def test_labels_are_physical(panda: Robot, geometry: np.ndarray) -> None:
    """Two DH fits of one arm (other signs and offsets) give the same rows."""
    half = 0.5 * math.pi
    rows = [
        (-half, 0.0, 0.333), (half, 0.0, 0.0), (half, 0.0825, 0.316),
        (-half, -0.0825, 0.0), (half, 0.0, 0.384), (half, 0.088, 0.0),
        (0.0, 0.0, 0.107),
    ]  # fmt: skip
    table = DHTable(
        "panda-craig", tuple(DHJoint(alpha=al, a=a, d=d) for al, a, d in rows)
    )
    c, s = math.cos(-math.pi / 4), math.sin(-math.pi / 4)
    tool = np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0.1034], [0, 0, 0, 1.0]])
    other = KinematicStructure("franka", table, (1.0,) * 7, np.eye(4), tool, 0, 0)
    other_geometry = kernel.pack_geometry(other, panda.lower, panda.upper)
    rng = np.random.default_rng(SEED)
    for _ in range(200):
        q = rng.uniform(panda.lower, panda.upper)
        pose = np.asarray(panda.fk(q))
        _, q_a, _ = _solve(geometry, pose, q[6])
        _, q_b, _ = _solve(other_geometry, pose, q[6])
        np.testing.assert_array_equal(np.isnan(q_a), np.isnan(q_b))
        assert np.nanmax(_angle_gap(q_a, q_b)) <= ATOL_Q
        # the Panda's branches: sign of sin q2 (shoulder), of -cos q5 (wrist,
        # where q4 is within its limits: axis 5 passes S at neither end)
        for b, row in enumerate(q_a):
            if not np.isnan(row[0]) and panda.lower[3] <= row[3] <= panda.upper[3]:
                assert (math.sin(row[1]) > 0) == bool(b & 1)
                assert (-math.cos(row[4]) > 0) == bool(b & 2)


def test_unreachable_and_bad_pose(geometry: np.ndarray) -> None:
    far = np.eye(4)
    far[:3, 3] = (3.0, 0.0, 0.5)
    status, q_all, _ = _solve(geometry, far, 0.0)
    assert status == OUT_OF_REACH
    assert np.isnan(q_all).all()
    status, distance, low, high = kernel.diagnose(geometry, far, 0.0)
    assert status == OUT_OF_REACH
    assert distance > high > low > 0.0
    skew = np.eye(4)
    skew[0, 1] = 0.1
    assert _solve(geometry, skew, 0.0)[0] == NOT_RIGID
    assert kernel.diagnose(geometry, skew, 0.0)[0] == NOT_RIGID
    q, valid = _batch(geometry, np.stack([skew, far]), np.zeros(2))
    assert not valid.any()
    assert np.isnan(q).all()


def test_parameter_of_and_track(panda: Robot, geometry: np.ndarray) -> None:
    rng = np.random.default_rng(SEED)
    q = rng.uniform(panda.lower, panda.upper, size=(20, 7))
    out = np.empty(20)
    kernel.parameter_of(geometry, q, out)
    np.testing.assert_array_equal(out, q[:, 6])
    for row in q:
        pose = np.asarray(panda.fk(row))
        _, q_all, flags = _solve(geometry, pose, row[6])
        branch = int(np.nanargmin(_angle_gap(q_all, row).max(axis=1)))
        q_out = np.empty(7)
        status, index, within = kernel.track(
            geometry, pose, row[6], row, branch, 1e-6, q_out
        )
        assert (status, index) == (OK, branch)
        assert within == bool(flags[branch] & WITHIN_LIMITS)
        np.testing.assert_allclose(q_out, row, rtol=0, atol=ATOL_Q)
        # a step too small for that branch: the nearest reached one
        _, other, _ = kernel.track(geometry, pose, row[6], row, (branch + 1) % 8,
                                   0.0, q_out)  # fmt: skip
        assert other == branch


def test_agrees_with_frankik(panda: Robot, geometry: np.ndarray) -> None:
    """Every solution of frankik (He & Liu) that reaches the pose is ours."""
    frankik = pytest.importorskip("frankik")
    rng = np.random.default_rng(SEED)
    n = 10_000
    q = rng.uniform(panda.lower, panda.upper, size=(n, 7))
    values = rng.uniform(panda.lower[6], panda.upper[6], n)
    poses = _poses(panda, q)
    q_all, _ = _batch(geometry, poses, values)
    # frankik's O_T_EE is libfranka's flange (panda_link8); our tool frame
    # panda_hand_tcp is flange · Rz(−π/4) · Tz(0.1034 m)
    c, s = math.cos(-math.pi / 4), math.sin(-math.pi / 4)
    flange_to_tool = np.array(
        [[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0.1034], [0, 0, 0, 1.0]]
    )
    measured = np.linalg.inv(np.asarray(panda.fk(q[0], "panda_link8"))) @ poses[0]
    np.testing.assert_allclose(measured, flange_to_tool, rtol=0, atol=ATOL_FK)
    theirs = dropped = snapped = imprecise = 0
    for i in range(n):
        rows = np.asarray(frankik.ik_full(poses[i] @ np.linalg.inv(flange_to_tool),
                                          q[i], values[i]))  # fmt: skip
        for row in rows[~np.isnan(rows).any(axis=1)]:
            residual = np.abs(np.asarray(panda.fk(row)) - poses[i]).max()
            if residual > ATOL_Q:  # frankik's snap of q2 to 0: not a solution
                assert row[1] == 0.0
                snapped += 1
                continue
            theirs += 1
            gaps = _angle_gap(q_all[i], row).max(axis=1)
            b = int(np.nanargmin(gaps))
            assert b < 4  # He & Liu's elbow
            if gaps[b] > ATOL_Q:  # frankik's own error, near a singularity:
                # its residual over σmin of the 6 × 6 Jacobian (q7 fixed) at ours
                sigma = np.linalg.svd(panda.jacobian(q_all[i, b])[:, :6])[1][-1]
                assert gaps[b] <= 10.0 * residual / sigma
                imprecise += 1
        # the other elbow within the Panda's limits: solutions frankik drops
        for row in q_all[i, 4:]:
            if not np.isnan(row[0]):
                dropped += bool(np.all((panda.lower < row) & (row < panda.upper)))
    assert theirs > 5_000
    assert dropped > 0
    assert snapped + imprecise < theirs / 100


def _end_kinds(geometry, pose, value, branch) -> tuple[float, float, float]:
    """Margins at one q7 for one branch: joints [rad], reach, |sin θ2|."""
    geo = geometry[0]
    _, q_all, _ = _solve(geometry, pose, value)
    row = q_all[branch]
    assert not np.isnan(row[0])  # an end is a feasible sample
    lower, upper = geo["lower"] + 1e-9, geo["upper"] - 1e-9
    joint = float(np.min(np.minimum(row - lower, upper - row)[:6]))
    reach = np.empty((1, 3))
    kernel.reach_margins(geometry, pose, np.array([value]), reach)
    theta2 = geo["joint_sign"][1] * row[1] + geo["theta_offset"][1]
    return (
        joint,
        float(min(reach[0, 0], reach[0, 1 + (branch >> 2)])),
        abs(math.sin(theta2)),
    )


def test_feasible_intervals(panda: Robot, geometry: np.ndarray) -> None:
    rng = np.random.default_rng(SEED)
    low, high = kernel.parameter_range(geometry)
    ends = 0
    for _ in range(12):
        q = rng.uniform(panda.lower, panda.upper)
        pose = np.asarray(panda.fk(q))
        intervals = compute_feasible_intervals(geometry, pose)
        assert len(intervals) == kernel.B
        _, q_all, _ = _solve(geometry, pose, q[6])
        own = int(np.nanargmin(_angle_gap(q_all, q).max(axis=1)))
        assert any(a - END_TOL <= q[6] <= b + END_TOL for a, b in intervals[own])
        for branch, runs in enumerate(intervals):
            flat = [x for run in runs for x in run]
            assert flat == sorted(flat)
            assert all(low <= x <= high for x in flat)
            for x in flat:
                if low < x < high:
                    joint, reach, shoulder = _end_kinds(geometry, pose, x, branch)
                    assert min(joint, reach, shoulder) <= ATOL_END
                    ends += 1
            # membership agrees with solve_pose away from the ends
            for value in rng.uniform(low, high, 100):
                if any(abs(value - x) < 1e-6 for x in flat):
                    continue
                _, q_one, flags = _solve(geometry, pose, value)
                feasible = bool(flags[branch] & WITHIN_LIMITS) and not np.isnan(
                    q_one[branch, 0]
                )
                inside = any(a <= value <= b for a, b in runs)
                assert feasible == inside
    assert ends > 20


def test_interpreted_equals_compiled(panda: Robot, geometry: np.ndarray) -> None:
    """A first call runs the Python source (``interpreted``): the same rows."""
    rng = np.random.default_rng(SEED)
    for _ in range(5):
        q = rng.uniform(panda.lower, panda.upper)
        pose = np.asarray(panda.fk(q))
        with interpreted():
            status_a, q_a, flags_a = _solve(geometry, pose, q[6])
            diagnosis_a = kernel.diagnose(geometry, pose, q[6])
        status_b, q_b, flags_b = _solve(geometry, pose, q[6])
        assert status_a == status_b
        np.testing.assert_array_equal(q_a, q_b)
        np.testing.assert_array_equal(flags_a, flags_b)
        assert diagnosis_a == kernel.diagnose(geometry, pose, q[6])
