"""Plot functions follow matplotlib's convention: optional ax/fig, Figure back,
a file only on request, nothing registered with pyplot."""

from __future__ import annotations

import re

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from workbench.plots.arm import TOOL_LABEL
from workbench.plots.trajectory import (
    NO_LIMIT,
    plot_cartesian,
    plot_joint_trajectory,
    plot_normal_spline,
)
from workbench.reports import _singularity_figures as figs
from workbench.singularities.along_path import find_closest_approaches
from workbench.singularities.conditions import compute_conditions
from workbench.singularities.directions import compute_degenerate_direction
from workbench.singularities.loci import compute_example_configurations
from workbench.singularities.measures import compute_joint_grid, compute_measures
from workbench.trajectory import compute_literal_spline, pick_and_place
from workbench.trajectory.cartesian import compute_cartesian_trajectory

Q_PICK = np.deg2rad([0.0, 45.0, 200.0, -100.0, 30.0, 10.0])
Q_PLACE = np.deg2rad([150.0, -100.0, -10.0, 100.0, -70.0, 170.0])


@pytest.fixture(scope="module")
def traj(puma):
    return pick_and_place(puma, Q_PICK, Q_PLACE, 10.0)


def _dashed_levels(ax) -> list[float]:
    return sorted(
        float(line.get_ydata()[0]) for line in ax.lines if line.get_linestyle() == "--"
    )


def test_joint_plot_one_row_per_joint_with_its_own_limits(puma, traj) -> None:
    fig = plot_joint_trajectory(traj, joints=(1, 4))
    assert isinstance(fig, Figure) and not plt.get_fignums()
    panels = [ax for ax in fig.axes if ax.lines]
    assert len(panels) == 2 * 3  # (joint 2, joint 5) × (q, q̇, q̈)
    for row, joint in enumerate((1, 4)):
        position, speed, _ = panels[3 * row : 3 * row + 3]
        np.testing.assert_allclose(
            _dashed_levels(position),
            np.rad2deg([puma.lower[joint], puma.upper[joint]]),
            rtol=0,
            atol=1e-9,
        )
        v = np.rad2deg(puma.velocity_limit[joint])
        np.testing.assert_allclose(_dashed_levels(speed), [-v, v], rtol=0, atol=1e-9)
        colours = {line.get_color() for line in position.lines}
        assert colours == {f"C{joint}"}  # curve and limits in the joint's colour
        t, q = position.lines[0].get_data()
        np.testing.assert_allclose(
            q, np.rad2deg(traj.sample(t)[0][:, joint]), rtol=0, atol=1e-9
        )


@pytest.mark.slow
def test_plots_draw_into_a_given_figure_and_save_on_request(traj, tmp_path) -> None:
    fig = plt.figure()
    assert plot_normal_spline(traj.spline, fig=fig) is fig
    assert len(fig.axes) >= 2
    assert plot_joint_trajectory(traj, tmp_path / "j.png", fig=fig) is fig
    assert Image.open(tmp_path / "j.png").size[0] > 500
    plt.close(fig)
    samples = compute_cartesian_trajectory(traj, np.linspace(0.0, 10.0, 51))
    assert len(plot_cartesian(samples).axes) == 4
    assert sorted(p.name for p in tmp_path.iterdir()) == ["j.png"]  # nothing else
    with pytest.raises(ValueError, match="unknown panel"):
        plot_cartesian(samples, which="nope")


def test_singularity_maps_take_an_axes(puma_kang, tmp_path) -> None:
    x = np.linspace(-np.pi / 2, np.pi / 2, 7)
    grid = compute_joint_grid(puma_kang, x, x, q_fixed=np.zeros(6))
    fig, (left, right) = plt.subplots(1, 2)
    overlay = {"shoulder": None, "elbow_theta3": None, "examples": {}}
    assert figs.plot_det_map(puma_kang, grid, ax=left, **overlay) is fig
    assert left.images and not right.images
    alone = figs.plot_det_map(puma_kang, grid, tmp_path / "det.png", **overlay)
    assert isinstance(alone, Figure)
    assert (tmp_path / "det.png").read_bytes().startswith(b"\x89PNG")
    assert figs.png_bytes(alone).startswith(b"\x89PNG")
    plt.close(fig)


# -- words: titles, axis labels with units, a legend entry for every mark ------


def _legend_texts(fig: Figure) -> list[str]:
    legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes)]
    return [t.get_text() for lg in legends if lg is not None for t in lg.get_texts()]


