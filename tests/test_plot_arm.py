"""Stick figures: points through the DH frame origins, artists on 3D axes."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from workbench.plots.arm import compute_arm_points, plot_arm, set_equal_axes

ATOL_EXACT = 1e-12


def test_points_are_the_dh_frame_origins(any_puma, rng) -> None:
    q = rng.uniform(any_puma.lower, any_puma.upper)
    points = compute_arm_points(any_puma, q)
    frames = any_puma.dh_table.frame_transforms(q)[:, :3, 3]
    np.testing.assert_allclose(points, frames, rtol=0, atol=ATOL_EXACT)
    np.testing.assert_allclose(points[-1], any_puma.fk(q).translation, atol=ATOL_EXACT)


def test_plot_arm_draws_links_joints_tool_and_wrist_axis(puma) -> None:
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    q = np.array([0.1, -0.8, 2.0, 0.3, 0.6, 0.0])
    artists = plot_arm(ax, puma, q, color="k", label="arm")
    assert len(artists) == 4
    links, wrist = artists[0], artists[-1]
    x, y, z = links.get_data_3d()
    np.testing.assert_allclose(
        np.c_[x, y, z], compute_arm_points(puma, q), atol=ATOL_EXACT
    )
    start, end = np.array(wrist.get_data_3d()).T
    np.testing.assert_allclose(np.linalg.norm(end - start), 0.08, atol=ATOL_EXACT)
    assert len(plot_arm(ax, puma, q, axis_length=0.0)) == 3
    set_equal_axes(ax, compute_arm_points(puma, q))
    lo, hi = ax.get_xlim()
    assert np.isclose(hi - lo, ax.get_zlim()[1] - ax.get_zlim()[0])
    plt.close(fig)
