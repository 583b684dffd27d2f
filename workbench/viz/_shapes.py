"""Meshcat objects drawn by the viewer besides the robot: triads and lines."""

from __future__ import annotations

import itertools

import meshcat
import meshcat.geometry as mg
import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

AXIS_COLORS = (0xE02020, 0x20A020, 0x2040E0)  # x red, y green, z blue


def _rgb_int(rgb: npt.ArrayLike) -> int:
    r, g, b = (
        round(255 * float(np.clip(c, 0.0, 1.0)))
        for c in np.asarray(rgb, dtype=np.float64)
    )
    return (r << 16) + (g << 8) + b


def draw_triad(node: meshcat.Visualizer, scale: float, opacity: float = 1.0) -> None:
    """Three cylinders along x (red), y (green), z (blue), ``scale`` long [m].

    Cylinders rather than lines: WebGL draws lines one pixel wide.
    """
    radius = scale / 18.0
    # meshcat cylinders lie along their y axis; turn y onto x, keep y, turn y onto z.
    turns = (
        np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1]], dtype=float),
        np.eye(3),
        np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], dtype=float),
    )
    for axis, (name, color, turn) in enumerate(
        zip("xyz", AXIS_COLORS, turns, strict=True)
    ):
        placement = np.eye(4)
        placement[:3, :3] = turn
        placement[axis, 3] = scale / 2.0
        material = mg.MeshLambertMaterial(color=color, opacity=opacity)
        node[name].set_object(mg.Cylinder(scale, radius), material)
        node[name].set_transform(placement)
    node["origin"].set_object(
        mg.Sphere(1.6 * radius), mg.MeshLambertMaterial(color=0x303030, opacity=opacity)
    )


def draw_polyline(
    node: meshcat.Visualizer, points: npt.ArrayLike, rgb: npt.ArrayLike
) -> None:
    """A line through ``points``, shape (K, 3) [m], colour RGB in [0, 1]."""
    vertices = np.asarray(points, dtype=np.float32).T
    node.set_object(
        mg.Line(mg.PointsGeometry(vertices), mg.LineBasicMaterial(color=_rgb_int(rgb)))
    )


def draw_marker(node: meshcat.Visualizer, radius: float, rgb: npt.ArrayLike) -> None:
    """A small sphere (path start and end markers)."""
    node.set_object(mg.Sphere(radius), mg.MeshLambertMaterial(color=_rgb_int(rgb)))


def draw_points(
    node: meshcat.Visualizer, points: npt.ArrayLike, rgb: npt.ArrayLike, size: float
) -> None:
    """Unlit square points at ``points`` (N, 3) [m], colours ``rgb`` (N, 3) in 0..1."""
    vertices = np.asarray(points, dtype=np.float32).T
    colors = np.clip(np.asarray(rgb, dtype=np.float32), 0.0, 1.0).T
    node.set_object(
        mg.Points(mg.PointsGeometry(vertices, colors), mg.PointsMaterial(size=size))
    )


def draw_floor_grid(
    node: meshcat.Visualizer, half_extent: float, step: float, z: float
) -> None:
    """Square grid in the plane ``z`` [m], ``step`` apart, centred on the z axis.

    Each line is cut into short segments: software WebGL (headless browsers)
    drops a whole line segment that crosses the camera plane.
    """
    count = round(half_extent / step)
    ticks = np.arange(-count, count + 1) * step
    cuts = np.linspace(-count * step, count * step, 2 * count + 1)
    pieces = []
    for tick in ticks:
        for a, b in itertools.pairwise(cuts):
            pieces += [[a, tick, z], [b, tick, z], [tick, a, z], [tick, b, z]]
    vertices = np.asarray(pieces, dtype=np.float32).T
    node.set_object(
        mg.LineSegments(
            mg.PointsGeometry(vertices),
            mg.LineBasicMaterial(color=0xB8C4D0, transparent=True, opacity=0.7),
        )
    )
