"""Meshes as their files mean them: Collada units and up axes, STL normals."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from tests._meshes import write_dae, write_stl
from workbench import load_robot
from workbench.model.mesh_files import (
    UP_AXIS_ROTATIONS,
    get_obj_with_uniform_faces,
    get_stl_with_normals,
    read_collada_frame,
)

INCH = 0.0254
#: The test box: 10 × 2 × 1 inches (0.254 × 0.0508 × 0.0254 m), long along x.
BOX_IN = (10.0, 2.0, 1.0)
BOX_M = tuple(INCH * v for v in BOX_IN)
#: The box's extent [m] along the link's axes once its file's unit and up axis are
#: honoured: the mesh loader (assimp) keeps vertices as float32 (ε = 1.2e-7,
#: 3e-8 m on 0.254 m).
EXTENT_TOL = 5e-8


def _arm(tmp_path: Path, mesh: Path, scale: str = "1 1 1") -> Path:
    """A one-joint arm whose link's visual and collision geometry is ``mesh``."""
    geometry = f'<geometry><mesh filename="{mesh}" scale="{scale}"/></geometry>'
    urdf = tmp_path / f"{mesh.stem}.urdf"
    urdf.write_text(
        f'<robot name="r"><link name="base"/><link name="l1"><visual>{geometry}'
        f"</visual><collision>{geometry}</collision></link>"
        '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>'
        '<axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/>'
        "</joint></robot>"
    )
    return urdf


def _extent(geometry: pin.GeometryObject) -> np.ndarray:
    """Size along the link frame's x, y, z of the geometry's box [m]."""
    geometry.geometry.computeLocalAABB()
    box = geometry.geometry.aabb_local
    lo, hi = np.array(box.min_), np.array(box.max_)
    corners = np.array(np.meshgrid(*zip(lo, hi, strict=True))).reshape(3, -1).T
    placed = np.array([geometry.placement.act(c) for c in corners])
    return placed.max(axis=0) - placed.min(axis=0)


def test_the_asset_of_a_collada_file_is_read(tmp_path: Path) -> None:
    inches = write_dae(tmp_path / "a.dae", meter=INCH, up_axis="Y_UP")
    assert read_collada_frame(str(inches)) == (INCH, "Y_UP")
    assert read_collada_frame(str(write_dae(tmp_path / "b.dae"))) == (1.0, "Z_UP")
    (tmp_path / "c.dae").write_text("not xml")
    assert read_collada_frame(str(tmp_path / "c.dae")) == (1.0, "Z_UP")
    for turn in UP_AXIS_ROTATIONS.values():
        np.testing.assert_allclose(turn @ turn.T, np.eye(3), atol=0)
        assert np.linalg.det(turn) == pytest.approx(1.0, abs=0)
    np.testing.assert_array_equal(UP_AXIS_ROTATIONS["Y_UP"] @ [0, 1, 0], [0, 0, 1])
    np.testing.assert_array_equal(UP_AXIS_ROTATIONS["X_UP"] @ [1, 0, 0], [0, 0, 1])
    np.testing.assert_array_equal(UP_AXIS_ROTATIONS["X_UP"] @ [0, -1, 0], [1, 0, 0])


@pytest.mark.parametrize(
    ("up", "expected"),
    [
        ("Z_UP", BOX_M),
        ("Y_UP", (BOX_M[0], BOX_M[2], BOX_M[1])),  # the file's y is the link's z
        ("X_UP", (BOX_M[1], BOX_M[2], BOX_M[0])),  # the file's x is the link's z
    ],
)
def test_inches_and_up_axes_reach_collision_and_visual_geometry(
    tmp_path: Path, up: str, expected: tuple[float, float, float]
) -> None:
    mesh = write_dae(tmp_path / f"box_{up}.dae", meter=INCH, up_axis=up, extent=BOX_IN)
    robot = load_robot(_arm(tmp_path, mesh))
    for model in (robot.collision_model, robot.visual_model):
        (geometry,) = model.geometryObjects
        np.testing.assert_allclose(_extent(geometry), expected, rtol=0, atol=EXTENT_TOL)
        np.testing.assert_allclose(
            np.abs(UP_AXIS_ROTATIONS[up] @ (np.asarray(geometry.meshScale) * BOX_IN)),
            np.array(expected),
            rtol=0,
            atol=EXTENT_TOL,
        )  # what the page draws: the file's vertices, scaled, then turned
    metres = write_dae(tmp_path / "box_m.dae", extent=BOX_M)
    plain = load_robot(_arm(tmp_path, metres)).collision_model.geometryObjects[0]
    np.testing.assert_allclose(_extent(plain), BOX_M, rtol=0, atol=EXTENT_TOL)


