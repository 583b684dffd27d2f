"""The Meshcat viewer: scene, animation, pages, live server, CLI and teach panel."""

from __future__ import annotations

import asyncio
import base64
import json
import re
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import umsgpack

from tests._interrupts import take_sigint
from tests.conftest import random_configurations, run_cli
from workbench import FrameNotFoundError, InputError, URDFLoadError, load_robot
from workbench.cli import EXIT_BAD_INPUT
from workbench.errors import DimensionError
from workbench.trajectory.csv_io import JointTrajectorySamples, write_trajectory_csv
from workbench.viz import (
    SingularityGauge,
    Viewer,
    get_singularity_color,
    write_trajectory_html,
)

ATOL_EXACT = 1e-12
ATOL_FLOAT32 = 1e-6  # tool path vertices are sent as float32
RED = get_singularity_color(0.0)
GREEN = get_singularity_color(1.0)
Q_DEG = [0.0, -45.0, 180.0, 0.0, 45.0, 0.0]
WRIST_SINGULAR_DEG = [0.0, -45.0, 180.0, 0.0, 0.0, 0.0]

THREE_R_URDF = """<?xml version="1.0"?>
<robot name="three_r">
  <link name="base"><visual><origin xyz="0 0 -0.05"/>
    <geometry><cylinder radius="0.06" length="0.1"/></geometry></visual></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1" effort="1"/></joint>
  <link name="l1"><visual><origin xyz="0.15 0 0"/>
    <geometry><box size="0.3 0.04 0.04"/></geometry></visual></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="1" effort="1"/></joint>
  <link name="l2"><visual><origin xyz="0.15 0 0"/>
    <geometry><box size="0.3 0.04 0.04"/></geometry></visual></link>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="1" effort="1"/></joint>
  <link name="l3"><visual><origin xyz="0.1 0 0"/>
    <geometry><sphere radius="0.03"/></geometry></visual></link>
  <joint name="tool_joint" type="fixed"><parent link="l3"/><child link="tool"/>
    <origin xyz="0.2 0 0"/></joint>
  <link name="tool"/>
</robot>
"""


@pytest.fixture(scope="module")
def three_r(tmp_path_factory: pytest.TempPathFactory):
    """A planar 3R arm of primitives (no DH table): the Jacobian gauge applies."""
    path = tmp_path_factory.mktemp("three_r") / "three_r.urdf"
    path.write_text(THREE_R_URDF, encoding="utf-8")
    return load_robot(path, tool_frame="tool")


def page_commands(page: str) -> list[dict]:
    """Decode the Meshcat commands a page replays."""
    scene = re.search(r"const WORKBENCH_SCENE = (\[.*?\]);\n", page).group(1)
    return [umsgpack.unpackb(base64.b64decode(c)) for c in json.loads(scene)]


def by_path(commands: list[dict], kind: str) -> dict[str, dict]:
    return {c["path"]: c for c in commands if c["type"] == kind}


def matrix(command: dict) -> np.ndarray:
    return np.array(command["matrix"]).reshape(4, 4).T


# -- scene contents ---------------------------------------------------------------


def test_page_is_self_contained(puma) -> None:
    page = Viewer(puma).render_html()
    assert "MeshCat.Viewer" in page
    assert not re.search(r"<(script|link|img|iframe)\b[^>]*\b(src|href)\s*=", page)
    assert "viewer.connect" not in page  # offline: no websocket


def test_every_geometry_is_placed_by_pinocchio(puma, rng) -> None:
    q = random_configurations(puma, rng, 1)[0]
    commands = page_commands(Viewer(puma, q).render_html())
    objects, transforms = (
        by_path(commands, "set_object"),
        by_path(commands, "set_transform"),
    )
    data, gdata = puma.model.createData(), puma.visual_model.createData()
    pin.forwardKinematics(puma.model, data, q)
    pin.updateGeometryPlacements(puma.model, data, puma.visual_model, gdata)
    for geometry, placement in zip(
        puma.visual_model.geometryObjects, gdata.oMg, strict=True
    ):
        path = f"/meshcat/robot/visuals/{geometry.name}"
        assert path in objects
        np.testing.assert_allclose(
            matrix(transforms[path]), placement.homogeneous, rtol=0, atol=ATOL_EXACT
        )


