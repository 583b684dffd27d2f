"""The workspace map on disk: layout, attributes, round trip, queries, bad paths."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import zarr
from hypothesis import given
from hypothesis import strategies as st

from workbench import Robot, load_robot
from workbench.errors import InputError
from workbench.singularities.conditions import ELBOW_TOL, SHOULDER_TOL, WRIST_TOL
from workbench.workspace import evaluate_block, make_pose_grid, singularity_margin
from workbench.workspace.build import build_map
from workbench.workspace.grid import PoseGrid
from workbench.workspace.manifest import write_manifest
from workbench.workspace.map_query import split_poses
from workbench.workspace.orientations import (
    quat_xyzw_from_rotations,
    rotation_angle_between,
    rotations_from_quat_xyzw,
)
from workbench.workspace.store import (
    ARRAYS,
    DONE,
    FORMAT,
    FORMAT_VERSION,
    BlockWriter,
    WorkspaceMap,
    create_store,
    get_array_names,
    get_attributes,
    get_partial_path,
    open_map,
)

#: A coarse grid: the whole map takes a fraction of a second.
RESOLUTION = 0.2  # [m]
ORIENTATIONS = 24
BLOCK_VOXELS = 64
#: Exact agreement of positions snapped to their voxel centre [m].
ATOL_POSITION = 1e-15
#: Agreement of rotation angles computed two ways [rad] (acos near 0).
ATOL_ANGLE = 1e-7
#: Rotation matrices rebuilt from quaternions.
ATOL_ROTATION = 1e-15


@pytest.fixture(scope="module")
def puma_map(tmp_path_factory: pytest.TempPathFactory) -> tuple[Robot, PoseGrid, Path]:
    robot = load_robot("puma560")
    grid = make_pose_grid(robot, resolution=RESOLUTION, orientations=ORIENTATIONS)
    path = tmp_path_factory.mktemp("maps") / "puma.zarr"
    build_map(robot, grid, path, workers=2, block_voxels=BLOCK_VOXELS)
    return robot, grid, path


def test_layout_arrays_chunks_and_flags(puma_map) -> None:
    _, grid, path = puma_map
    group = zarr.open_group(path, mode="r")  # plain Zarr, no workbench
    names = set(group.array_keys())
    data = {"reached", "branches", "dexterity", "shoulder", "elbow", "wrist"}
    data |= {"limit_margin", "reachability", "dexterity_best", "dexterity_median"}
    data |= {"near_singular_fraction"}
    assert names == data | {"positions", "orientations", "done", "checksums"}
    voxels, orientations = grid.voxel_count, grid.orientation_count
    for name in data:
        array = group[name]
        info = ARRAYS[name]
        assert str(array.dtype) == info.dtype
        per_pose = name in {"reached", "branches", "dexterity", "shoulder"} | {
            "elbow",
            "wrist",
            "limit_margin",
        }
        assert info.per_pose == per_pose
        assert array.shape == ((voxels, orientations) if per_pose else (voxels,))
        assert array.chunks == (
            (BLOCK_VOXELS, orientations) if per_pose else (BLOCK_VOXELS,)
        )
        assert array.attrs["units"] == info.units
        assert array.attrs["description"] == info.description
    done = group["done"]
    assert done.shape == (-(-voxels // BLOCK_VOXELS),) and done.chunks == (1,)
    assert np.all(done[...] == 1)
    assert group["positions"].shape == (voxels, 3)
    assert group["orientations"].shape == (orientations, 4)


def _files(folder: Path) -> dict[str, bytes]:
    return {
        str(f.relative_to(folder)): f.read_bytes()
        for f in sorted(folder.rglob("*"))
        if f.is_file()
    }


def test_block_writer_stores_what_zarr_stores(puma_map, tmp_path, monkeypatch) -> None:
    """Chunks encoded and written by the block writer are Zarr's own, bitwise."""
    robot, grid, path = puma_map
    group = zarr.open_group(path, mode="r")
    names = get_array_names(group)
    blocks = -(-grid.voxel_count // BLOCK_VOXELS)
    assert grid.voxel_count % BLOCK_VOXELS  # the last chunk is cut by the array's end
    reference = tmp_path / "zarr.zarr"
    create_store(
        reference,
        grid,
        names=names,
        block_voxels=BLOCK_VOXELS,
        attrs=get_attributes(group),
        blocks=blocks,
    )
    plain = zarr.open_group(reference, mode="r+")  # Zarr's own setitem
    for block in range(blocks):
        start = block * BLOCK_VOXELS
        stop = min(start + BLOCK_VOXELS, grid.voxel_count)
        data = evaluate_block(robot, grid, start, stop)
        for name in names:
            plain[name][start:stop] = data[name]
        plain[DONE][block] = 1
    write_manifest(plain, names)
    built = _files(path)
    assert built == _files(reference)
    assert len([k for k in built if "/c/" in k]) < blocks * (len(names) + 1)
    # a block of fill values only: its chunk files are removed, as Zarr does
    copy = tmp_path / "copy.zarr"
    shutil.copytree(path, copy)
    block = next(b for b in range(blocks) if (copy / f"reached/c/{b}/0").is_file())
    start = block * BLOCK_VOXELS
    for name in names:
        plain[name][start : start + BLOCK_VOXELS] = ARRAYS[name].fill_value
    voxels = (BLOCK_VOXELS, grid.orientation_count)
    empty = {
        name: np.full(
            voxels if ARRAYS[name].per_pose else voxels[:1],
            ARRAYS[name].fill_value,
            dtype=ARRAYS[name].dtype,
        )
        for name in names
    }
    BlockWriter(copy).write(block, start, empty)
    assert not (copy / f"reached/c/{block}/0").exists()
    assert _files(copy) == _files(reference)
    assert not any(k.endswith(".partial") for k in _files(copy))
    # where the store is not a local folder, the writer goes through Zarr
    monkeypatch.setattr(zarr.storage, "LocalStore", type("OtherStore", (), {}))
    through_zarr = tmp_path / "through_zarr.zarr"
    shutil.copytree(path, through_zarr)
    BlockWriter(through_zarr).write(block, start, empty)
    assert _files(through_zarr) == _files(reference)


def test_attributes_say_what_the_map_is(puma_map) -> None:
    robot, grid, path = puma_map
    attrs = zarr.open_group(path, mode="r").attrs.asdict()
    assert attrs["format"] == FORMAT == "workbench-workspace-map"
    assert attrs["format_version"] == FORMAT_VERSION == 2
    assert attrs["robot"] == "puma560" and attrs["tool_frame"] == robot.tool_frame
    sha = hashlib.sha256(Path(robot.urdf_path).read_bytes()).hexdigest()
    assert attrs["urdf_sha256"] == sha
    assert attrs["family"] == "opw"
    assert attrs["sampled"] is False and attrs["samples"] is None
    assert attrs["sampling"] is None and attrs["scene"] is None
    assert attrs["joint_limits"] == {
        "lower": robot.lower.tolist(),
        "upper": robot.upper.tolist(),
    }
    assert attrs["grid"] == {
        "origin": grid.origin.tolist(),
        "resolution": RESOLUTION,
        "shape": list(grid.shape),
        "bounds": grid.bounds.tolist(),
    }
    assert attrs["orientation_set"] == json.loads(json.dumps(grid.orientation_set))
    assert attrs["orientation_set"]["count"] == ORIENTATIONS
    assert attrs["block_voxels"] == BLOCK_VOXELS
    assert attrs["tolerances"] == {
        "shoulder": SHOULDER_TOL,
        "elbow": ELBOW_TOL,
        "wrist": WRIST_TOL,
    }
    assert set(attrs["versions"]) == {
        "workbench",
        "pinocchio",
        "numpy",
        "numba",
        "zarr",
        "dask",
    }
    assert attrs["versions"]["zarr"] == zarr.__version__


def test_round_trip_equals_direct_evaluation(puma_map) -> None:
    robot, grid, path = puma_map
    atlas = open_map(path)
    stored = atlas.grid
    for name in ("positions", "origin", "bounds", "orientations", "rotations"):
        assert np.array_equal(getattr(stored, name), getattr(grid, name)), name
    assert stored.resolution == grid.resolution and stored.shape == grid.shape
    assert json.dumps(stored.orientation_set) == json.dumps(
        json.loads(json.dumps(grid.orientation_set))
    )
    direct = evaluate_block(robot, grid, 0, grid.voxel_count)
    assert set(atlas.names) == set(direct) - {"collision_free"}
    for name, values in direct.items():
        assert atlas[name].tobytes() == values.tobytes(), name
    assert np.array_equal(atlas["positions"], grid.positions)
    assert atlas.sampled is False
    assert "dexterity" in atlas and "collision_free" not in atlas


def test_query_at_grid_poses_and_near_them(puma_map, rng) -> None:
    robot, grid, path = puma_map
    atlas = open_map(path)
    direct = evaluate_block(robot, grid, 0, grid.voxel_count)
    count = 300
    voxel = rng.integers(0, grid.voxel_count, count)
    orientation = rng.integers(0, grid.orientation_count, count)
    # moved within the voxel (less than half an edge per axis) and turned a little
    offset = rng.uniform(-0.45, 0.45, (count, 3)) * RESOLUTION
    turn = rng.normal(size=(count, 3))
    turn *= 1e-3 / np.linalg.norm(turn, axis=1, keepdims=True)
    poses = np.zeros((count, 4, 4))
    for k in range(count):
        pose = grid.pose(voxel[k], orientation[k])
        poses[k, :3, :3] = pose[:3, :3] @ pin.exp3(turn[k])
        poses[k, :3, 3] = pose[:3, 3] + offset[k]
        poses[k, 3, 3] = 1.0
    result = atlas.query(poses)
    assert np.array_equal(result.voxel, voxel)
    assert np.array_equal(result.orientation, orientation)
    assert result.inside.all()
    assert np.array_equal(result.branches, direct["branches"][voxel, orientation])
    assert np.array_equal(result.reached, direct["reached"][voxel, orientation])
    for name in ("dexterity", "limit_margin"):
        expected = direct[name][voxel, orientation].astype(np.float64)
        assert getattr(result, name).tobytes() == expected.tobytes(), name
    margin = singularity_margin(
        *(direct[k][voxel, orientation] for k in ("shoulder", "elbow", "wrist"))
    )
    assert result.singularity_margin.tobytes() == margin.tobytes()
    np.testing.assert_allclose(
        result.position_error, np.linalg.norm(offset, axis=1), rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(result.orientation_error, 1e-3, rtol=0, atol=ATOL_ANGLE)
    rows = np.concatenate(
        [poses[:, :3, 3], quat_xyzw_from_rotations(poses[:, :3, :3])], axis=1
    )
    again = atlas.query(rows)
    for name in ("voxel", "orientation", "branches", "dexterity", "position_error"):
        assert getattr(again, name).tobytes() == getattr(result, name).tobytes()


def test_query_outside_the_grid(puma_map) -> None:
    _, grid, path = puma_map
    far = grid.bounds[1] + 10 * RESOLUTION
    result = open_map(path).query(np.array([[*far, 0.0, 0.0, 0.0, 1.0]]))
    assert result.voxel.tolist() == [-1] and result.inside.tolist() == [False]
    assert result.branches.tolist() == [0] and result.reached.tolist() == [0]
    for name in ("dexterity", "singularity_margin", "limit_margin", "position_error"):
        assert np.isnan(getattr(result, name)).all(), name
    assert 0 <= result.orientation[0] < grid.orientation_count


@given(st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4))
def test_quaternions_of_rotations_round_trip(values) -> None:
    quat = np.array(values)
    if np.linalg.norm(quat) < 1e-3:
        return
    quat /= np.linalg.norm(quat)
    rotation = rotations_from_quat_xyzw(quat[None])
    again = quat_xyzw_from_rotations(rotation)
    assert again[0, 3] >= 0.0
    np.testing.assert_allclose(
        rotations_from_quat_xyzw(again), rotation, rtol=0, atol=ATOL_ROTATION * 10
    )
    expected = pin.Quaternion(rotation[0]).coeffs()
    assert rotation_angle_between(again[0], expected) < ATOL_ANGLE


def test_bad_query_poses_are_refused(puma_map) -> None:
    atlas = open_map(puma_map[2])
    with pytest.raises(InputError, match=r"\(N, 4, 4\) or \(N, 7\)"):
        atlas.query(np.zeros((3, 6)))
    with pytest.raises(InputError, match="finite"):
        atlas.query(np.full((1, 7), np.nan))
    with pytest.raises(InputError, match="unit norm"):
        atlas.query(np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0]]))
    skewed = np.eye(4)[None].copy()
    skewed[0, 0, 1] = 0.1
    with pytest.raises(InputError, match=r"poses\[0\] is not a rigid transform"):
        atlas.query(skewed)
    mirrored = np.diag([1.0, 1.0, -1.0, 1.0])[None]
    with pytest.raises(InputError, match="rigid"):
        split_poses(mirrored)


