r"""Numeric singularity measures of any arm, from the SVD of its Jacobian.

For the tool-frame Jacobian :math:`J` (LOCAL_WORLD_ALIGNED, shape (6, nv)) with
singular values :math:`\sigma_1 \ge \dots \ge \sigma_6`:

* :math:`\sigma_{\min} = \sigma_6` — distance of :math:`J` from the nearest
  rank-deficient matrix (spectral norm);
* Yoshikawa's manipulability :math:`\sqrt{\det(J J^T)} = \prod_i \sigma_i`;
* the condition number :math:`\sigma_1 / \sigma_6` (inf when singular).

The rows of :math:`J` mix m/s and rad/s, so these numbers depend on the length
unit (SI here); only their zeros do not. Everything here is vectorised over a
leading batch axis. The singular values come from a compiled one-sided Jacobi
SVD (``_svd_kernel``, as accurate as ``np.linalg.svd`` and faster on batches
of small matrices); the grids over joint values take their Jacobians from the
compiled chain (:func:`workbench.ik.compute_jacobians_local`) instead of a
Python loop over Pinocchio, and the determinant of an OPW or UR-type arm from
the analytic factorisation of :mod:`workbench.singularities.conditions`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.ik import compute_jacobians_local
from workbench.model.dh import DHTable
from workbench.model.robot import Robot
from workbench.singularities import _svd_kernel
from workbench.singularities.conditions import (
    compute_det_j_analytic,
    find_factorisation,
)
from workbench.validation import as_finite_array

FloatArray = npt.NDArray[np.float64]
#: ``progress(done, total)``, called after each chunk of a long computation.
ProgressCallback = Callable[[int, int], None]

#: Grid points per chunk (bounds memory: a chunk of batched Jacobians is
#: 6 × 6 × 8 bytes × this).
CHUNK = 65_536


@dataclass(frozen=True, slots=True)
class JacobianMeasures:
    r"""SVD measures of Jacobians, each of shape ``batch`` (the leading dims).

    Attributes:
        singular_values: Shape batch + (min(6, nv),), descending [mixed units].
        sigma_min: Smallest singular value.
        manipulability: Yoshikawa's :math:`\sqrt{\det(J J^T)}`.
        condition_number: :math:`\sigma_{\max} / \sigma_{\min}`; inf if singular.
        det_j: :math:`\det J` [m³ for an arm of revolute joints] when J is
            square (nv = 6), else None.
    """

    singular_values: FloatArray
    sigma_min: FloatArray
    manipulability: FloatArray
    condition_number: FloatArray
    det_j: FloatArray | None


def compute_singular_values(jacobians: npt.ArrayLike) -> FloatArray:
    """Singular values of Jacobians (..., 6, nv), descending, shape (..., min(6, nv)).

    Compiled one-sided Jacobi (``_svd_kernel``): each value within a few
    units of roundoff times the largest of its matrix, as ``np.linalg.svd``.
    The kernel runs without the GIL, so threads can share a large batch.

    Raises:
        InputError: If the shape is not (..., 6, nv) with nv ≥ 1.
    """
    jac = np.asarray(jacobians, dtype=np.float64)
    if jac.ndim < 2 or jac.shape[-2] != 6 or jac.shape[-1] < 1:
        raise InputError(f"Jacobians must have shape (..., 6, nv), got {jac.shape}")
    flat = np.ascontiguousarray(jac.reshape(-1, 6, jac.shape[-1]))
    sv = np.empty((flat.shape[0], min(6, jac.shape[-1])))
    _svd_kernel.singular_values(flat, sv)
    return sv.reshape(*jac.shape[:-2], sv.shape[-1])


def compute_measures_from_jacobians(jacobians: npt.ArrayLike) -> JacobianMeasures:
    """Measures of Jacobians of shape (..., 6, nv).

    Raises:
        InputError: If the shape is not (..., 6, nv) with nv ≥ 1.
    """
    jac = np.asarray(jacobians, dtype=np.float64)
    sv = compute_singular_values(jac)
    sigma_min = sv[..., -1]
    with np.errstate(divide="ignore"):
        condition = np.where(sigma_min > 0.0, sv[..., 0] / sigma_min, np.inf)
    det: FloatArray | None = np.linalg.det(jac) if jac.shape[-1] == 6 else None
    return JacobianMeasures(sv, sigma_min, np.prod(sv, axis=-1), condition, det)


def compute_measures(robot: Robot, q: npt.ArrayLike) -> JacobianMeasures:
    """Measures at configurations ``q`` of shape (nq,) or (N, nq) [rad].

    Uses Pinocchio's tool-frame Jacobian (one call per configuration).

    Raises:
        DimensionError: If the joint count is wrong.
        NonFiniteError: If ``q`` holds NaN or inf.
    """
    q = np.asarray(q, dtype=np.float64)
    if q.ndim == 1:
        batch = robot.check_configuration(q)[None]
    else:
        batch = as_finite_array(q, (q.shape[0] if q.ndim else 1, robot.nq), "q")
    jacobians = np.stack([robot.jacobian(qi) for qi in batch])
    measures = compute_measures_from_jacobians(jacobians)
    if q.ndim == 1:
        m = measures
        return JacobianMeasures(
            m.singular_values[0],
            m.sigma_min[0],
            m.manipulability[0],
            m.condition_number[0],
            None if m.det_j is None else m.det_j[0],
        )
    return measures


def compute_dh_jacobians(table: DHTable, q: npt.ArrayLike) -> FloatArray:
    r"""Tool-frame Jacobians of a DH arm for a batch, in numpy (no Pinocchio).

    Column i is :math:`[z_{i-1} \times (p - o_{i-1});\ z_{i-1}]` in base axes,
    i.e. Pinocchio's LOCAL_WORLD_ALIGNED Jacobian of the last DH frame.

    Args:
        table: The DH table.
        q: Configurations, shape (N, nq) [rad].

    Returns:
        Shape (N, 6, nq).
    """
    q = np.asarray(q, dtype=np.float64)
    q = as_finite_array(q, (q.shape[0] if q.ndim == 2 else -1, table.nq), "q")
    theta = q + np.array([j.theta_offset for j in table.joints])
    ct, st = np.cos(theta), np.sin(theta)
    n = q.shape[0]
    rot = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    pos = np.zeros((n, 3))
    axes, origins = np.empty((table.nq, n, 3)), np.empty((table.nq, n, 3))
    for i, joint in enumerate(table.joints):
        axes[i], origins[i] = rot[:, :, 2], pos
        ca, sa = np.cos(joint.alpha), np.sin(joint.alpha)
        link = np.zeros((n, 3, 3))
        link[:, 0, 0], link[:, 0, 1], link[:, 0, 2] = (
            ct[:, i],
            -st[:, i] * ca,
            st[:, i] * sa,
        )
        link[:, 1, 0], link[:, 1, 1], link[:, 1, 2] = (
            st[:, i],
            ct[:, i] * ca,
            -ct[:, i] * sa,
        )
        link[:, 2, 1], link[:, 2, 2] = sa, ca
        step = np.stack(
            [joint.a * ct[:, i], joint.a * st[:, i], np.full(n, joint.d)], 1
        )
        pos = pos + np.einsum("nij,nj->ni", rot, step)
        rot = rot @ link
    jac = np.empty((n, 6, table.nq))
    jac[:, :3, :] = np.cross(axes, pos[None] - origins).transpose(1, 2, 0)
    jac[:, 3:, :] = axes.transpose(1, 2, 0)
    return jac


@dataclass(frozen=True, slots=True)
class JointGrid:
    """A quantity over a grid of two joints, the others held fixed.

    Attributes:
        joints: Indices of the two joints (0-based; (1, 2) is (θ2, θ3)).
        x: Values of the first joint, shape (nx,) [rad].
        y: Values of the second joint, shape (ny,) [rad].
        q_fixed: Configuration the other joints are taken from, (nq,) [rad].
        values: Dict name -> array of shape (ny, nx) (row = y, column = x).
        method: How it was computed (``"analytic"``, ``"compiled"``,
            ``"pinocchio"``).
        seconds: Wall time of the computation [s].
    """

    joints: tuple[int, int]
    x: FloatArray
    y: FloatArray
    q_fixed: FloatArray
    values: dict[str, FloatArray]
    method: str
    seconds: float

    def configurations(self) -> FloatArray:
        """The grid's configurations, shape (ny, nx, nq) [rad]."""
        return _grid_configurations(self.q_fixed, self.joints, self.x, self.y)


