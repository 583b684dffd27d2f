"""Maps that cannot lie: damaged and edited stores are refused in one line.

Each kind of damage (a chunk deleted, truncated, replaced or rewritten
through Zarr, an attribute edited by hand or out of its schema, an array's
metadata edited) is made on a copy of one small map and fed to every command
that reads a map (``workspace place``, ``view``, ``report``, ``verify``):
each exits 2 with one line on stderr naming the damage, and writes nothing.
A good map verifies; a map of format version 1 is refused with the advice to
upgrade it, and ``verify --upgrade`` makes it whole.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import zarr

from tests.conftest import run_cli
from workbench.errors import InputError
from workbench.workspace import open_map
from workbench.workspace.manifest import CHECKSUMS, MANIFEST
from workbench.workspace.verify import verify_map

pytestmark = pytest.mark.subprocess

#: The small map every case damages a copy of (16 voxels × 8 orientations per
#: block: several chunks per array).
MAP = [
    *"workspace map --robot puma560 --resolution 0.4 --orientations 8".split(),
    *"--workers 1 --block-voxels 16 --out".split(),
]
TASK = "x,y,z,qx,qy,qz,qw\n0.5,0.1,0.3,0,0,0,1\n"


@pytest.fixture(scope="module")
def good_map(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("integrity")
    path = folder / "map.zarr"
    from workbench.cli import main

    assert main(["-q", *MAP, str(path)]) == 0
    return path


def _edit_attribute(name: str, value: Any) -> Callable[[Path], None]:
    """Set the (dotted) group attribute ``name`` in ``zarr.json`` by hand."""

    def edit(path: Path) -> None:
        meta = json.loads((path / "zarr.json").read_text())
        *parents, last = name.split(".")
        node = meta["attributes"]
        for part in parents:
            node = node[part]
        node[last] = value
        (path / "zarr.json").write_text(json.dumps(meta))

    return edit


def _edit_array_metadata(array: str, key: str, value: Any) -> Callable[[Path], None]:
    def edit(path: Path) -> None:
        file = path / array / "zarr.json"
        meta = json.loads(file.read_text())
        meta[key] = value
        file.write_text(json.dumps(meta))

    return edit


def _first_chunk(path: Path, array: str) -> Path:
    return sorted(f for f in (path / array / "c").rglob("*") if f.is_file())[0]


def _delete_chunk(array: str) -> Callable[[Path], None]:
    return lambda path: _first_chunk(path, array).unlink()


def _truncate_chunk(array: str) -> Callable[[Path], None]:
    def edit(path: Path) -> None:
        chunk = _first_chunk(path, array)
        chunk.write_bytes(chunk.read_bytes()[:7])

    return edit


def _garbage_chunk(array: str) -> Callable[[Path], None]:
    def edit(path: Path) -> None:
        chunk = _first_chunk(path, array)
        size = chunk.stat().st_size
        chunk.write_bytes(np.random.default_rng(0).bytes(size))

    return edit


def _through_zarr(array: str, value: float) -> Callable[[Path], None]:
    """Rewrite the first row of ``array`` with Zarr (valid chunks, other values)."""

    def edit(path: Path) -> None:
        group = zarr.open_group(path, mode="r+")
        group[array][0] = value

    return edit


def _add_stray_chunk(path: Path) -> None:
    """A chunk file where the manifest records a chunk of fill values only."""
    checksums = zarr.open_group(path, mode="r")[CHECKSUMS][...]
    row = int(np.flatnonzero(checksums[:, 0, 0] == 0)[0])
    chunk = _first_chunk(path, "reached")
    (chunk.parent.parent / str(row)).mkdir(exist_ok=True)
    shutil.copy(chunk, chunk.parent.parent / str(row) / "0")


def _zarr_format_2(path: Path) -> None:
    meta = json.loads((path / "zarr.json").read_text())
    meta["zarr_format"] = 2
    (path / "zarr.json").write_text(json.dumps(meta))


#: Damage → the text the one-line error must hold.
DAMAGES: dict[str, tuple[Callable[[Path], None], str]] = {
    "positions chunk deleted": (
        _delete_chunk("positions"),
        "array 'positions', chunk 0: the chunk file is missing",
    ),
    "data chunk deleted": (_delete_chunk("reached"), "the chunk file is missing"),
    "data chunk truncated": (_truncate_chunk("dexterity"), "was changed (7 bytes"),
    "positions chunk garbage": (
        _garbage_chunk("positions"),
        "array 'positions', chunk 0: the chunk file was changed",
    ),
    "reachability rewritten 7.5": (
        _through_zarr("reachability", 7.5),
        "array 'reachability', chunk 0: the chunk file was changed",
    ),
    "orientations rewritten NaN": (
        _through_zarr("orientations", float("nan")),
        "array 'orientations', chunk 0: the chunk file was changed",
    ),
    "positions rewritten NaN": (
        _through_zarr("positions", float("nan")),
        "'positions', chunk 0: the chunk file was changed",
    ),
    "chunk where none was": (_add_stray_chunk, "a chunk file is there where"),
    "resolution 0": (
        _edit_attribute("grid.resolution", 0),
        "attribute grid.resolution: must be > 0, got 0",
    ),
    "resolution -0.1": (
        _edit_attribute("grid.resolution", -0.1),
        "attribute grid.resolution: must be > 0",
    ),
    "resolution NaN": (
        _edit_attribute("grid.resolution", float("nan")),
        "attribute grid.resolution: must be finite",
    ),
    "resolution abc": (
        _edit_attribute("grid.resolution", "abc"),
        "attribute grid.resolution: must be a number, got 'abc'",
    ),
    "resolution null": (
        _edit_attribute("grid.resolution", None),
        "attribute grid.resolution: must be a number, got None",
    ),
    "origin of 2 numbers": (
        _edit_attribute("grid.origin", [0.0, 0.0]),
        "attribute grid.origin: must be a list of 3 numbers",
    ),
    "covering radius a string": (
        _edit_attribute("orientation_set.covering_radius", "0.5"),
        "attribute orientation_set.covering_radius: must be a number",
    ),
    "negative shape": (
        _edit_attribute("grid.shape", [-5, 5, 5]),
        "attribute grid.shape[0]: must be >= 1",
    ),
    "urdf_sha256 edited": (
        _edit_attribute("urdf_sha256", "0" * 64),
        "attribute 'urdf_sha256' was changed after the map was written",
    ),
    "urdf_sha256 not hex": (
        _edit_attribute("urdf_sha256", "xyz"),
        "attribute urdf_sha256: must be 64 hex digits",
    ),
    "family edited": (
        _edit_attribute("family", "ur"),
        "attribute 'family' was changed",
    ),
    "family unknown": (_edit_attribute("family", "scara"), "attribute family: must"),
    "tolerances edited": (
        _edit_attribute("tolerances.wrist", 0.5),
        "attribute 'tolerances' was changed",
    ),
    "redundancy added": (
        _edit_attribute("redundancy", {"parameter": "q7"}),
        "attribute redundancy: only a seven-axis exact map has one",
    ),
    "sampled edited": (_edit_attribute("sampled", True), "attribute samples: must"),
    "block_voxels edited": (
        _edit_attribute("block_voxels", 32),
        "in chunks of (16, 8), expected",
    ),
    "attribute added": (
        _edit_attribute("note", "hand-made"),
        "attribute 'note' was added",
    ),
    "manifest removed": (
        _edit_attribute(MANIFEST, None),
        "no manifest: it was not finished by a build",
    ),
    "chunk shape edited": (
        _edit_array_metadata(
            "dexterity",
            "chunk_grid",
            {"name": "regular", "configuration": {"chunk_shape": [8, 8]}},
        ),
        "array 'dexterity' is",
    ),
    "codec edited": (
        _edit_array_metadata(
            "reached", "codecs", [{"name": "bytes", "configuration": {}}]
        ),
        "the metadata (zarr.json) of array 'reached' was changed",
    ),
    "fill value edited": (
        _edit_array_metadata("dexterity", "fill_value", 0.0),
        "the metadata (zarr.json) of array 'dexterity' was changed",
    ),
    "checksums deleted": (
        lambda path: shutil.rmtree(path / CHECKSUMS),
        "no array 'checksums'",
    ),
    "checksums rewritten": (
        _through_zarr(CHECKSUMS, 1),  # the same size: its digest tells
        "array 'checksums', chunk 0: the chunk file was changed",
    ),
    "zarr_format 2": (_zarr_format_2, "is not a workspace map (zarr.json is of"),
}

#: Every command that reads a map, ``{map}`` its path.
COMMANDS = {
    "place": [
        *"workspace place --robot puma560 --map {map} --region 0 0.4 0 0.4".split(),
        *"--resolution 0.2 --yaw-step 90 --top 2 --targets task.csv".split(),
        *"--json".split(),
    ],
    "view": ["workspace", "view", "{map}", "--html", "out.html"],
    "report": ["workspace", "report", "{map}", "--out", "out.html"],
    "verify": ["workspace", "verify", "{map}"],
}


@pytest.fixture()
def damaged(good_map: Path, tmp_path: Path, request: pytest.FixtureRequest) -> Path:
    copy = tmp_path / "map.zarr"
    shutil.copytree(good_map, copy)
    DAMAGES[request.param][0](copy)
    (tmp_path / "task.csv").write_text(TASK)
    return copy


#: (damage, command) where the command reads none of the damaged chunk (whose
#: file has its recorded size): it answers, as it does on the good map.
UNREAD = {("reachability rewritten 7.5", "place")}


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("damaged", DAMAGES, indirect=True)
def test_a_damaged_map_is_refused_in_one_line(
    damaged: Path, command: str, good_map: Path, capsys, monkeypatch, request
) -> None:
    monkeypatch.chdir(damaged.parent)
    argv = [part.format(map=damaged) for part in COMMANDS[command]]
    code, out, err = run_cli(capsys, *argv)
    damage = request.node.callspec.params["damaged"]
    if (damage, command) in UNREAD:
        good = [part.format(map=good_map) for part in COMMANDS[command]]
        code_good, out_good, err_good = run_cli(capsys, *good)
        assert (code, err) == (code_good, err_good) == (0, "")
        answer, expected = json.loads(out), json.loads(out_good)
        assert answer.pop("seconds") > 0 and expected.pop("seconds") > 0
        assert answer == expected
        return
    assert code == 2, (code, err)
    assert err.count("\n") == 1 and DAMAGES[damage][1] in err, err
    assert not (damaged.parent / "out.html").exists()


def test_a_good_map_verifies_and_answers(good_map: Path, capsys) -> None:
    check = verify_map(good_map)
    assert check.format_version == 2 and check.checksums and not check.upgraded
    group = zarr.open_group(good_map, mode="r")
    chunks = sum(
        -(-group[name].shape[0] // group[name].chunks[0])
        for name in group.attrs[MANIFEST]["arrays"]
    )
    assert check.chunks == chunks and 0 < check.chunks_stored <= chunks
    assert check.values == sum(
        group[name].size for name in group.attrs[MANIFEST]["arrays"]
    )
    code, out, err = run_cli(capsys, "workspace", "verify", str(good_map), "--json")
    assert code == 0 and err == "" and json.loads(out) == check.as_dict()
    atlas = open_map(good_map)
    for name in atlas.names:  # the checked reader reads what Zarr reads
        np.testing.assert_array_equal(atlas[name], group[name][...])


def test_a_query_reads_only_the_chunks_it_touches(good_map, tmp_path) -> None:
    """A damaged chunk is found when read, not before: queries elsewhere answer."""
    copy = tmp_path / "map.zarr"
    shutil.copytree(good_map, copy)
    atlas = open_map(good_map)
    last = atlas.grid.voxel_count - 1
    pose = np.eye(4)
    pose[:3, 3] = atlas.grid.positions[last]
    expected = atlas.query(pose[None])
    chunk = copy / "dexterity" / "c" / "0" / "0"
    data = bytearray(chunk.read_bytes())
    data[-1] ^= 0xFF  # chunk 0 changed, its size kept; the pose lies in the last one
    chunk.write_bytes(bytes(data))
    damaged = open_map(copy)
    answer = damaged.query(pose[None])
    np.testing.assert_array_equal(answer.dexterity, expected.dexterity)
    first = np.eye(4)
    first[:3, 3] = atlas.grid.positions[0]
    with pytest.raises(InputError, match=r"'dexterity', chunk 0: .* changed .check"):
        damaged.query(first[None])


def _as_version_1(path: Path) -> None:
    """The map as the workbench wrote it before maps carried a manifest."""
    shutil.rmtree(path / CHECKSUMS)
    group = zarr.open_group(path, mode="r+")
    attrs = dict(group.attrs.asdict())
    del attrs[MANIFEST]
    attrs["format_version"] = 1
    group.attrs.clear()
    group.attrs.update(attrs)


def test_a_version_1_map_is_refused_then_upgraded(good_map, tmp_path, capsys) -> None:
    old = tmp_path / "old.zarr"
    shutil.copytree(good_map, old)
    _as_version_1(old)
    with pytest.raises(InputError, match="format version 1, written without check"):
        open_map(old)
    code, out, err = run_cli(capsys, "workspace", "verify", str(old))
    assert code == 0 and "done flags (format version 1)" in out and "--upgrade" in out
    broken = tmp_path / "broken.zarr"
    shutil.copytree(old, broken)
    zarr.open_group(broken, mode="r+")["reachability"][0] = 7.5
    code, out, err = run_cli(capsys, "workspace", "verify", str(broken), "--upgrade")
    assert code == 2 and "value 7.5 outside [0, 1]" in err and err.count("\n") == 1
    assert zarr.open_group(broken, mode="r").attrs["format_version"] == 1
    check = verify_map(old, upgrade=True)
    assert check.upgraded and check.format_version == 2
    assert verify_map(old).checksums
    for name in open_map(good_map).names:  # the same data, now checked
        np.testing.assert_array_equal(open_map(old)[name], open_map(good_map)[name])


def test_a_map_path_that_loops_is_refused(tmp_path) -> None:
    loop = tmp_path / "loop.zarr"
    loop.symlink_to(loop)
    with pytest.raises(InputError):
        open_map(loop)
