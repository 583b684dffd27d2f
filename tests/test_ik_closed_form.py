"""Closed-form IK of PUMA-type arms: every branch, errata, singularities, CLI."""

from __future__ import annotations

import json
import math
from dataclasses import FrozenInstanceError, replace
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.conftest import run_cli as run
from workbench import Robot, load_robot, paper_data
from workbench.cli import EXIT_BAD_INPUT, EXIT_INFEASIBLE
from workbench.errors import (
    DimensionError,
    InfeasibleError,
    InputError,
    NonFiniteError,
    UnreachableError,
    UnsupportedRobotError,
)
from workbench.ik import _puma_kernel as kernel
from workbench.ik._atan2_kernel import atan2_into
from workbench.ik._puma import LIMIT_TOL, geometry_from_dh
from workbench.ik.closed_form import (
    BRANCHES,
    WRIST_SINGULAR_TOL,
    analytic,
    analytic_batch,
    nearest,
)
from workbench.model.dh import DHJoint, DHTable
from workbench.model.urdf_generator import generate_urdf
from workbench.poses import ANGELES7_PRINTED_TOL, se3_from_angeles7
from workbench.singularities import compute_conditions

ATOL_FK = 1e-9  # every branch reproduces the target (observed ~1e-15)
ATOL_SAME_Q = 1e-6  # [rad] the generating q is among the branches
# Batch (numpy's SIMD atan2) and single (libm's) differ in the last bits; next to
# a wrist singularity theta4/theta6 amplify that by 1/|sin theta5|.
ATOL_BATCH = 1e-9
TABLE3_TOL_DEG = 1.0  # Table II is printed to 2 decimals
N_RANDOM = 2000
TWO_PI = 2.0 * math.pi


def wrapped(d: np.ndarray) -> np.ndarray:
    return np.remainder(d + np.pi, TWO_PI) - np.pi


def fk_error(robot: Robot, q: np.ndarray, target: np.ndarray) -> float:
    return float(np.abs(robot.fk(q).homogeneous - target).max())


def robot_from_table(table: DHTable) -> Robot:
    model = pin.buildModelFromXML(generate_urdf(table))
    return Robot(
        table.name,
        model,
        Path(f"{table.name}.urdf"),
        table.tool_frame,
        package_dirs=[],
        dh_table=table,
    )


def check_round_trip(robot: Robot, q: np.ndarray) -> list:
    target = robot.fk(q).homogeneous
    solutions = analytic(robot, target)
    assert [s.branch for s in solutions] == list(BRANCHES)
    for s in solutions:
        assert fk_error(robot, s.q, target) <= ATOL_FK, s.branch
    steps = [np.abs(wrapped(s.q - q)).max() for s in solutions]
    if min(steps) > ATOL_SAME_Q:  # wrist singular: q is another family member
        fixed = [
            (s.q[[0, 1, 2, 4]], s.q[3] + s.q[5], s.q[3] - s.q[5])
            for s in solutions
            if s.wrist_singular
        ]
        assert any(
            np.abs(wrapped(others - q[[0, 1, 2, 4]])).max() <= ATOL_SAME_Q
            and min(abs(wrapped(plus - q[3] - q[5])), abs(wrapped(minus - q[3] + q[5])))
            <= ATOL_SAME_Q
            for others, plus, minus in fixed
        )
    return solutions


# -- every branch, both models ---------------------------------------------------


def test_random_configurations_every_branch_reaches_the_pose(any_puma, rng) -> None:
    qs = rng.uniform(any_puma.lower, any_puma.upper, size=(N_RANDOM, 6))
    targets = np.array([any_puma.fk(q).homogeneous for q in qs])
    q_batch, valid = analytic_batch(any_puma, targets)
    assert q_batch.shape == (N_RANDOM, 8, 6)
    assert valid.all()
    for q, target, batch in zip(qs, targets, q_batch, strict=True):
        solutions = check_round_trip(any_puma, q)
        single = np.array([s.q for s in solutions])
        np.testing.assert_allclose(batch, single, rtol=0, atol=ATOL_BATCH)
        gaps = np.abs(wrapped(single[:, None] - single[None])).max(axis=2)
        assert gaps[~np.eye(8, dtype=bool)].min() > ATOL_SAME_Q  # 8 distinct
        assert fk_error(any_puma, batch[-1], target) <= ATOL_FK


@settings(max_examples=150, deadline=None)
@given(
    name=st.sampled_from(["puma560", "puma560-kang"]),
    u=st.lists(st.floats(0.0, 1.0), min_size=6, max_size=6),
)
def test_round_trip_property(name: str, u: list[float]) -> None:
    robot = load_robot(name)
    q = robot.lower + np.array(u) * (robot.upper - robot.lower)
    check_round_trip(robot, q)