def test_singularity_gauge_analytic_for_puma(puma) -> None:
    gauge = SingularityGauge.from_robot(puma)
    assert gauge.method == "analytic"
    assert gauge.compute_distance(np.deg2rad(WRIST_SINGULAR_DEG)) == 0.0
    assert 0.0 < gauge.compute_distance(np.deg2rad(Q_DEG)) <= 1.0
    np.testing.assert_allclose(
        gauge.compute_color(np.deg2rad(WRIST_SINGULAR_DEG)), RED, rtol=0, atol=0
    )


def test_singularity_gauge_jacobian_for_any_urdf(three_r) -> None:
    gauge = SingularityGauge.from_robot(three_r)
    assert gauge.method == "jacobian"
    assert gauge.compute_distance([0.3, 0.0, 0.5]) == pytest.approx(0.0, abs=1e-9)
    assert gauge.compute_distance([0.3, 1.2, -0.8]) > 0.2


def test_links_coloured_by_singularity_distance_base_kept(puma) -> None:
    viewer = Viewer(puma, np.deg2rad(WRIST_SINGULAR_DEG), color_by_singularity=True)
    colors = {
        c["path"]: c["value"]
        for c in page_commands(viewer.render_html())
        if c["type"] == "set_property" and c["property"] == "color"
    }
    assert "/meshcat/robot/visuals/frame0_0" not in colors  # the fixed base
    np.testing.assert_allclose(
        colors["/meshcat/robot/visuals/link2_1"], [*RED, 1.0], rtol=0, atol=ATOL_EXACT
    )


def test_play_trajectory_animates_every_geometry(puma) -> None:
    t = np.cumsum(np.full(200, 0.01)) + 1.0  # starts at 1 s: keys start at 0
    s = np.linspace(0.0, 1.0, t.size)[:, None]
    q = np.deg2rad(Q_DEG) + s * np.deg2rad([90, -30, -20, 40, 60, 90])
    viewer = Viewer(puma, color_by_singularity=True)
    viewer.play_trajectory(t, q)
    commands = page_commands(viewer.render_html())
    (animation,) = [c for c in commands if c["type"] == "set_animation"]
    clips = {a["path"]: a["clip"] for a in animation["animations"]}
    data, gdata = puma.model.createData(), puma.visual_model.createData()
    pin.forwardKinematics(puma.model, data, q[-1])
    pin.updateGeometryPlacements(puma.model, data, puma.visual_model, gdata)
    for geometry, placement in zip(
        puma.visual_model.geometryObjects, gdata.oMg, strict=True
    ):
        tracks = {
            tr["name"]: tr["keys"]
            for tr in clips[f"/meshcat/robot/visuals/{geometry.name}"]["tracks"]
        }
        times = [k["time"] for k in tracks[".position"]]
        assert times[0] == 0.0
        assert times[-1] == pytest.approx(t[-1] - t[0], abs=ATOL_EXACT)
        assert len(times) <= 2 * 30 + 2  # 2 s at 30 frames per second at most
        np.testing.assert_allclose(
            tracks[".position"][-1]["value"],
            placement.translation,
            rtol=0,
            atol=ATOL_EXACT,
        )
    colour = clips["/meshcat/robot/visuals/link2_1/<object>"]["tracks"][0]
    assert (colour["name"], colour["type"]) == (".material.color", "color")
    line = by_path(commands, "set_object")["/meshcat/tool_path/line"]
    vertices = line["object"]["geometries"][0]["data"]["attributes"]["position"]
    assert vertices["itemSize"] == 3
    assert len(vertices["array"].data) == 3 * t.size * 4  # float32 bytes


def test_play_trajectory_rejects_bad_input(puma) -> None:
    viewer = Viewer(puma)
    q = np.zeros((3, 6))
    with pytest.raises(InputError, match="strictly increasing"):
        viewer.play_trajectory([0.0, 0.2, 0.1], q)
    with pytest.raises(DimensionError, match="t must have shape"):
        viewer.play_trajectory([0.0, 0.1], q)
    with pytest.raises(DimensionError, match="q must have shape"):
        viewer.play_trajectory([0.0, 0.1, 0.2], np.zeros((3, 5)))


def test_tool_path_is_the_fk_of_every_sample(puma, rng) -> None:
    q = random_configurations(puma, rng, 5)
    points = Viewer(puma).show_tool_path(q)
    expected = np.array([puma.fk(qk).translation for qk in q])
    np.testing.assert_allclose(points, expected, rtol=0, atol=ATOL_EXACT)


