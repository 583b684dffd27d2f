"""Exact checks of IK targets: shape, finiteness, rigidity (``poses.RIGIDITY_TOL``).

The compiled kernels (``_kernel_common.is_rigid``) make the same test with
the same tolerance; a pose they refuse comes here for the message.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import DimensionError, InputError, NonFiniteError
from workbench.poses import RIGIDITY_TOL, check_rigid_rows, compute_rigidity_errors

FloatArray = npt.NDArray[np.float64]


def pose_rows(target: pin.SE3 | npt.ArrayLike) -> list[list[float]]:
    """Rows of the (4, 4) homogeneous matrix as floats, every check made.

    The checks of the kernels' rigidity test (``_kernel_common.is_rigid``),
    which word the error.

    Raises:
        DimensionError: If ``target`` is not (4, 4).
        NonFiniteError: If an entry is not a number, NaN or infinite.
        InputError: If the bottom row is not [0, 0, 0, 1] or R is not a rotation.
    """
    if isinstance(target, pin.SE3):
        rows = target.homogeneous.tolist()
    else:
        try:
            arr = np.asarray(target, dtype=np.float64)
        except (TypeError, ValueError) as err:
            raise NonFiniteError(f"target must be numbers, got {target!r}") from err
        if arr.shape != (4, 4):
            raise DimensionError("target", (4, 4), arr.shape)
        rows = arr.tolist()
    if not math.isfinite(math.fsum(map(abs, (*rows[0], *rows[1], *rows[2], *rows[3])))):
        raise NonFiniteError(f"target must be finite, got {rows}")
    bottom = rows[3]
    if max(abs(bottom[0]), abs(bottom[1]), abs(bottom[2]), abs(bottom[3] - 1.0)) > (
        RIGIDITY_TOL
    ):
        raise InputError(f"target must have bottom row [0, 0, 0, 1], got {bottom}")
    rotation = [row[:3] for row in rows[:3]]
    check_rigid_rows(
        rotation, [row[3] for row in rows[:3]], RIGIDITY_TOL, "target rotation"
    )
    return rows


def as_targets(targets: npt.ArrayLike) -> FloatArray:
    """``targets`` as a C-contiguous float array (N, 4, 4), not yet checked."""
    try:
        t = np.ascontiguousarray(targets, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise NonFiniteError("targets must be numbers") from err
    if t.ndim != 3 or t.shape[1:] != (4, 4):
        expected = (t.shape[0] if t.ndim else 0, 4, 4)
        raise DimensionError("targets", expected, t.shape)
    return t


def check_poses(poses: FloatArray, start: int) -> None:
    """Raise unless every pose of ``poses`` (n, 4, 4) is finite and rigid.

    The exact checks of :func:`pose_rows`, vectorised; ``start`` is the index
    of ``poses[0]`` in the caller's batch, for the message.
    """
    finite = np.isfinite(poses.reshape(len(poses), 16)).all(axis=1)
    if not finite.all():
        raise NonFiniteError(
            f"targets must be finite: pose {start + int(np.argmin(finite))} has "
            "NaN or inf"
        )
    err, det = compute_rigidity_errors(poses)
    bad = (err > RIGIDITY_TOL) | (det <= 0.0)
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(
            f"targets must be rigid transforms: pose {start + i} is not "
            f"(max |R^T R - I| or bottom-row error {err[i]:.3g} > "
            f"{RIGIDITY_TOL:g}, or det R = {det[i]:.6g} <= 0)"
        )
