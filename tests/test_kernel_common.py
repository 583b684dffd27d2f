"""``workbench.ik._kernel_common``: what the compiled closed forms share."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from workbench import load_robot
from workbench.errors import InputError
from workbench.ik import (
    Flag,
    SolveFlag,
    _flags,
    _puma_kernel,
    _redundant_common,
    _ur_kernel,
    get_solver,
)
from workbench.ik import _kernel_common as common
from workbench.ik._targets import pose_rows
from workbench.poses import RIGIDITY_TOL

_BITS = (
    "REACHED",
    "WITHIN_LIMITS",
    "SHOULDER_SINGULAR",
    "ELBOW_SINGULAR",
    "WRIST_SINGULAR",
    "PARAMETER_SINGULAR",
)
_STATUSES = ("OK", "NOT_RIGID", "OUT_OF_REACH", "IN_CYLINDER")


def test_one_flag_encoding_for_every_kernel() -> None:
    """Each bit once, named in one place, and the same in 6R and 7R kernels."""
    bits = [getattr(_flags, name) for name in _BITS]
    assert sorted(bits) == [1 << k for k in range(len(_BITS))]  # each bit once
    for name in _BITS:
        assert getattr(_redundant_common, name) == getattr(_flags, name)
        assert int(getattr(Flag, name)) == getattr(_flags, name)
    assert max(bits) < 256  # one uint8 per branch
    for name in _STATUSES:
        assert getattr(_puma_kernel, name) == getattr(common, name)
        assert getattr(_ur_kernel, name) == getattr(common, name)
    assert len({getattr(common, name) for name in _STATUSES}) == 4
    # the solve-level bits (ik.SolveFlag): each once, and none is a branch bit
    solve = [_flags.BRANCH_VANISHED, _flags.BRANCHES_MERGED, _flags.SOLUTIONS_UNLISTED]
    assert sorted(solve) == [1, 2, 4]
    assert [int(flag) for flag in SolveFlag] == solve


@pytest.fixture(scope="module")
def solvers() -> list:
    return [get_solver(load_robot(name)) for name in ("puma560", "ur5")]


def _rotation(q: list[float]) -> np.ndarray:
    w, x, y, z = np.asarray(q) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


_SPECIAL = st.sampled_from([math.nan, math.inf, -math.inf])


@settings(max_examples=300, deadline=None)
@given(
    quaternion=st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4).filter(
        lambda q: np.linalg.norm(q) > 0.1
    ),
    entry=st.integers(0, 15),
    change=st.one_of(
        st.floats(-3.0 * RIGIDITY_TOL, 3.0 * RIGIDITY_TOL), st.just(0.0), _SPECIAL
    ),
    mirrored=st.booleans(),
)
def test_kernels_refuse_exactly_the_poses_the_exact_checks_refuse(
    solvers, quaternion, entry, change, mirrored
) -> None:
    """NOT_RIGID (one pose and batch) if and only if ``pose_rows`` raises."""
    pose = np.eye(4)
    pose[:3, :3] = _rotation(quaternion)
    pose[:3, 3] = 0.3, -0.2, 0.4
    if mirrored:  # det R = -1
        pose[:3, 2] *= -1.0
    pose.flat[entry] += change
    try:
        pose_rows(pose)
        rigid = True
    except InputError:
        rigid = False
    for solver in solvers:
        kernel, geometry = solver._kernel, solver.geometry
        q, flags = np.empty((8, 6)), np.empty(8, dtype=np.uint8)
        status = kernel.solve_pose(geometry, pose, np.empty(0), q, flags, True)
        assert (status == common.NOT_RIGID) == (not rigid)
        n = kernel.N_ANGLES
        y, x = np.empty(n), np.empty(n)
        codes, exact = np.empty(1, np.int8), np.empty(1, np.int64)
        odd = np.empty(1, np.uint8)
        flat = np.ascontiguousarray(pose).reshape(16)
        kernel.batch_arguments(geometry, flat, y, x, codes, exact, odd, True)
        assert bool(odd[0] & 2) == (not rigid)


def test_nearest_or_kept_and_row_within_limits() -> None:
    """The seven-axis kernels' branch choice and limit test (any row length)."""
    q = np.array([[0.0, 0.0], [1.0, 0.0], [np.nan, np.nan], [0.1, 0.0]])
    reference = np.array([0.2, 0.0])
    assert common.nearest_or_kept(q, reference, 1, 1.0) == 1  # kept: step 0.64
    assert common.nearest_or_kept(q, reference, 1, 0.5) == 3  # too far: nearest
    assert common.nearest_or_kept(q, reference, 2, 1.0) == 3  # NaN row skipped
    assert common.nearest_or_kept(np.full((2, 2), np.nan), reference, 0, 1.0) == -1
    geo = np.zeros(1, dtype=[("lower", "f8", 2), ("upper", "f8", 2)]).view(np.recarray)[
        0
    ]
    geo.lower[:], geo.upper[:] = -0.5, 0.5
    assert [common.row_within_limits(geo, q, b) for b in range(4)] == [
        True,
        False,
        False,
        True,
    ]
