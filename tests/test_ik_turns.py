"""Every in-limit representative: joints whose range exceeds a full turn.

``ik.analytic(..., representatives="all")`` and ``workbench ik --all --all-turns``
list each branch's ``q ± 2πk`` within the limits. The KUKA KR6 R700's a6 turns
±350° (two representatives for most angles, one for |q6| > 10°); the UR5's joints
turn ±360° except the elbow.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.conftest import run_cli
from workbench import InputError, load_robot
from workbench.cli import EXIT_BAD_INPUT
from workbench.ik import analytic
from workbench.ik.turns import get_turns

#: FK residual of every representative [m and rad]: the same pose.
FK_TOL = 1e-12
TAU = 2.0 * math.pi


def test_turns_within_limits() -> None:
    assert get_turns(0.5, -6.1, 6.1) == [-1, 0]  # 0.5 - 2π is in, 0.5 + 2π is not
    assert get_turns(-0.5, -6.1, 6.1) == [0, 1]
    assert get_turns(0.1, -6.1, 6.1) == [0]  # 0.1 - 2π = -6.18: out
    assert get_turns(3.0, -6.1, 6.1) == [-1, 0]
    assert get_turns(0.5, -1.0, 1.0) == [0]
    assert get_turns(0.0, -math.inf, math.inf) == [0]


@pytest.mark.parametrize("name", ["kuka-kr6-r700", "ur5"])
def test_every_representative_reaches_the_pose_within_the_limits(name: str) -> None:
    robot = load_robot(name)
    rng = np.random.default_rng(0)
    for q in rng.uniform(robot.lower, robot.upper, size=(5, 6)):
        target = robot.fk(q)
        one = analytic(robot, target)
        every = analytic(robot, target, representatives="all")
        wide = [j for j in range(6) if robot.upper[j] - robot.lower[j] > TAU]
        expected = sum(
            math.prod(
                len(get_turns(s.q[j], robot.lower[j], robot.upper[j])) for j in wide
            )
            for s in one
        )
        assert len(every) == expected > len(one)
        labels = [s.branch for s in every]
        assert len(set(labels)) == len(labels)  # each labelled with its turns
        plain = {s.branch: s.q for s in one}
        for s in every:
            pose = robot.fk(s.q)
            assert np.abs(pose.homogeneous - target.homogeneous).max() <= FK_TOL
            base = s.branch.split(" (")[0]
            turns = np.round((s.q - plain[base]) / TAU)
            np.testing.assert_allclose(
                s.q, plain[base] + TAU * turns, rtol=0, atol=1e-12
            )
            assert all(turns[j] == 0 for j in range(6) if j not in wide)
            assert s.within_limits == bool(
                np.all(s.q >= robot.lower - 1e-9) and np.all(s.q <= robot.upper + 1e-9)
            )
            if base == s.branch:  # the solve's own representative: unchanged
                np.testing.assert_array_equal(s.q, plain[base])
        generating = [s for s in every if np.abs(s.q - q).max() <= 1e-9]
        assert len(generating) == 1  # q itself is one of them, whatever its turn


def test_bad_option_and_the_command_line(capsys) -> None:
    robot = load_robot("kuka-kr6-r700")
    with pytest.raises(InputError, match="representatives must be one of one, all"):
        analytic(robot, robot.fk(np.zeros(6)), representatives="every")
    q = np.deg2rad([10, -40, 30, 20, 50, 5])
    matrix = [str(x) for x in robot.fk(q).homogeneous.ravel()]
    base = ("ik", "--robot", "kuka-kr6-r700", "--matrix", *matrix, "--json")
    code, out, err = run_cli(capsys, *base, "--all", "--all-turns")
    assert (code, err) == (0, "")
    rows = json.loads(out)["solutions"]
    assert any("(q6-1)" in row["branch"] for row in rows)
    assert len(rows) == len(analytic(robot, robot.fk(q), representatives="all"))
    code, out, err = run_cli(capsys, *base, "--all-turns")
    assert code == EXIT_BAD_INPUT and "give --all too" in err
