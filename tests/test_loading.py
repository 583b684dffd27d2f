"""load_robot: catalog names, URDF paths, package:// meshes, and bad input."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from workbench import (
    DimensionError,
    FrameNotFoundError,
    InputError,
    JointNotFoundError,
    NonFiniteError,
    RobotNotFoundError,
    URDFLoadError,
    get_robot_names,
    load_robot,
)
from workbench.model.catalog import (
    CATALOG,
    get_catalog_urdf,
    get_example_robot_data_dir,
)
from workbench.model.packages import MeshNotFoundError

ARMS = {"ur5": (6, "tool0"), "panda": (7, "panda_hand_tcp"), "xarm7": (7, "link_eef")}


def test_every_catalog_urdf_exists() -> None:
    missing = [name for name in CATALOG if not get_catalog_urdf(name).is_file()]
    assert missing == []


@pytest.mark.parametrize("name", sorted(CATALOG))
def test_every_catalog_robot_loads(name: str) -> None:
    robot = load_robot(name)
    assert robot.nq >= 1
    assert robot.tool_frame in robot.frame_names
    pose = robot.fk(np.clip(np.zeros(robot.nq), robot.lower, robot.upper))
    assert np.all(np.isfinite(pose.homogeneous))


@pytest.mark.parametrize(("name", "expected"), sorted(ARMS.items()))
def test_arms_have_their_tool_frame(name: str, expected: tuple[int, str]) -> None:
    robot = load_robot(name)
    assert (robot.nq, robot.tool_frame) == expected
    assert robot.jacobian(np.zeros(robot.nq)).shape == (6, robot.nv)


def test_meshes_resolve_from_package_uris() -> None:
    robot = load_robot("ur5")
    paths = [Path(g.meshPath) for g in robot.visual_model.geometryObjects if g.meshPath]
    assert paths and all(p.is_file() for p in paths)
    assert len(robot.collision_model.geometryObjects) > 0


def test_urdf_path_with_package_uris_relative_to_its_parents(tmp_path: Path) -> None:
    """A copied robot folder resolves package:// against the URDF's parents."""
    source = get_example_robot_data_dir()
    root = tmp_path / "share" / "example-robot-data" / "robots"
    shutil.copytree(source / "ur_description", root / "ur_description")
    robot = load_robot(
        root / "ur_description" / "urdf" / "ur5_robot.urdf", tool_frame="tool0"
    )
    paths = [Path(g.meshPath) for g in robot.visual_model.geometryObjects if g.meshPath]
    assert paths and all(str(p).startswith(str(tmp_path)) for p in paths)


def test_puma_geometry_is_primitives(puma) -> None:
    assert len(puma.visual_model.geometryObjects) >= 12
    assert puma.joint_names == [f"joint{i}" for i in range(1, 7)]


def test_with_limits_overrides_speed_and_acceleration(puma) -> None:
    faster = puma.with_limits(velocity_limit=[3.0] * 6, acceleration_limit=[10.0] * 6)
    assert faster.velocity_limit.tolist() == [3.0] * 6
    assert faster.acceleration_limit.tolist() == [10.0] * 6
    assert puma.velocity_limit.tolist() != faster.velocity_limit.tolist()
    with pytest.raises(InputError, match="must be > 0"):
        puma.with_limits(velocity_limit=[0.0] * 6)
    with pytest.raises(DimensionError, match="velocity_limit"):
        puma.with_limits(velocity_limit=[1.0] * 5)


def test_stored_limits_are_read_only(puma) -> None:
    with pytest.raises(ValueError, match="read-only"):
        puma.lower[0] = 0.0


def test_unknown_robot_lists_valid_names() -> None:
    with pytest.raises(RobotNotFoundError) as info:
        load_robot("puma561")
    message = str(info.value)
    assert "unknown robot 'puma561'" in message
    assert "puma560, puma560-kang" in message and "ur5" in message
    assert set(get_robot_names()) == set(CATALOG)


def test_missing_urdf(tmp_path: Path) -> None:
    with pytest.raises(URDFLoadError, match="URDF file not found"):
        load_robot(tmp_path / "nothing.urdf")


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("hello", "not a URDF"),
        ("<robot name='x'><link name='a'/>", "malformed URDF"),
        (
            "<robot name='x'><link name='a'/><link name='b'/><joint name='j' "
            "type='revolute'><parent link='a'/><child link='b'/></joint></robot>",
            "does not specify limits",
        ),
        ("<robot name='x'><link name='a'/></robot>", "no moving joint"),
    ],
)
def test_malformed_urdf(tmp_path: Path, text: str, fragment: str, capfd) -> None:
    path = tmp_path / "bad.urdf"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(URDFLoadError) as info:
        load_robot(path)
    assert fragment in str(info.value)
    assert capfd.readouterr().err == ""  # urdfdom's own messages are captured


def test_missing_mesh_is_a_clear_error(tmp_path: Path) -> None:
    path = tmp_path / "arm.urdf"
    path.write_text(
        "<robot name='x'><link name='a'/><link name='b'><visual><geometry>"
        "<mesh filename='package://nowhere/meshes/b.stl'/></geometry></visual></link>"
        "<joint name='j' type='revolute'><parent link='a'/><child link='b'/>"
        "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint></robot>",
        encoding="utf-8",
    )
    with pytest.raises(MeshNotFoundError) as info:  # at load, not when drawn
        load_robot(path)
    message = str(info.value)
    assert "package://nowhere/meshes/b.stl: package 'nowhere' not found" in message
    assert f"looked in {tmp_path} and its parents" in message
    assert "--package-dir DIR or --package-dir nowhere=DIR" in message
    assert "\n" not in message and isinstance(info.value, URDFLoadError)


def test_unknown_tool_frame_lists_frames() -> None:
    with pytest.raises(FrameNotFoundError, match=r"valid frames: .*tool0"):
        load_robot("ur5", tool_frame="flange")


def test_wrong_joint_count_and_nan(puma) -> None:
    with pytest.raises(DimensionError, match=r"6 values expected, 5 given"):
        puma.fk(np.zeros(5))
    with pytest.raises(NonFiniteError, match="must be finite"):
        puma.jacobian([0, 0, np.nan, 0, 0, 0])
    with pytest.raises(FrameNotFoundError, match="frame 'nope'"):
        puma.fk(np.zeros(6), frame="nope")


def test_unknown_locked_joint_is_reported(monkeypatch) -> None:
    from workbench.model import catalog

    entry = catalog.CatalogEntry(
        "ur_description/urdf/ur5_robot.urdf", "tool0", ("gripper",)
    )
    monkeypatch.setitem(catalog.CATALOG, "ur5_broken", entry)
    with pytest.raises(JointNotFoundError, match="joint 'gripper' not in the model"):
        load_robot("ur5_broken")
