"""``workbench workspace map``: JSON keys, text, bad input, progress lines."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

from tests.conftest import run_cli as run
from workbench import load_robot
from workbench import progress as progress_module
from workbench.cli import EXIT_BAD_INPUT
from workbench.collision import Obstacle, Scene, write_scene
from workbench.progress import Progress
from workbench.workspace import make_pose_grid
from workbench.workspace.store import open_map

SMALL = ["--resolution", "0.25", "--orientations", "16", "--block-voxels", "64"]
KEYS = {"robot", "voxels", "orientations", "poses", "sampled", "reachable_fraction"}
KEYS |= {"seconds", "poses_per_second", "store", "samples", "blocks"}
KEYS |= {"blocks_computed", "redundancy_samples"}


@pytest.mark.slow
def test_map_json_keys_and_the_map(capsys, tmp_path) -> None:
    out_path = tmp_path / "puma.zarr"
    code, out, err = run(
        capsys,
        "workspace",
        "map",
        "--robot",
        "puma560",
        *SMALL,
        "--workers",
        "2",
        "--out",
        str(out_path),
        "--json",
    )
    assert (code, err) == (0, "")
    summary = json.loads(out)
    assert set(summary) == KEYS
    grid = make_pose_grid(load_robot("puma560"), resolution=0.25, orientations=16)
    assert summary["robot"] == "puma560" and summary["sampled"] is False
    assert summary["voxels"] == grid.voxel_count and summary["orientations"] == 16
    assert summary["poses"] == grid.pose_count and summary["samples"] is None
    assert summary["redundancy_samples"] is None  # a six-axis arm
    assert summary["store"] == str(out_path.absolute())
    assert summary["blocks"] == summary["blocks_computed"] == -(-grid.voxel_count // 64)
    assert summary["seconds"] > 0 and summary["poses_per_second"] > 0
    atlas = open_map(out_path)
    reachability = atlas["reachability"].astype(np.float64)
    assert summary["reachable_fraction"] == np.sum(reachability) / len(reachability)
    assert np.array_equal(atlas["positions"], grid.positions)


@pytest.mark.slow
def test_map_text_cone_and_sampled(capsys, tmp_path) -> None:
    code, out, err = run(
        capsys,
        "workspace",
        "map",
        "--robot",
        "ur5",
        *SMALL,
        "--cone",
        "0",
        "0",
        "-1",
        "30",
        "--out",
        str(tmp_path / "ur5.zarr"),
    )
    assert (code, err) == (0, "")
    assert "exact" in out and "reachable" in out and "M poses/s" in out
    attrs = open_map(tmp_path / "ur5.zarr").attrs
    assert attrs["orientation_set"]["half_angle"] == pytest.approx(np.radians(30))
    assert attrs["family"] == "ur"
    code, out, err = run(
        capsys,
        "workspace",
        "map",
        "--robot",
        "panda",
        *SMALL,
        "--samples",
        "5000",
        "--out",
        str(tmp_path / "panda.zarr"),
        "--json",
    )
    assert (code, err) == (0, "")
    summary = json.loads(out)
    assert summary["sampled"] is True and summary["samples"] == 5000
    assert open_map(tmp_path / "panda.zarr").sampled


def test_map_with_a_scene(capsys, tmp_path) -> None:
    import pinocchio as pin

    scene = Scene("box", (Obstacle("b", "box", (0.2, 0.2, 0.2), pin.SE3.Identity()),))
    write_scene(scene, tmp_path / "scene.json")
    code, _, err = run(
        capsys,
        "workspace",
        "map",
        "--robot",
        "puma560",
        "--resolution",
        "0.4",
        "--orientations",
        "4",
        "--scene",
        str(tmp_path / "scene.json"),
        "--out",
        str(tmp_path / "scene.zarr"),
        "--json",
    )
    assert (code, err) == (0, "")
    assert "collision_free" in open_map(tmp_path / "scene.zarr").names


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--robot", "puma56"], "valid names: "),
        (["--robot", "puma560", "--workers", "2", "--scheduler", "tcp://h:1"], "not"),
        (["--robot", "puma560", "--workers", "0"], "must be 1..4096"),
        (["--robot", "puma560", "--resolution", "-1"], "must be > 0"),
        (["--robot", "puma560", "--orientations", "x"], "not an integer"),
        (["--robot", "puma560", "--cone", "0", "0", "0", "30"], "axis"),
        (["--robot", "puma560", "--cone", "0", "0", "1", "nan"], "not a finite"),
        (
            ["--robot", "panda", "--scene", "SCENE"],
            "seven-axis map checks no collisions",
        ),
        (
            ["--robot", "panda", "--samples", "9", "--scene", "SCENE"],
            "sampled map checks no collisions",
        ),
        (["--robot", "puma560", "--scene", "missing.json"], "missing.json"),
        (["--robot", "puma560", "--out", "EXISTS"], "already exists"),
        (["--robot", "puma560", "--out", "no/such/folder/m.zarr"], "does not exist"),
    ],
)
def test_bad_input_exits_2_with_one_line(capsys, tmp_path, argv, message) -> None:
    write_scene(Scene("empty"), tmp_path / "scene.json")
    (tmp_path / "exists.zarr").mkdir()
    replaced = [
        {
            "SCENE": str(tmp_path / "scene.json"),
            "EXISTS": str(tmp_path / "exists.zarr"),
        }.get(a, a).replace("no/such", str(tmp_path / "no/such"))
        for a in argv
    ]
    if "--out" not in replaced:
        replaced += ["--out", str(tmp_path / "m.zarr")]
    code, out, err = run(capsys, "workspace", "map", *SMALL, *replaced)
    assert code == EXIT_BAD_INPUT
    assert out == "" and len(err.strip().splitlines()) == 1
    assert message in err
    assert not (tmp_path / "m.zarr").exists()


def test_progress_lines_count_blocks_with_time_left(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("WORKBENCH_PROGRESS", "1")
    monkeypatch.setattr(progress_module, "PROGRESS_DELAY", 0.0)
    monkeypatch.setattr(progress_module, "COUNT_INTERVAL", 0.0)
    argv = ["workspace", "map", "--robot", "puma560", *SMALL, "--workers", "1"]
    code, _, err = run(capsys, *argv, "--out", str(tmp_path / "a.zarr"))
    assert code == 0
    lines = [line for line in err.splitlines() if "blocks (" in line]
    assert lines[0].startswith("workbench: workspace map: 0/")
    assert lines[-1].startswith("workbench: workspace map: ") and "(100%)" in lines[-1]
    assert any("left" in line for line in lines) and "elapsed" in lines[-1]
    for quiet, environ in ((["-q"], "1"), ([], "0")):
        monkeypatch.setenv("WORKBENCH_PROGRESS", environ)
        name = f"q{len(quiet)}.zarr"
        code, _, err = run(capsys, *quiet, *argv, "--out", str(tmp_path / name))
        assert code == 0 and "blocks" not in err


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_count_on_a_terminal_redraws_one_line(monkeypatch) -> None:
    monkeypatch.setattr(progress_module, "REDRAW_INTERVAL", 0.0)
    stream = _Terminal()
    with Progress("work", delay=0.0, stream=stream) as progress:
        for done in range(4):
            progress.count(done, 3, unit="blocks", label="map")
    text = stream.getvalue()
    assert text.count("\r") >= 3 and "map: 3/3 blocks (100%)" in text
    assert text.endswith("\n") and text.count("\n") <= 2  # the message, the count
    log = io.StringIO()
    with Progress("work", delay=60.0, stream=log) as progress:
        progress.count(1, 2)
    assert log.getvalue() == ""  # a quick command prints nothing


def test_progress_estimates_each_stage_from_its_own_counts(monkeypatch) -> None:
    """A new label starts a new estimate: the first count of a stage has none."""
    monkeypatch.setattr(progress_module, "COUNT_INTERVAL", 0.0)
    log = io.StringIO()
    with Progress("work", delay=0.0, stream=log) as progress:
        for label in ("first", "second"):
            for done in range(3):
                progress.count(done, 4, unit="points", label=label)
    lines = [line for line in log.getvalue().splitlines() if "points" in line]
    assert [line.split(":")[1].strip() for line in lines] == ["first"] * 3 + [
        "second"
    ] * 3
    assert ["left" in line for line in lines] == [False, True, True] * 2


def test_seconds_are_formatted_for_people() -> None:
    assert progress_module._format_seconds(8.14) == "8.1 s"
    assert progress_module._format_seconds(245.0) == "4 min 05 s"
    assert progress_module._format_seconds(7385.0) == "2 h 03 min"
