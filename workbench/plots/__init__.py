"""Matplotlib figures: joint trajectories, the arm in 3D, workspace maps, motions.

Each function draws into a given ``ax``/``fig`` or a new figure, returns the
``matplotlib.figure.Figure`` and writes a PNG only when given a path. The
trajectory figures (:mod:`.trajectory`) and the planned motions
(:mod:`.motion`) import matplotlib, so they are loaded on first use:
importing the package (or a report module) stays free of it.
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
    from workbench.plots.motion import plot_planned_around
    from workbench.plots.trajectory import (
        plot_cartesian,
        plot_joint_trajectory,
        plot_normal_spline,
        save_figure,
    )

#: Names loaded on first access, and their modules.
_LAZY = {
    "plot_cartesian": "trajectory",
    "plot_joint_trajectory": "trajectory",
    "plot_normal_spline": "trajectory",
    "plot_planned_around": "motion",
    "save_figure": "trajectory",
}

__all__ = [
    "VoxelField",
    "compute_arm_points",
    "plot_arm",
    "plot_cartesian",
    "plot_histograms",
    "plot_horizontal_slices",
    "plot_joint_trajectory",
    "plot_normal_spline",
    "plot_planned_around",
    "plot_vertical_sections",
    "save_figure",
    "set_equal_axes",
]


def __getattr__(name: str) -> Any:
    """The trajectory figures, imported (with matplotlib) when first asked for."""
    if name in _LAZY:
        module = importlib.import_module(f"workbench.plots.{_LAZY[name]}")
        return getattr(module, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
