"""Workspace map pages: the Meshcat view, the HTML report, their figures and commands.

The maps are real ones (``build_map`` on a coarse PUMA grid). Figures and key
numbers are checked against the map's arrays selected independently (by voxel
position, per-pose arrays); both pages are rendered offline in headless
Chromium (``tests/_chromium.py``) and must load without a console error, with
the viridis colours of the voxels where they are drawn.
"""

from __future__ import annotations

import base64
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import zarr
from PIL import Image

from tests._chromium import take_screenshot
from tests.conftest import run_cli
from tests.test_viz_browser import changed
from workbench import load_robot
from workbench.collision import parse_scene
from workbench.errors import DimensionError, InputError
from workbench.plots.workspace import (
    EMPTY_LABEL,
    VoxelField,
    get_layer_coordinates,
    get_volume,
    plot_histograms,
    plot_horizontal_slices,
    plot_vertical_sections,
)
from workbench.reports.workspace_report import (
    build_workspace_report,
    choose_heights,
    compute_singular_distances,
    write_workspace_report,
)
from workbench.viz.workspace_view import make_workspace_viewer
from workbench.workspace import make_pose_grid
from workbench.workspace.build import build_map
from workbench.workspace.manifest import write_manifest
from workbench.workspace.store import get_array_names, open_map

RESOLUTION = 0.1  # [m], coarse: a map in about a second
ORIENTATIONS = 16
#: Positions are multiples of the resolution: exact to a few ulps.
ATOL_POSITION = 1e-12
WIDTH, HEIGHT = 900, 650
#: RGB distance [0..255] within which a pixel counts as a colour of the scale.
COLOR_TOL = 12


@pytest.fixture(scope="module")
def map_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished PUMA map, 10 cm voxels × 16 orientations."""
    robot = load_robot("puma560")
    grid = make_pose_grid(robot, resolution=RESOLUTION, orientations=ORIENTATIONS)
    path = tmp_path_factory.mktemp("maps") / "puma.zarr"
    build_map(robot, grid, path, workers=1)
    return path


@pytest.fixture(scope="module")
def puma_map(map_path: Path):
    return open_map(map_path)


@pytest.fixture(scope="module")
def empty_map_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A map of a box far out of the arm's reach: no voxel reached."""
    robot = load_robot("puma560")
    bounds = [[3.0, 3.0, 3.0], [3.3, 3.3, 3.3]]
    grid = make_pose_grid(robot, resolution=RESOLUTION, orientations=8, bounds=bounds)
    path = tmp_path_factory.mktemp("maps") / "far.zarr"
    build_map(robot, grid, path, workers=1)
    return path


def _layer_mask(puma_map, axis: int, coordinate: float) -> np.ndarray:
    """Voxels whose centre lies in the layer at ``coordinate`` (by position)."""
    positions = puma_map.grid.positions
    return np.abs(positions[:, axis] - coordinate) < 0.5 * RESOLUTION


def _field(puma_map, name: str = "reachability") -> VoxelField:
    return VoxelField(name, f"{name} [1]", puma_map[name].astype(float), 0.0, 1.0)


# -- figures -------------------------------------------------------------------


def test_volume_follows_the_grid_order(puma_map) -> None:
    grid = puma_map.grid
    layers = [get_layer_coordinates(grid, axis) for axis in range(3)]
    expected = np.meshgrid(*layers, indexing="ij")
    for axis in range(3):
        volume = get_volume(grid, grid.positions[:, axis])
        np.testing.assert_allclose(volume, expected[axis], rtol=0, atol=ATOL_POSITION)


