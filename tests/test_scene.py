"""Scene files: strict validation, round trips, meshes, the papers' scenes."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given
from hypothesis import strategies as st

from workbench.collision import (
    CollisionChecker,
    Obstacle,
    Scene,
    get_angeles_scene,
    parse_scene,
    read_scene,
    write_scene,
)
from workbench.errors import SceneFileError
from workbench.model.urdf_generator import get_pedestal_cylinder
from workbench.tasks import SimulatedFish
from workbench.tasks.fish_program import KANG_BASE_HEIGHT
from workbench.tasks.fish_scene import build_fish_mesh, get_fish_cutting_scene

ATOL_EXACT = 1e-12
CUBE_OBJ = """v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
"""


def _one(obj: dict) -> dict:
    return {"name": "cell", "objects": [obj]}


BOX = {"name": "b", "shape": "box", "size": [0.1, 0.2, 0.3], "position": [0, 0, 0]}


@pytest.mark.parametrize(
    ("obj", "fragment"),
    [
        ({"name": "x", "shape": "cone", "radius": 1}, "unknown shape 'cone'"),
        ({**BOX, "size": [0.1, -0.2, 0.3]}, "must be > 0"),
        ({"name": "s", "shape": "sphere", "radius": 0}, "must be > 0"),
        ({**BOX, "position": [0, math.nan, 0]}, "must be finite"),
        ({**BOX, "quat_xyzw": [0, 0, 0, 2]}, "norm 1"),
        ({**BOX, "colour": [1, 0, 0, 1]}, "unknown key(s) colour"),
        ({**BOX, "size": [0.1, 0.2]}, "list of 3 numbers"),
        ({**BOX, "size": [0.1, True, 0.3]}, "list of 3 numbers"),
        ({"name": "c", "shape": "cylinder", "radius": 0.1}, "missing key 'length'"),
        ({"name": "m", "shape": "mesh", "file": "nowhere.stl"}, "mesh file not found"),
        ({"name": "m", "shape": "mesh"}, "needs 'file' or 'vertices'"),
        ({**BOX, "rpy": [0, 0, 0], "quat_xyzw": [0, 0, 0, 1]}, "not both"),
        ({**BOX, "allow": "link1"}, "list of link names"),
        ({**BOX, "name": ""}, "non-empty string"),
    ],
)
def test_bad_objects_name_the_problem(tmp_path: Path, obj, fragment) -> None:
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(_one(obj)), encoding="utf-8")
    with pytest.raises(SceneFileError) as info:
        read_scene(path)
    assert fragment in str(info.value)
    assert "\n" not in str(info.value)


def test_bad_files(tmp_path: Path) -> None:
    with pytest.raises(SceneFileError, match="cannot read scene"):
        read_scene(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{", encoding="utf-8")
    with pytest.raises(SceneFileError, match="not valid JSON"):
        read_scene(bad)
    with pytest.raises(SceneFileError, match="duplicate object name"):
        parse_scene({"objects": [BOX, BOX]})
    with pytest.raises(SceneFileError, match="'frame' must be 'base'"):
        parse_scene({"frame": "world", "objects": []})
    with pytest.raises(SceneFileError, match="'objects' must be a list"):
        parse_scene({"objects": {}})


def test_nan_literal_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "nan.json"  # Python's json reads NaN: the check must not
    path.write_text(
        '{"objects": [{"name": "b", "shape": "sphere", "radius": 0.1, '
        '"position": [0, NaN, 0]}]}',
        encoding="utf-8",
    )
    with pytest.raises(SceneFileError, match="must be finite"):
        read_scene(path)


sizes = st.floats(1e-3, 2.0)
coords = st.floats(-2.0, 2.0)


@given(
    box=st.tuples(sizes, sizes, sizes),
    radius=sizes,
    length=sizes,
    position=st.tuples(coords, coords, coords),
    rpy=st.tuples(coords, coords, coords),
)
def test_round_trip(box, radius, length, position, rpy) -> None:
    placement = pin.SE3(pin.rpy.rpyToMatrix(np.array(rpy)), np.array(position))
    scene = Scene(
        "s",
        (
            Obstacle("box", "box", box, placement, ("link1",)),
            Obstacle("cyl", "cylinder", (radius, length), placement),
            Obstacle("ball", "sphere", (radius,), placement),
        ),
    )
    again = parse_scene(json.loads(json.dumps(scene.to_dict())))
    for a, b in zip(scene.obstacles, again.obstacles, strict=True):
        assert (a.name, a.shape, a.allow) == (b.name, b.shape, b.allow)
        np.testing.assert_allclose(a.size, b.size, rtol=0, atol=0)
        np.testing.assert_allclose(
            a.placement.homogeneous, b.placement.homogeneous, rtol=0, atol=ATOL_EXACT
        )


def test_mesh_file_relative_to_the_scene(tmp_path: Path, puma) -> None:
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "cube.obj").write_text(CUBE_OBJ, encoding="utf-8")
    scene_path = tmp_path / "scene.json"
    cube = {
        "name": "cube",
        "shape": "mesh",
        "file": "meshes/cube.obj",
        "scale": [0.05, 0.05, 0.05],
        "position": [0.5, 0.0, 0.3],
    }
    box = {**BOX, "name": "box", "size": [0.1, 0.1, 0.1], "position": [0.5, 0.0, 0.3]}
    scene_path.write_text(json.dumps({"objects": [cube]}), encoding="utf-8")
    box_path = tmp_path / "box.json"
    box_path.write_text(json.dumps({"objects": [box]}), encoding="utf-8")
    q = np.zeros(6)
    mesh_d = CollisionChecker(puma, read_scene(scene_path), self_collision=False)
    box_d = CollisionChecker(puma, read_scene(box_path), self_collision=False)
    np.testing.assert_allclose(  # same cube: same distances (surface vs solid apart)
        mesh_d.compute_distances(q), box_d.compute_distances(q), rtol=0, atol=1e-9
    )
    written = write_scene(read_scene(scene_path), tmp_path / "again.json")
    assert read_scene(written).obstacles[0].mesh_file == tmp_path / "meshes/cube.obj"


def test_angeles_scene(puma) -> None:
    scene = get_angeles_scene(puma)
    pedestal, table = scene.obstacles
    radius, length, z = get_pedestal_cylinder(puma.dh_table)
    assert pedestal.size == (radius, length) and pedestal.allow == ("link1",)
    assert pedestal.placement.translation[2] == z
    wrist = puma.fk(np.deg2rad([0, 45, 200, -100, 30, 10])).translation
    top = table.placement.translation[2] + table.size[2] / 2
    assert top == pytest.approx(wrist[2] - 0.10, abs=ATOL_EXACT)


def test_fish_scene_in_the_base_frame(puma_kang) -> None:
    fish = SimulatedFish(3)
    scene = get_fish_cutting_scene(puma_kang, fish)
    names = [o.name for o in scene.obstacles]
    assert names == ["pedestal", "cutting_table", "fish"]
    table, body = scene.obstacles[1], scene.obstacles[2]
    top = table.placement.translation[2] + table.size[2] / 2
    assert top == pytest.approx(fish.table_z - KANG_BASE_HEIGHT, abs=ATOL_EXACT)
    z = body.vertices[:, 2] + KANG_BASE_HEIGHT  # back to the world frame
    assert z.min() == pytest.approx(fish.table_z, abs=ATOL_EXACT)
    y = 0.5 * (fish.head_y + fish.tail_y)
    assert z.max() >= fish.flesh_top(fish.center_x, y) - 1e-3
    assert set(body.allow) == {"link5", "link6", "wrist_center"}


def test_fish_mesh_is_closed() -> None:
    vertices, triangles = build_fish_mesh(SimulatedFish())
    edges: dict[tuple[int, int], int] = {}
    for tri in triangles.tolist():
        for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            key = (min(a, b), max(a, b))
            edges[key] = edges.get(key, 0) + 1
    assert set(edges.values()) == {2}  # every edge shared by two triangles
    assert triangles.max() < len(vertices)