def test_angles_wrapped_into_the_joint_range(any_puma, rng) -> None:
    for q in rng.uniform(-np.pi, np.pi, size=(200, 6)):
        for s in analytic(any_puma, any_puma.fk(q)):
            for j, x in enumerate(s.q):
                lo, hi = any_puma.lower[j], any_puma.upper[j]
                reps = x + TWO_PI * np.arange(-3, 4)
                if np.any((reps >= lo - 1e-9) & (reps <= hi + 1e-9)):
                    assert lo - 1e-9 <= x <= hi + 1e-9
                else:
                    assert -np.pi < x <= np.pi
            inside = (any_puma.lower - 1e-9 <= s.q) & (s.q <= any_puma.upper + 1e-9)
            assert s.within_limits == bool(inside.all())


def _wrap_reference(x: float, lower: float, upper: float) -> float:
    """The documented representative of angle x within [lower, upper], by math."""
    y = math.remainder(x, TWO_PI)
    y = math.pi if y <= -math.pi else y
    for z in (y, y + TWO_PI, y - TWO_PI, y + 2 * TWO_PI, y - 2 * TWO_PI):
        if lower - LIMIT_TOL <= z <= upper + LIMIT_TOL:
            return z
    return y


def test_kernel_wraps_as_documented(rng) -> None:
    """Joint values of DH angles for random limits and offsets (kernel vs math)."""
    none = np.empty(0)
    table = _puma_type_tables(rng, 1)[0]
    for trial in range(300):
        lo = rng.uniform(-12.0, 3.0)
        hi = lo + rng.uniform(0.0, 15.0)
        if trial % 5 == 0:
            lo, hi = -math.pi, math.pi
        offset = 0.0 if trial % 3 else rng.uniform(-4.0, 4.0)
        joints = list(table.joints)
        joints[3] = replace(joints[3], theta_offset=offset)
        lower, upper = np.full(6, -math.pi), np.full(6, math.pi)
        lower[3], upper[3] = lo, hi
        geo = geometry_from_dh(replace(table, joints=tuple(joints)), lower, upper)
        record = kernel.pack_geometry(geo)[0]
        thetas = rng.uniform(-math.pi, math.pi, 30)
        thetas[:3] = -math.pi, math.pi, offset
        for theta in thetas:
            got = kernel.common.joint_value(record, 3, theta, none, False)
            assert got == pytest.approx(
                _wrap_reference(theta - offset, lo, hi), abs=1e-12
            )


@given(st.floats(-1e6, 1e6))
def test_kernel_remainder_is_ieee(x: float) -> None:
    r = kernel.common.remainder(x)
    assert r == math.remainder(x, TWO_PI) or abs(r) == pytest.approx(math.pi)


def test_solution_is_frozen_and_read_only(puma) -> None:
    s = analytic(puma, puma.fk(np.full(6, 0.3)))[0]
    with pytest.raises(FrozenInstanceError):
        s.branch = "x"  # type: ignore[misc]
    with pytest.raises(ValueError, match="read-only"):
        s.q[0] = 1.0
    assert (s.index, s.branch) == (0, "right/elbow-up/no-flip")


def _puma_type_tables(rng: np.random.Generator, count: int) -> list[DHTable]:
    half = math.pi / 2.0
    tables = []
    for i in range(count):
        s = rng.choice([-1.0, 1.0], size=6)
        offsets = rng.uniform(-3.0, 3.0, size=6)
        joints = (
            DHJoint(s[0] * half, 0.0, rng.uniform(-0.5, 0.5), offsets[0]),
            DHJoint(
                0.0, s[5] * rng.uniform(0.2, 0.6), rng.uniform(-0.2, 0.2), offsets[1]
            ),
            DHJoint(
                s[2] * half, rng.uniform(-0.1, 0.1), rng.uniform(-0.2, 0.2), offsets[2]
            ),
            DHJoint(s[3] * half, 0.0, s[1] * rng.uniform(0.2, 0.6), offsets[3]),
            DHJoint(s[4] * half, 0.0, 0.0, offsets[4]),
            DHJoint((0.0, 0.3, -1.2)[i % 3], 0.0, rng.uniform(-0.2, 0.2), offsets[5]),
        )
        tables.append(DHTable(f"puma-type-{i}", joints, tool_frame="tool"))
    return tables


