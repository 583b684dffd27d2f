"""Stick figures: points through the DH frame origins, matplotlib's conventions."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from PIL import Image

from workbench.plots.arm import TOOL_LABEL, compute_arm_points, plot_arm, set_equal_axes

ATOL_EXACT = 1e-12
Q = np.array([0.1, -0.8, 2.0, 0.3, 0.6, 0.0])


def test_points_are_the_dh_frame_origins(any_puma, rng) -> None:
    q = rng.uniform(any_puma.lower, any_puma.upper)
    points = compute_arm_points(any_puma, q)
    frames = any_puma.dh_table.frame_transforms(q)[:, :3, 3]
    np.testing.assert_allclose(points, frames, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(points[-1], any_puma.fk(q).translation, atol=ATOL_EXACT)


def test_plot_arm_on_given_axes_draws_links_joints_tool_and_wrist_axis(puma) -> None:
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    assert plot_arm(puma, Q, ax=ax, color="k", label="arm") is fig
    assert len(ax.lines) == 4
    links, wrist = ax.lines[0], ax.lines[-1]
    assert links.get_label() == "arm"
    x, y, z = links.get_data_3d()
    np.testing.assert_allclose(
        np.c_[x, y, z], compute_arm_points(puma, Q), atol=ATOL_EXACT
    )
    start, end = np.array(wrist.get_data_3d()).T
    np.testing.assert_allclose(np.linalg.norm(end - start), 0.08, atol=ATOL_EXACT)
    assert [line.get_label() for line in ax.lines[2:]] == [
        TOOL_LABEL,
        "x axis of frame4",
    ]
    plot_arm(puma, Q, ax=ax, axis_length=0.0)
    assert len(ax.lines) == 4 + 3
    plot_arm(puma, Q, ax=ax)
    _, labels = ax.get_legend_handles_labels()
    assert labels == ["arm", TOOL_LABEL, "x axis of frame4"]  # each named once
    set_equal_axes(ax, compute_arm_points(puma, Q))
    lo, hi = ax.get_xlim()
    assert np.isclose(hi - lo, ax.get_zlim()[1] - ax.get_zlim()[0])
    plt.close(fig)


def test_plot_arm_without_axes_makes_a_figure_and_saves_on_request(
    puma, tmp_path
) -> None:
    fig = plot_arm(puma, Q)
    assert isinstance(fig, Figure) and len(fig.axes) == 1
    assert not plt.get_fignums()  # not registered with pyplot
    ax = fig.axes[0]
    assert ax.get_title() == "puma560, base frame"
    assert [ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()] == [
        "x [m]",
        "y [m]",
        "z [m]",
    ]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend == [TOOL_LABEL, "x axis of frame4"]
    ranges = [np.ptp(lim) for lim in (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())]
    np.testing.assert_allclose(ranges, ranges[0], rtol=1e-12)  # equal axes
    path = tmp_path / "sub" / "arm.png"
    assert plot_arm(puma, Q, path) is not None
    assert Image.open(path).size[0] > 100
