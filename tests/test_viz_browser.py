"""The exported page rendered offline in headless Chromium: the arm is drawn.

Chromium comes from the system; when it is missing and we are root, the
session fixture ``chromium`` (``tests/conftest.py``) installs it (``apt-get
install -y chromium``), else the tests skip and say why. WebGL runs on
SwiftShader (software), no GPU needed. ``tests/_chromium.py`` drives Chromium
over the DevTools protocol, with a deadline on every step and no retry (see its
docstring for why).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
from PIL import Image

from tests._chromium import take_screenshot
from workbench import Robot, load_robot
from workbench.viz import Viewer

WIDTH, HEIGHT = 800, 600
PIXEL_CHANGED = 40  # max |RGB difference| above which a pixel counts as changed
Q1_DEG = [0.0, -45.0, 180.0, 0.0, 45.0, 0.0]
Q2_DEG = [60.0, -90.0, 160.0, 30.0, 30.0, 0.0]


def screenshot(
    chromium: str, page: str, path: Path, script: str | None = None
) -> np.ndarray:
    """Save ``page`` next to ``path``, render it offline, return RGB (H, W, 3)."""
    html = path.with_suffix(".html")
    html.write_text(page, encoding="utf-8")
    take_screenshot(chromium, html, path, width=WIDTH, height=HEIGHT, script=script)
    image = np.asarray(Image.open(path).convert("RGB"), dtype=np.int16)
    assert image.shape == (HEIGHT, WIDTH, 3)
    return image


def seek(t: float) -> str:
    """Script that pauses the page's animation at time ``t`` [s] (the scrubber)."""
    return f"viewer.animator.pause(); viewer.animator.seek({t});"


