"""Closed-form IK of any arm cross-checked against EAIK and numerical IK.

EAIK (the ``bench`` extra) solves the same chain by subproblem decomposition
from the joint axes; the test is skipped when it is not installed. ik-geo is
in the extra too, but its 1.0.3 Python bindings return least-squares answers
that miss the pose on these arms (see ``benchmarks/bench_ik_closed_form.py``),
so it is benchmarked, not used as a reference.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

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
