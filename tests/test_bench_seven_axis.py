"""The agreement checks of benchmarks/bench_seven_axis.py, run small.

They count what they say: frankik's answers (given the flange pose) reach the
TCP pose and are among ours, a multi-start Gauss-Newton at a fixed arm angle
finds only our branches, and the round trip through the parameter holds.
"""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from benchmarks.bench_seven_axis import (
    _HAND,
    agreement_frankik,
    agreement_multistart,
    round_trip,
)
from workbench import load_robot

needs_frankik = pytest.mark.skipif(
    importlib.util.find_spec("frankik") is None, reason="frankik: bench extra"
)


@needs_frankik
def test_frankiks_fk_is_the_hand_tcp_and_its_ik_takes_the_flange() -> None:
    import frankik

    robot = load_robot("panda")
    q = np.random.default_rng(0).uniform(robot.lower, robot.upper)
    tcp = robot.fk(q).homogeneous
    assert np.abs(frankik.fk(q) - tcp).max() < 1e-12
    answers = frankik.ik_full(tcp @ np.linalg.inv(_HAND), q, q[6])
    assert np.nanmin(np.abs(answers - q).max(axis=1)) < 1e-9


@needs_frankik
def test_every_frankik_answer_is_among_ours() -> None:
    result = agreement_frankik(load_robot("panda"), 200)
    assert isinstance(result, dict)
    assert result["frankik_solutions"] > 200
    assert result["not_in_ours_after_polish"] == 0
    assert result["ours_fk_residual"] < 1e-12


def test_multistart_solutions_at_the_same_arm_angle_are_ours() -> None:
    result = agreement_multistart(load_robot("iiwa14"), 4, starts=6)
    assert result["numerical_solutions"] > 0
    assert result["not_in_ours"] == 0


@pytest.mark.parametrize("name", ["panda", "iiwa14"])
def test_round_trip_through_the_parameter(name: str) -> None:
    assert round_trip(load_robot(name), 500)["worst_rad"] < 1e-9