def test_any_puma_type_table(rng) -> None:
    """Signs of alpha, offsets, d1, d6, alpha6, negative a2/d4: derived, not copied."""
    for table in _puma_type_tables(rng, 12):
        robot = robot_from_table(table)
        qs = rng.uniform(-np.pi, np.pi, size=(25, 6))
        targets = np.array([robot.fk(q).homogeneous for q in qs])
        q_batch, valid = analytic_batch(robot, targets)
        assert valid.all()
        for q, batch in zip(qs, q_batch, strict=True):
            single = np.array([s.q for s in check_round_trip(robot, q)])
            np.testing.assert_allclose(batch, single, rtol=0, atol=ATOL_BATCH)


@pytest.mark.slow
def test_labels_match_robotics_toolbox(rng) -> None:
    rtb = pytest.importorskip("roboticstoolbox")
    peer = rtb.models.DH.Puma560()
    joints = tuple(
        DHJoint(link.alpha, link.a, link.d, link.offset) for link in peer.links
    )
    robot = robot_from_table(DHTable("rtb-puma560", joints, tool_frame="tool"))
    letters = {"right": "r", "left": "l", "up": "u", "down": "d"}
    for q in rng.uniform(-2.5, 2.5, size=(10, 6)):
        target = peer.fkine(q).A
        for s in analytic(robot, target):
            arm, elbow, wrist = s.branch.split("/")
            config = letters[arm] + letters[elbow[6:]] + wrist[0]
            theirs = peer.ikine_a(target, config=config)
            assert theirs.success
            assert np.abs(wrapped(theirs.q - s.q)).max() < 1e-6, config


# -- Angeles et al. Tables II and III --------------------------------------------


@pytest.mark.parametrize(
    ("printed", "q_deg", "branch"),
    [
        (
            paper_data.ANGELES_PICK_ANGELES7,
            paper_data.ANGELES_PICK_Q_DEG,
            "right/elbow-down/no-flip",
        ),
        (
            paper_data.ANGELES_PLACE_ANGELES7,
            paper_data.ANGELES_PLACE_Q_DEG,
            "right/elbow-up/flip",
        ),
    ],
)
def test_angeles_table2_recovers_table3(puma, printed, q_deg, branch) -> None:
    target = se3_from_angeles7(printed, tol=ANGELES7_PRINTED_TOL)
    solutions = analytic(puma, target)
    errors = [
        np.abs(np.rad2deg(wrapped(s.q - np.deg2rad(q_deg)))).max() for s in solutions
    ]
    best = solutions[int(np.argmin(errors))]
    assert min(errors) < TABLE3_TOL_DEG
    assert best.branch == branch


# -- Kang's printed formulas (docs/errata-kang-ik.md) -----------------------------


def _kang_samples(robot: Robot):
    a2, a3, d3, d4 = 0.4318, 0.0203, 0.1254, 0.4318
    assert robot.dh_table.joints[2].a == a3
    for q in np.random.default_rng(0).uniform(robot.lower, robot.upper, (N_RANDOM, 6)):
        (nx, ox, ax, px), (ny, oy, ay, py), (nz, oz, az, pz) = (
            robot.fk(q).homogeneous[:3].tolist()
        )
        t1, t2, t3, t4 = q[:4]
        c1, s1, c4, s4 = math.cos(t1), math.sin(t1), math.cos(t4), math.sin(t4)
        c23, s23 = math.cos(t2 + t3), math.sin(t2 + t3)
        x = px * c1 + py * s1
        r, phi = math.hypot(px, py), math.atan2(py, px)
        bo, co = (ox * c1 + oy * s1) * c23 + oz * s23, ox * s1 - oy * c1
        bn, cn = (nx * c1 + ny * s1) * c23 + nz * s23, nx * s1 - ny * c1
        ba, ca = (ax * c1 + ay * s1) * c23 + az * s23, ax * s1 - ay * c1
        psi = math.acos(
            (a2**2 - d4**2 - a3**2 + x**2 + pz**2) / (2 * a2 * math.hypot(x, pz))
        )
        theta3 = [
            math.atan2(
                x * math.cos(t) + pz * math.sin(t) - a2,
                x * math.sin(t) - pz * math.cos(t),
            )
            - math.atan2(a3, d4)
            for t in (math.atan2(pz, x) + psi, math.atan2(pz, x) - psi)
        ]
        yield {
            "q": q,
            "x": x,
            "theta1_right": phi + math.asin(d3 / r),
            "theta1_left_printed": phi + math.asin(d3 / r) + math.pi,
            "theta1_left_fixed": phi - math.asin(d3 / r) + math.pi,
            "theta23": [
                (math.atan2(pz, x) + psi, theta3[0]),
                (math.atan2(pz, x) - psi, theta3[1]),
            ],
            "theta4_first": math.atan2(ca, ba),
            "theta4_second": math.atan2(-ca, -ba),
            "theta5": math.atan2(
                -ba * c4 - ca * s4, (ax * c1 + ay * s1) * s23 - az * c23
            ),
            "theta6_printed": math.atan2(-bo * c4 + co * s4, co * c4 - bo * s4),
            "theta6_fixed": math.atan2(cn * c4 - bn * s4, co * c4 - bo * s4),
        }


