"""Mesh files as their files mean them: Collada units and up axes, STL normals.

Two things in the mesh files of real robot descriptions are dropped on the way
to the collision checker and the browser, and both are common in ROS-Industrial
packages:

* a Collada file's ``<asset><unit meter="…"/>`` (e.g. 0.0254, inches) and
  ``<up_axis>`` (``Y_UP``, ``X_UP``): the mesh loader of coal (assimp) and
  Meshcat's page (three.js merges the file's nodes without the scene's scale and
  turn) both read the coordinates as metres, Z up. :func:`honour_collada_frames`
  folds the unit into each geometry's ``meshScale`` (and its collision mesh,
  loaded again at that scale) and the up axis into its ``placement``, as ROS's
  own viewer reads such files;
* an STL file whose facet normals are zero (or missing): the page shades the
  mesh with them, black. :func:`get_stl_with_normals` gives the file's
  triangles with each facet's normal computed from its vertices (their order),
  for the page to draw.

And one the page itself cannot read: an OBJ file whose faces give texture
coordinates in some groups and not in others (``f 1/1/1`` and ``f 1//1``, as
in the Franka Panda's visual meshes): three.js merges the groups' geometries
only when they have the same attributes, and the page drops the whole mesh.
:func:`get_obj_with_uniform_faces` gives the file without its texture
coordinates (the page colours the mesh; it draws no textures).
"""

from __future__ import annotations

import struct
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pinocchio as pin

FloatArray = npt.NDArray[np.float64]

#: The rotation that turns a Collada file's coordinates into the Z-up frame of
#: the description, by its ``<up_axis>`` (the Collada 1.4 meanings: ``Y_UP``,
#: up +y, right +x; ``X_UP``, up +x, right −y).
UP_AXIS_ROTATIONS: dict[str, FloatArray] = {
    "Z_UP": np.eye(3),
    "Y_UP": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),
    "X_UP": np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]]),
}
#: A facet normal shorter than this counts as missing.
ZERO_NORMAL_TOL = 1e-12


def read_collada_frame(path: str) -> tuple[float, str]:
    """``(metres per unit, up axis)`` of a Collada file; ``(1.0, "Z_UP")`` if unstated.

    Only the ``<asset>`` element is read (the file is parsed as a stream and
    left at its end). A file that is not readable XML gives the default: the
    mesh loader then reports it.
    """
    meter, up = 1.0, "Z_UP"
    try:
        for _, element in ET.iterparse(path, events=("end",)):
            tag = element.tag.rsplit("}", 1)[-1]
            if tag == "unit":
                value = float(element.get("meter", "1"))
                if np.isfinite(value) and value > 0.0:
                    meter = value
            elif tag == "up_axis" and element.text:
                text = element.text.strip().upper()
                if text in UP_AXIS_ROTATIONS:
                    up = text
            elif tag == "asset":
                break
    except (OSError, ET.ParseError, ValueError):
        pass
    return meter, up


def honour_collada_frames(model: pin.GeometryModel) -> int:
    """Give every Collada geometry of ``model`` its file's unit and up axis, in place.

    A geometry's ``meshScale`` is multiplied by the unit (in the frame the up
    axis turns to) and its ``placement`` turned by :data:`UP_AXIS_ROTATIONS`; a
    collision mesh (a coal BVH, built by the loader at the old scale) is
    loaded again at the new one.

    Returns:
        How many geometries changed.
    """
    import coal

    changed = 0
    for geometry in model.geometryObjects:
        path = geometry.meshPath
        if not path.lower().endswith(".dae"):
            continue
        meter, up = read_collada_frame(path)
        if meter == 1.0 and up == "Z_UP":
            continue
        turn = UP_AXIS_ROTATIONS[up]
        # S_urdf · R · unit = R · S' · unit, S' the URDF scale in the file's axes
        scale = np.abs(turn.T) @ np.asarray(geometry.meshScale) * meter
        if isinstance(geometry.geometry, coal.BVHModelBase):
            geometry.geometry = coal.MeshLoader().load(path, scale)
        geometry.meshScale = scale
        geometry.placement = geometry.placement * pin.SE3(turn, np.zeros(3))
        changed += 1
    return changed