def test_array_access_names_what_is_there(puma_map) -> None:
    atlas = open_map(puma_map[2])
    assert isinstance(atlas, WorkspaceMap) and "puma560" in repr(atlas)
    with pytest.raises(InputError, match="no array 'collision_free'; it has reached"):
        atlas["collision_free"]
    assert atlas["done"].dtype == np.uint8


def _copy(puma_map, tmp_path: Path, name: str = "copy.zarr") -> Path:
    target = tmp_path / name
    shutil.copytree(puma_map[2], target)
    return target


def test_open_refuses_what_is_no_map(puma_map, tmp_path) -> None:
    with pytest.raises(InputError, match=r"no workspace map at .*: not found"):
        open_map(tmp_path / "missing.zarr")
    (tmp_path / "file.zarr").write_text("x")
    with pytest.raises(InputError, match="not a workspace map"):
        open_map(tmp_path / "file.zarr")
    (tmp_path / "empty.zarr").mkdir()
    with pytest.raises(InputError, match=r"no Zarr v3 zarr\.json"):
        open_map(tmp_path / "empty.zarr")
    other = zarr.open_group(tmp_path / "other.zarr", mode="w", attributes={"a": 1})
    other.create_array("x", shape=(2,), dtype="f8")
    with pytest.raises(InputError, match="attribute format is None"):
        open_map(tmp_path / "other.zarr")
    broken = tmp_path / "broken.zarr"
    broken.mkdir()
    (broken / "zarr.json").write_text("{not json")
    with pytest.raises(InputError, match="is not a workspace map"):
        open_map(broken)


