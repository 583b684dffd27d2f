"""ROS descriptions as users bring them: packages found the ROS way, xacro, meshes.

The ROS-Industrial KUKA KR16 and LBR iiwa 14 descriptions
(``tests/data/ros_industrial``, text files copied from their repository, see its
PROVENANCE.md) are loaded from their xacro sources and compared with the URDFs the
packages ship; small meshes are written at every path they name.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from tests._meshes import write_meshes_of, write_stl
from tests.conftest import run_cli
from workbench import URDFLoadError, load_robot
from workbench.cli import EXIT_BAD_INPUT
from workbench.model.packages import MeshNotFoundError, get_package_lookup
from workbench.workspace.robot_spec import get_robot_spec, load_spec_robot

DATA = Path(__file__).parent / "data" / "ros_industrial"
#: The shipped KR16 URDF prints π/2 with 11 decimals (1.57079632679): its tool0
#: is 4.9e-12 rad off the xacro's exact value, and its limits (degrees in radians
#: with 11 decimals) up to 2.7e-12 rad.
PRINTED_DIGITS_TOL = 1e-11
FK_TOL = 1e-12


def _arm_urdf(mesh: str, name: str = "arm") -> str:
    """A 2-joint arm whose links' visual and collision geometry is ``mesh``."""
    geometry = f'<geometry><mesh filename="{mesh}"/></geometry>'
    links = "".join(
        f'<link name="l{i}"><visual>{geometry}</visual><collision>{geometry}'
        "</collision></link>"
        for i in (1, 2)
    )
    joints = "".join(
        f'<joint name="j{i}" type="revolute"><parent link="{p}"/><child link="l{i}"/>'
        f'<origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>'
        '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        for i, p in ((1, "base"), (2, "l1"))
    )
    return f'<robot name="{name}"><link name="base"/>{links}{joints}</robot>'


def _package(folder: Path, name: str) -> Path:
    """A ROS package ``name`` in ``folder`` (whose name may differ) with one mesh."""
    folder.mkdir(parents=True)
    (folder / "package.xml").write_text(
        f'<?xml version="1.0"?><package format="2"><name>{name}</name>'
        "<version>1.0.0</version><description>test</description>"
        '<maintainer email="a@b.c">a</maintainer><license>BSD</license></package>'
    )
    write_stl(folder / "meshes" / "link.stl")
    return folder


@pytest.fixture
def no_ros_path(monkeypatch) -> None:
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)


def _mesh_paths(robot) -> set[Path]:
    return {Path(g.meshPath) for g in robot.collision_model.geometryObjects}


def test_a_package_is_found_by_its_package_xml_name(
    tmp_path: Path, no_ros_path
) -> None:
    workspace = tmp_path / "ws" / "src"
    package = _package(workspace / "kr16_description-main", "my_arm_support")
    urdf = tmp_path / "robot.urdf"
    urdf.write_text(_arm_urdf("package://my_arm_support/meshes/link.stl"))
    expected = {package / "meshes" / "link.stl"}
    for given in ([workspace], [tmp_path / "ws"], [package]):
        assert _mesh_paths(load_robot(urdf, package_dirs=given)) == expected
    assert _mesh_paths(load_robot(urdf, package_dirs=[f"my_arm_support={package}"]))
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("ROS_PACKAGE_PATH", f"/no/such/folder:{tmp_path / 'ws'}")
        assert _mesh_paths(load_robot(urdf)) == expected


def test_the_package_a_description_is_in_and_its_neighbours(
    tmp_path: Path, no_ros_path
) -> None:
    source = tmp_path / "src"
    own = _package(source / "arm-checkout", "arm_description")
    neighbour = _package(source / "shared_meshes_v2", "shared_meshes")
    (own / "urdf").mkdir()
    urdf = own / "urdf" / "arm.urdf"
    text = _arm_urdf("package://arm_description/meshes/link.stl")
    urdf.write_text(
        text.replace(
            '<link name="l2"><visual><geometry><mesh filename="package://arm_description',
            '<link name="l2"><visual><geometry><mesh filename="package://shared_meshes',
            1,
        )
    )
    paths = {Path(g.meshPath) for g in load_robot(urdf).visual_model.geometryObjects}
    assert paths == {own / "meshes" / "link.stl", neighbour / "meshes" / "link.stl"}