def changed(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Boolean (H, W): pixels that differ between two screenshots."""
    return np.abs(a - b).max(axis=2) > PIXEL_CHANGED


def arm_region(robot: Robot, q: np.ndarray, viewer: Viewer) -> tuple[int, ...]:
    """Pixel box (left, top, right, bottom) of the arm's geometry on screen.

    Projects the corners of every geometry's bounding box with the page's
    camera (pinhole, vertical field of view, z up), independently of the viewer.
    """
    data, gdata = robot.model.createData(), robot.visual_model.createData()
    pin.forwardKinematics(robot.model, data, q)
    pin.updateGeometryPlacements(robot.model, data, robot.visual_model, gdata)
    corners = []
    for geometry, placement in zip(
        robot.visual_model.geometryObjects, gdata.oMg, strict=True
    ):
        geometry.geometry.computeLocalAABB()
        box = geometry.geometry.aabb_local
        lo, hi = np.array(box.min_), np.array(box.max_)
        for corner in np.array(np.meshgrid(*zip(lo, hi, strict=True))).reshape(3, -1).T:
            corners.append(placement.act(corner))
    camera = viewer.get_camera()
    eye, target = np.array(camera.position), np.array(camera.target)
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    tan_half = np.tan(np.deg2rad(camera.fov_deg) / 2.0)
    d = np.array(corners) - eye
    depth = d @ forward
    x = (d @ right) / (depth * tan_half * WIDTH / HEIGHT)
    y = (d @ up) / (depth * tan_half)
    cols, rows = (x + 1.0) / 2.0 * WIDTH, (1.0 - y) / 2.0 * HEIGHT
    return (int(cols.min()), int(rows.min()), int(cols.max()) + 1, int(rows.max()) + 1)


def test_arm_is_drawn_where_the_camera_frames_it(chromium, puma, tmp_path) -> None:
    q = np.deg2rad(Q1_DEG)
    viewer = Viewer(puma, q, color_by_singularity=True)
    with_arm = screenshot(
        chromium, viewer.render_html(legend=False), tmp_path / "arm.png"
    )
    viewer.set_visible("robot", False)  # the same page without the robot
    empty = screenshot(
        chromium, viewer.render_html(legend=False), tmp_path / "empty.png"
    )

    left, top, right, bottom = arm_region(puma, q, viewer)
    # Sensible camera: the arm is whole on screen and fills a good part of it.
    assert 0 <= left < right <= WIDTH and 0 <= top < bottom <= HEIGHT
    assert (right - left) > 0.2 * WIDTH and (bottom - top) > 0.5 * HEIGHT

    diff = changed(with_arm, empty)
    inside = np.zeros_like(diff)
    inside[top:bottom, left:right] = True
    assert diff[inside].mean() > 0.1, "too few arm pixels where the arm stands"
    margin = np.zeros_like(diff)  # tolerate antialiasing just outside the box
    margin[max(top - 4, 0) : bottom + 4, max(left - 4, 0) : right + 4] = True
    assert diff[~margin].sum() <= 0.01 * diff.sum(), "pixels changed off the arm"


def test_two_configurations_give_two_images(chromium, puma, tmp_path) -> None:
    viewer = Viewer(puma, np.deg2rad(Q1_DEG))
    viewer.set_camera([1.8, 1.5, 0.8], [0.1, 0.0, -0.1])  # one camera for both
    first = screenshot(chromium, viewer.render_html(legend=False), tmp_path / "q1.png")
    viewer.display(np.deg2rad(Q2_DEG))
    second = screenshot(chromium, viewer.render_html(legend=False), tmp_path / "q2.png")
    assert changed(first, second).mean() > 0.01


def test_animation_scrubs_pose_and_singularity_colour(chromium, puma, tmp_path) -> None:
    t = np.linspace(0.0, 2.0, 61)  # [s]
    q = np.tile(np.deg2rad(Q1_DEG), (t.size, 1))
    q[:, 4] = np.deg2rad(45.0 - 45.0 * t)  # θ5 passes 0 (wrist singular) at 1 s
    viewer = Viewer(puma, color_by_singularity=True)
    viewer.play_trajectory(t, q)
    page = viewer.render_html(legend=False)
    start = screenshot(chromium, page, tmp_path / "t0.png", seek(0.0))
    middle = screenshot(chromium, page, tmp_path / "t1.png", seek(1.0))

    def red(image: np.ndarray) -> float:
        r, g, b = image[..., 0], image[..., 1], image[..., 2]
        return float(((r > 150) & (g < 70) & (b < 70)).mean())

    assert red(start) < 0.001  # far from singular: green links
    assert red(middle) > 0.01  # singular: red links
    assert changed(start, middle).mean() > 0.01


def test_title_and_legend_are_drawn_top_left(chromium, puma, tmp_path) -> None:
    t = np.linspace(0.0, 2.0, 61)  # [s]
    q = np.tile(np.deg2rad(Q1_DEG), (t.size, 1))
    q[:, 0] = np.linspace(0.0, 1.0, t.size)
    viewer = Viewer(puma, color_by_singularity=True, title="A titled page")
    viewer.show_frames()
    viewer.play_trajectory(t, q)
    pause = seek(0.0)
    bare = screenshot(
        chromium, viewer.render_html(legend=False), tmp_path / "a.png", pause
    )
    shown = screenshot(chromium, viewer.render_html(), tmp_path / "b.png", pause)
    rows, cols = np.nonzero(changed(bare, shown))
    assert rows.size > 0.02 * WIDTH * HEIGHT  # a box, not a few pixels
    assert cols.min() < 0.05 * WIDTH and rows.min() < 0.05 * HEIGHT  # top left
    assert cols.max() < 0.5 * WIDTH and rows.max() < 0.5 * HEIGHT
    box = shown[rows.min() : rows.max(), cols.min() : cols.max()]
    r, g, b = box[..., 0], box[..., 1], box[..., 2]
    assert ((r > 180) & (g < 80) & (b < 80)).sum() > 50  # red end of the ramp
    assert ((g > 150) & (r < 90) & (b < 110)).sum() > 50  # green end


def test_legend_starts_folded_in_a_small_view(chromium, puma, tmp_path) -> None:
    """Inlined in a notebook or the docs, the legend leaves the arm in view."""
    from workbench.viz._legend import SMALL_VIEW_PX

    width, height = SMALL_VIEW_PX[0] - 160, SMALL_VIEW_PX[1] - 60
    viewer = Viewer(puma, np.deg2rad(Q1_DEG), color_by_singularity=True)
    viewer.show_frames()

    def render(name: str, page: str, script: str | None = None) -> np.ndarray:
        html = (tmp_path / name).with_suffix(".html")
        html.write_text(page, encoding="utf-8")
        png = html.with_suffix(".png")
        take_screenshot(chromium, html, png, width=width, height=height, script=script)
        return np.asarray(Image.open(png).convert("RGB"), dtype=np.int16)

    bare = render("bare", viewer.render_html(legend=False))
    folded = render("folded", viewer.render_html())
    opened = render(
        "opened",
        viewer.render_html(),
        "document.querySelector('#workbench-legend summary').click(); true",
    )
    rows, _ = np.nonzero(changed(bare, folded))
    assert rows.size > 0  # the title is there
    assert rows.max() < 0.12 * height  # one line at the top
    assert changed(bare, folded).sum() < 0.05 * width * height
    assert changed(bare, opened).sum() > 2.0 * changed(bare, folded).sum()


def _boxed_arm(tmp_path: Path, mesh_of) -> Path:
    """A three-link arm (0.9 m tall at q = 0), each link drawn by ``mesh_of(i)``."""
    links, joints = [], []
    for i in (1, 2, 3):
        geometry = f'<geometry><mesh filename="{mesh_of(i)}"/></geometry>'
        links.append(
            f'<link name="l{i}"><visual><origin xyz="0 0 0.15"/>{geometry}</visual>'
            f'<collision><origin xyz="0 0 0.15"/>{geometry}</collision></link>'
        )
        parent, z = ("base", 0.0) if i == 1 else (f"l{i - 1}", 0.3)
        axis = "0 0 1" if i == 1 else "0 1 0"
        joints.append(
            f'<joint name="j{i}" type="revolute"><parent link="{parent}"/>'
            f'<child link="l{i}"/><origin xyz="0 0 {z}"/><axis xyz="{axis}"/>'
            '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        )
    urdf = tmp_path / "boxed.urdf"
    urdf.write_text(
        f'<robot name="boxed"><link name="base"/>{"".join(links)}{"".join(joints)}'
        "</robot>"
    )
    return urdf


def test_an_arm_whose_meshes_are_in_inches_is_framed_and_drawn(
    chromium, tmp_path
) -> None:
    from tests._meshes import write_dae

    # 4 × 4 × 11.8 inches (0.1 × 0.1 × 0.3 m) per link, in a Y-up file
    def mesh_of(i: int) -> Path:
        extent = (4.0, 11.811, 4.0)  # the file's y is up
        return write_dae(
            tmp_path / f"l{i}.dae", meter=0.0254, up_axis="Y_UP", extent=extent
        )

    robot = load_robot(_boxed_arm(tmp_path, mesh_of))
    q = np.array([0.3, 0.4, -0.8])
    viewer = Viewer(robot, q)
    camera = viewer.get_camera()
    distance = np.linalg.norm(np.subtract(camera.position, camera.target))
    assert distance < 5.0, "the camera is placed for the arm's real size (~1 m)"
    with_arm = screenshot(
        chromium, viewer.render_html(legend=False), tmp_path / "a.png"
    )
    viewer.set_visible("robot", False)
    empty = screenshot(chromium, viewer.render_html(legend=False), tmp_path / "e.png")
    left, top, right, bottom = arm_region(robot, q, viewer)
    assert 0 <= left < right <= WIDTH and 0 <= top < bottom <= HEIGHT
    assert (bottom - top) > 0.4 * HEIGHT
    diff = changed(with_arm, empty)
    inside = np.zeros_like(diff)
    inside[top:bottom, left:right] = True
    assert diff[inside].mean() > 0.2, "too few arm pixels where the arm stands"
    margin = np.zeros_like(diff)
    margin[max(top - 4, 0) : bottom + 4, max(left - 4, 0) : right + 4] = True
    assert diff[~margin].sum() <= 0.01 * diff.sum(), "the arm is drawn off its box"


def test_obj_meshes_with_texture_coordinates_in_part_are_drawn(
    chromium, tmp_path
) -> None:
    from tests._meshes import write_mixed_obj

    def mesh_of(i: int) -> Path:
        return write_mixed_obj(tmp_path / f"l{i}.obj", size=0.2)

    robot = load_robot(_boxed_arm(tmp_path, mesh_of))
    viewer = Viewer(robot, np.array([0.3, 0.4, -0.8]))
    with_arm = screenshot(
        chromium, viewer.render_html(legend=False), tmp_path / "a.png"
    )
    viewer.set_visible("robot", False)
    empty = screenshot(chromium, viewer.render_html(legend=False), tmp_path / "e.png")
    assert changed(with_arm, empty).mean() > 0.02, "the arm is drawn"


def test_stl_meshes_without_normals_are_shaded_in_colour(chromium, tmp_path) -> None:
    from tests._meshes import write_stl

    def mesh_of(i: int) -> Path:
        return write_stl(tmp_path / f"l{i}.stl", size=0.2, zero_normals=True)

    robot = load_robot(_boxed_arm(tmp_path, mesh_of))
    q = np.array([0.3, 0.4, -0.8])
    viewer = Viewer(robot, q, color_by_singularity=True)
    with_arm = screenshot(
        chromium, viewer.render_html(legend=False), tmp_path / "a.png"
    )
    viewer.set_visible("robot", False)
    empty = screenshot(chromium, viewer.render_html(legend=False), tmp_path / "e.png")
    arm = changed(with_arm, empty)
    assert arm.mean() > 0.02, "the arm is drawn"
    pixels = with_arm[arm]
    brightness = pixels.max(axis=1)
    assert np.median(brightness) > 80, "the arm is shaded, not black"
    chroma = pixels.max(axis=1) - pixels.min(axis=1)
    assert np.median(chroma) > 40, "the singularity colour shows"