def _grid_configurations(
    q_fixed: FloatArray, joints: tuple[int, int], x: FloatArray, y: FloatArray
) -> FloatArray:
    q = np.broadcast_to(q_fixed, (y.size, x.size, q_fixed.size)).copy()
    q[:, :, joints[0]] = x[None, :]
    q[:, :, joints[1]] = y[:, None]
    return q


def compute_joint_grid(
    robot: Robot,
    x: npt.ArrayLike,
    y: npt.ArrayLike,
    *,
    q_fixed: npt.ArrayLike,
    joints: tuple[int, int] = (1, 2),
    quantity: str = "det_j",
    progress: ProgressCallback | None = None,
) -> JointGrid:
    """``det_j`` or the SVD measures over a grid of two joints.

    ``quantity="det_j"`` on a PUMA-type arm uses the analytic factorisation
    (a 1000 × 1000 grid takes well under a second); ``quantity="svd"`` gives
    ``sigma_min``, ``manipulability``, ``condition_number`` and ``det_j``
    from the compiled chain's Jacobians (:func:`compute_jacobians_local`) and
    the compiled SVD. A robot with a joint the chain does not model (a mimic
    joint) falls back to one Pinocchio call per point (slow: keep such grids
    small).

    Args:
        robot: Any robot.
        x: First joint values, shape (nx,) [rad].
        y: Second joint values, shape (ny,) [rad].
        q_fixed: Values of the other joints, shape (nq,) [rad].
        joints: The two joint indices (0-based).
        quantity: ``"det_j"`` or ``"svd"``.
        progress: Called as ``progress(done, total)`` after each chunk.

    Raises:
        InputError: If a joint index, ``quantity`` or an array is invalid.
    """
    if quantity not in ("det_j", "svd"):
        raise InputError(f"quantity must be 'det_j' or 'svd', got {quantity!r}")
    if len(set(joints)) != 2 or not all(0 <= j < robot.nq for j in joints):
        raise InputError(f"joints must be two indices in [0, {robot.nq}), got {joints}")
    x = as_finite_array(x, np.shape(x), "x").ravel()
    y = as_finite_array(y, np.shape(y), "y").ravel()
    q_fixed = robot.check_configuration(q_fixed)
    start = time.perf_counter()
    flat = _grid_configurations(q_fixed, joints, x, y).reshape(-1, robot.nq)
    method, compute = _grid_method(robot, quantity)
    chunks: list[dict[str, FloatArray]] = []
    for begin in range(0, flat.shape[0], CHUNK):
        chunks.append(compute(flat[begin : begin + CHUNK]))
        if progress is not None:
            progress(min(begin + CHUNK, flat.shape[0]), flat.shape[0])
    values = {
        key: np.concatenate([c[key] for c in chunks]).reshape(y.size, x.size)
        for key in chunks[0]
    }
    seconds = time.perf_counter() - start
    return JointGrid((joints[0], joints[1]), x, y, q_fixed, values, method, seconds)