def _same(a: float, b: float) -> bool:
    return abs(math.remainder(a - b, TWO_PI)) < 1e-9


def test_kang_printed_formulas(puma_kang) -> None:
    """What the paper prints and fails (rows 1, 5, 7 of the errata)."""
    left = s5_positive = 0
    for s in _kang_samples(puma_kang):
        q = s["q"]
        if s["x"] < 0.0:  # left arm
            left += 1
            assert not _same(s["theta1_left_printed"], q[0])
        if math.sin(q[4]) > 0.0:  # printed "if s5 > 0" case gives theta4 + pi
            s5_positive += 1
            assert _same(s["theta4_first"], q[3] + math.pi)
        assert not _same(s["theta6_printed"], q[5])
    assert left > N_RANDOM / 3 and s5_positive > N_RANDOM / 3


def test_kang_corrected_formulas(puma_kang) -> None:
    """The printed rows 2, 3, 4, 6 and the corrections of rows 1, 5, 7."""
    for s in _kang_samples(puma_kang):
        q = s["q"]
        theta1 = s["theta1_right"] if s["x"] > 0.0 else s["theta1_left_fixed"]
        assert _same(theta1, q[0])
        assert any(_same(a, q[1]) and _same(b, q[2]) for a, b in s["theta23"])
        theta4 = s["theta4_first"] if math.sin(q[4]) < 0.0 else s["theta4_second"]
        assert _same(theta4, q[3])
        assert _same(s["theta5"], q[4])
        assert _same(s["theta6_fixed"], q[5])


def test_kang_singular_family_is_theta4_plus_theta6(any_puma) -> None:
    """At θ5 = 0, FK depends on θ4 + θ6 only: "θ6 = −θ4" is the family's direction."""
    q = np.array([0.4, 1.9, 0.3, 0.8, 0.0, 0.5])  # theta5 = 0
    assert abs(compute_conditions(any_puma, q).wrist) <= ATOL_FK
    target = any_puma.fk(q).homogeneous
    for theta4 in np.linspace(-3.0, 3.0, 7):
        member = q + np.array([0, 0, 0, theta4 - q[3], 0, q[3] - theta4])  # sum kept
        assert fk_error(any_puma, member, target) <= ATOL_FK
    literal = q + np.array([0, 0, 0, 0, 0, -q[3] - q[5]])  # theta6 = -theta4 exactly
    assert fk_error(any_puma, literal, target) > 0.1


# -- singularities and continuity ------------------------------------------------


def _singular_q(robot: Robot) -> np.ndarray:
    q2 = -0.9 if robot.name == "puma560" else 2.2
    return np.array([0.3, q2, 1.2, 0.7, 0.0, -0.4])


def test_wrist_singularity_is_flagged_and_split(any_puma) -> None:
    q = _singular_q(any_puma)
    target = any_puma.fk(q).homogeneous
    solutions = analytic(any_puma, target)
    singular = [s for s in solutions if s.wrist_singular]
    assert len(singular) == 2  # the no-flip/flip pair of the generating arm
    for s in solutions:
        assert fk_error(any_puma, s.q, target) <= ATOL_FK
    q_batch, _ = analytic_batch(any_puma, target[None])
    np.testing.assert_allclose(
        q_batch[0], [s.q for s in solutions], rtol=0, atol=ATOL_BATCH
    )
    no_flip, flip = singular
    assert no_flip.q[3] == 0.0  # theta4 = 0 without q_previous
    np.testing.assert_allclose(no_flip.q[:3], q[:3], rtol=0, atol=1e-12)
    np.testing.assert_allclose(no_flip.q[3] + no_flip.q[5], q[3] + q[5], atol=1e-12)
    np.testing.assert_allclose(
        np.abs(wrapped(flip.q - no_flip.q)), [0, 0, 0, np.pi, 0, np.pi], atol=1e-12
    )

    previous = q + np.array([0.0, 0.0, 0.0, 0.05, 0.01, -0.03])
    s = nearest(analytic(any_puma, target, q_previous=previous), previous)
    assert s.wrist_singular
    assert fk_error(any_puma, s.q, target) <= ATOL_FK
    # theta4 + theta6 is fixed: the step is shared evenly, -0.01 each
    np.testing.assert_allclose(
        s.q - previous, [0, 0, 0, -0.01, -0.01, -0.01], atol=1e-12
    )


