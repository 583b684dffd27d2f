"""Matplotlib figures: joint trajectories, the arm in 3D, workspace maps.

Each function draws into a given ``ax``/``fig`` or a new figure, returns the
``matplotlib.figure.Figure`` and writes a PNG only when given a path. The
trajectory figures (:mod:`.trajectory`) import matplotlib, so they are loaded
on first use: importing the package (or a report module) stays free of it.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from workbench.plots.arm import compute_arm_points, plot_arm, set_equal_axes
from workbench.plots.workspace import (
    VoxelField,
    plot_histograms,
    plot_horizontal_slices,
    plot_vertical_sections,
)

if TYPE_CHECKING:
    from workbench.plots.trajectory import (
        plot_cartesian,
        plot_joint_trajectory,
        plot_normal_spline,
        save_figure,
    )

#: Names loaded from :mod:`.trajectory` on first access.
_LAZY = ("plot_cartesian", "plot_joint_trajectory", "plot_normal_spline", "save_figure")

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


def __getattr__(name: str) -> Any:
    """The trajectory figures, imported (with matplotlib) when first asked for."""
    if name in _LAZY:
        return getattr(importlib.import_module("workbench.plots.trajectory"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
