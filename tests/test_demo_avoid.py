"""The demo's obstacle on Table III's path, planned around: files, numbers, page."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from tests.test_viz_browser import screenshot, seek
from tests.test_viz_collision import NO_LEGEND
from workbench import paper_data
from workbench.collision import CollisionChecker, get_angeles_obstacle_scene
from workbench.demo import format_avoid, run_avoid_demo
from workbench.demo.avoid import ACCELERATION_LIMIT, FILES
from workbench.demo.run import round_for_json
from workbench.motion import time_scale, verify_trajectory
from workbench.trajectory import check_limits
from workbench.trajectory.csv_io import read_trajectory_csv

#: The CSV's positions against the trajectory they sample [rad].
ATOL_CSV = 1e-9
#: Share of the screenshot's pixels that must show the (red) cube.
MIN_CUBE_SHARE = 0.001
#: Largest growth of the red pixels from t = 0 (free) to halfway: no contact.
MAX_RED_GROWTH = 1.5
#: Share of pixels that must change between two instants of the animation.
MIN_MOVED_SHARE = 0.01


@pytest.fixture(scope="module")
def quick(tmp_path_factory: pytest.TempPathFactory, puma) -> tuple[dict, Path]:
    out = tmp_path_factory.mktemp("avoid_quick")
    return run_avoid_demo(puma, out, plots=False), out


def test_without_plots_writes_the_csv_only(quick, puma) -> None:
    summary, out = quick
    assert sorted(p.name for p in out.iterdir()) == ["avoid.csv", "avoid.csv.json"]
    assert summary["csv"] == str(out / FILES["csv"])
    assert "figure" not in summary and "html" not in summary
    assert summary["needed"] and summary["solved"]
    json.dumps(round_for_json(summary))  # JSON-ready


def test_the_spline_collides_and_the_plan_does_not(quick, puma) -> None:
    summary, out = quick
    assert summary["scene"] == "angeles-obstacle"
    # The tool passes through the cube's centre: deeper than half its edge.
    assert summary["obstacle_penetration"] > 0.5 * summary["obstacle"]["size"][0]
    assert summary["direct_penetration"] >= summary["obstacle_penetration"]
    assert {c["body_b"] for c in summary["direct_contacts"]} >= {"obstacle"}
    waypoints = np.array(summary["waypoints"])
    np.testing.assert_array_equal(
        waypoints[[0, -1]],
        np.radians([paper_data.ANGELES_PICK_Q_DEG, paper_data.ANGELES_PLACE_Q_DEG]),
    )
    # The CSV is the time-scaled polyline of the waypoints, within the limits.
    limited = puma.with_limits(acceleration_limit=ACCELERATION_LIMIT)
    motion = time_scale(limited, waypoints)
    assert check_limits(motion) == []
    samples = read_trajectory_csv(out / FILES["csv"], puma.nq)
    np.testing.assert_allclose(
        samples.q, motion.sample(samples.t)[0], rtol=0, atol=ATOL_CSV
    )
    assert samples.t[-1] == pytest.approx(summary["duration"], abs=1e-12)
    report = verify_trajectory(
        CollisionChecker(limited, get_angeles_obstacle_scene(limited)), motion
    )
    assert report.collision_free
    assert report.min_clearance == pytest.approx(summary["min_clearance"], abs=0.0)


def test_summary_text_names_the_numbers(quick) -> None:
    text = format_avoid(quick[0])
    assert "10 cm cube" in text and "planned around (seed 0" in text
    assert f"{len(quick[0]['waypoints'])} waypoints" in text


@pytest.mark.slow
def test_figure_and_page_are_written_and_drawn(chromium, puma, tmp_path) -> None:
    summary = run_avoid_demo(puma, tmp_path, plots=True)
    figure, page = Path(summary["figure"]), Path(summary["html"])
    assert figure.name == FILES["figure"] and page.name == FILES["html"]
    rgb = np.asarray(Image.open(figure).convert("RGB"), dtype=np.int16)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    planned = (b > 150) & (r < 80) & (g > 90) & (g < 150)  # tab:blue
    direct = (r > 230) & (g > 110) & (g < 160) & (b < 60)  # tab:orange
    assert planned.mean() > 0.002 and direct.mean() > 0.002
    html = page.read_text(encoding="utf-8")
    assert "obstacle" in html and "Table III" in html
    start = screenshot(chromium, html, tmp_path / "t0.png", NO_LEGEND + seek(0.0))
    middle = screenshot(
        chromium,
        html,
        tmp_path / "half.png",
        NO_LEGEND + seek(0.5 * summary["duration"]),
    )
    red = [_red_share(image) for image in (start, middle)]
    # The cube is drawn; halfway no link turns red (the colour of a contact):
    # the red pixels are the cube's and the closest-point markers' only.
    assert red[0] > MIN_CUBE_SHARE
    assert red[1] < MAX_RED_GROWTH * red[0]
    moved = np.abs(start - middle).max(axis=2) > 40
    assert moved.mean() > MIN_MOVED_SHARE


def _red_share(image: np.ndarray) -> float:
    """Share of red pixels: the cube's colour, and a contact's, under shading."""
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    return float(((r > 150) & (g < 80) & (b < 80)).mean())