@pytest.mark.parametrize("samples", [61, 60])  # through theta5 = 0 exactly, or not
def test_path_through_wrist_singularity_never_flips(any_puma, samples) -> None:
    q0, q1 = _singular_q(any_puma), _singular_q(any_puma)
    q0[3:] = [0.5, 0.3, 0.2]
    q1[3:] = [0.9, -0.3, 0.6]
    q1[:3] += [0.2, 0.1, 0.1]
    nominal = np.abs(q1 - q0).max() / (samples - 1)
    previous = q0
    label = nearest(analytic(any_puma, any_puma.fk(q0)), q0).branch
    for t in np.linspace(0.0, 1.0, samples):
        target = any_puma.fk(q0 + t * (q1 - q0))
        s = nearest(analytic(any_puma, target, q_previous=previous), previous)
        assert np.abs(s.q - previous).max() <= 2.0 * nominal + 1e-12
        previous = s.q
    np.testing.assert_allclose(previous, q1, rtol=0, atol=1e-9)
    # keeping the start's label instead ends on the flip twin: theta4 off by pi
    naive = next(x for x in analytic(any_puma, target) if x.branch == label)
    assert abs(wrapped(naive.q[3] - q1[3])) > 3.0


def test_q_previous_picks_the_representative_nearest(puma) -> None:
    q = np.array([0.2, -1.0, 1.5, 3.0, 0.5, -3.0])
    previous = q + np.array([TWO_PI, 0.0, 0.0, 0.02, 0.0, -0.02])  # beyond the range
    s = nearest(analytic(puma, puma.fk(q), q_previous=previous), previous)
    np.testing.assert_allclose(s.q - previous, [0, 0, 0, -0.02, 0, 0.02], atol=1e-9)
    assert not s.within_limits


def test_nearest_is_kangs_rule_generalised(puma) -> None:
    q = np.array([0.2, -1.0, 1.5, 0.4, 0.02, 0.3])
    solutions = analytic(puma, puma.fk(q))
    s = nearest(solutions, q + np.array([0, 0, 0, 0, -0.05, 0]))  # theta5 < 0 nearby
    np.testing.assert_allclose(s.q, q, atol=1e-9)


# -- errors ----------------------------------------------------------------------


def _pose(xyz: list[float]) -> np.ndarray:
    target = np.eye(4)
    target[:3, 3] = xyz
    return target


@pytest.mark.parametrize(
    ("xyz", "fragment"),
    [
        ([2.0, 0.0, 0.0], r"out of reach: wrist centre at distance 2 m from the "),
        ([0.0, 0.0, 0.0], r"distance 0 m from the shoulder, reach is \[0.1254"),
        ([0.05, 0.0, 0.5], "inside the unreachable cylinder of radius 0.1254 m"),
    ],
)
def test_unreachable(any_puma, xyz, fragment) -> None:
    with pytest.raises(UnreachableError, match=fragment) as info:
        analytic(any_puma, _pose(xyz))
    assert isinstance(info.value, InfeasibleError)
    q, valid = analytic_batch(
        any_puma, np.array([_pose(xyz), any_puma.fk(np.zeros(6)).homogeneous])
    )
    assert valid.tolist() == [[False] * 8, [True] * 8]
    assert np.isnan(q[0]).all() and np.isfinite(q[1]).all()


@pytest.mark.parametrize(
    ("target", "error", "fragment"),
    [
        (np.full((4, 4), np.nan), NonFiniteError, "must be finite"),
        (np.diag([1.0, 1.0, np.inf, 1.0]), NonFiniteError, "must be finite"),
        (np.diag([1.1, 1.0, 1.0, 1.0]), InputError, "not orthonormal"),
        (np.diag([1.0, 1.0, -1.0, 1.0]), InputError, "a reflection"),
        (np.diag([1.0, 1.0, 1.0, 2.0]), InputError, "bottom row"),
        (np.eye(3), DimensionError, r"shape \(4, 4\), got shape \(3, 3\)"),
        ("pose", NonFiniteError, "must be numbers"),
    ],
)
def test_bad_target(puma, target, error, fragment) -> None:
    with pytest.raises(error, match=fragment):
        analytic(puma, target)


