"""The truth of benchmarks/bench_workspace.py against ik.analytic, pose by pose.

The accuracy part of the benchmark rates the maps against ``exact_counts``
(``ik.analytic_batch`` and a limit test with 2π representatives, written there
independently of the atlas); here it agrees with ``ik.analytic``'s branches and
their ``within_limits`` flags, and the error rates count what they say.
"""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.bench_workspace import error_rates, exact_counts, held_out_poses
from workbench import load_robot
from workbench.ik import UnreachableError, analytic
from workbench.workspace import make_pose_grid


@pytest.mark.slow
@pytest.mark.parametrize("name", ["puma560", "ur5"])
def test_exact_counts_are_the_closed_forms_branches_within_limits(name: str) -> None:
    robot = load_robot(name)
    grid = make_pose_grid(robot, resolution=0.3, orientations=8)
    poses = held_out_poses(robot, grid, 300, seed=2)
    assert np.all(np.abs(np.linalg.det(poses[:, :3, :3]) - 1.0) < 1e-12)
    reached, within = exact_counts(robot, poses)
    assert np.all(within[:150] >= 1)  # tool poses of in-limit configurations
    assert 0 < np.count_nonzero(within[150:]) < 150  # box poses: some, not all
    for pose, r, w in zip(poses, reached, within, strict=True):
        try:
            solutions = analytic(robot, pose)
        except UnreachableError:
            solutions = []
        assert r == len(solutions)
        assert w == sum(s.within_limits for s in solutions)


def test_error_rates_count_wrong_answers_per_class() -> None:
    truth = np.array([True, True, True, True, False, False])
    said = np.array([True, False, True, True, True, False])
    assert error_rates(truth, said) == (0.5, 0.25)
    fp, fn = error_rates(np.ones(3, dtype=bool), np.ones(3, dtype=bool))
    assert np.isnan(fp) and fn == 0.0
