r"""Deterministic, near-uniform sets of tool orientations for the workspace grid.

Two sets, both exactly ``n`` unit quaternions **x y z w** with ``w >= 0``
(rotation of the tool frame in the robot's base frame):

* :func:`uniform_orientations`: super-Fibonacci spirals (M. Alexa, "Super-Fibonacci
  Spirals: Fast, Low-Discrepancy Sampling of SO(3)", CVPR 2022). Point
  :math:`i` has :math:`s = i + 1/2`, :math:`r = \sqrt{s/n}`,
  :math:`R = \sqrt{1 - s/n}`, :math:`\alpha = 2\pi s/\sqrt2`,
  :math:`\beta = 2\pi s/\psi` (:math:`\psi = 1.533751168755204\ldots`, the root
  of :math:`\psi^4 = \psi + 4`) and quaternion
  :math:`(x, y, z, w) = (r\sin\alpha, r\cos\alpha, R\sin\beta, R\cos\beta)`.
* :func:`cone_orientations`: tool axis (z of the tool frame) within
  ``half_angle`` of a direction, free rotation about the tool axis. The same
  spiral in the region's own coordinates, in which the Haar measure is
  uniform: :math:`\cos\theta = 1 - (s/n)(1 - \cos h)` (area-uniform on the
  cap), azimuth :math:`\varphi = 2\pi s/\sqrt2`, spin :math:`\psi' = 2\pi
  s/\psi`; rotation :math:`B\,R_z(\varphi)\,R_y(\theta)\,R_z(\psi')`, B the
  shortest rotation taking z to the direction.

The **covering radius** of a set (largest rotation angle from a rotation of
the region to its nearest member) is an estimate: the worst of
:data:`COVERING_SAMPLES` random rotations of the region (fixed seed
:data:`COVERING_SEED`), then each of the :data:`COVERING_REFINED` worst ones
climbed locally to a larger distance (pattern search). It is a lower bound of
the true radius that the refinement makes tight to about 1e-4 rad; cached per
set, computed once per process (a second or two).
"""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.validation import as_finite_array

if TYPE_CHECKING:
    from scipy.spatial import cKDTree

FloatArray = npt.NDArray[np.float64]

#: The second constant of the super-Fibonacci spiral (root of ψ⁴ = ψ + 4).
SUPER_FIBONACCI_PSI = 1.533751168755204288118041
#: Random rotations the covering radius is estimated from.
COVERING_SAMPLES = 1_000_000
#: Seed of those rotations (the estimate is the same in every process).
COVERING_SEED = 20220
#: Worst samples refined by the local search.
COVERING_REFINED = 8
#: Smallest step of the local search [rad of the parameters].
_REFINE_MIN_STEP = 1e-5
_CHUNK = 1 << 17