def test_bad_batch(puma) -> None:
    good = puma.fk(np.zeros(6)).homogeneous
    with pytest.raises(DimensionError, match="targets"):
        analytic_batch(puma, np.zeros((3, 3, 4)))
    with pytest.raises(NonFiniteError, match="pose 1 has NaN"):
        analytic_batch(puma, np.array([good, np.full((4, 4), np.nan)]))
    with pytest.raises(InputError, match="pose 0 is not"):
        analytic_batch(puma, np.array([2.0 * good, good]))


def test_bad_q_previous_and_empty_nearest(puma) -> None:
    target = puma.fk(np.zeros(6))
    with pytest.raises(DimensionError, match="q"):
        analytic(puma, target, q_previous=[0.0] * 5)
    with pytest.raises(DimensionError, match="q_previous"):
        nearest(analytic(puma, target), [0.0] * 5)
    with pytest.raises(NonFiniteError, match="q_previous"):
        nearest(analytic(puma, target), [np.nan] * 6)
    with pytest.raises(NonFiniteError, match="q must be finite"):
        analytic(puma, target, q_previous=[np.nan] * 6)
    with pytest.raises(InputError, match="at least one"):
        nearest([], np.zeros(6))


def test_unsupported_robots(puma, rng) -> None:
    """Without a DH table the structure comes from the axes: same branches."""
    no_table = Robot(
        "plain", puma.model, puma.urdf_path, puma.tool_frame, package_dirs=[]
    )
    for q in rng.uniform(puma.lower, puma.upper, size=(50, 6)):
        target = puma.fk(q)
        with_table, from_axes = analytic(puma, target), analytic(no_table, target)
        assert [s.branch for s in from_axes] == [s.branch for s in with_table]
        np.testing.assert_allclose(
            [s.q for s in from_axes], [s.q for s in with_table], rtol=0, atol=1e-9
        )
    joints = list(puma.dh_table.joints)
    joints[1] = replace(joints[1], alpha=math.pi / 2.0)
    bent = robot_from_table(replace(puma.dh_table, name="bent", joints=tuple(joints)))
    with pytest.raises(UnsupportedRobotError, match=r"axes 2 and 3 are not parallel"):
        analytic_batch(bent, np.eye(4)[None])
    assert WRIST_SINGULAR_TOL <= ATOL_FK / math.pi


# -- command line ----------------------------------------------------------------


def test_cli_all_branches_recover_table3(capsys) -> None:
    printed = paper_data.ANGELES_PLACE_ANGELES7 * [1, 1, 1, 1, 1e3, 1e3, 1e3]
    code, out, err = run(
        capsys, "ik", "--robot", "puma560", "--angeles7", *map(str, printed),
        "--mm", "--all", "--json",
    )  # fmt: skip
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert result["robot"] == "puma560"
    assert len(result["solutions"]) == 8
    for row in result["solutions"]:
        assert set(row) >= {"branch", "q", "q_deg", "within_limits", "residual"}
        assert row["residual"] < 1e-9
        np.testing.assert_allclose(np.deg2rad(row["q_deg"]), row["q"], atol=1e-12)
    errors = [
        np.abs(
            wrapped(np.deg2rad(r["q_deg"]) - np.deg2rad(paper_data.ANGELES_PLACE_Q_DEG))
        ).max()
        for r in result["solutions"]
    ]
    assert np.rad2deg(min(errors)) < TABLE3_TOL_DEG


def test_cli_inputs_agree(capsys, puma) -> None:
    pose = puma.fk(np.array([0.2, -1.0, 1.5, 0.4, 0.6, 0.3]))
    quat_wxyz = pin.Quaternion(pose.rotation).coeffs()[[3, 0, 1, 2]]
    answers = []
    for flag, numbers in (
        ("--matrix", pose.homogeneous.ravel()),
        ("--xyz-quat-wxyz", np.r_[pose.translation, quat_wxyz]),
    ):
        code, out, err = run(
            capsys,
            "ik",
            "--robot",
            "puma560",
            flag,
            *map(repr, numbers.tolist()),
            "--json",
        )
        assert (code, err) == (0, "")
        (row,) = json.loads(out)["solutions"]
        assert row["within_limits"] and row["residual"] < 1e-9
        answers.append(row["q"])
    np.testing.assert_allclose(answers[0], answers[1], atol=1e-9)


