"""Matplotlib figures: joint trajectories, the arm in 3D, workspace maps.

Each function draws into a given ``ax``/``fig`` or a new figure, returns the
``matplotlib.figure.Figure`` and writes a PNG only when given a path.
"""

from workbench.plots.arm import compute_arm_points, plot_arm, set_equal_axes
from workbench.plots.trajectory import (
    plot_cartesian,
    plot_joint_trajectory,
    plot_normal_spline,
    save_figure,
)
from workbench.plots.workspace import (
    VoxelField,
    plot_histograms,
    plot_horizontal_slices,
    plot_vertical_sections,
)

__all__ = [
    "VoxelField",
    "compute_arm_points",
    "plot_arm",
    "plot_cartesian",
    "plot_histograms",
    "plot_horizontal_slices",
    "plot_joint_trajectory",
    "plot_normal_spline",
    "plot_vertical_sections",
    "save_figure",
    "set_equal_axes",
]
