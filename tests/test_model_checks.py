"""URDF joints checked at load: mimic joints, zero axes, inverted limits, 0 limits,
joint values of continuous joints, package folders."""

from __future__ import annotations

import os
import re
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from workbench import DimensionError, InputError, URDFLoadError, load_robot
from workbench.ik import UnsupportedRobotError, analytic, numeric
from workbench.model.catalog import get_own_urdf_dir
from workbench.model.urdf_joints import MimicJoint
from workbench.trajectory import minimum_duration, pick_and_place

ATOL_EXACT = 1e-12  # same arithmetic up to rounding
MULTIPLIER, OFFSET = 2.0, 0.1  # the mimic joint of the small arm

_LIMIT = '<limit lower="-3" upper="3" velocity="{v}" effort="1"/>'


def _joint(
    name: str,
    parent: str,
    child: str,
    *,
    xyz: str = "0 0 0.3",
    axis: str = "0 1 0",
    kind: str = "revolute",
    limit: str | None = None,
    extra: str = "",
) -> str:
    """One ``<joint>`` element; ``limit`` defaults to ±3 rad at 1 rad/s."""
    limit = _LIMIT.format(v=1) if limit is None else limit
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
        f'<child link="{child}"/><origin xyz="{xyz}"/><axis xyz="{axis}"/>'
        f"{limit}{extra}</joint>"
    )


def _urdf(path: Path, *joints: str, links: str = "") -> Path:
    """A URDF of ``joints``; every link they name is bare unless in ``links``."""
    names = set(re.findall(r'link="(\w+)"', "".join(joints)))
    names -= set(re.findall(r'<link name="(\w+)"', links))
    body = "".join(f'<link name="{n}"/>' for n in sorted(names)) + links
    path.write_text(f'<robot name="arm">{body}{"".join(joints)}</robot>')
    return path


def _three_joints(path: Path, mimic: str = "") -> Path:
    """j1 (z), j2 (y), j3 (y) in series; j3 carries ``mimic``."""
    return _urdf(
        path,
        _joint("j1", "base", "l1", axis="0 0 1"),
        _joint("j2", "l1", "l2"),
        _joint("j3", "l2", "l3", xyz="0.3 0 0.05", extra=mimic),
        _joint("tip", "l3", "l4", xyz="0.2 0.1 0", kind="fixed", limit=""),
    )


MIMIC_TAG = f'<mimic joint="j2" multiplier="{MULTIPLIER}" offset="{OFFSET}"/>'


@pytest.fixture(scope="module")
def arms(tmp_path_factory: pytest.TempPathFactory):
    """The small arm with j3 mimicking j2, and the same arm with j3 free."""
    folder = tmp_path_factory.mktemp("mimic")
    mimic = load_robot(_three_joints(folder / "mimic.urdf", MIMIC_TAG))
    free = load_robot(_three_joints(folder / "free.urdf"))
    return mimic, free


def test_mimic_joint_has_no_coordinate(arms) -> None:
    mimic, free = arms
    assert (mimic.nq, mimic.nv, free.nq) == (2, 2, 3)
    assert mimic.joint_names == ["j1", "j2"] and mimic.n_joints == 2
    assert mimic.mimic_joints == (MimicJoint("j3", "j2", MULTIPLIER, OFFSET),)
    assert free.mimic_joints == ()


@given(q=arrays(np.float64, 2, elements=st.floats(-3.0, 3.0)))
def test_mimic_fk_and_jacobian_follow_the_leader(arms, q) -> None:
    """FK and Jacobian equal the free arm's with q3 = m q2 + o (chain rule)."""
    mimic, free = arms
    q_free = np.array([q[0], q[1], MULTIPLIER * q[1] + OFFSET])
    np.testing.assert_allclose(
        mimic.fk(q).homogeneous, free.fk(q_free).homogeneous, rtol=0, atol=ATOL_EXACT
    )
    jac_free = free.jacobian(q_free)
    expected = jac_free[:, :2] + np.outer(jac_free[:, 2], [0.0, MULTIPLIER])
    np.testing.assert_allclose(mimic.jacobian(q), expected, rtol=0, atol=ATOL_EXACT)