def test_an_explicit_mapping_wins_over_the_folders(tmp_path: Path, no_ros_path) -> None:
    first = _package(tmp_path / "a" / "pkg", "pkg")
    second = _package(tmp_path / "b" / "elsewhere", "pkg")
    urdf = tmp_path / "robot.urdf"
    urdf.write_text(_arm_urdf("package://pkg/meshes/link.stl"))
    both = [tmp_path / "a", f"pkg={second}"]
    assert _mesh_paths(load_robot(urdf, package_dirs=both)) == {
        second / "meshes" / "link.stl"
    }
    assert _mesh_paths(load_robot(urdf, package_dirs=[tmp_path / "a"])) == {
        first / "meshes" / "link.stl"
    }


def test_relative_file_and_odd_uris(tmp_path: Path, no_ros_path) -> None:
    mesh = write_stl(tmp_path / "meshes" / "link.stl")
    for uri in ("meshes/link.stl", f"file://{mesh}", str(mesh)):
        urdf = tmp_path / "robot.urdf"
        urdf.write_text(_arm_urdf(uri))
        assert _mesh_paths(load_robot(urdf)) == {mesh}
    urdf.write_text(_arm_urdf("http://example.com/link.stl"))
    with pytest.raises(MeshNotFoundError, match="scheme 'http' are not supported"):
        load_robot(urdf)


def test_a_missing_mesh_is_one_error_at_load_naming_where_it_looked(
    capsys, tmp_path: Path, no_ros_path
) -> None:
    package = _package(tmp_path / "ws" / "arm", "arm")
    urdf = tmp_path / "robot.urdf"
    urdf.write_text(_arm_urdf("package://arm/meshes/missing.stl"))
    with pytest.raises(MeshNotFoundError) as info:
        load_robot(urdf, package_dirs=[tmp_path / "ws"])
    message = str(info.value)
    assert (
        f"no file {package / 'meshes' / 'missing.stl'} (in package arm at {package})"
        in message
    )
    assert "--package-dir" in message
    urdf.write_text(_arm_urdf("package://nowhere/meshes/link.stl"))
    code, out, err = run_cli(capsys, "fk", "--robot", str(urdf), "--rad", "0", "0")
    assert code == EXIT_BAD_INPUT and out == "" and err.count("\n") == 1
    assert "package 'nowhere' not found (looked in" in err
    assert "--package-dir DIR or --package-dir nowhere=DIR" in err
    nowhere = _package(tmp_path / "other" / "x", "nowhere")
    mapped = f"nowhere={nowhere}"
    code, out, err = run_cli(capsys, "fk", "--robot", str(urdf), "--package-dir",
                             mapped, "--rad", "0", "0", "--json")  # fmt: skip
    assert (code, err) == (0, "") and json.loads(out)["robot"] == str(urdf)


def test_a_missing_package_folder_is_refused(tmp_path: Path) -> None:
    with pytest.raises(URDFLoadError, match="package folder not found: arm="):
        get_package_lookup(tmp_path / "x.urdf", [f"arm={tmp_path / 'none'}"])


# -- xacro ---------------------------------------------------------------------
def _copy_packages(tmp_path: Path) -> tuple[Path, dict[str, Path]]:
    """The vendored packages in a folder of ``tmp_path``, with small meshes."""
    root = tmp_path / "src"
    shutil.copytree(DATA, root)
    folders = {p.name: p for p in root.iterdir() if p.is_dir()}
    for urdf in root.glob("*/urdf/*.urdf"):
        write_meshes_of(urdf.read_text(), folders)
    return root, folders


@pytest.mark.parametrize(
    ("package", "stem", "tool_frame", "tol"),
    [
        ("kuka_kr16_support", "kr16_2", "tool0", PRINTED_DIGITS_TOL),
        ("kuka_lbr_iiwa_support", "lbr_iiwa_14_r820", "tool0", 0.0),
    ],
)
def test_ros_industrial_xacros_equal_their_urdfs(
    tmp_path: Path, no_ros_path, package, stem, tool_frame, tol
) -> None:
    root, _ = _copy_packages(tmp_path)
    xacro = load_robot(root / package / "urdf" / f"{stem}.xacro", tool_frame=tool_frame)
    urdf = load_robot(root / package / "urdf" / f"{stem}.urdf", tool_frame=tool_frame)
    assert xacro.joint_names == urdf.joint_names and xacro.nq == urdf.nq
    np.testing.assert_allclose(xacro.lower, urdf.lower, rtol=0, atol=tol)
    np.testing.assert_allclose(xacro.upper, urdf.upper, rtol=0, atol=tol)
    rng = np.random.default_rng(0)
    low, high = np.maximum(xacro.lower, urdf.lower), np.minimum(xacro.upper, urdf.upper)
    worst = max(
        np.abs(xacro.fk(q).homogeneous - urdf.fk(q).homogeneous).max()
        for q in rng.uniform(low, high, size=(200, xacro.nq))
    )
    assert worst <= max(tol, FK_TOL)
    assert xacro.visual_model.ngeoms == urdf.visual_model.ngeoms > 0
    again = tmp_path / f"{stem}.urdf"  # the expansion, as a URDF: the same model
    again.write_text(xacro.description)
    same = load_robot(again, tool_frame=tool_frame)
    for q in rng.uniform(low, high, size=(20, xacro.nq)):
        np.testing.assert_array_equal(same.fk(q).homogeneous, xacro.fk(q).homogeneous)