def test_horizontal_slices_show_the_voxels_of_each_layer(puma_map) -> None:
    field = _field(puma_map)
    heights = [-0.3, 0.0, 0.41]  # the last one between layers: the nearest is drawn
    fig = plot_horizontal_slices(puma_map.grid, field, heights)
    images = [ax.images[0] for ax in fig.axes if ax.images]
    assert len(images) == len(heights)
    positions = puma_map.grid.positions
    for image, z in zip(images, heights, strict=True):
        z_layer = RESOLUTION * round(z / RESOLUTION)
        mask = _layer_mask(puma_map, 2, z_layer)
        data = np.ma.filled(image.get_array(), np.nan)  # rows y, columns x
        ix = np.rint((positions[mask, 0] - positions[:, 0].min()) / RESOLUTION)
        iy = np.rint((positions[mask, 1] - positions[:, 1].min()) / RESOLUTION)
        drawn = data[iy.astype(int), ix.astype(int)]
        np.testing.assert_array_equal(drawn, field.values[mask])
        assert image.axes.get_title() == f"z = {z_layer:+.3f} m"
        assert image.axes.get_xlabel() in ("x [m]", "")
    colorbar = fig.axes[-1]
    assert colorbar.get_ylabel() == "reachability [1]"


def test_vertical_section_is_the_plane_through_the_base_axis(puma_map) -> None:
    reach = _field(puma_map)
    best = puma_map["dexterity_best"].astype(float)
    dexterity = VoxelField("dexterity", "[m³]", best, 0.0, float(np.nanmax(best)))
    fig = plot_vertical_sections(puma_map.grid, [reach, dexterity])
    panels = [ax for ax in fig.axes if ax.images]
    assert [ax.get_xlabel() for ax in panels] == ["x [m]", "x [m]"]
    assert [ax.get_ylabel() for ax in panels] == ["z [m]", "z [m]"]
    mask = _layer_mask(puma_map, 1, 0.0)
    positions = puma_map.grid.positions
    ix = np.rint((positions[mask, 0] - positions[:, 0].min()) / RESOLUTION).astype(int)
    iz = np.rint((positions[mask, 2] - positions[:, 2].min()) / RESOLUTION).astype(int)
    for ax, field in zip(panels, (reach, dexterity), strict=True):
        data = np.ma.filled(ax.images[0].get_array(), np.nan)
        np.testing.assert_array_equal(data[iz, ix], field.values[mask])
    assert "y = +0.000 m" in fig.get_suptitle()


def test_histograms_count_the_voxels_with_a_value(puma_map) -> None:
    field = _field(puma_map, "near_singular_fraction")
    fig = plot_histograms([field], bins=10)
    heights = [patch.get_height() for patch in fig.axes[0].patches]
    assert sum(heights) == np.isfinite(field.values).sum()


def _legend_texts(fig) -> list[str]:
    return [t.get_text() for legend in fig.legends for t in legend.get_texts()]


def test_map_figures_have_a_title_and_a_legend_for_every_mark(puma_map) -> None:
    grid = puma_map.grid
    reach = _field(puma_map)
    values = np.where(reach.values > 0.0, reach.values, np.nan)  # grey: none
    reach = VoxelField(reach.name, reach.label, values, 0.0, 1.0)
    slices = plot_horizontal_slices(grid, reach, [-0.3, 0.0])
    assert slices.get_suptitle() == (
        "reachability: horizontal slices seen from above, base frame"
    )
    assert _legend_texts(slices) == ["base axis (x = y = 0)", EMPTY_LABEL]
    titled = plot_horizontal_slices(grid, reach, [0.0], title="puma560: reach")
    assert titled.get_suptitle() == "puma560: reach"
    sections = plot_vertical_sections(grid, [reach], title="puma560")
    assert sections.get_suptitle().startswith("puma560: section y = +0.000 m")
    assert _legend_texts(sections) == [
        "robot base (origin of the base frame)",
        "base axis (x = 0)",
        EMPTY_LABEL,
    ]
    full = VoxelField("one", "one [1]", np.ones(grid.voxel_count), 0.0, 2.0)
    assert EMPTY_LABEL not in _legend_texts(plot_vertical_sections(grid, [full]))
    histograms = plot_histograms([reach])
    assert histograms.get_suptitle()
    (ax,) = histograms.axes
    assert ax.get_xlabel() == reach.label and ax.get_ylabel().startswith("voxels")