def test_open_refuses_other_versions_damage_and_unfinished_builds(
    puma_map, tmp_path
) -> None:
    newer = _copy(puma_map, tmp_path, "newer.zarr")
    zarr.open_group(newer, mode="r+").attrs["format_version"] = 3
    with pytest.raises(
        InputError, match="format version 3; this workbench reads version 2"
    ):
        open_map(newer)
    damaged = _copy(puma_map, tmp_path, "damaged.zarr")
    shutil.rmtree(damaged / "orientations")
    with pytest.raises(InputError, match=r"damaged workspace map .*'orientations'"):
        open_map(damaged)
    unfinished = _copy(puma_map, tmp_path, "unfinished.zarr")
    zarr.open_group(unfinished, mode="r+")["done"][1] = 0
    with pytest.raises(InputError, match=r"damaged .*done flags lost: 1 of \d+ blocks"):
        open_map(unfinished)  # a finished map (its manifest says so) lost a flag
    zarr.open_group(unfinished, mode="r+").attrs.pop("manifest")
    with pytest.raises(InputError, match="unfinished map build"):
        open_map(unfinished)
    partial = get_partial_path(tmp_path / "p.zarr")
    shutil.copytree(puma_map[2], partial)
    with pytest.raises(InputError, match=r"unfinished map build \(\d+ of \d+ blocks"):
        open_map(partial)