def test_xacro_arguments_and_find(capsys, tmp_path: Path, no_ros_path) -> None:
    package = _package(tmp_path / "ws" / "arm-git", "arm_description")
    (package / "urdf").mkdir()
    (package / "urdf" / "macro.xacro").write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<xacro:macro name="arm" params="prefix length">'
        + _arm_urdf("package://arm_description/meshes/link.stl")
        .removeprefix('<robot name="arm">')
        .removesuffix("</robot>")
        .replace(' name="', ' name="${prefix}')
        .replace(' link="', ' link="${prefix}')
        .replace('xyz="0 0 0.1"', 'xyz="0 0 ${length}"')
        + "</xacro:macro></robot>"
    )
    top = tmp_path / "cell.urdf.xacro"
    top.write_text(
        '<robot name="cell" xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<xacro:arg name="length" default="0.1"/>'
        '<xacro:include filename="$(find arm_description)/urdf/macro.xacro"/>'
        '<xacro:arm prefix="left_" length="$(arg length)"/></robot>'
    )
    given = [tmp_path / "ws"]
    robot = load_robot(top, package_dirs=given, xacro_args={"length": "0.25"})
    assert robot.joint_names == ["left_j1", "left_j2"]
    assert robot.fk(np.zeros(2)).translation[2] == pytest.approx(0.5, abs=1e-15)
    assert load_robot(top, package_dirs=given).fk(np.zeros(2)).translation[2] == (
        pytest.approx(0.2, abs=1e-15)
    )
    code, out, err = run_cli(capsys, "fk", "--robot", str(top), "--package-dir",
                             str(tmp_path / "ws"), "--xacro-arg", "length:=0.25",
                             "--rad", "0", "0", "--json")  # fmt: skip
    assert (code, err) == (0, "")
    assert json.loads(out)["position"][2] == pytest.approx(0.5, abs=1e-15)
    assert robot.xacro_args == (("length", "0.25"),)
    again = load_spec_robot(get_robot_spec(robot))  # as a workspace worker loads it
    assert (
        again.joint_names == robot.joint_names and again.xacro_args == robot.xacro_args
    )
    np.testing.assert_array_equal(again.fk(np.zeros(2)).homogeneous,
                                  robot.fk(np.zeros(2)).homogeneous)  # fmt: skip
    code, out, err = run_cli(capsys, "fk", "--robot", str(top), "--rad", "0", "0")
    assert code == EXIT_BAD_INPUT and err.count("\n") == 1
    assert "$(find arm_description): package 'arm_description' not found" in err
    code, _, err = run_cli(capsys, "fk", "--robot", str(top), "--xacro-arg", "length")
    assert code == EXIT_BAD_INPUT and "expected NAME:=VALUE" in err


def test_xacro_errors_are_one_line(tmp_path: Path, no_ros_path) -> None:
    bad = tmp_path / "bad.xacro"
    bad.write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:nope/></robot>'
    )
    with pytest.raises(URDFLoadError, match="xacro:") as info:
        load_robot(bad)
    assert "\n" not in str(info.value)
    needs = tmp_path / "needs.xacro"
    needs.write_text(
        '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<link name="$(arg length)"/></robot>'
    )
    with pytest.raises(
        URDFLoadError, match=r"'length' is not set .*--xacro-arg length"
    ):
        load_robot(needs)
    urdf = tmp_path / "plain.urdf"
    urdf.write_text(_arm_urdf(str(write_stl(tmp_path / "m.stl"))))
    with pytest.raises(URDFLoadError, match="for a file that is no xacro"):
        load_robot(urdf, xacro_args={"a": "1"})