def test_ghosts_one_node_per_branch_without_base(puma) -> None:
    q = np.deg2rad(Q_DEG)
    flip = q + np.deg2rad([0.0, 0.0, 0.0, 180.0, -90.0, 180.0])  # wrist flip twin
    viewer = Viewer(puma)
    viewer.show_ghosts([q, q], labels=["old", "older"])
    viewer.show_ghosts([q, flip], labels=["right/elbow-up/no-flip", "flip"])
    objects = by_path(page_commands(viewer.render_html()), "set_object")
    ghosts = [p for p in objects if p.startswith("/meshcat/ghosts/")]
    assert {p.split("/")[3] for p in ghosts} == {"right-elbow-up-no-flip", "flip"}
    assert not any("frame0" in p for p in ghosts)  # the base is the arm's
    material = objects[ghosts[0]]["object"]["materials"][0]
    assert material["transparent"] and material["opacity"] == pytest.approx(0.3)
    with pytest.raises(InputError, match="1 labels for 2"):
        viewer.show_ghosts([q, flip], labels=["one"])


def test_ghosts_of_the_collision_geometry(puma) -> None:
    """``collision=True`` draws each ghost with the collision model's objects."""
    q = np.deg2rad(Q_DEG)
    drawn = {}
    for collision in (False, True):
        viewer = Viewer(puma)
        viewer.show_ghosts([q], labels=["g"], collision=collision)
        objects = by_path(page_commands(viewer.render_html()), "set_object")
        drawn[collision] = {
            p.rsplit("/", 1)[1] for p in objects if p.startswith("/meshcat/ghosts/g/")
        }
    collision_names = {g.name for g in puma.collision_model.geometryObjects}
    visual_names = {g.name for g in puma.visual_model.geometryObjects}
    assert drawn[True] and drawn[True] <= collision_names
    assert drawn[False] <= visual_names
    viewer = Viewer(puma)
    viewer.show_ghosts([q], labels=["g"], collision=True)
    assert "ghosts drawn with the collision geometry" in viewer.render_html()


def test_targets_frames_and_visibility(puma) -> None:
    viewer = Viewer(puma)
    target = puma.fk(np.deg2rad(Q_DEG))
    viewer.add_target("pick", target)
    viewer.show_frames()
    viewer.set_visible("floor", False)
    commands = page_commands(viewer.render_html())
    transforms = by_path(commands, "set_transform")
    np.testing.assert_allclose(
        matrix(transforms["/meshcat/targets/pick"]),
        target.homogeneous,
        rtol=0,
        atol=ATOL_EXACT,
    )
    np.testing.assert_allclose(
        matrix(transforms["/meshcat/frames/wrist_center"]),
        puma.fk(viewer.q).homogeneous,
        rtol=0,
        atol=ATOL_EXACT,
    )
    hidden = by_path(commands, "set_property")["/meshcat/floor"]
    assert (hidden["property"], hidden["value"]) == ("visible", False)
    with pytest.raises(InputError, match="orthonormal"):
        viewer.add_target("bad", np.diag([2.0, 1.0, 1.0, 1.0]))
    with pytest.raises(FrameNotFoundError, match="nope"):
        viewer.show_frames(["nope"])


def test_camera_frames_the_arm_from_front_right_above(puma) -> None:
    viewer = Viewer(puma, np.deg2rad(Q_DEG))
    camera = viewer.get_camera()
    offset = np.subtract(camera.position, camera.target)
    assert offset[0] > 0 and offset[1] > 0 and offset[2] > 0
    assert 1.0 < np.linalg.norm(offset) < 5.0  # metres, for a ~1 m arm
    viewer.set_camera([2.0, 0.0, 1.0], [0.0, 0.0, 0.0])
    assert viewer.get_camera().position == (2.0, 0.0, 1.0)
    with pytest.raises(DimensionError):
        viewer.set_camera([2.0, 0.0], [0.0, 0.0, 0.0])


def test_any_urdf_is_drawn(three_r) -> None:
    viewer = Viewer(three_r, [0.3, 1.2, -0.8], color_by_singularity=True)
    objects = by_path(page_commands(viewer.render_html()), "set_object")
    assert {"/meshcat/robot/visuals/l1_0", "/meshcat/robot/visuals/l3_0"} <= set(
        objects
    )


