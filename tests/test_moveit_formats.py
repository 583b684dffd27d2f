"""MoveIt planning scenes and motion requests, on MotionBenchMaker's own files.

The scenes and requests in ``tests/data/motionbenchmaker`` (provenance in its
README) are read into scenes and configurations and checked against the
YAML read independently here; the start and the goal of every problem are
free of collision with the exact checker (the Panda: MotionBenchMaker's own).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from workbench import load_robot
from workbench.collision import CollisionChecker, read_scene, write_scene
from workbench.errors import InputError, SceneFileError
from workbench.motion import MotionRequest, read_request

DATA = Path(__file__).parent / "data" / "motionbenchmaker"
PROBLEMS = sorted(DATA.glob("*/*_scene0001.yaml"))
#: Poses read from YAML and rebuilt (quaternion → matrix) [m, 1].
ATOL_POSE = 1e-15
#: MotionBenchMaker's Panda (its collision meshes; provenance in the README).
MBM_PANDA = DATA / "panda" / "panda.urdf"


def _request_file(scene: Path) -> Path:
    return scene.with_name(scene.name.replace("scene", "request"))


def _shapes(document: dict) -> list[tuple[str, list[float], dict]]:
    """(type, dimensions, pose) of every primitive, read here without the workbench."""
    out = []
    for item in document["world"]["collision_objects"]:
        for primitive, pose in zip(
            item["primitives"], item["primitive_poses"], strict=True
        ):
            out.append((primitive["type"], primitive["dimensions"], pose))
    return out


@pytest.mark.parametrize("path", PROBLEMS, ids=lambda p: f"{p.parent.name}-{p.stem}")
def test_a_motionbenchmaker_scene_reads_as_its_primitives(path: Path) -> None:
    document = yaml.safe_load(path.read_text())
    scene = read_scene(path)
    shapes = _shapes(document)
    assert len(scene.obstacles) == len(shapes) > 0
    ids = [item["id"] for item in document["world"]["collision_objects"]]
    assert [o.name for o in scene.obstacles] == ids  # one primitive per object
    for obstacle, (kind, dims, pose) in zip(scene.obstacles, shapes, strict=True):
        assert obstacle.shape == kind
        # MoveIt's cylinder is (height, radius); the workbench's (radius, length)
        size = [dims[1], dims[0]] if kind == "cylinder" else dims
        assert list(obstacle.size) == size
        x, y, z, w = pose["orientation"]
        rotation = pin.Quaternion(w, x, y, z).normalized().toRotationMatrix()
        np.testing.assert_allclose(
            obstacle.placement.rotation, rotation, rtol=0, atol=ATOL_POSE
        )
        assert obstacle.placement.translation.tolist() == pose["position"]
        assert obstacle.allow == ()  # the matrix's entries are link pairs only


@pytest.mark.parametrize("path", PROBLEMS, ids=lambda p: f"{p.parent.name}-{p.stem}")
def test_a_motionbenchmaker_request_reads_as_configurations(path: Path) -> None:
    robot = load_robot(path.parent.name)
    document = yaml.safe_load(_request_file(path).read_text())
    request = read_request(_request_file(path), robot)
    assert isinstance(request, MotionRequest)
    state = document["start_state"]["joint_state"]
    given = dict(zip(state["name"], state["position"], strict=True))
    assert request.start.tolist() == [given[n] for n in robot.joint_names]
    goal = {
        c["joint_name"]: c["position"]
        for c in document["goal_constraints"][0]["joint_constraints"]
    }
    assert request.goal.tolist() == [goal[n] for n in robot.joint_names]
    assert len(given) > robot.n_joints  # the gripper's joints: ignored
    for q in request:
        assert np.all(robot.lower <= q) and np.all(q <= robot.upper)


@pytest.mark.slow
@pytest.mark.parametrize("path", PROBLEMS, ids=lambda p: f"{p.parent.name}-{p.stem}")
def test_a_motionbenchmaker_problem_is_free_at_its_ends(path: Path) -> None:
    """Valid problems: start and goal free of collision with the exact checker.

    The Panda is MotionBenchMaker's own (its URDF and collision meshes, the
    gripper open); the UR5 the catalog's (no gripper).
    """
    robot = load_robot(MBM_PANDA if path.parent.name == "panda" else "ur5")
    scene = read_scene(path)
    request = read_request(_request_file(path), robot)
    checker = CollisionChecker(robot, scene)
    for q in request:
        assert np.min(np.asarray(checker.compute_distances(q))) > 0


def test_a_moveit_scene_round_trips_through_json(tmp_path: Path) -> None:
    scene = read_scene(PROBLEMS[0])
    again = read_scene(write_scene(scene, tmp_path / "scene.json"))
    for a, b in zip(scene.obstacles, again.obstacles, strict=True):
        assert (a.name, a.shape, a.size) == (b.name, b.shape, b.size)
        np.testing.assert_allclose(
            a.placement.homogeneous, b.placement.homogeneous, rtol=0, atol=ATOL_POSE
        )


def _write(tmp_path: Path, document: object, name: str = "scene.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(document))
    return path


BOX = {"type": "box", "dimensions": [0.1, 0.2, 0.3]}
POSE = {"position": [0.5, 0.0, 0.2], "orientation": [0, 0, 0, 1]}


def test_moveit_scene_variants_read(tmp_path: Path) -> None:
    """Numeric types, mapping poses, object poses, several shapes, meshes, allow."""
    document = {
        "name": "cell",
        "world": {
            "collision_objects": [
                {
                    "id": "pair",
                    "header": {"frame_id": "base_link"},
                    "pose": {"position": {"x": 1.0, "y": 0.0, "z": 0.0}},
                    "primitives": [{"type": 2, "dimensions": [0.05]}, BOX],
                    "primitive_poses": [POSE, POSE],
                },
                {
                    "id": "tri",
                    "meshes": [
                        {
                            "vertices": [
                                {"x": 0, "y": 0, "z": 0},
                                {"x": 0.1, "y": 0, "z": 0},
                                {"x": 0, "y": 0.1, "z": 0},
                            ],
                            "triangles": [{"vertex_indices": [0, 1, 2]}],
                        }
                    ],
                    "mesh_poses": [POSE],
                },
            ]
        },
        "allowed_collision_matrix": {
            "entry_names": ["tri", "wrist_3_link"],
            "entry_values": [[False, True], [True, False]],
        },
    }
    scene = read_scene(_write(tmp_path, document))
    assert scene.name == "cell"
    assert [(o.name, o.shape) for o in scene.obstacles] == [
        ("pair/0", "sphere"),
        ("pair/1", "box"),
        ("tri", "mesh"),
    ]
    assert scene.obstacles[0].placement.translation.tolist() == [1.5, 0.0, 0.2]
    assert scene.obstacles[2].allow == ("wrist_3_link",)
    assert scene.obstacles[2].vertices.shape == (3, 3)
    CollisionChecker(load_robot("ur5"), scene)  # the names are the robot's


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"type": "cone", "dimensions": [0.1, 0.1]}, "type 'cone' is not read"),
        ({"type": 4, "dimensions": [0.1, 0.1]}, "type 4 is not read"),
        (
            {"type": "box", "dimensions": [0.1, 0.2]},
            "dimensions must be a list of 3 numbers",
        ),
        ({"type": "box", "dimensions": [0.1, -0.2, 1]}, "dimensions must be > 0"),
        (
            {"type": "box", "dimensions": [0.1, ".nan", 1]},
            "must be a list of 3 numbers",
        ),
        (
            {"type": "cylinder", "dimensions": [0.1, float("inf")]},
            "dimensions must be finite",
        ),
    ],
)
def test_bad_moveit_primitives_are_refused(tmp_path, change, message) -> None:
    document = {
        "world": {
            "collision_objects": [
                {"id": "x", "primitives": [change], "primitive_poses": [POSE]}
            ]
        }
    }
    with pytest.raises(SceneFileError, match=message):
        read_scene(_write(tmp_path, document))


@pytest.mark.parametrize(
    ("document", "message"),
    [
        ("- a\n- b\n", "not a MoveIt planning scene"),
        ("world: [\n", "not valid YAML"),
        (
            {"world": {"collision_objects": [{"id": "x", "primitives": [BOX]}]}},
            "1 primitives with 0 poses",
        ),
        (
            {
                "world": {
                    "collision_objects": [
                        {
                            "id": "x",
                            "primitives": [BOX],
                            "primitive_poses": [
                                {"position": [0, 0, 0], "orientation": [0, 0, 0, 2]}
                            ],
                        }
                    ]
                }
            },
            "orientation must have norm 1, got 2",
        ),
        (
            {
                "world": {
                    "collision_objects": [
                        {"id": "x", "primitives": [BOX], "primitive_poses": [POSE]},
                        {"id": "x", "primitives": [BOX], "primitive_poses": [POSE]},
                    ]
                }
            },
            "duplicate object name 'x'",
        ),
        (
            {
                "world": {
                    "collision_objects": [
                        {
                            "id": name,
                            "header": {"frame_id": name},
                            "primitives": [BOX],
                            "primitive_poses": [POSE],
                        }
                        for name in ("a", "b")
                    ]
                }
            },
            "objects in several frames",
        ),
        ({"world": {"octomap": {"octomap": {"data": [1]}}}}, "octomaps are not read"),
        (
            {
                "world": {
                    "collision_objects": [
                        {
                            "id": "x",
                            "operation": 1,
                            "primitives": [BOX],
                            "primitive_poses": [POSE],
                        }
                    ]
                }
            },
            "operation 1 is not ADD",
        ),
    ],
)
def test_bad_moveit_scenes_are_refused(tmp_path, document, message) -> None:
    path = tmp_path / "scene.yml"
    text = document if isinstance(document, str) else yaml.safe_dump(document)
    path.write_text(text)
    with pytest.raises(SceneFileError, match=message):
        read_scene(path)


def test_bad_motion_requests_are_refused(tmp_path: Path) -> None:
    robot = load_robot("ur5")
    names = robot.joint_names
    start = {"joint_state": {"name": names, "position": [0.0] * 6}}
    goal = [{"joint_constraints": [{"joint_name": n, "position": 0.1} for n in names]}]
    good = {"start_state": start, "goal_constraints": goal}
    assert (
        read_request(_write(tmp_path, good, "r.yaml"), robot).goal.tolist() == [0.1] * 6
    )
    cases = [
        ({"goal_constraints": goal}, "no start_state.joint_state"),
        ({"start_state": start}, "no goal_constraints"),
        ({"start_state": start, "goal_constraints": goal * 2}, "2 goal constraints"),
        (
            {
                "start_state": {
                    "joint_state": {"name": names[:5], "position": [0] * 5}
                },
                "goal_constraints": goal,
            },
            "start_state gives no value for joint 'wrist_3_joint'",
        ),
        (
            {
                "start_state": start,
                "goal_constraints": [
                    {"joint_constraints": goal[0]["joint_constraints"][1:]}
                ],
            },
            "goal_constraints gives no value for joint 'shoulder_pan_joint'",
        ),
        (
            {
                "start_state": {"joint_state": {"name": names, "position": ["a"] * 6}},
                "goal_constraints": goal,
            },
            "joint 'shoulder_pan_joint' must be a finite number, got 'a'",
        ),
    ]
    for document, message in cases:
        with pytest.raises(InputError, match=message):
            read_request(_write(tmp_path, document, "r.yaml"), robot)
    (tmp_path / "r.yaml").write_text(json.dumps(good)[:-3])
    with pytest.raises(InputError, match="not valid YAML"):
        read_request(tmp_path / "r.yaml", robot)
