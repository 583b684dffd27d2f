"""Plot functions follow matplotlib's convention: optional ax/fig, Figure back,
a file only on request, nothing registered with pyplot."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.figure import Figure
from PIL import Image

from workbench.plots.trajectory import (
    plot_cartesian,
    plot_joint_trajectory,
    plot_normal_spline,
)
from workbench.reports import _singularity_figures as figs
from workbench.singularities.measures import compute_joint_grid
from workbench.trajectory import pick_and_place
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