def test_write_trajectory_html(puma, tmp_path) -> None:
    t = np.linspace(0.0, 1.0, 11)
    q = np.tile(np.deg2rad(Q_DEG), (11, 1))
    samples = JointTrajectorySamples(t, q, 0 * q, 0 * q)
    path = write_trajectory_html(puma, samples, tmp_path / "preview.html")
    commands = page_commands(path.read_text(encoding="utf-8"))
    assert [c["type"] for c in commands].count("set_animation") == 1
    with pytest.raises(DimensionError):
        write_trajectory_html(
            puma, JointTrajectorySamples(t, q[:, :5], q, q), tmp_path / "x.html"
        )


# -- robustness ---------------------------------------------------------------------


def test_missing_mesh_is_a_urdf_load_error(tmp_path, capsys) -> None:
    urdf = tmp_path / "missing.urdf"
    urdf.write_text(
        THREE_R_URDF.replace(
            '<sphere radius="0.03"/>', '<mesh filename="package://gone/l3.stl"/>'
        ),
        encoding="utf-8",
    )
    with pytest.raises(URDFLoadError, match="package 'gone' not found"):
        Viewer(load_robot(urdf))
    code, _, err = run_cli(
        capsys, "view", "--robot", str(urdf), "--html", str(tmp_path / "x.html")
    )
    assert code == EXIT_BAD_INPUT
    assert err.startswith("workbench: error:") and "gone/l3.stl" in err
    assert err.count("\n") == 1
    assert not (tmp_path / "x.html").exists()


def test_unloadable_urdf_exits_2(tmp_path, capsys) -> None:
    urdf = tmp_path / "broken.urdf"
    urdf.write_text(THREE_R_URDF.replace("</robot>", ""), encoding="utf-8")
    code, _, err = run_cli(
        capsys, "view", "--robot", str(urdf), "--html", str(tmp_path / "x.html")
    )
    assert code == EXIT_BAD_INPUT
    assert "malformed URDF" in err


@pytest.fixture()
def good_csv(tmp_path) -> Path:
    t = np.linspace(0.0, 1.0, 5)
    q = np.tile(np.deg2rad(Q_DEG), (5, 1))
    path = tmp_path / "ok.csv"
    write_trajectory_csv(path, JointTrajectorySamples(t, q, 0 * q, 0 * q))
    return path


def _drop_joint(line: str) -> str:
    """A CSV line of 6 joints as one of 5: drop q6, qd6, qdd6."""
    fields = line.split(",")
    return ",".join(fields[:6] + fields[7:12] + fields[13:18])


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda lines: [_drop_joint(line) for line in lines],
            "line 1: the header has 5",
        ),
        (lambda lines: [*lines[:3], "0.6,1,2", *lines[3:]], "line 4: 3 fields"),
        (
            lambda lines: [*lines[:2], lines[2].replace(",", ",abc,", 1)[:-1]],
            "line 3: ",
        ),
    ],
    ids=["joint-count", "short-row", "not-a-number"],
)
def test_bad_trajectory_csv_exits_2_with_line(
    good_csv, tmp_path, capsys, edit, message
) -> None:
    lines = good_csv.read_text(encoding="utf-8").splitlines()
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(edit(lines)) + "\n", encoding="utf-8")
    out = tmp_path / "x.html"
    code, _, err = run_cli(
        capsys,
        "view",
        "--robot",
        "puma560",
        "--trajectory",
        str(bad),
        "--html",
        str(out),
    )
    assert code == EXIT_BAD_INPUT, err
    assert message in err
    assert not out.exists()


# -- command line -------------------------------------------------------------------


def test_cli_writes_pose_and_trajectory_pages(good_csv, tmp_path, capsys) -> None:
    pose = tmp_path / "pose.html"
    code, out, err = run_cli(
        capsys,
        "view",
        "--robot",
        "puma560",
        "--deg",
        *map(str, Q_DEG),
        "--html",
        str(pose),
    )
    assert (code, err) == (0, "")
    assert str(pose) in out
    assert "set_animation" not in {c["type"] for c in page_commands(pose.read_text())}
    anim = tmp_path / "anim.html"
    code, _, err = run_cli(
        capsys,
        "view",
        "--robot",
        "puma560",
        "--trajectory",
        str(good_csv),
        "--html",
        str(anim),
    )
    assert (code, err) == (0, "")
    assert "set_animation" in {c["type"] for c in page_commands(anim.read_text())}


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["0", "0", "0", "0", "0", "0"], "need --deg or --rad"),
        (["--deg"], "need joint values"),
        (["--deg", "1", "2"], "6 values expected, 2 given"),
        (["--deg", *map(str, Q_DEG), "--trajectory", "x.csv"], "not both"),
        (["--ik-branches"], "needs joint values"),
        (["--trajectory", "nowhere.csv"], "cannot read trajectory"),
    ],
)
def test_cli_input_errors_exit_2(tmp_path, capsys, args, message) -> None:
    out = str(tmp_path / "x.html")
    code, _, err = run_cli(capsys, "view", "--robot", "puma560", *args, "--html", out)
    assert code == EXIT_BAD_INPUT
    assert message in err