@pytest.mark.parametrize(
    ("argv", "code", "fragment"),
    [
        (["--xyz-quat-wxyz", "2", "0", "0", "1", "0", "0", "0"], EXIT_INFEASIBLE,
         "out of reach: wrist centre at distance 2 m"),
        (["--xyz-quat-wxyz", "50", "0", "500", "1", "0", "0", "0", "--mm"],
         EXIT_INFEASIBLE, "unreachable cylinder"),
        (["--xyz-quat-wxyz", "0.3", "0", "0.3", "1", "1", "0", "0"], EXIT_BAD_INPUT,
         "unit norm"),
        (["--matrix", *["1"] * 16], EXIT_BAD_INPUT, "bottom row"),
        (["--angeles7", "0.5", "0.5", "0.5", "0.5", "0.1", "0.2", "nan"],
         EXIT_BAD_INPUT, "not a finite number"),
        (["--angeles7", "0", "0", "0", "1", "0.3"], EXIT_BAD_INPUT, "expected 7"),
    ],
)  # fmt: skip
def test_cli_errors(capsys, argv, code, fragment) -> None:
    got, out, err = run(capsys, "ik", "--robot", "puma560", *argv)
    assert got == code
    assert out == ""
    assert fragment in err
    assert err.count("\n") == 1


def test_cli_no_branch_within_limits_and_non_puma(capsys, puma) -> None:
    q = np.deg2rad([64.0, -158.0, 20.0, -82.0, 137.0, -157.0])
    numbers = puma.fk(q).homogeneous.ravel()
    code, _, err = run(
        capsys, "ik", "--robot", "puma560", "--matrix", *map(repr, numbers.tolist())
    )
    assert code == EXIT_INFEASIBLE and "none of the 8" in err
    code, out, _ = run(
        capsys,
        "ik",
        "--robot",
        "puma560",
        "--matrix",
        *map(repr, numbers.tolist()),
        "--all",
    )
    assert code == 0 and out.count("outside joint limits") == 8
    # A URDF path has no DH table: the closed form from the joint axes.
    path = str(puma.urdf_path)
    code, _, err = run(
        capsys, "ik", "--robot", path, "--matrix", *map(repr, numbers.tolist())
    )
    assert code == EXIT_INFEASIBLE and "none of the 8" in err
    inside = puma.fk(np.deg2rad([10.0, -40.0, 170.0, 20.0, 40.0, 30.0])).homogeneous
    code, out, _ = run(
        capsys, "ik", "--robot", path, "--matrix", *map(repr, inside.ravel().tolist())
    )
    assert code == 0 and "solver closed-form" in out


# -- fast paths (performance work) agree with the general ones ----------------------


def test_continuing_branch_is_nearest_or_stays_on_the_twins(rng) -> None:
    """The planner's branch choice: a twin of the previous pair when near enough."""
    robot = load_robot("puma560")
    for q in rng.uniform(robot.lower, robot.upper, size=(100, 6)):
        prev = q + rng.normal(0.0, 0.05, 6)
        solutions = analytic(robot, robot.fk(q), q_previous=prev)
        q_all = np.array([s.q for s in solutions])
        best = nearest(solutions, prev).index
        assert kernel.common.continuing_branch(q_all, prev, best >> 1, 1.0) == best
        for pair in range(4):  # not near enough: the nearest of all eight
            assert kernel.common.continuing_branch(q_all, prev, pair, 0.0) == best
        step2 = ((q_all - prev) ** 2).sum(axis=1)
        twin = 2 * (best >> 1) ^ 2  # another pair, within a generous step
        chosen = kernel.common.continuing_branch(q_all, prev, twin >> 1, 100.0)
        assert chosen in (twin, twin + 1)
        assert step2[chosen] == step2[twin : twin + 2].min()


def test_solution_fields_are_read_only_and_pickle(puma) -> None:
    import pickle

    solutions = analytic(puma, puma.fk(np.array([0.2, -0.7, 1.1, 0.4, 0.9, -0.3])))
    for s in solutions:
        for field in ("q", "branch", "index", "within_limits", "wrist_singular"):
            with pytest.raises(FrozenInstanceError):
                setattr(s, field, None)
        copy = pickle.loads(pickle.dumps(s))
        assert (copy.branch, copy.index) == (s.branch, s.index)
        assert (copy.within_limits, copy.wrist_singular) == (
            s.within_limits,
            s.wrist_singular,
        )
        np.testing.assert_array_equal(copy.q, s.q)
        assert repr(copy) == repr(s)
    assert [s.q.base is solutions[0].q.base for s in solutions] == [True] * 8