@pytest.fixture(scope="module")
def puma_mimic(tmp_path_factory: pytest.TempPathFactory):
    """Angeles' PUMA with joint 6 mimicking joint 4."""
    text = (get_own_urdf_dir() / "puma560.urdf").read_text()
    start = text.index('<joint name="joint6"')
    end = text.index("</joint>", start)
    text = text[:end] + '<mimic joint="joint4"/>' + text[end:]
    path = tmp_path_factory.mktemp("puma") / "puma_mimic.urdf"
    path.write_text(text)
    return load_robot(path, tool_frame="wrist_center")


def test_ik_refuses_a_mimic_arm_naming_the_joints(puma_mimic) -> None:
    """No closed-form branch can break q6 = q4: the solvers refuse the arm."""
    assert puma_mimic.nq == 5
    target = puma_mimic.fk(np.array([0.1, -0.5, 0.3, 0.4, 0.6]))
    with pytest.raises(UnsupportedRobotError, match="joint6 follows joint4"):
        analytic(puma_mimic, target)
    with pytest.raises(InputError, match="'joint6' follows 'joint4'"):
        numeric(puma_mimic, target)


@pytest.mark.parametrize(
    ("joints", "message"),
    [
        (  # leader after its follower: siblings are visited by name
            (
                _joint("j1", "base", "l1"),
                _joint("b_lead", "l1", "l2"),
                _joint("a_follow", "l1", "l3", extra='<mimic joint="b_lead"/>'),
            ),
            "joint 'a_follow' mimics 'b_lead', which Pinocchio cannot represent",
        ),
        (
            (_joint("j1", "base", "l1", extra='<mimic joint="nope"/>'),),
            "joint 'j1' mimics 'nope', which is not a moving joint",
        ),
        (
            (
                _joint("j1", "base", "l1"),
                _joint("j2", "l1", "l2", extra='<mimic joint="j1"/>'),
                _joint("j3", "l2", "l3", extra='<mimic joint="j2"/>'),
            ),
            "joint 'j3' mimics 'j2', which mimics another joint itself",
        ),
        (
            (
                _joint("j1", "base", "l1", kind="continuous"),
                _joint("j2", "l1", "l2", extra='<mimic joint="j1"/>'),
            ),
            "joint 'j2' mimics 'j1': mimic joints must be revolute or prismatic",
        ),
        ((_joint("j1", "base", "l1", axis="0 0 0"),), "'j1' has a zero-length axis"),
        (
            (_joint("j1", "base", "l1", axis="0 0 0", kind="prismatic"),),
            "'j1' has a zero-length axis (xyz='0 0 0')",
        ),
        (
            (
                _joint(
                    "j1",
                    "base",
                    "l1",
                    limit='<limit lower="3" upper="-3" velocity="1" effort="1"/>',
                ),
            ),
            "joint 'j1' has lower limit 3 above its upper limit -3",
        ),
    ],
)
def test_malformed_joints_are_refused(tmp_path: Path, joints, message) -> None:
    path = _urdf(tmp_path / "bad.urdf", *joints)
    with pytest.raises(URDFLoadError, match=_escaped(message)) as info:
        load_robot(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def _escaped(text: str) -> str:
    return re.escape(text)


def test_a_sibling_leader_named_first_is_honoured(tmp_path: Path) -> None:
    robot = load_robot(
        _urdf(
            tmp_path / "siblings.urdf",
            _joint("j1", "base", "l1"),
            _joint("a_lead", "l1", "l2"),
            _joint("b_follow", "l1", "l3", extra='<mimic joint="a_lead"/>'),
        )
    )
    assert robot.mimic_joints == (MimicJoint("b_follow", "a_lead", 1.0, 0.0),)


def test_jacobian_derivative_refuses_mimic_joints(arms) -> None:
    """Pinocchio 4.1 gets dJ/dt of a mimic arm wrong (off by O(1) against finite
    differences, docs/pinocchio-notes.md): refused, naming the joints."""
    with pytest.raises(InputError, match="mimic joints \\(j3 follows j2\\)"):
        arms[0].jacobian_time_derivative(np.zeros(2), np.ones(2))


def test_mimic_of_a_fixed_joint_is_ignored_and_equal_limits_pass(tmp_path) -> None:
    robot = load_robot(
        _urdf(
            tmp_path / "ok.urdf",
            _joint(
                "j1",
                "base",
                "l1",
                limit='<limit lower="1" upper="1" velocity="1" effort="1"/>',
            ),
            _joint(
                "f", "l1", "l2", kind="fixed", limit="", extra='<mimic joint="j1"/>'
            ),
        )
    )
    assert (robot.nq, robot.mimic_joints, robot.lower[0]) == (1, (), 1.0)


def test_catalog_hands_pinocchio_cannot_mimic_are_locked() -> None:
    romeo = load_robot("romeo")
    assert "LHand" not in romeo.joint_names and "LFinger12" not in romeo.joint_names
    panda = load_robot("pr2")
    assert panda.nq == 24 and len(panda.mimic_joints) == 10


# --- limits of 0: not given ---------------------------------------------------


def test_zero_velocity_in_a_urdf_means_no_limit(tmp_path: Path) -> None:
    path = _urdf(
        tmp_path / "v0.urdf",
        _joint("j1", "base", "l1", limit=_LIMIT.format(v=0)),
        _joint("j2", "l1", "l2", limit=_LIMIT.format(v=2)),
    )
    robot = load_robot(path)
    assert robot.velocity_limit.tolist() == [np.inf, 2.0]
    q0, q1 = np.zeros(2), np.array([2.0, 1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no divide-by-zero anywhere
        t_min = minimum_duration(robot, q0, q1)
        traj = pick_and_place(robot, q0, q1, t_min)
        violations = traj.check_limits()
    # only j2 binds: T = |Δ2| max|ṡ| / v2, the same as a robot without j1's limit
    peak = traj.spline.velocity.peak
    np.testing.assert_allclose(t_min, 1.0 * peak / 2.0, rtol=ATOL_EXACT, atol=0)
    assert violations == []
    fast = pick_and_place(robot, q0, q1, t_min / 10)
    assert {v.joint for v in fast.check_limits() if v.kind == "velocity"} == {"j2"}


def test_with_limits_takes_one_value_for_every_joint(puma) -> None:
    slower = puma.with_limits(velocity_limit=0.5, acceleration_limit=np.inf)
    assert slower.velocity_limit.tolist() == [0.5] * 6
    assert np.all(np.isinf(slower.acceleration_limit))
    for bad in (0.0, -1.0, np.nan):
        with pytest.raises(InputError, match="velocity_limit must be > 0"):
            puma.with_limits(velocity_limit=bad)
    with pytest.raises(InputError, match="must be numbers"):
        puma.with_limits(acceleration_limit="fast")


# --- joint values: one angle per continuous joint ------------------------------


@pytest.fixture(scope="module")
def kinova():
    """Kinova Jaco 2 (6 joints, 3 continuous: nq = 9, nv = 6)."""
    return load_robot("kinova")


def test_kinova_sizes(kinova) -> None:
    assert (kinova.nq, kinova.nv, kinova.n_joints) == (9, 6, 6)


def _q_by_hand(robot, values: np.ndarray) -> np.ndarray:
    """Pinocchio's q written joint by joint, independently of the Robot methods."""
    q = []
    moving = [j for j in robot.model.joints[1:] if j.nv]
    for joint, value in zip(moving, values, strict=True):
        q += [np.cos(value), np.sin(value)] if joint.nq == 2 else [value]
    return np.array(q)


angles6 = arrays(np.float64, 6, elements=st.floats(-10.0, 10.0))


@given(values=angles6)
def test_joint_values_round_trip(kinova, values) -> None:
    q = kinova.q_from_joint_values(values)
    np.testing.assert_allclose(q, _q_by_hand(kinova, values), rtol=0, atol=0)
    back = kinova.joint_values_from_q(q)
    continuous = np.array([j.nq == 2 for j in kinova.model.joints[1:] if j.nv])
    wrapped = np.where(continuous, np.angle(np.exp(1j * values)), values)
    np.testing.assert_allclose(back, wrapped, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(
        kinova.q_from_joint_values(back), q, rtol=0, atol=ATOL_EXACT
    )
    np.testing.assert_array_equal(kinova.as_configuration(values), q)
    np.testing.assert_array_equal(kinova.as_configuration(q), q)  # nq: as is


def test_joint_values_of_one_coordinate_joints_are_q(puma) -> None:
    q = np.array([0.1, -0.2, 0.3, -0.4, 0.5, -0.6])
    for converted in (
        puma.q_from_joint_values(q),
        puma.joint_values_from_q(q),
        puma.as_configuration(q),
    ):
        np.testing.assert_array_equal(converted, q)


def test_wrong_joint_value_counts(kinova) -> None:
    with pytest.raises(DimensionError, match="6 values expected, 7 given"):
        kinova.as_configuration(np.zeros(7))
    with pytest.raises(DimensionError, match="joint values"):
        kinova.q_from_joint_values(np.zeros(9))


def test_a_planar_joint_has_no_single_value(tmp_path: Path) -> None:
    robot = load_robot(
        _urdf(tmp_path / "planar.urdf", _joint("p", "base", "l1", kind="planar"))
    )
    assert robot.nq == 4 and robot.nv == 3
    with pytest.raises(InputError, match=r"joint 'p' .* no single joint value"):
        robot.q_from_joint_values(np.zeros(1))
    assert robot.as_configuration(pin.neutral(robot.model)).shape == (4,)


# --- package:// folders ---------------------------------------------------------

_STL = """solid t
facet normal 0 0 1
outer loop
vertex 0 0 0
vertex 0.1 0 0
vertex 0 0.1 0
endloop
endfacet
endsolid t
"""


def write_packaged_arm(tmp_path: Path) -> tuple[Path, Path]:
    """A URDF whose meshes are in a package folder elsewhere: (urdf, packages)."""
    packages = tmp_path / "ws" / "src"
    meshes = packages / "mypkg" / "meshes"
    meshes.mkdir(parents=True)
    (meshes / "tri.stl").write_text(_STL)
    geometry = '<geometry><mesh filename="package://mypkg/meshes/tri.stl"/></geometry>'
    links = "".join(
        f'<link name="m{i}"><visual>{geometry}</visual>'
        f"<collision>{geometry}</collision></link>"
        for i in (1, 2)
    )
    folder = tmp_path / "robot" / "urdf"
    folder.mkdir(parents=True)
    urdf = _urdf(
        folder / "arm.urdf",
        _joint("j1", "base", "m1", axis="0 0 1"),
        _joint("j2", "m1", "m2"),
        links=links,
    )
    return urdf, packages


def test_package_uris_need_a_package_folder(tmp_path, monkeypatch) -> None:
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    monkeypatch.delenv("AMENT_PREFIX_PATH", raising=False)
    urdf, packages = write_packaged_arm(tmp_path)
    with pytest.raises(
        URDFLoadError, match=re.escape("package://mypkg/meshes/tri.stl")
    ):
        load_robot(urdf)  # every mesh is resolved when the robot is loaded
    expected = packages / "mypkg" / "meshes" / "tri.stl"
    for given_dir in (packages, packages / "mypkg"):  # a package's own folder too
        robot = load_robot(urdf, package_dirs=[given_dir])
        paths = [Path(g.meshPath) for g in robot.visual_model.geometryObjects]
        assert paths == [expected, expected]
    monkeypatch.setenv(
        "ROS_PACKAGE_PATH", os.pathsep.join(["/no/such/dir", str(packages)])
    )
    robot = load_robot(urdf)
    assert Path(robot.collision_model.geometryObjects[0].meshPath) == expected


def test_a_missing_package_folder_is_refused(tmp_path) -> None:
    with pytest.raises(URDFLoadError, match=r"package folder not found: .*nope"):
        load_robot("puma560", package_dirs=[tmp_path / "nope"])