def test_no_limit_note_is_a_legend_clear_of_the_curve(traj) -> None:
    fig = plot_joint_trajectory(traj)
    FigureCanvasAgg(fig).draw()
    notes = [ax for ax in fig.axes if ax.get_legend() is not None]
    assert notes, "the PUMA has no acceleration limits: each panel says so"
    for ax in notes:
        legend = ax.get_legend()
        assert [t.get_text() for t in legend.get_texts()] == [NO_LIMIT]
        assert not ax.texts  # no free text laid over the data
        box = legend.get_window_extent()
        curve = ax.lines[0]
        points = ax.transData.transform(np.c_[curve.get_xdata(), curve.get_ydata()])
        inside = (
            (points[:, 0] >= box.x0)
            & (points[:, 0] <= box.x1)
            & (points[:, 1] >= box.y0)
            & (points[:, 1] <= box.y1)
        )
        assert not inside.any(), ax.get_ylabel()


def test_cartesian_and_spline_figures_name_units_and_marks(traj) -> None:
    samples = compute_cartesian_trajectory(traj, np.linspace(0.0, 10.0, 51))
    fig = plot_cartesian(samples)
    for ax in fig.axes:
        assert ax.get_title()
        assert re.search(r"\[.+\]", ax.get_ylabel()), ax.get_ylabel()
        assert ax.get_legend() is not None
    assert fig.axes[-1].get_xlabel() == "time t [s]"
    velocity = fig.axes[-1].get_ylabel()
    assert all(unit in velocity for unit in ("m/s", "rad/s", "m/s²", "rad/s²"))
    spline = plot_normal_spline(
        traj.spline,
        literal=compute_literal_spline(traj.spline.n_points, 5.0),
        literal_amplitude=5.0,
    )
    for ax in spline.axes:
        assert ax.get_title() or ax.get_ylabel()  # the twin axis has no title
        assert re.search(r"\[.+\]", ax.get_ylabel()), ax.get_ylabel()
    assert "t = 1, where s must be 1" in _legend_texts(spline)


def test_singularity_figures_name_every_mark(puma, traj) -> None:
    examples = compute_example_configurations(puma)
    x = np.linspace(-np.pi, np.pi, 9)
    det_grid = compute_joint_grid(puma, x, x, q_fixed=np.zeros(6))
    svd_grid = compute_joint_grid(puma, x, x, q_fixed=np.zeros(6), quantity="svd")
    overlay = {"shoulder": None, "elbow_theta3": None, "examples": examples}
    maps = (
        (figs.plot_det_map, det_grid, "[m³]"),
        (figs.plot_sigma_map, svd_grid, "m/rad and 1"),
    )
    for plot, grid, unit in maps:
        ax = plot(puma, grid, **overlay).axes[0]
        assert ax.get_xlabel() == "θ2 [deg]" and ax.get_ylabel() == "θ3 [deg]"
        assert ax.get_title().startswith("puma560: ")
        assert unit in ax.get_figure().axes[-1].get_ylabel()  # the colour bar
        texts = [t.get_text() for t in ax.get_legend().get_texts()]
        assert "joint limits" in texts
        assert "singular configuration (numbered)" in texts
    for measure, unit in (("manipulability", "[m³]"), ("condition_number", "m/rad")):
        colorbar = figs.plot_measure_map(puma, svd_grid, measure).axes[-1]
        assert unit in colorbar.get_ylabel(), measure
    directions = {
        name: compute_degenerate_direction(puma, q, name.split(",")[0])
        for name, q in examples.items()
    }
    arms = figs.plot_singular_arms(puma, examples, directions)
    assert arms.get_suptitle().startswith("puma560: ")
    texts = _legend_texts(arms)
    assert {"arm", "axis 1", "u (degenerate)", TOOL_LABEL} <= set(texts)
    assert len(texts) == len(set(texts))  # each mark named once
    for ax in arms.axes:
        assert [ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()] == [
            "x [m]",
            "y [m]",
            "z [m]",
        ]
    t = np.linspace(0.0, traj.duration, 101)
    q = traj.sample(t)[0]
    signals = compute_conditions(puma, q).as_dict()
    signals["sigma_min"] = compute_measures(puma, q).sigma_min
    along = figs.plot_distances_along_path(
        t, signals, find_closest_approaches(puma, t, q)
    )
    assert along.get_suptitle()
    assert _legend_texts(along) == [
        "signed distance",
        "zero: singular",
        "closest approach",
        "crossing",
    ]
    for ax in along.axes:
        assert re.search(r"\[.+\]", ax.get_ylabel()), ax.get_ylabel()
    assert along.axes[-1].get_xlabel() == "t [s]"
