"""The scene and the collision highlights in the viewer, in headless Chromium."""

from __future__ import annotations

import numpy as np

from tests.test_viz_browser import screenshot, seek
from workbench import paper_data
from workbench.collision import CollisionChecker, get_angeles_scene
from workbench.tasks import run_fish_cutting
from workbench.tasks.fish_scene import get_fish_cutting_scene
from workbench.trajectory import pick_and_place
from workbench.viz import Viewer, write_trajectory_html
from workbench.viz.collision_overlay import CLOSEST_RGB, CONTACT_RGB

# Pixel counts look at the scene only: the legend box has red and orange keys too.
NO_LEGEND = "document.getElementById('workbench-legend').remove();"
Q_PICK = np.deg2rad(paper_data.ANGELES_PICK_Q_DEG)
Q_PLACE = np.deg2rad(paper_data.ANGELES_PLACE_Q_DEG)


def red(image: np.ndarray) -> float:
    """Share of clearly red pixels (contact colour under Lambert shading)."""
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    return float(((r > 150) & (g < 60) & (b < 60)).mean())


def test_overlay_colours_follow_the_contacts(puma) -> None:
    checker = CollisionChecker(puma, get_angeles_scene(puma))
    viewer = Viewer(puma)
    viewer.show_collisions(checker)
    overlay = viewer._overlay
    colors, markers = overlay.compute_state(Q_PICK)
    pedestal = overlay.obstacle_nodes["pedestal"]
    assert colors[pedestal] == list(CONTACT_RGB)
    upper_arm = overlay.link_nodes["link2"]
    assert all(colors[node] == list(CONTACT_RGB) for node in upper_arm)
    assert all(
        colors[node] != list(CONTACT_RGB) for node in overlay.link_nodes["link4"]
    )
    colors, markers = overlay.compute_state(Q_PLACE)
    assert list(CONTACT_RGB) not in colors.values()
    assert list(CLOSEST_RGB) in colors.values()
    a, b = markers["closest/a"][:3, 3], markers["closest/b"][:3, 3]
    assert np.linalg.norm(a - b) > 0.0


def test_pick_pose_shows_the_contact_in_red(chromium, puma, tmp_path) -> None:
    checker = CollisionChecker(puma, get_angeles_scene(puma))
    viewer = Viewer(puma, Q_PICK)
    viewer.show_collisions(checker)
    viewer.set_camera([1.4, 1.2, 0.3], [0.0, 0.0, -0.3])
    contact = screenshot(
        chromium, viewer.render_html(legend=False), tmp_path / "pick.png"
    )
    viewer.display(Q_PLACE)
    free = screenshot(
        chromium, viewer.render_html(legend=False), tmp_path / "place.png"
    )
    assert red(contact) > 0.01  # the upper arm and the pedestal
    assert red(free) < 0.001


def test_animation_highlights_contacts_over_time(chromium, puma, tmp_path) -> None:
    traj = pick_and_place(puma, Q_PICK, Q_PLACE, paper_data.ANGELES_DURATION)
    samples = traj.sample_uniform(20.0)
    checker = CollisionChecker(puma, get_angeles_scene(puma))
    path = write_trajectory_html(puma, samples, tmp_path / "p.html", checker=checker)
    page = path.read_text(encoding="utf-8")
    start = screenshot(chromium, page, tmp_path / "t0.png", NO_LEGEND + seek(0.0))
    late = screenshot(chromium, page, tmp_path / "t8.png", NO_LEGEND + seek(8.0))
    assert red(start) > 0.002  # link2 in the pedestal at the pick
    assert red(late) < 0.0005  # clear near the place


def test_fishcut_page_shows_fish_and_table(chromium, puma_kang, tmp_path) -> None:
    result = run_fish_cutting(puma_kang)
    scene = get_fish_cutting_scene(puma_kang, result.fish, result.setup)
    checker = CollisionChecker(puma_kang, scene)
    servo = result.servo
    with_scene = write_trajectory_html(
        puma_kang, servo, tmp_path / "fish.html", checker=checker
    ).read_text(encoding="utf-8")
    assert "scene" in with_scene
    image = screenshot(
        chromium, with_scene, tmp_path / "fish.png", NO_LEGEND + seek(0.0)
    )
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    fish = (r > 170) & (g > 90) & (g < 170) & (b > 70) & (b < 150) & (r - b > 60)
    wood = (r > 90) & (r < 190) & (g > 60) & (g < 140) & (b < 90) & (r - b > 50)
    assert fish.mean() > 0.002 and wood.mean() > 0.005
