"""Targets for any arm: position only, position and one tool axis, full pose.

``ik.numeric(..., weights=...)`` weighs the entries of the SE(3) error (target
frame); ``ik.select(..., weights=...)`` and ``workbench ik --position-only`` /
``--free-axis`` go through it. A four-axis arm (base yaw, shoulder, elbow, wrist
pitch, as the Lynxmotion AL5D) reaches points, not poses.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.conftest import run_cli
from workbench import InputError, load_robot
from workbench.cli import EXIT_BAD_INPUT, EXIT_INFEASIBLE
from workbench.ik import TARGET_PARTS, numeric, numeric_batch, select

#: The solver's default convergence threshold on the (weighted) error.
TOL = 1e-10
#: A converged position [m] and axis [rad] (the threshold, with rounding).
REACHED = 2e-10


def _four_axis_arm(tmp_path: Path) -> Path:
    """Base yaw, shoulder, elbow and wrist pitch (AL5D-like lengths) [m]."""
    joints = [
        ("base", "l1", "0 0 0.07", "0 0 1"),
        ("l1", "l2", "0 0 0", "0 1 0"),
        ("l2", "l3", "0 0 0.146", "0 1 0"),
        ("l3", "l4", "0 0 0.187", "0 1 0"),
    ]
    body = "".join(f'<link name="l{i}"/>' for i in range(1, 5))
    body += '<link name="tip"/>'
    for i, (parent, child, xyz, axis) in enumerate(joints, start=1):
        body += (
            f'<joint name="j{i}" type="revolute"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{xyz}"/><axis xyz="{axis}"/>'
            '<limit lower="-2.6" upper="2.6" effort="1" velocity="1"/></joint>'
        )
    body += (
        '<joint name="tip" type="fixed"><parent link="l4"/><child link="tip"/>'
        '<origin xyz="0 0 0.086"/></joint>'
    )
    path = tmp_path / "four_axis.urdf"
    path.write_text(f'<robot name="four"><link name="base"/>{body}</robot>')
    return path


@pytest.fixture(scope="module")
def ur5() -> object:
    return load_robot("ur5")


@pytest.fixture(scope="module")
def four(tmp_path_factory) -> object:
    return load_robot(_four_axis_arm(tmp_path_factory.mktemp("arm")), tool_frame="tip")


def _turned(pose: pin.SE3, axis: np.ndarray, angle: float) -> pin.SE3:
    """``pose`` turned by ``angle`` about its own ``axis``."""
    return pose * pin.SE3(pin.exp3(angle * axis), np.zeros(3))


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_position_only_reaches_the_point_in_any_orientation(puma, seed: int) -> None:
    rng = np.random.default_rng(seed)
    q = rng.uniform(puma.lower, puma.upper)
    target = pin.SE3(pin.exp3(rng.normal(size=3)), puma.fk(q).translation)
    result = numeric(puma, target, part="position")
    assert result.success and result.position_error <= REACHED
    assert np.linalg.norm(puma.fk(result.q).translation - target.translation) <= REACHED


@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_a_free_axis_keeps_the_tool_axis_along_the_targets(ur5, axis: str) -> None:
    rng = np.random.default_rng(3)
    column = "xyz".index(axis)
    for _ in range(10):
        q = rng.uniform(-2.5, 2.5, size=6)
        unit = np.eye(3)[column]
        target = _turned(ur5.fk(q), unit, rng.uniform(-np.pi, np.pi))
        result = numeric(ur5, target, part=f"free-{axis}")
        assert result.success
        pose = ur5.fk(result.q)
        assert np.linalg.norm(pose.translation - target.translation) <= REACHED
        cos = pose.rotation[:, column] @ target.rotation[:, column]
        assert np.arccos(min(cos, 1.0)) <= 1e-7  # (the angle of a cos: its sqrt)


def test_a_four_axis_arm_reaches_points_and_gets_the_best_pose(four) -> None:
    rng = np.random.default_rng(0)
    for _ in range(20):
        q = rng.uniform(-1.5, 1.5, size=4)
        point = pin.SE3(pin.exp3(rng.normal(size=3)), four.fk(q).translation)
        result = numeric(four, point, part="position")
        assert result.success and result.position_error <= REACHED
        full = numeric(four, point)  # six numbers asked of four joints
        assert not full.success  # the best pose found, with its residuals
        assert np.isfinite(full.position_error) and full.rotation_error > 0.0
        assert full.error == pytest.approx(
            np.linalg.norm(pin.log6(point.actInv(four.fk(full.q))).vector), rel=1e-9
        )
    with pytest.raises(Exception, match="best residual"):
        select(four, point)  # the whole pose: out of reach, with the residual said
    assert np.allclose(four.fk(select(four, point, part="position").q).translation,
                       point.translation, atol=REACHED)  # fmt: skip


def test_weights_are_checked_and_the_batch_takes_them(puma) -> None:
    for bad in ([1, 1, 1], [1, 1, 1, 1, 1, -1], [0] * 6, [np.nan] * 6):
        with pytest.raises(InputError, match="weights"):
            numeric(puma, puma.fk(np.zeros(6)), weights=bad)
    with pytest.raises(InputError, match="part 'orientation'"):
        numeric(puma, puma.fk(np.zeros(6)), part="orientation")
    with pytest.raises(InputError, match="part='pose' only"):
        numeric(puma, puma.fk(np.zeros(6)), part="position", weights=[1] * 6)
    assert set(TARGET_PARTS) == {"pose", "position", "free-x", "free-y", "free-z"}
    rng = np.random.default_rng(1)
    qs = rng.uniform(puma.lower, puma.upper, size=(8, 6))
    targets = np.array(
        [
            pin.SE3(pin.exp3(rng.normal(size=3)), puma.fk(q).translation).homogeneous
            for q in qs
        ]
    )
    batch = numeric_batch(puma, targets, part="position")
    assert batch.success.all() and (batch.position_error <= REACHED).all()
    weighted = numeric(puma, puma.fk(qs[0]), weights=[1, 1, 1, 0.5, 0.5, 0.5])
    assert weighted.success and weighted.position_error <= REACHED


def test_the_command_line_asks_for_part_of_a_pose(capsys, tmp_path: Path) -> None:
    urdf = _four_axis_arm(tmp_path)
    four = load_robot(urdf, tool_frame="tip")
    point = four.fk(np.array([0.3, 0.4, 0.5, -0.6]))
    values = [*point.translation, 1, 0, 0, 0]  # an orientation it cannot take
    base = ("ik", "--robot", str(urdf), "--tool-frame", "tip", "--xyz-quat-wxyz")
    args = (*base, *map(str, values))
    code, out, err = run_cli(capsys, *args, "--position-only", "--json")
    assert (code, err) == (0, "")
    result = json.loads(out)
    assert result["solver"] == "numeric" and result["target"] == "position"
    (row,) = result["solutions"]
    assert row["residual"] <= REACHED
    np.testing.assert_allclose(four.fk(np.array(row["q"])).translation,
                               point.translation, atol=REACHED)  # fmt: skip
    code, out, err = run_cli(capsys, *args)  # the whole pose: out of reach
    assert code == EXIT_INFEASIBLE and err.count("\n") == 1 and "best residual" in err
    code, out, err = run_cli(capsys, *args, "--position-only", "--free-axis", "z")
    assert code == EXIT_BAD_INPUT and err.count("\n") == 1
    code, out, err = run_cli(capsys, *args, "--position-only", "--all")
    assert code == EXIT_BAD_INPUT and "--all does not apply" in err
    code, out, err = run_cli(capsys, *args, "--position-only")
    assert code == 0 and "target position only" in out and "residual" in out
