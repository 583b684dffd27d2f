"""Small mesh files for tests: STL boxes, Collada boxes with a unit and an up axis."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: A box's 8 corners (unit cube centred at 0) and its 12 triangles.
CORNERS = np.array(
    [[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
)
TRIANGLES = np.array(
    [
        [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
        [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],
    ]
)  # fmt: skip


def write_stl(path: Path, size: float = 0.05, *, zero_normals: bool = False) -> Path:
    """An ASCII STL box of edge ``size`` [m]; its facet normals 0 if asked."""
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = ["solid box"]
    for tri in TRIANGLES:
        a, b, c = CORNERS[tri] * size
        n = np.cross(b - a, c - a)
        n = np.zeros(3) if zero_normals else n / np.linalg.norm(n)
        lines += [f"facet normal {n[0]:g} {n[1]:g} {n[2]:g}", "outer loop"]
        lines += [f"vertex {p[0]:.9g} {p[1]:.9g} {p[2]:.9g}" for p in (a, b, c)]
        lines += ["endloop", "endfacet"]
    lines.append("endsolid box")
    path.write_text("\n".join(lines) + "\n")
    return path


def write_dae(
    path: Path,
    size: float = 0.05,
    *,
    meter: float = 1.0,
    up_axis: str = "Z_UP",
    extent: tuple[float, float, float] | None = None,
) -> Path:
    """A Collada box of edge ``size`` in its own unit (``meter`` m per unit).

    ``extent`` (in file units) stretches the box along x, y, z instead.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    scale = np.array(extent if extent is not None else (size, size, size))
    points = " ".join(f"{v:.9g}" for v in (CORNERS * scale).ravel())
    indices = " ".join(str(i) for i in TRIANGLES.ravel())
    path.write_text(
        f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="unit" meter="{meter}"/><up_axis>{up_axis}</up_axis></asset>
  <library_geometries>
    <geometry id="box" name="box"><mesh>
      <source id="box-pos">
        <float_array id="box-pos-array" count="24">{points}</float_array>
        <technique_common><accessor source="#box-pos-array" count="8" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/>
          <param name="Z" type="float"/></accessor></technique_common></source>
      <vertices id="box-vtx"><input semantic="POSITION" source="#box-pos"/></vertices>
      <triangles count="12"><input semantic="VERTEX" source="#box-vtx" offset="0"/>
        <p>{indices}</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes><visual_scene id="scene">
    <node id="box-node"><instance_geometry url="#box"/></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""
    )
    return path


def write_meshes_of(urdf_text: str, folder_of: dict[str, Path]) -> list[Path]:
    """A small mesh at every ``package://PKG/path`` a description names.

    Args:
        urdf_text: The description.
        folder_of: Package name → its folder.

    Returns:
        The files written.
    """
    import re

    written = []
    for pkg, rest in sorted(
        set(re.findall(r'package://([^/"\']+)/([^"\']+)', urdf_text))
    ):
        path = folder_of[pkg] / rest
        if path.suffix.lower() == ".dae":
            written.append(write_dae(path))
        else:
            written.append(write_stl(path))
    return written


def write_mixed_obj(path: Path, size: float = 1.0) -> Path:
    """A cube [m] as OBJ whose faces give texture coordinates in one group only.

    As in the Franka Panda's visual meshes: ``f v/vt/vn`` in the first group,
    ``f v//vn`` in the second, which the browser's OBJ loader cannot merge.
    """
    h = 0.5 * size
    corners = [(x, y, z) for x in (-h, h) for y in (-h, h) for z in (-h, h)]
    quads = [
        (0, 1, 3, 2),
        (4, 6, 7, 5),
        (0, 4, 5, 1),
        (2, 3, 7, 6),
        (0, 2, 6, 4),
        (1, 5, 7, 3),
    ]
    normals = [(-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0), (0, 0, -1), (0, 0, 1)]
    lines = [f"v {x} {y} {z}" for x, y, z in corners]
    lines += ["vt 0 0", "vt 1 0", "vt 1 1"]
    lines += [f"vn {x} {y} {z}" for x, y, z in normals]
    for k, (a, b, c, d) in enumerate(quads):
        if k == 0:
            lines.append("g textured")
        elif k == 3:
            lines.append("g plain")
        for tri in ((a, b, c), (a, c, d)):
            if k < 3:
                lines.append(
                    "f "
                    + " ".join(f"{v + 1}/{i + 1}/{k + 1}" for i, v in enumerate(tri))
                )
            else:
                lines.append("f " + " ".join(f"{v + 1}//{k + 1}" for v in tri))
    path.write_text("\n".join(lines) + "\n")
    return path