def test_a_urdf_scale_composes_with_the_unit(tmp_path: Path) -> None:
    mesh = write_dae(tmp_path / "box.dae", meter=INCH, up_axis="Y_UP", extent=BOX_IN)
    robot = load_robot(_arm(tmp_path, mesh, scale="2 3 4"))  # in the link's axes
    (geometry,) = robot.collision_model.geometryObjects
    expected = np.array([2 * BOX_M[0], 3 * BOX_M[2], 4 * BOX_M[1]])
    np.testing.assert_allclose(_extent(geometry), expected, rtol=0, atol=EXTENT_TOL)


def _read_binary_stl(data: bytes) -> tuple[np.ndarray, np.ndarray]:
    (count,) = struct.unpack_from("<I", data, 80)
    assert len(data) == 84 + 50 * count
    rows = np.frombuffer(
        data, dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")], offset=84
    )
    return rows["v"].astype(float), rows["n"].astype(float)


@pytest.mark.parametrize("binary", [False, True])
def test_zero_normals_are_computed_from_the_vertex_order(
    tmp_path: Path, binary
) -> None:
    path = write_stl(tmp_path / "z.stl", zero_normals=True)
    good = write_stl(tmp_path / "g.stl")
    if binary:
        vertices, _ = _read_binary_stl(get_stl_with_normals(path) or b"")
        rows = np.zeros(12, dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
        rows["v"] = vertices
        path.write_bytes(b"x" * 80 + struct.pack("<I", 12) + rows.tobytes())
    fixed = get_stl_with_normals(path)
    assert fixed is not None and get_stl_with_normals(good) is None
    vertices, normals = _read_binary_stl(fixed)
    edges = np.cross(vertices[:, 1] - vertices[:, 0], vertices[:, 2] - vertices[:, 0])
    unit = edges / np.linalg.norm(edges, axis=1, keepdims=True)
    np.testing.assert_allclose(normals, unit, atol=1e-6)  # (float32 in the file)
    centre = vertices.mean(axis=1)
    assert np.all(np.einsum("ij,ij->i", normals, centre) > 0)  # outward on the box


def test_an_obj_with_texture_coordinates_in_part_loses_them(tmp_path: Path) -> None:
    from tests._meshes import write_mixed_obj

    path = write_mixed_obj(tmp_path / "mixed.obj")
    text = get_obj_with_uniform_faces(path)
    assert text is not None and "vt" not in text
    faces = [line.split()[1:] for line in text.splitlines() if line.startswith("f ")]
    assert len(faces) == 12 and all("//" in v for face in faces for v in face)
    original = path.read_text().splitlines()
    kept = [line for line in original if not line.startswith(("vt", "f "))]
    assert [line for line in text.splitlines() if not line.startswith("f ")] == kept
    # The same vertices and normals, face by face.
    before = [
        [(v.split("/")[0], v.split("/")[2]) for v in line.split()[1:]]
        for line in original
        if line.startswith("f ")
    ]
    assert [[tuple(v.split("//")) for v in face] for face in faces] == before
    uniform = tmp_path / "uniform.obj"
    uniform.write_text(text)
    assert get_obj_with_uniform_faces(uniform) is None
    assert get_obj_with_uniform_faces(tmp_path / "missing.obj") is None