def _grid_method(
    robot: Robot, quantity: str
) -> tuple[str, Callable[[FloatArray], dict[str, FloatArray]]]:
    if quantity == "det_j":
        if find_factorisation(robot) is not None:
            return "analytic", lambda q: {"det_j": compute_det_j_analytic(robot, q)}
    try:
        compute_jacobians_local(robot, np.zeros((0, robot.nq)))
    except InputError:  # a joint the compiled chain does not model
        compiled = False
    else:
        compiled = True

    def svd(q: FloatArray) -> dict[str, FloatArray]:
        if compiled:
            jac = compute_jacobians_local(robot, q)
        else:
            jac = np.stack([robot.jacobian(qi) for qi in q])
        m = compute_measures_from_jacobians(jac)
        out = {
            "sigma_min": m.sigma_min,
            "manipulability": m.manipulability,
            "condition_number": m.condition_number,
        }
        if m.det_j is not None:
            out["det_j"] = m.det_j
        return out

    return ("compiled" if compiled else "pinocchio"), svd


@dataclass(frozen=True, slots=True)
class DetCrossCheck:
    """Analytic det J against ``np.linalg.det`` of Pinocchio's Jacobian.

    Attributes:
        q: Configurations checked, shape (N, 6) [rad].
        analytic: Factorised det J, shape (N,) [m³].
        pinocchio: ``np.linalg.det(robot.jacobian(q))``, shape (N,) [m³].
        relative_error: ``|analytic - pinocchio| / |pinocchio|``, shape (N,).
    """

    q: FloatArray
    analytic: FloatArray
    pinocchio: FloatArray
    relative_error: FloatArray

    @property
    def max_relative_error(self) -> float:
        """Largest relative error over the configurations."""
        return float(self.relative_error.max())


def cross_check_det_j(robot: Robot, q: npt.ArrayLike) -> DetCrossCheck:
    """Compare the factorised det J with Pinocchio's at configurations (N, 6).

    Raises:
        NotPumaTypeError: If the robot is not of PUMA type.
    """
    q = np.atleast_2d(np.asarray(q, dtype=np.float64))
    q = as_finite_array(q, (q.shape[0], robot.nq), "q")
    analytic = compute_det_j_analytic(robot, q)
    pinocchio = np.array([np.linalg.det(robot.jacobian(qi)) for qi in q])
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.abs(analytic - pinocchio) / np.abs(pinocchio)
    return DetCrossCheck(q, analytic, pinocchio, rel)