def rotations_from_quat_xyzw(quat_xyzw: FloatArray) -> FloatArray:
    """Rotation matrices of unit quaternions, vectorised.

    Args:
        quat_xyzw: Shape (N, 4), unit quaternions x y z w (not checked).

    Returns:
        Shape (N, 3, 3) rotations (frame of the quaternion in the base frame).
    """
    x, y, z, w = np.moveaxis(np.asarray(quat_xyzw, dtype=np.float64), -1, 0)
    out = np.empty((*x.shape, 3, 3))
    out[..., 0, 0] = 1.0 - 2.0 * (y * y + z * z)
    out[..., 0, 1] = 2.0 * (x * y - z * w)
    out[..., 0, 2] = 2.0 * (x * z + y * w)
    out[..., 1, 0] = 2.0 * (x * y + z * w)
    out[..., 1, 1] = 1.0 - 2.0 * (x * x + z * z)
    out[..., 1, 2] = 2.0 * (y * z - x * w)
    out[..., 2, 0] = 2.0 * (x * z - y * w)
    out[..., 2, 1] = 2.0 * (y * z + x * w)
    out[..., 2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return out


def quat_xyzw_from_rotations(rotations: FloatArray) -> FloatArray:
    """Unit quaternions x y z w (w >= 0) of rotation matrices, vectorised.

    Shepperd's method: from the largest of the four squared components, so
    accurate for every rotation (half turns too).

    Args:
        rotations: Shape (N, 3, 3) rotations (not checked).

    Returns:
        Shape (N, 4).
    """
    r = np.asarray(rotations, dtype=np.float64)
    m00, m11, m22 = r[:, 0, 0], r[:, 1, 1], r[:, 2, 2]
    squares = np.stack(
        [
            1 + m00 - m11 - m22,
            1 - m00 + m11 - m22,
            1 - m00 - m11 + m22,
            1 + m00 + m11 + m22,
        ],
        axis=-1,
    )  # 4 x², 4 y², 4 z², 4 w²
    pick = np.argmax(squares, axis=1)
    big = 0.5 * np.sqrt(np.take_along_axis(squares, pick[:, None], axis=1)[:, 0])
    quarter = 0.25 / big
    zy, xz, yx = (
        r[:, 2, 1] - r[:, 1, 2],
        r[:, 0, 2] - r[:, 2, 0],
        r[:, 1, 0] - r[:, 0, 1],
    )
    yz, zx, xy = (
        r[:, 2, 1] + r[:, 1, 2],
        r[:, 0, 2] + r[:, 2, 0],
        r[:, 1, 0] + r[:, 0, 1],
    )
    candidates = np.stack(
        [
            np.stack([big, xy * quarter, zx * quarter, zy * quarter], axis=-1),
            np.stack([xy * quarter, big, yz * quarter, xz * quarter], axis=-1),
            np.stack([zx * quarter, yz * quarter, big, yx * quarter], axis=-1),
            np.stack([zy * quarter, xz * quarter, yx * quarter, big], axis=-1),
        ],
        axis=1,
    )
    quat = candidates[np.arange(len(r)), pick]
    return np.where(quat[:, 3:4] < 0.0, -quat, quat)


def quat_multiply_xyzw(a: FloatArray, b: FloatArray) -> FloatArray:
    """Hamilton product ``a ⊗ b`` of quaternions x y z w, shapes broadcast (..., 4)."""
    ax, ay, az, aw = np.moveaxis(np.asarray(a, dtype=np.float64), -1, 0)
    bx, by, bz, bw = np.moveaxis(np.asarray(b, dtype=np.float64), -1, 0)
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def rotation_angle_between(a: FloatArray, b: FloatArray) -> FloatArray:
    """Angle [rad] of the rotation between unit quaternions, shapes broadcast (..., 4).

    ``2 acos |a · b|``, in [0, π] (``q`` and ``-q`` are the same rotation).
    """
    dot = np.abs(np.sum(np.asarray(a) * np.asarray(b), axis=-1))
    return 2.0 * np.arccos(np.minimum(dot, 1.0))


def _canonical(quat: FloatArray) -> FloatArray:
    """Unit quaternions with ``w >= 0``, read-only."""
    quat = quat / np.linalg.norm(quat, axis=-1, keepdims=True)
    quat = np.where(quat[:, 3:4] < 0.0, -quat, quat)
    quat.setflags(write=False)
    return quat


def _check_count(n: int) -> int:
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise InputError(f"orientation count must be a positive integer, got {n!r}")
    return int(n)


def _spiral(n: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The spiral's stratified fraction ``s/n`` and its two angles [rad], each (n,)."""
    s = np.arange(n, dtype=np.float64) + 0.5
    alpha = 2.0 * np.pi * np.mod(s / math.sqrt(2.0), 1.0)
    beta = 2.0 * np.pi * np.mod(s / SUPER_FIBONACCI_PSI, 1.0)
    return s / n, alpha, beta


def uniform_orientations(n: int) -> tuple[FloatArray, dict[str, object]]:
    """``n`` rotations near-uniform on SO(3), by super-Fibonacci spirals.

    Args:
        n: Number of rotations (>= 1).

    Returns:
        ``(quat_xyzw, orientation_set)``: (n, 4) read-only unit quaternions
        x y z w, w >= 0, and the set's description ``{"construction":
        "super-fibonacci", "count": n, "covering_radius": rad}`` (module
        docstring: the radius is an estimate).

    Raises:
        InputError: If ``n`` is not a positive integer.
    """
    n = _check_count(n)
    return _uniform(n), {
        "construction": "super-fibonacci",
        "count": n,
        "covering_radius": _uniform_covering_radius(n),
    }


@functools.cache
def _uniform(n: int) -> FloatArray:
    fraction, alpha, beta = _spiral(n)
    r, big_r = np.sqrt(fraction), np.sqrt(1.0 - fraction)
    quat = np.stack(
        [
            r * np.sin(alpha),
            r * np.cos(alpha),
            big_r * np.sin(beta),
            big_r * np.cos(beta),
        ],
        axis=-1,
    )
    return _canonical(quat)


def _base_rotation(axis: FloatArray) -> FloatArray:
    """Quaternion x y z w of the shortest rotation taking z to unit ``axis``."""
    cos = float(np.clip(axis[2], -1.0, 1.0))
    turn = np.cross([0.0, 0.0, 1.0], axis)
    norm = float(np.linalg.norm(turn))
    if norm < 1e-12:  # along ±z: identity, or half a turn about x
        return np.array([0.0, 0.0, 0.0, 1.0] if cos > 0 else [1.0, 0.0, 0.0, 0.0])
    angle = math.atan2(norm, cos)
    return np.append(math.sin(angle / 2.0) * turn / norm, math.cos(angle / 2.0))


def _cone_quaternions(
    base: FloatArray, theta: FloatArray, phi: FloatArray, spin: FloatArray
) -> FloatArray:
    r"""Quaternions of :math:`B\,R_z(\varphi)\,R_y(\theta)\,R_z(\psi')` (ZYZ Euler)."""
    c, s = np.cos(theta / 2.0), np.sin(theta / 2.0)
    plus, minus = (phi + spin) / 2.0, (phi - spin) / 2.0
    zyz = np.stack(
        [-s * np.sin(minus), s * np.cos(minus), c * np.sin(plus), c * np.cos(plus)],
        axis=-1,
    )
    return quat_multiply_xyzw(base, zyz)


def _as_cone(axis: npt.ArrayLike, half_angle: float) -> tuple[FloatArray, float]:
    direction = as_finite_array(axis, (3,), "cone axis")
    scale = float(np.max(np.abs(direction)))
    if scale == 0.0:
        raise InputError("cone axis must be a nonzero vector")
    direction = direction / scale  # no overflow (1e308) or underflow (1e-320)
    norm = float(np.linalg.norm(direction))
    half = float(as_finite_array(half_angle, (), "cone half_angle"))
    if not 0.0 < half <= math.pi:
        raise InputError(f"cone half_angle must be in (0, π] rad, got {half!r}")
    return direction / norm, half


def cone_orientations(
    axis: npt.ArrayLike, half_angle: float, n: int
) -> tuple[FloatArray, dict[str, object]]:
    """``n`` rotations whose tool axis lies within ``half_angle`` of ``axis``.

    Near-uniform over that region of SO(3) (module docstring), free rotation
    about the tool axis; e.g. ``axis = (0, 0, -1)`` for top-down grasps.

    Args:
        axis: Shape (3,), direction in the base frame (normalised here).
        half_angle: Half-angle of the cone [rad], in (0, π].
        n: Number of rotations (>= 1).

    Returns:
        ``(quat_xyzw, orientation_set)``: (n, 4) read-only unit quaternions
        x y z w, w >= 0, and ``{"construction": "super-fibonacci-cone", "count",
        "covering_radius" (within the region, an estimate), "axis" (unit, list),
        "half_angle"}``.

    Raises:
        InputError: If ``axis`` is zero or not finite (3,), ``half_angle`` is
            outside (0, π], or ``n`` is not a positive integer.
    """
    direction, half = _as_cone(axis, half_angle)
    n = _check_count(n)
    key = (tuple(direction.tolist()), half, n)
    return _cone(*key), {
        "construction": "super-fibonacci-cone",
        "count": n,
        "covering_radius": _cone_covering_radius(*key),
        "axis": list(key[0]),
        "half_angle": half,
    }


@functools.cache
def _cone(axis: tuple[float, ...], half: float, n: int) -> FloatArray:
    fraction, alpha, beta = _spiral(n)
    theta = np.arccos(1.0 - fraction * (1.0 - math.cos(half)))
    return _canonical(
        _cone_quaternions(_base_rotation(np.array(axis)), theta, alpha, beta)
    )


def _nearest_angle(tree: cKDTree, quat: FloatArray) -> FloatArray:
    """Rotation angle [rad] from each quaternion (N, 4) to its nearest set member."""
    chord = np.empty(len(quat))
    for start in range(0, len(quat), _CHUNK):
        chord[start : start + _CHUNK] = tree.query(quat[start : start + _CHUNK])[0]
    dot = np.clip(1.0 - 0.5 * chord * chord, -1.0, 1.0)  # |a·b| of the nearer of ±b
    return 2.0 * np.arccos(dot)


def _tree(members: FloatArray) -> cKDTree:
    """KD-tree of the members and their antipodes (nearest by chord = by angle)."""
    from scipy.spatial import cKDTree  # (SciPy: imported when first used)

    return cKDTree(np.concatenate([members, -members]))


def _refine(
    tree: cKDTree,
    params: FloatArray,
    to_quat: functools.partial[FloatArray],
    clip: functools.partial[FloatArray],
    step: float,
) -> float:
    """Largest nearest-member angle found climbing from each row of ``params``.

    Pattern search: each parameter ± the step, moving while it helps, the
    step halved down to :data:`_REFINE_MIN_STEP`.
    """
    best = 0.0
    for start in params:
        point = start.copy()
        value = float(_nearest_angle(tree, to_quat(point[None]))[0])
        size = step
        while size > _REFINE_MIN_STEP:
            moves = np.concatenate([np.eye(len(point)), -np.eye(len(point))]) * size
            trial = clip(point + moves)
            values = _nearest_angle(tree, to_quat(trial))
            k = int(np.argmax(values))
            if values[k] > value:
                point, value = trial[k], float(values[k])
            else:
                size /= 2.0
        best = max(best, value)
    return best


def _estimate(
    members: FloatArray,
    samples: FloatArray,
    to_quat: functools.partial[FloatArray],
    clip: functools.partial[FloatArray],
) -> float:
    tree = _tree(members)
    angles = _nearest_angle(tree, to_quat(samples))
    worst = np.argsort(angles)[-COVERING_REFINED:]
    refined = _refine(tree, samples[worst], to_quat, clip, float(angles[worst[-1]]) / 4)
    return max(float(angles[worst[-1]]), refined)


def _unit_rows(params: FloatArray) -> FloatArray:
    return params / np.linalg.norm(params, axis=-1, keepdims=True)


def _identity(params: FloatArray) -> FloatArray:
    return params


@functools.cache
def _uniform_covering_radius(n: int) -> float:
    rng = np.random.default_rng(COVERING_SEED)
    samples = _unit_rows(rng.standard_normal((COVERING_SAMPLES, 4)))
    to_quat = functools.partial(_unit_rows)
    return _estimate(_uniform(n), samples, to_quat, functools.partial(_identity))


def _cone_params_to_quat(base: FloatArray, params: FloatArray) -> FloatArray:
    """Quaternions of cone parameters rows (cos θ, φ, ψ')."""
    theta = np.arccos(params[:, 0])
    return _cone_quaternions(base, theta, params[:, 1], params[:, 2])


def _clip_cone(low: float, params: FloatArray) -> FloatArray:
    clipped = params.copy()
    clipped[:, 0] = np.clip(clipped[:, 0], low, 1.0)
    return clipped


@functools.cache
def _cone_covering_radius(axis: tuple[float, ...], half: float, n: int) -> float:
    rng = np.random.default_rng(COVERING_SEED)
    low = math.cos(half)
    samples = np.stack(
        [
            rng.uniform(low, 1.0, COVERING_SAMPLES),
            rng.uniform(0.0, 2.0 * np.pi, COVERING_SAMPLES),
            rng.uniform(0.0, 2.0 * np.pi, COVERING_SAMPLES),
        ],
        axis=-1,
    )
    to_quat = functools.partial(_cone_params_to_quat, _base_rotation(np.array(axis)))
    clip = functools.partial(_clip_cone, low)
    return _estimate(_cone(axis, half, n), samples, to_quat, clip)


__all__ = [
    "COVERING_REFINED",
    "COVERING_SAMPLES",
    "COVERING_SEED",
    "SUPER_FIBONACCI_PSI",
    "cone_orientations",
    "quat_multiply_xyzw",
    "quat_xyzw_from_rotations",
    "rotation_angle_between",
    "rotations_from_quat_xyzw",
    "uniform_orientations",
]
