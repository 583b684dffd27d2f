"""Closed-form IK of any arm cross-checked against EAIK, ik-geo and numerical IK.

EAIK and ik-geo (the ``bench`` extra) solve the same chain by subproblem
decomposition from the joint axes; each test is skipped when its peer is not
installed. ik-geo takes the chain in the form its solvers assume: the points
on axes that meet (4, 5, 6 of an OPW arm, 5 and 6 of a UR arm) at the point
where they meet, and the rotation as a list of columns.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from benchmarks.bench_ik_agreement import eaik_solver, ik_geo_solver, rounded_urdf
from workbench import Robot, load_robot
from workbench.ik import analytic, get_structure, numeric
from workbench.ik.structure import axis_lines

MODELS = ("puma560", "kuka-kr6-r700", "abb-irb2400", "ur3", "ur5", "ur10")
ATOL_Q = 1e-7  # [rad] the same configuration, modulo 2π
N_POSES = 200


def wrapped(d: np.ndarray) -> np.ndarray:
    return np.remainder(d + np.pi, 2.0 * math.pi) - np.pi


def eaik_robot(robot: Robot):
    """EAIK's model of the same chain, and the tool rotation at q = 0.

    EAIK takes the axes H (6, 3) and the offsets P (7, 3) between points on
    them at q = 0, and solves for the tool pose with the rotation at q = 0
    taken as the identity.
    """
    hp = pytest.importorskip("eaik.IK_HP")
    directions, points = axis_lines(robot)
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, np.zeros(6))
    tool = data.oMf[robot.tool_frame_id]
    offsets = np.diff(np.vstack([np.zeros(3), points, tool.translation]), axis=0)
    return hp.HPRobot(directions, offsets), tool.rotation


@pytest.mark.parametrize("name", MODELS)
def test_every_eaik_solution_is_a_branch_and_back(name: str) -> None:
    robot = load_robot(name)
    peer, rotation0 = eaik_robot(robot)
    rng = np.random.default_rng(11)
    matched = 0
    for q in rng.uniform(robot.lower, robot.upper, size=(N_POSES, 6)):
        target = robot.fk(q).homogeneous
        ours = np.array([s.q for s in analytic(robot, target)])
        pose = target.copy()
        pose[:3, :3] = target[:3, :3] @ rotation0.T
        solution = peer.IK(pose)
        theirs = np.array(solution.Q)[~np.asarray(solution.is_LS, dtype=bool)]
        for q_peer in theirs:
            assert np.abs(wrapped(ours - q_peer)).max(axis=1).min() <= ATOL_Q
        for q_ours in ours:
            assert np.abs(wrapped(theirs - q_ours)).max(axis=1).min() <= ATOL_Q
        matched += len(ours)
    assert matched >= 4 * N_POSES


def ik_geo_robot(robot: Robot):
    """ik-geo's model of the same chain, and the tool rotation at q = 0.

    ik-geo takes H (6, 3) and P (7, 3) as EAIK does, but its solvers assume
    zero offsets between axes that meet: ``spherical_two_parallel`` (OPW) never
    reads p45 and p56, ``three_parallel_two_intersecting`` (UR) adds p56 to p45
    as if q5 did not turn it. So the points on those axes are moved to where
    the axes meet (``axis_lines`` gives each axis's point nearest the origin).
    """
    ik_geo = pytest.importorskip("ik_geo")
    family = get_structure(robot).family
    directions, points = axis_lines(robot)
    k = 3 if family == "opw" else 4  # first of the axes that meet
    a, u, b, v = points[k], directions[k], points[k + 1], directions[k + 1]
    s = np.linalg.lstsq(np.column_stack([u, -v]), b - a, rcond=None)[0][0]
    points = points.copy()
    points[k:] = a + s * u
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, np.zeros(6))
    tool = data.oMf[robot.tool_frame_id]
    offsets = np.diff(np.vstack([np.zeros(3), points, tool.translation]), axis=0)
    make = (
        ik_geo.Robot.three_parallel_two_intersecting
        if family == "ur"
        else ik_geo.Robot.spherical_two_parallel
    )
    return make(directions, offsets), tool.rotation


@pytest.mark.parametrize("name", MODELS)
def test_every_ik_geo_solution_is_a_branch_and_back(name: str) -> None:
    robot = load_robot(name)
    peer, rotation0 = ik_geo_robot(robot)
    rng = np.random.default_rng(13)
    matched = 0
    for q in rng.uniform(robot.lower, robot.upper, size=(N_POSES, 6)):
        target = robot.fk(q).homogeneous
        ours = np.array([s.q for s in analytic(robot, target)])
        # get_ik reads R[j] as column j of the rotation
        rotation = (target[:3, :3] @ rotation0.T).T
        answers = peer.get_ik(rotation, target[:3, 3])
        theirs = np.array([q_p for q_p, is_ls in answers if not is_ls]).reshape(-1, 6)
        for q_peer in theirs:
            error = np.abs(robot.fk(q_peer).homogeneous - target).max()
            assert error <= 1e-9
            assert np.abs(wrapped(ours - q_peer)).max(axis=1).min() <= ATOL_Q
        for q_ours in ours:
            assert np.abs(wrapped(theirs - q_ours)).max(axis=1).min() <= ATOL_Q
        matched += len(ours)
    assert matched >= 4 * N_POSES


@pytest.mark.parametrize("name", ["puma560", "kuka-kr6-r700", "ur5"])
def test_numeric_ik_lands_on_a_branch(name: str) -> None:
    """``ik.numeric`` (public API) converges to one of the closed-form branches."""
    robot = load_robot(name)
    rng = np.random.default_rng(12)
    landed = 0
    for q in rng.uniform(robot.lower, robot.upper, size=(20, 6)):
        target = robot.fk(q)
        result = numeric(robot, target, rng=0)
        if not result.success:
            continue
        ours = np.array([s.q for s in analytic(robot, target)])
        assert np.abs(wrapped(ours - result.q)).max(axis=1).min() <= 1e-6
        landed += 1
    assert landed >= 15
    assert get_structure(robot).family in ("opw", "ur")


# -- URDFs that are of their family only up to rounding ---------------------------

ROUNDED = ("kuka-kr6-r700", "puma560", "ur5")
ATOL_Q_ROUNDED = 1e-9  # [rad] refined branches against the peers' exact answers
MIN_SIGMA = 1e-2  # poses whose Jacobian has a smaller singular value are skipped


@pytest.mark.parametrize("peer_name", ["eaik", "ik_geo"])
@pytest.mark.parametrize("name", ROUNDED)
def test_rounded_urdf_branches_agree_with_peers(
    name: str, peer_name: str, tmp_path
) -> None:
    """Rounded URDF (1e-9 off), away from singularities: same branches to 1e-9.

    Our branches are refined on the model (FK residual <= 1e-12); EAIK and
    ik-geo solve the model's own axes.
    """
    pytest.importorskip("eaik.IK_HP" if peer_name == "eaik" else "ik_geo")
    robot = rounded_urdf(name, tmp_path)
    solve = (eaik_solver if peer_name == "eaik" else ik_geo_solver)(robot)
    assert callable(solve), solve  # (a string says why the peer refused)
    rng = np.random.default_rng(14)
    model, data = robot.model, robot.model.createData()
    compared = 0
    for q in rng.uniform(robot.lower, robot.upper, size=(N_POSES, 6)):
        jacobian = pin.computeJointJacobians(model, data, q)
        if np.linalg.svd(jacobian, compute_uv=False)[-1] < MIN_SIGMA:
            continue
        target = robot.fk(q).homogeneous
        ours = np.array([s.q for s in analytic(robot, target)])
        theirs = solve(target)
        assert len(theirs) == len(ours)
        for q_peer in theirs:
            assert np.abs(wrapped(ours - q_peer)).max(axis=1).min() <= ATOL_Q_ROUNDED
        for q_ours in ours:
            assert np.abs(wrapped(theirs - q_ours)).max(axis=1).min() <= ATOL_Q_ROUNDED
        compared += 1
    assert compared >= N_POSES // 2