def test_cli_needs_html_or_serve(capsys) -> None:
    code, _, err = run_cli(capsys, "view", "--robot", "puma560")
    assert code == EXIT_BAD_INPUT
    assert "--html" in err and "--serve" in err


def test_cli_ik_branches(tmp_path, capsys) -> None:
    out = tmp_path / "branches.html"
    argv = ["view", "--robot", "puma560", "--deg", *map(str, Q_DEG), "--ik-branches"]
    code, _, err = run_cli(capsys, *argv, "--html", str(out))
    assert (code, err) == (0, "")
    objects = by_path(page_commands(out.read_text()), "set_object")
    assert (
        len({p.split("/")[3] for p in objects if p.startswith("/meshcat/ghosts/")}) > 1
    )


@pytest.mark.slow
@pytest.mark.subprocess
def test_viz_is_imported_lazily() -> None:
    code = "import sys, workbench, workbench.cli; print(sorted(m for m in sys.modules"
    code += " if m.split('.')[0] in ('meshcat', 'ipywidgets', 'tornado')"
    code += " or m.startswith('workbench.viz')))"
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "[]"


# -- live server --------------------------------------------------------------------


def fetch(url: str, timeout: float = 5.0) -> str:
    with urllib.request.urlopen(url, timeout=timeout) as response:
        return response.read().decode("utf-8")


async def watch_scene(viewer: Viewer, url: str, q_next: np.ndarray) -> list[dict]:
    """Connect like a page: receive the scene, then the update ``display`` sends."""
    from tornado.websocket import websocket_connect

    expected = len(page_commands(viewer.render_html()))
    connection = await websocket_connect(url.replace("http://", "ws://") + "ws")
    scene = [umsgpack.unpackb(await connection.read_message()) for _ in range(expected)]
    viewer.display(q_next)
    update = umsgpack.unpackb(await connection.read_message())
    connection.close()
    return [*scene, update]


def test_server_pushes_scene_then_updates(puma) -> None:
    viewer = Viewer(puma)
    url = viewer.start_server()
    try:
        assert url.startswith("http://127.0.0.1:")
        page = fetch(url)
        assert "MeshCat.Viewer" in page and 'location.host + "/ws"' in page
        assert viewer.wait_for_browser(timeout=0.01) is False
        q_next = np.deg2rad(Q_DEG)
        *scene, update = asyncio.run(watch_scene(viewer, url, q_next))
        assert "/meshcat/robot/visuals/link2_1" in by_path(scene, "set_object")
        assert viewer.wait_for_browser(timeout=5.0) is True
        assert update["type"] == "set_transform"
        geometry_id = puma.visual_model.getGeometryId(update["path"].split("/")[-1])
        data, gdata = puma.model.createData(), puma.visual_model.createData()
        pin.forwardKinematics(puma.model, data, q_next)
        pin.updateGeometryPlacements(puma.model, data, puma.visual_model, gdata)
        np.testing.assert_allclose(
            matrix(update), gdata.oMg[geometry_id].homogeneous, rtol=0, atol=ATOL_EXACT
        )
    finally:
        viewer.stop_server()
    with pytest.raises(urllib.error.URLError):
        fetch(url, timeout=2.0)


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.mark.slow
@pytest.mark.subprocess
def test_cli_serve_until_interrupted() -> None:
    port = free_port()
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "workbench",
            "view",
            "--robot",
            "puma560",
            "--deg",
            *map(str, Q_DEG),
            "--serve",
            "--port",
            str(port),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=take_sigint,  # a background job (`cmd &`) inherits it ignored
    )
    url = f"http://127.0.0.1:{port}/"
    try:
        deadline = time.monotonic() + 30.0
        while True:
            try:
                page = fetch(url, timeout=2.0)
                break
            except (urllib.error.URLError, ConnectionError):
                assert process.poll() is None, process.stderr.read()
                assert time.monotonic() < deadline, "server did not come up"
                time.sleep(0.2)
        assert "MeshCat.Viewer" in page
        assert process.poll() is None  # still serving after the page was fetched
    finally:
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=15)
    assert process.returncode == 0, err
    assert url in out