def test_targets_near_the_rigidity_tolerance(puma) -> None:
    """Poses the quick acceptance test leaves to the exact checks: same answer."""
    good = puma.fk(np.array([0.2, -0.7, 1.1, 0.4, 0.9, -0.3])).homogeneous
    for scale, ok in ((1.0 + 2e-7, True), (1.0 + 4.5e-7, True), (1.0 + 6e-7, False)):
        target = good.copy()
        target[:3, 0] *= scale  # |x| - 1 between the two tolerances, or beyond
        if ok:
            single = np.array([s.q for s in analytic(puma, target)])
            batch, valid = analytic_batch(puma, target[None])
            assert valid.all()
            np.testing.assert_allclose(batch[0], single, rtol=0, atol=ATOL_BATCH)
        else:
            with pytest.raises(InputError, match="orthonormal"):
                analytic(puma, target)
            with pytest.raises(InputError, match="pose 0 is not"):
                analytic_batch(puma, target[None])
    flipped = good.copy()
    flipped[:3, 2] *= -1.0  # a reflection: orthonormal, det -1
    with pytest.raises(InputError, match="reflection"):
        analytic(puma, flipped)
    with pytest.raises(InputError, match="pose 0 is not"):
        analytic_batch(puma, flipped[None])
    with pytest.raises(NonFiniteError):
        analytic(puma, pin.SE3(good[:3, :3], np.array([np.nan, 0.0, 0.0])))


def test_batch_result_layout(puma, rng) -> None:
    """Several chunks; values as the single solve's; arrays of the caller's."""
    qs = rng.uniform(puma.lower, puma.upper, size=(5000, 6))  # several chunks
    targets = np.array([puma.fk(q).homogeneous for q in qs])
    q_batch, valid = analytic_batch(puma, targets)
    assert q_batch.shape == (5000, 8, 6) and valid.all()
    assert q_batch.flags.c_contiguous
    for i in (0, 2047, 2048, 4999):
        single = np.array([s.q for s in analytic(puma, targets[i])])
        np.testing.assert_allclose(q_batch[i], single, rtol=0, atol=ATOL_BATCH)
    q_batch[3] = 0.0  # writable, like any result array
    assert not q_batch[3].any()


def _ulps(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance in units in the last place (doubles ordered as integers)."""
    ia, ib = a.view(np.int64), b.view(np.int64)
    magnitude = np.int64(0x7FFFFFFFFFFFFFFF)
    ia = np.where(ia < 0, -(ia & magnitude), ia)
    ib = np.where(ib < 0, -(ib & magnitude), ib)
    return np.abs(ia - ib)


#: Special values of the atan2 test: zeros, infinities, NaN, extremes, subnormals.
_ATAN2_SPECIALS = np.array(
    [0.0, -0.0, math.inf, -math.inf, math.nan, 1.0, -1.0, 0.66, 5e-324, -5e-324, 1e-307]
)
_ATAN2_SPECIALS = np.concatenate([_ATAN2_SPECIALS, [np.finfo(float).max, -1e308]])


def test_atan2_into_special_values_as_numpy() -> None:
    y, x = (a.ravel() for a in np.meshgrid(_ATAN2_SPECIALS, _ATAN2_SPECIALS))
    out = np.empty_like(y)
    atan2_into(y, x, out)
    expected = np.arctan2(y, x)
    np.testing.assert_array_equal(np.isnan(out), np.isnan(expected))
    finite = ~np.isnan(expected)
    assert _ulps(out[finite], expected[finite]).max() <= 2
    np.testing.assert_array_equal(np.signbit(out[finite]), np.signbit(expected[finite]))


def test_atan2_into_within_two_ulp_of_numpy() -> None:
    rng = np.random.default_rng(7)
    n = 200_000
    exponents = rng.uniform(-1074, 1023, (2, n))
    signs = rng.choice([-1.0, 1.0], (2, n))
    y = np.concatenate([rng.standard_normal(n), signs[0] * 2.0 ** exponents[0]])
    x = np.concatenate([rng.standard_normal(n), signs[1] * 2.0 ** exponents[1]])
    near = rng.uniform(-1.0, 1.0, n)  # |y| ≈ |x|: both reductions and the octants
    y = np.concatenate([y, near * rng.uniform(0.5, 1.5, n)])
    x = np.concatenate([x, near * signs[0]])
    out = np.empty_like(y)
    atan2_into(y, x, out)
    assert _ulps(out, np.arctan2(y, x)).max() <= 2


@given(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(allow_nan=True, allow_infinity=True),
)
@settings(max_examples=300, deadline=None)
def test_atan2_into_any_pair(y: float, x: float) -> None:
    out = np.empty(1)
    atan2_into(np.array([y]), np.array([x]), out)
    expected = np.arctan2(y, x)
    if math.isnan(expected):
        assert math.isnan(out[0])
    else:
        assert _ulps(out, np.array([expected]))[0] <= 2
        assert math.copysign(1.0, out[0]) == math.copysign(1.0, expected)
