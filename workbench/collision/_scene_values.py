"""The values of scene files, checked: numbers, unit quaternions, inline meshes.

Shared by the JSON scenes (:mod:`workbench.collision.scene_file`) and the
MoveIt planning scenes (:mod:`workbench.collision.moveit_scene`): one check
and one message for each kind of value.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import SceneFileError

FloatArray = npt.NDArray[np.float64]

#: Tolerance on the norm of a scene quaternion.
QUATERNION_NORM_TOL = 1e-6


def numbers(value: Any, size: int, where: str, *, positive: bool = False) -> FloatArray:
    """``value`` as (size,) float64: a list of finite JSON numbers (no bools).

    Raises:
        SceneFileError: ``WHERE must be a list of N numbers``, ``... must be
            finite`` or (``positive``) ``... must be > 0``.
    """
    ok = isinstance(value, list) and len(value) == size
    if not ok or any(
        isinstance(v, bool) or not isinstance(v, int | float) for v in value
    ):
        raise SceneFileError(f"{where} must be a list of {size} numbers, got {value!r}")
    arr = np.array(value, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        raise SceneFileError(f"{where} must be finite, got {value!r}")
    if positive and np.any(arr <= 0.0):
        raise SceneFileError(f"{where} must be > 0, got {value!r}")
    return arr


def floats(values: FloatArray) -> tuple[float, ...]:
    """``values`` as a tuple of Python floats (an obstacle's size)."""
    return tuple(float(v) for v in values)


def rotation_from_quat_xyzw(quat: FloatArray, where: str) -> FloatArray:
    """The rotation matrix (3, 3) of a quaternion x y z w of norm 1 (±tolerance).

    Raises:
        SceneFileError: ``WHERE must have norm 1, got N``.
    """
    norm = float(np.linalg.norm(quat))
    if not math.isclose(norm, 1.0, abs_tol=QUATERNION_NORM_TOL):
        raise SceneFileError(f"{where} must have norm 1, got {norm:.6g}")
    x, y, z, w = quat / norm
    return np.asarray(pin.Quaternion(w, x, y, z).toRotationMatrix())  # w first


def mesh_arrays(
    vertices: list[FloatArray], triangles: list[Any], where: str
) -> tuple[FloatArray, npt.NDArray[np.int64]]:
    """Read-only (V, 3) vertices [m] and (T, 3) triangles of an inline mesh.

    Args:
        vertices: The checked vertices, (3,) each.
        triangles: Each three vertex indices.
        where: For the message.

    Raises:
        SceneFileError: If a triangle is not 3 integer indices below V.
    """
    v = np.array(vertices, dtype=np.float64).reshape(-1, 3)
    for item in triangles:
        ok = isinstance(item, list) and len(item) == 3
        if not ok or not all(type(i) is int and 0 <= i < len(v) for i in item):
            raise SceneFileError(
                f"{where}: a triangle must be 3 vertex indices < {len(v)}, got {item!r}"
            )
    t = np.array(triangles, dtype=np.int64)
    v.setflags(write=False)
    t.setflags(write=False)
    return v, t