def test_figure_input_errors(puma_map) -> None:
    grid = puma_map.grid
    with pytest.raises(InputError, match="at least one height"):
        plot_horizontal_slices(grid, _field(puma_map), [])
    with pytest.raises(DimensionError):
        plot_vertical_sections(grid, [VoxelField("bad", "", np.zeros(3), 0.0, 1.0)])
    with pytest.raises(InputError, match="vmax > vmin"):
        plot_vertical_sections(
            grid, [VoxelField("flat", "", np.zeros(grid.voxel_count), 1.0, 1.0)]
        )
    with pytest.raises(InputError, match="at least one field"):
        plot_histograms([])


# -- report --------------------------------------------------------------------


@pytest.mark.slow
def test_report_key_numbers_from_the_per_pose_arrays(puma_map) -> None:
    report = build_workspace_report(puma_map)
    summary = report.summary
    dexterity = puma_map["dexterity"]  # (V, O): NaN where no branch is usable
    usable = np.isfinite(dexterity)
    reached = usable.any(axis=1)
    every = usable.all(axis=1)
    volume = RESOLUTION**3
    assert summary["reachable_voxels"] == reached.sum() > 0
    assert summary["reachable_volume_m3"] == pytest.approx(
        reached.sum() * volume, rel=1e-12
    )
    assert summary["dexterous_voxels"] == every.sum() > 0
    assert summary["dexterous_fraction"] == pytest.approx(
        every.sum() / reached.sum(), rel=1e-12
    )
    assert summary["reached_pose_fraction"] == pytest.approx(usable.mean(), rel=1e-6)
    assert summary["dexterity_best_max"] == pytest.approx(
        np.nanmax(dexterity), rel=1e-7
    )
    distance = np.linalg.norm(puma_map.grid.positions[reached], axis=1).max()
    assert summary["max_reach_m"] == pytest.approx(distance, rel=1e-12)
    assert summary["poses"] == puma_map.grid.voxel_count * ORIENTATIONS
    assert summary["covering_radius_deg"] == pytest.approx(
        np.degrees(puma_map.attrs["orientation_set"]["covering_radius"]), rel=1e-12
    )
    assert summary["figures"] == list(report.figures)
    assert set(report.figures) == {
        "reachability_slices",
        "dexterity_slices",
        "sections",
        "histograms",
        "singular_regions",
        "singular_slices",
    }
    json.dumps(summary)  # JSON-ready


def test_singular_distances_per_voxel(puma_map) -> None:
    tolerances = puma_map.attrs["tolerances"]
    medians, fractions = compute_singular_distances(puma_map, tolerances)
    shoulder = puma_map["shoulder"]
    for v in np.flatnonzero(np.isfinite(shoulder).any(axis=1))[::97]:
        values = shoulder[v][np.isfinite(shoulder[v])]
        assert medians["shoulder"][v] == np.median(values.astype(float))
        near = np.count_nonzero(values < tolerances["shoulder"]) / values.size
        assert fractions["shoulder"][v] == near
    unreached = ~np.isfinite(shoulder).any(axis=1)
    assert np.isnan(medians["elbow"][unreached]).all()
    assert np.isnan(fractions["wrist"][unreached]).all()


def test_slice_heights_spread_over_the_reached_layers(puma_map) -> None:
    heights = choose_heights(puma_map.grid, puma_map["reachability"], 4)
    z = puma_map.grid.positions[puma_map["reachability"] > 0, 2]
    assert len(heights) == 4 and heights == sorted(heights)
    assert z.min() < heights[0] and heights[-1] < z.max()
    for h in heights:
        assert np.min(np.abs(z - h)) < ATOL_POSITION  # a reached layer


@pytest.mark.slow
def test_report_page_is_self_contained(puma_map, tmp_path) -> None:
    report = write_workspace_report(puma_map, tmp_path / "report.html")
    page = (tmp_path / "report.html").read_text(encoding="utf-8")
    assert page == report.html
    assert not re.search(r"""(src|href)=["'](?!data:)""", page)  # nothing to fetch
    images = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    assert len(images) == len(report.figures)
    for data in images:
        assert base64.b64decode(data)[:8] == b"\x89PNG\r\n\x1a\n"
    for text in ("Key numbers", "reachable volume", "covering radius", "m³"):
        assert text in page


