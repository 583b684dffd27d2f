"""The page's initial camera: where it stands and what it looks at."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

#: Direction from the scene's centre to the camera: front right, above.
VIEW_DIRECTION = np.array([1.0, 0.85, 0.6]) / np.linalg.norm([1.0, 0.85, 0.6])


@dataclass(frozen=True, slots=True)
class CameraView:
    """Initial camera of a page, in the base frame.

    Attributes:
        position: Camera position, shape (3,) [m].
        target: Point looked at and orbited around, shape (3,) [m].
        fov_deg: Vertical field of view [deg].
    """

    position: tuple[float, ...]
    target: tuple[float, ...]
    fov_deg: float = 45.0


def frame_points(points: npt.ArrayLike, *, fov_deg: float = 45.0) -> CameraView:
    """A camera on :data:`VIEW_DIRECTION` that sees every point, z up.

    Args:
        points: Shape (N, 3) [m], base frame.
        fov_deg: Vertical field of view [deg].

    Returns:
        The camera looks at the centre of the points' bounding box from just
        far enough for the box's circumscribed sphere to fit the view height.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    center = 0.5 * (lo + hi)
    radius = max(0.5 * float(np.linalg.norm(hi - lo)), 0.05)
    distance = 1.05 * radius / np.sin(np.deg2rad(fov_deg / 2.0))
    position = center + distance * VIEW_DIRECTION
    return CameraView(tuple(position.tolist()), tuple(center.tolist()), fov_deg)
