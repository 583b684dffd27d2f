"""DH tables and the generated URDFs, checked against Pinocchio."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from tests.conftest import PUMA_NAMES, random_configurations
from workbench import DHTable, DHTableError, generate_urdf, load_robot
from workbench.model.catalog import get_own_urdf_dir

ATOL_EXACT = 1e-12
ATOL_FD = 1e-6
SAMPLES = 300


@pytest.mark.parametrize(
    "name", [*PUMA_NAMES, "kuka-kr6-r700", "abb-irb2400", "generic6r", "iiwa14"]
)
def test_committed_urdf_equals_fresh_generation(name: str) -> None:
    folder = get_own_urdf_dir()
    table = DHTable.from_json(folder / f"{name}.dh.json")
    committed = (folder / f"{name}.urdf").read_text(encoding="utf-8")
    assert committed == generate_urdf(table), f"regenerate urdf/{name}.urdf"


def test_fk_equals_dh_product(any_puma, rng) -> None:
    table = any_puma.dh_table
    for q in random_configurations(any_puma, rng, SAMPLES):
        np.testing.assert_allclose(
            any_puma.fk(q).homogeneous,
            table.forward_kinematics(q),
            rtol=0,
            atol=ATOL_EXACT,
        )


def test_every_dh_frame_is_a_pinocchio_frame(any_puma, rng) -> None:
    q = random_configurations(any_puma, rng, 1)[0]
    frames = any_puma.dh_table.frame_transforms(q)
    for i, expected in enumerate(frames):
        np.testing.assert_allclose(
            any_puma.fk(q, frame=f"frame{i}").homogeneous,
            expected,
            rtol=0,
            atol=ATOL_EXACT,
        )


def test_jacobian_equals_dh_geometric_jacobian(any_puma, rng) -> None:
    table = any_puma.dh_table
    for q in random_configurations(any_puma, rng, SAMPLES):
        np.testing.assert_allclose(
            any_puma.jacobian(q), table.geometric_jacobian(q), rtol=0, atol=ATOL_EXACT
        )


def test_reference_frames_relate_by_adjoint(any_puma, rng) -> None:
    q = random_configurations(any_puma, rng, 1)[0]
    pose = any_puma.fk(q)
    local, world = any_puma.jacobian_local(q), any_puma.jacobian_world(q)
    aligned = pin.SE3(pose.rotation, np.zeros(3))
    np.testing.assert_allclose(
        any_puma.jacobian(q), aligned.toActionMatrix() @ local, rtol=0, atol=ATOL_EXACT
    )
    np.testing.assert_allclose(
        world, pose.toActionMatrix() @ local, rtol=0, atol=ATOL_EXACT
    )


def test_jacobian_equals_finite_differences(any_puma, rng) -> None:
    h = 1e-6
    for q in random_configurations(any_puma, rng, 20):
        pose = any_puma.fk(q)
        numeric = np.empty((6, any_puma.nv))
        for j in range(any_puma.nv):
            dq = np.zeros(any_puma.nv)
            dq[j] = h
            plus, minus = any_puma.fk(q + dq), any_puma.fk(q - dq)
            numeric[:3, j] = (plus.translation - minus.translation) / (2 * h)
            # Angular velocity in base axes: log of the relative rotation.
            numeric[3:, j] = pin.log3(plus.rotation @ minus.rotation.T) / (2 * h)
        del pose
        np.testing.assert_allclose(any_puma.jacobian(q), numeric, rtol=0, atol=ATOL_FD)


def test_jacobian_time_derivative_equals_finite_differences(any_puma, rng) -> None:
    h = 1e-6
    for q in random_configurations(any_puma, rng, 20):
        v = rng.uniform(-1.0, 1.0, any_puma.nv)
        numeric = (any_puma.jacobian(q + h * v) - any_puma.jacobian(q - h * v)) / (
            2 * h
        )
        np.testing.assert_allclose(
            any_puma.jacobian_time_derivative(q, v), numeric, rtol=0, atol=ATOL_FD
        )


def test_puma_limits_are_the_papers(puma, puma_kang) -> None:
    deg = np.rad2deg
    np.testing.assert_allclose(
        deg(puma.lower), [-160, -225, -45, -170, -135, -170], atol=1e-12
    )
    np.testing.assert_allclose(
        deg(puma.upper), [160, 45, 225, 170, 135, 170], atol=1e-12
    )
    # Kang's zeros: theta2 + 180 deg, theta5 sign flipped (urdf/README.md).
    np.testing.assert_allclose(
        deg(puma_kang.lower), [-160, -45, -45, -170, -135, -170], atol=1e-12
    )
    np.testing.assert_allclose(
        deg(puma_kang.upper), [160, 225, 225, 170, 135, 170], atol=1e-12
    )
    assert np.all(np.isinf(puma.acceleration_limit))


def test_kang_model_is_angeles_model_in_other_joint_zeros(puma, puma_kang, rng) -> None:
    """The joint mapping documented in urdf/README.md, checked at random q.

    The two tables differ in a3 (19.05 vs 20.3 mm), so Angeles' a3 is put into
    Kang's table first; then only the joint zeros and the base frame differ.
    """
    rows = list(puma_kang.dh_table.joints)
    rows[2] = dataclasses.replace(rows[2], a=puma.dh_table.joints[2].a)
    kang = dataclasses.replace(puma_kang.dh_table, joints=tuple(rows))
    base = pin.SE3(np.diag([-1.0, -1.0, 1.0]), np.zeros(3))  # Rz(pi)
    for q in random_configurations(puma, rng, 100):
        q_kang = q + np.array([0.0, math.pi, 0.0, 0.0, 0.0, 0.0])
        q_kang[4] = -q[4]
        np.testing.assert_allclose(
            kang.forward_kinematics(q_kang),
            (base * puma.fk(q)).homogeneous,
            rtol=0,
            atol=ATOL_EXACT,
        )


def test_generator_handles_any_standard_table(tmp_path: Path, rng) -> None:
    rows = [
        {
            "alpha": float(rng.uniform(-3, 3)),
            "a": float(rng.uniform(-1, 1)),
            "d": float(rng.uniform(-1, 1)),
            "theta_offset": float(rng.uniform(-3, 3)),
        }
        for _ in range(5)
    ]
    table = DHTable.from_dict(
        {"name": "random arm", "joints": rows, "tool_frame": "flange"}
    )
    path = tmp_path / "arm.urdf"
    path.write_text(generate_urdf(table), encoding="utf-8")
    robot = load_robot(path)
    assert robot.tool_frame == "flange"
    for q in rng.uniform(-math.pi, math.pi, size=(50, 5)):
        np.testing.assert_allclose(
            robot.fk(q).homogeneous,
            table.forward_kinematics(q),
            rtol=0,
            atol=ATOL_EXACT,
        )
    assert robot.velocity_limit.tolist() == [1.0] * 5  # stated default


@pytest.mark.parametrize(
    ("mutate", "fragment"),
    [
        (lambda t: t.pop("joints"), "'joints' must be a non-empty list"),
        (lambda t: t["joints"][0].pop("alpha"), "joint 1: missing key(s) alpha"),
        (lambda t: t["joints"][1].update(a="x"), "joint 2: 'a' must be a number"),
        (lambda t: t["joints"][0].update(d=float("nan")), "'d' must be finite"),
        (lambda t: t["joints"][0].update(lower=1.0, upper=-1.0), "lower limit"),
        (lambda t: t["joints"][0].update(velocity=0.0), "velocity limit must be > 0"),
        (lambda t: t["joints"][0].update(theta=0.0), "unknown key(s) theta"),
        (lambda t: t.update(convention="modified"), "only 'standard'"),
        (lambda t: t.update(name=""), "'name' must be a non-empty string"),
        (lambda t: t.update(extra=1), "unknown key(s) extra"),
    ],
)
def test_malformed_dh_table_is_rejected(mutate, fragment) -> None:
    raw = json.loads(
        (get_own_urdf_dir() / "puma560.dh.json").read_text(encoding="utf-8")
    )
    mutate(raw)
    with pytest.raises(DHTableError, match=None) as info:
        DHTable.from_dict(raw)
    assert fragment in str(info.value)


def test_unreadable_dh_table_is_rejected(tmp_path: Path) -> None:
    with pytest.raises(DHTableError, match="cannot read DH table"):
        DHTable.from_json(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json", encoding="utf-8")
    with pytest.raises(DHTableError, match="not valid JSON"):
        DHTable.from_json(bad)