@pytest.mark.slow
def test_report_of_a_map_that_reaches_nothing(empty_map_path) -> None:
    report = build_workspace_report(open_map(empty_map_path))
    assert report.summary["reachable_voxels"] == 0
    assert report.summary["reachable_volume_m3"] == 0.0
    assert report.summary["dexterity_best_max"] is None
    assert "Key numbers" in report.html


# -- view ----------------------------------------------------------------------


def _slider_data(page: str) -> dict:
    return json.loads(re.search(r'\}\)\((\{"layers".*?\})\);', page).group(1))


def test_view_has_one_node_per_reached_layer(puma_map) -> None:
    viewer = make_workspace_viewer(puma_map)
    page = viewer.render_html()
    data = _slider_data(page)
    reached = puma_map["reachability"] > 0
    z = np.unique(np.round(puma_map.grid.positions[reached, 2], 9))
    np.testing.assert_allclose(data["heights"], z, rtol=0, atol=ATOL_POSITION)
    assert data["layers"] == [f"z{h:+.3f}" for h in z]
    assert 'id="wb-slice-cut" type="checkbox" checked' in page
    assert "fraction of the orientations reached [1]" in page


def test_view_dexterity_scale_ends_on_a_round_tick(puma_map) -> None:
    page = make_workspace_viewer(
        puma_map, measure="dexterity", cut_away=False
    ).render_html()
    ticks = re.findall(r'<span style="left: ([0-9.]+)%">([^<]+)</span>', page)
    assert ticks[0] == ("0", "0") and ticks[-1][0] == "100"
    top = float(ticks[-1][1])
    assert np.nanmax(puma_map["dexterity_best"]) <= top
    assert "[m³]" in page
    assert 'id="wb-slice-cut" type="checkbox">' in page


def test_view_input_errors(puma_map, map_path, tmp_path) -> None:
    with pytest.raises(InputError, match="unknown measure 'volume'"):
        make_workspace_viewer(puma_map, measure="volume")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="not the URDF the map was built from"):
        make_workspace_viewer(puma_map, robot=load_robot("ur5"))
    renamed = tmp_path / "renamed.zarr"
    shutil.copytree(map_path, renamed)
    meta = json.loads((renamed / "zarr.json").read_text())
    meta["attributes"]["robot"] = "my-arm"
    (renamed / "zarr.json").write_text(json.dumps(meta))
    with pytest.raises(InputError, match="attribute 'robot' was changed after"):
        open_map(renamed)  # an edit: the manifest's digest differs
    group = zarr.open_group(renamed, mode="r+")  # a map made so elsewhere
    write_manifest(group, get_array_names(group))
    with pytest.raises(InputError, match="'my-arm' is no catalog name"):
        make_workspace_viewer(open_map(renamed))
    page = make_workspace_viewer(open_map(renamed), robot=load_robot("puma560"))
    assert page.robot.name == "puma560"


def test_view_of_a_map_that_reaches_nothing(empty_map_path) -> None:
    page = make_workspace_viewer(open_map(empty_map_path)).render_html()
    assert "No voxel is reached" in page


@pytest.mark.slow
def test_view_draws_the_scene_of_a_map_built_with_one(tmp_path) -> None:
    robot = load_robot("puma560")
    table = {"name": "table", "shape": "box", "size": [0.6, 0.8, 0.05]}
    scene = parse_scene({"objects": [table | {"position": [0.6, 0.0, -0.45]}]})
    bounds = [[0.3, -0.2, -0.6], [0.7, 0.2, -0.2]]
    grid = make_pose_grid(robot, resolution=RESOLUTION, orientations=8, bounds=bounds)
    build_map(robot, grid, tmp_path / "cell.zarr", workers=1, scene=scene)
    cell_map = open_map(tmp_path / "cell.zarr")
    page = make_workspace_viewer(cell_map).render_html()
    assert "<b>Collisions</b> with the scene (table)" in page
    assert "Key numbers" in build_workspace_report(cell_map).html