def get_stl_with_normals(path: str | Path) -> bytes | None:
    """The STL file's triangles as binary STL with normals, if it lacks some.

    Returns:
        The bytes of a binary STL whose every facet normal is the unit normal
        of its vertices (right-handed order), or None when every facet of the
        file already has a normal (or the file is not an STL this reads).
    """
    triangles, normals = _read_stl(Path(path))
    if triangles is None or normals is None:
        return None
    lengths = np.linalg.norm(normals, axis=1)
    if np.all(lengths > ZERO_NORMAL_TOL):
        return None
    edges = np.cross(
        triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]
    )
    norm = np.linalg.norm(edges, axis=1, keepdims=True)
    computed = np.divide(edges, norm, out=np.zeros_like(edges), where=norm > 0.0)
    records = np.zeros(
        len(triangles),
        dtype=[("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attr", "<u2")],
    )
    records["normal"] = computed
    records["vertices"] = triangles
    header = b"normals computed from the vertex order".ljust(80, b" ")
    return header + struct.pack("<I", len(triangles)) + records.tobytes()


def get_obj_with_uniform_faces(path: str | Path) -> str | None:
    """The OBJ file without texture coordinates, if only some faces give them.

    Returns:
        The file's text with its ``vt`` lines dropped and every face vertex
        ``v/vt/vn`` written ``v//vn`` (``v/vt``: ``v``), or None when every
        face gives texture coordinates or none does (or the file cannot be
        read as text).
    """
    try:
        lines = Path(path).read_text().splitlines()
    except (OSError, UnicodeDecodeError):
        return None
    kinds = set()
    for line in lines:
        if line.startswith("f "):
            for vertex in line.split()[1:]:
                parts = vertex.split("/")
                kinds.add(len(parts) > 1 and parts[1] != "")
            if len(kinds) > 1:
                break
    if len(kinds) < 2:
        return None
    out = []
    for line in lines:
        if line.startswith("vt"):
            continue
        if line.startswith("f "):
            vertices = []
            for vertex in line.split()[1:]:
                parts = vertex.split("/")
                normal = parts[2] if len(parts) > 2 else ""
                vertices.append(f"{parts[0]}//{normal}" if normal else parts[0])
            line = "f " + " ".join(vertices)
        out.append(line)
    return "\n".join(out) + "\n"


def _read_stl(path: Path) -> tuple[FloatArray | None, FloatArray | None]:
    """``(triangles (T, 3, 3), normals (T, 3))`` of an ASCII or binary STL."""
    try:
        data = path.read_bytes()
    except OSError:
        return None, None
    if len(data) >= 84:
        (count,) = struct.unpack_from("<I", data, 80)
        if len(data) == 84 + 50 * count:  # binary
            records = np.frombuffer(
                data,
                dtype=[
                    ("normal", "<f4", 3),
                    ("vertices", "<f4", (3, 3)),
                    ("attr", "<u2"),
                ],
                count=count,
                offset=84,
            )
            return (
                records["vertices"].astype(np.float64),
                records["normal"].astype(np.float64),
            )
    try:
        words = data.decode("ascii").split()
    except UnicodeDecodeError:
        return None, None
    normals, vertices = [], []
    for i, word in enumerate(words):
        if word == "normal":
            normals.append([float(w) for w in words[i + 1 : i + 4]])
        elif word == "vertex":
            vertices.append([float(w) for w in words[i + 1 : i + 4]])
    if not vertices or len(vertices) != 3 * len(normals):
        return None, None
    return np.array(vertices).reshape(-1, 3, 3), np.array(normals)


__all__ = [
    "UP_AXIS_ROTATIONS",
    "ZERO_NORMAL_TOL",
    "get_obj_with_uniform_faces",
    "get_stl_with_normals",
    "honour_collada_frames",
    "read_collada_frame",
]