# -- teach panel --------------------------------------------------------------------


def test_teach_panel_sliders_drive_view_and_readout(puma) -> None:
    pytest.importorskip("ipywidgets")
    from workbench.viz import TeachPanel

    panel = TeachPanel(puma, np.deg2rad(Q_DEG), live=False)
    assert len(panel.sliders) == puma.nq
    np.testing.assert_allclose(panel.q, np.deg2rad(Q_DEG), rtol=0, atol=ATOL_EXACT)
    lines = panel.get_readout()
    assert lines[0].startswith("tool pose:")
    assert any(line.startswith("det J =") for line in lines)
    assert any(line.startswith("singularity distance (analytic)") for line in lines)
    assert any(line.startswith("shoulder =") for line in lines)
    try:
        from workbench.ik import analytic  # noqa: F401
    except ImportError:
        assert not any("IK branch" in line for line in lines)
    else:
        assert any(line.startswith("IK branch: ") for line in lines)
    panel.sliders[4].value = 0.0  # θ5 = 0: wrist singular
    np.testing.assert_allclose(panel.viewer.q[4], 0.0, rtol=0, atol=ATOL_EXACT)
    assert "singularity distance (analytic) = 0.000" in panel.get_readout()
    assert "<iframe srcdoc=" in panel.view.value
    q_pick = np.deg2rad([0.0, 45.0, 200.0, -100.0, 30.0, 10.0])  # θ3 beyond 180°
    panel.set_configuration(q_pick)
    np.testing.assert_allclose(panel.q, q_pick, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(panel.viewer.q, q_pick, rtol=0, atol=ATOL_EXACT)
    distance = SingularityGauge.from_robot(puma).compute_distance(q_pick)
    assert f"singularity distance (analytic) = {distance:.3f}" in panel.get_readout()


def test_teach_panel_live_and_any_robot(three_r) -> None:
    pytest.importorskip("ipywidgets")
    from workbench.viz import TeachPanel

    panel = TeachPanel(three_r)
    try:
        url = re.search(r'src="([^"]+)"', panel.view.value).group(1)
        assert "MeshCat.Viewer" in fetch(url)
        lines = panel.get_readout()
        assert any(line.startswith("manipulability") for line in lines)  # 6×3 J
        assert not any(line.startswith(("shoulder", "IK branch")) for line in lines)
    finally:
        panel.close()


def test_every_page_has_a_title_and_a_legend(puma) -> None:
    viewer = Viewer(puma, color_by_singularity=True, title="Sec. V <pick>")
    viewer.show_frames()
    page = viewer.render_html()
    assert "<title>Sec. V &lt;pick&gt;</title>" in page
    legend = '<details id="workbench-legend" open><summary><h1>Sec. V &lt;pick&gt;</h1>'
    assert legend in page
    assert "distance to the nearest singularity" in page
    assert "frame wrist_center: x red, y green, z blue" in page
    assert "start of the path" not in page
    viewer.play_trajectory([0.0, 1.0], np.zeros((2, 6)))
    viewer.show_ghosts(np.zeros((2, 6)), labels=["one", "two"])
    viewer.add_target("goal", np.eye(4))
    page = viewer.render_html()
    for text in ("tool path", "start of the path", "end of the path", "Ghost arms"):
        assert text in page
    assert "targets goal" in page and ">two<" in page
    assert "workbench-legend" not in viewer.render_html(legend=False)
    plain = Viewer(puma)  # no colouring: no colour scale
    assert "nearest singularity" not in plain.render_html()
    assert "<h1>workbench viewer: puma560</h1>" in plain.render_html()


def test_collision_pages_explain_their_colours(puma) -> None:
    from workbench.collision import CollisionChecker, get_angeles_scene

    viewer = Viewer(puma, color_by_singularity=True)
    assert "nearest singularity" in viewer.render_html()
    viewer.show_collisions(CollisionChecker(puma, get_angeles_scene(puma)))
    page = viewer.render_html()
    assert "nearest singularity" not in page  # the links now show contacts
    assert "with the scene (pedestal, pick_table)" in page
    for text in ("link, no contact", "in contact", "closest pair"):
        assert text in page