@pytest.mark.slow
def test_sampled_map_report_and_view(tmp_path) -> None:
    """A 7-axis arm: a sampled map, manipulability only (no singularity factors)."""
    robot = load_robot("panda")
    grid = make_pose_grid(robot, resolution=0.2, orientations=8)
    build_map(robot, grid, tmp_path / "panda.zarr", workers=1, samples=20_000)
    panda_map = open_map(tmp_path / "panda.zarr")
    report = build_workspace_report(panda_map)
    assert report.summary["sampled"] and report.summary["samples"] == 20_000
    assert report.summary["near_singular_by_kind"] == {}
    assert "singular_regions" not in report.figures
    assert "This map holds no singularity\nmeasures" in report.html
    assert "A <b>sampled</b> map: 20000 random configurations" in report.html
    reach = panda_map["reachability"]
    assert report.summary["reachable_voxels"] == np.count_nonzero(reach > 0) > 0
    page = make_workspace_viewer(panda_map, measure="dexterity").render_html()
    assert len(_slider_data(page)["layers"]) > 1


# -- pages in Chromium -----------------------------------------------------------


def _viridis_index(image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per pixel: whether it is a viridis colour, and its place on the scale."""
    from matplotlib import colormaps

    table = np.round(255 * colormaps["viridis"](np.linspace(0, 1, 256))[:, :3])
    flat = image.reshape(-1, 1, 3)
    found = np.zeros(flat.shape[0], dtype=bool)
    index = np.zeros(flat.shape[0])
    for start in range(0, flat.shape[0], 20000):  # bounded memory
        d = np.abs(flat[start : start + 20000] - table[None]).max(axis=2)
        found[start : start + 20000] = d.min(axis=1) <= COLOR_TOL
        index[start : start + 20000] = d.argmin(axis=1) / 255.0
    return found.reshape(image.shape[:2]), index.reshape(image.shape[:2])


def _render(chromium_path: str, page: str, png: Path, script: str | None = None):
    html = png.with_suffix(".html")
    html.write_text(page, encoding="utf-8")
    errors = take_screenshot(
        chromium_path, html, png, width=WIDTH, height=HEIGHT, script=script
    )
    assert errors == [], errors
    return np.asarray(Image.open(png).convert("RGB"), dtype=np.int16)


SLICE_ONLY = (
    "var s = document.getElementById('wb-slice'); s.value = {k};"
    "document.getElementById('wb-slice-only').click(); true"
)


def test_view_page_draws_viridis_voxels_and_slices(
    chromium, puma_map, tmp_path
) -> None:
    viewer = make_workspace_viewer(puma_map)
    page = viewer.render_html(legend=False)
    full = _render(chromium, page, tmp_path / "full.png")
    viewer.set_visible("voxels", False)
    bare = _render(chromium, viewer.render_html(legend=False), tmp_path / "bare.png")
    voxels = changed(full, bare)
    assert voxels.mean() > 0.05, "too few voxel pixels"
    is_viridis, index = _viridis_index(full)
    assert is_viridis[voxels].mean() > 0.9
    # PUMA: most reached voxels are reached in most orientations (yellow-green).
    reach = puma_map["reachability"]
    assert np.median(reach[reach > 0]) > 0.5
    assert np.median(index[voxels & is_viridis]) > 0.5

    with_legend = make_workspace_viewer(puma_map).render_html()
    middle = len(_slider_data(with_legend)["layers"]) // 2
    one = _render(
        chromium, with_legend, tmp_path / "one.png", SLICE_ONLY.format(k=middle)
    )
    legend_free = np.zeros_like(voxels)
    legend_free[:, WIDTH // 2 :] = True  # the legend box sits at the top left
    one_layer = changed(one, bare) & legend_free
    assert 0 < one_layer.sum() < 0.5 * (voxels & legend_free).sum()


def test_view_page_dexterity_loads_cleanly(chromium, puma_map, tmp_path) -> None:
    page = make_workspace_viewer(puma_map, measure="dexterity").render_html()
    image = _render(chromium, page, tmp_path / "dexterity.png")
    is_viridis, _ = _viridis_index(image)
    assert is_viridis.mean() > 0.03


def test_report_page_loads_every_figure(chromium, puma_map, tmp_path) -> None:
    page = build_workspace_report(puma_map).html
    loaded = (
        "Promise.all([...document.images].map(i => i.decode())).then(() => {"
        " if ([...document.images].some(i => i.naturalWidth === 0))"
        " throw new Error('an image did not load'); return true; })"
    )
    image = _render(chromium, page, tmp_path / "report.png", loaded)
    assert (np.abs(image - 255).max(axis=2) > 40).mean() > 0.05  # not blank


# -- command line ----------------------------------------------------------------


def _workspace(capsys, command: str, map_path: Path, *options: object):
    """``workbench workspace COMMAND MAP OPTIONS...`` in-process: (code, out, err)."""
    return run_cli(capsys, "workspace", command, str(map_path), *map(str, options))


@pytest.mark.slow
def test_cli_view_and_report(capsys, map_path, tmp_path) -> None:
    html = tmp_path / "view.html"
    code, out, err = _workspace(
        capsys, "view", map_path, "--html", html, "--measure", "dexterity"
    )
    assert (code, err) == (0, "")
    assert out.startswith(f"wrote {html}") and html.stat().st_size > 100_000
    assert "Voxel colour: dexterity" in html.read_text(encoding="utf-8")

    report = tmp_path / "report.html"
    code, out, err = _workspace(capsys, "report", map_path, "--out", report, "--json")
    assert (code, err) == (0, "")
    summary = json.loads(out)
    assert summary["out"] == str(report)
    assert summary["reachable_voxels"] > 0 and report.is_file()


@pytest.mark.slow
def test_cli_report_heights(capsys, map_path, tmp_path) -> None:
    code, out, _ = _workspace(
        capsys, "report", map_path, "--out", tmp_path / "r.html",
        "--heights", "0.2", "-0.13", "--json",
    )  # fmt: skip
    assert code == 0
    assert json.loads(out)["slice_heights_m"] == [0.2, -0.1]  # their voxel layers


@pytest.mark.parametrize("command", ["view", "report"])
def test_cli_bad_map_path(capsys, map_path, tmp_path, command) -> None:
    flag, out_file = ("--html" if command == "view" else "--out"), tmp_path / "x.html"
    not_a_map = tmp_path / "folder.zarr"
    not_a_map.mkdir()
    unfinished = tmp_path / "unfinished.zarr"
    shutil.copytree(map_path, unfinished)
    zarr.open_group(unfinished, mode="r+")["done"][0] = 0
    for path, message in (
        (tmp_path / "missing.zarr", "no workspace map"),
        (not_a_map, "is not a workspace map"),
        (unfinished, "is a damaged workspace map (done flags lost: 1 of"),
    ):
        code, out, err = _workspace(capsys, command, path, flag, out_file)
        assert (code, out) == (2, "")
        assert err.count("\n") == 1 and message in err, err
    assert not out_file.exists()


def test_cli_bad_output_measure_and_robot(capsys, map_path, tmp_path) -> None:
    code, _, err = _workspace(
        capsys, "view", map_path, "--html", tmp_path / "no" / "such" / "v.html"
    )
    assert code == 2 and "does not exist" in err
    code, _, err = _workspace(
        capsys, "view", map_path, "--html", tmp_path / "v.html", "--measure", "volume"
    )
    assert code == 2 and "invalid choice" in err
    code, _, err = _workspace(
        capsys, "view", map_path, "--html", tmp_path / "v.html", "--robot", "ur5"
    )
    assert code == 2 and "not the URDF the map was built from" in err
    assert not (tmp_path / "v.html").exists()


def test_cli_report_refuses_a_height_outside_the_map(capsys, map_path, tmp_path):
    out_file = tmp_path / "r.html"
    code, out, err = _workspace(
        capsys, "report", map_path, "--out", out_file, "--heights", "0.2", "1e300"
    )
    assert (code, out) == (2, "") and err.count("\n") == 1
    assert "slice height 1e+300 m is outside the map's z range" in err
    assert not out_file.exists()
