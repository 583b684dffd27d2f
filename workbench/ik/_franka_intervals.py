r"""Feasible q7 of a Franka-type arm for one pose: intervals per branch.

For each of the eight branches of :mod:`workbench.ik._franka_kernel`, the q7
(within q7's limits) where the branch reaches the pose and every joint is
within its limits, as sorted disjoint closed intervals. Sampled, then refined:

* each condition is a margin g(q7), feasible where every margin is ≥ 0: the
  reach margins of ``_franka_kernel.reach_margins`` (elbow, then the wrist
  of the branch's elbow), smooth in q7; and, where the branch reaches, the
  margin of each joint q1..q6 to its limits, measured on the circle (inside:
  the distance to the nearer limit; outside: minus the distance to the
  nearer limit, either way round), continuous where the branch is;
* a cell [t_i, t_{i+1}] is *settled* when every branch's feasibility is
  constant on it: some margin certainly negative, or every margin certainly
  positive, "certainly" under the slope bound L = SLOPE_SAFETY × the largest
  finite-difference slope of that margin over the cell and its two
  neighbours: g stays ≥ (g_i + g_{i+1} − L h) / 2 and ≤ (g_i + g_{i+1} + L h) / 2
  on a cell of width h;
* unsettled cells are halved (one ``solve_batch`` call per round for all of
  them) until settled or END_TOL (1e-12 rad) wide; a cell that narrow whose
  ends differ holds an interval end, taken at its feasible sample (so every
  returned end is feasible and within END_TOL of the true one).

What is guaranteed: every interval end is exact to END_TOL; an interval or
gap narrower than a cell is found whenever each margin's slope on that cell
stays within the slope bound above (it holds near smooth margins; a joint's
margin moves as √ near a reach boundary and jumps by π where the two
shoulder branches swap labels, |sin θ2| = 0: there the finite-difference
slopes grow with each halving, and the cells are halved down to END_TOL).
Intervals narrower than END_TOL may be missed.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench.ik import _franka_kernel as kernel
from workbench.ik._puma import LIMIT_TOL

FloatArray = npt.NDArray[np.float64]

#: Initial samples of q7 over its range.
SAMPLES = 1025
#: Width [rad] at which an unsettled cell stops being halved: the accuracy
#: of an interval end.
END_TOL = 1e-12
#: Factor on the finite-difference slopes that bounds a margin's slope.
SLOPE_SAFETY = 4.0
#: Margin given to a joint whose limits span a full turn or more.
_FREE = 10.0


def _joint_margins(q: FloatArray, lower: FloatArray, upper: FloatArray) -> FloatArray:
    """Margins [rad] of (…, 6) joint values to [lower, upper] on the circle."""
    width = upper - lower
    x = np.mod(q - lower, 2.0 * math.pi)
    inside = np.minimum(x, width - x)
    outside = -np.minimum(x - width, 2.0 * math.pi - x)
    margin = np.where(x <= width, inside, outside)
    return np.where(width >= 2.0 * math.pi, _FREE, margin)


def _margins(geometry: np.ndarray, pose: FloatArray, t: FloatArray) -> FloatArray:
    """Margins (N, 8, 8) at q7 = t (N,): elbow, wrist, q1..q6 (NaN: unreached)."""
    n = t.shape[0]
    poses = np.ascontiguousarray(np.broadcast_to(pose, (n, 4, 4)))
    q = np.empty((n, kernel.B, 7))
    valid = np.empty((n, kernel.B), dtype=np.bool_)
    kernel.solve_batch(geometry, poses, t, q, valid)
    reach = np.empty((n, 3))
    kernel.reach_margins(geometry, pose, t, reach)
    geo = geometry[0]
    lower, upper = geo["lower"][:6] + LIMIT_TOL, geo["upper"][:6] - LIMIT_TOL
    out = np.empty((n, kernel.B, 8))
    out[:, :, 0] = reach[:, :1]
    elbow = np.arange(kernel.B) >> 2
    out[:, :, 1] = reach[:, 1 + elbow]
    out[:, :, 2:] = _joint_margins(q[:, :, :6], lower, upper)  # NaN: unreached
    return out


def _slopes(t_left, t_right, g_left, g_right) -> FloatArray:
    """Finite-difference slopes (cells, 8, 8) of the margins; NaN → inf."""
    h = (t_right - t_left)[:, None, None]
    slope = np.abs(g_right - g_left) / h
    return np.where(np.isnan(slope), np.inf, slope)


def _settled(h, g_left, g_right, bound) -> npt.NDArray[np.bool_]:
    """Per cell: every branch's feasibility is constant on it.

    ``h`` (cells,) widths [rad]; ``g_left``, ``g_right`` (cells, 8, 8)
    margins at its ends; ``bound`` (cells, 8, 8) the slope bounds before
    SLOPE_SAFETY.
    """
    h = h[:, None, None]
    total = g_left + g_right
    spread = SLOPE_SAFETY * bound * h
    with np.errstate(invalid="ignore"):  # inf - inf: not settled
        low, high = total - spread, total + spread
    reached = np.all(low[:, :, :2] >= 0.0, axis=2)  # throughout the cell
    dead = np.any(high[:, :, :2] < 0.0, axis=2)
    never = reached & np.any(high < 0.0, axis=2)
    always = reached & np.all(low >= 0.0, axis=2)
    return np.all(dead | never | always, axis=1)


def compute_feasible_intervals(
    geometry: np.ndarray, pose: FloatArray
) -> list[list[tuple[float, float]]]:
    """The q7 intervals where each branch reaches ``pose`` within the limits.

    Args:
        geometry: From ``_franka_kernel.pack_geometry``.
        pose: (4, 4) pose of the tool frame in the base frame [m], finite and
            rigid.

    Returns:
        Per branch (8 lists, :data:`~workbench.ik._franka_kernel.BRANCHES`
        order), sorted disjoint closed intervals ``(low, high)`` [rad] of q7
        within its limits; each end within END_TOL of the true one (module
        docstring: what is guaranteed).
    """
    low, high = kernel.parameter_range(geometry)
    pose = np.ascontiguousarray(pose, dtype=np.float64)
    t = np.linspace(low, high, SAMPLES)
    g = _margins(geometry, pose, t)
    samples_t, samples_g = [t], [g]
    # open cells: ends, margins there, slopes of the neighbouring cells
    slope = _slopes(t[:-1], t[1:], g[:-1], g[1:])
    tl, tr, gl, gr = t[:-1], t[1:], g[:-1], g[1:]
    sl = np.concatenate([slope[:1], slope[:-1]])
    sr = np.concatenate([slope[1:], slope[-1:]])
    while tl.size:
        bound = np.maximum(np.maximum(sl, sr), _slopes(tl, tr, gl, gr))
        split = ~_settled(tr - tl, gl, gr, bound) & (tr - tl > END_TOL)
        tl, tr, gl, gr = tl[split], tr[split], gl[split], gr[split]
        sl, sr = sl[split], sr[split]
        tm = 0.5 * (tl + tr)
        gm = _margins(geometry, pose, tm)
        samples_t.append(tm)
        samples_g.append(gm)
        left, right = _slopes(tl, tm, gl, gm), _slopes(tm, tr, gm, gr)
        tl, tr = np.concatenate([tl, tm]), np.concatenate([tm, tr])
        gl, gr = np.concatenate([gl, gm]), np.concatenate([gm, gr])
        sl, sr = np.concatenate([sl, left]), np.concatenate([right, sr])
    t, g = np.concatenate(samples_t), np.concatenate(samples_g)
    order = np.argsort(t, kind="stable")
    t, g = t[order], g[order]
    # (N, 8): the kernel's reach (no NaN) and the joints within their limits
    feasible = np.all(g[:, :, 2:] >= 0.0, axis=2)
    return [_runs(t, feasible[:, b]) for b in range(kernel.B)]


def _runs(t: FloatArray, feasible: npt.NDArray[np.bool_]) -> list[tuple[float, float]]:
    """Maximal runs of feasible samples as (first, last) q7 pairs."""
    padded = np.concatenate([[False], feasible, [False]]).astype(np.int8)
    edges = np.diff(padded)
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1) - 1
    return [(float(t[a]), float(t[b])) for a, b in zip(starts, ends, strict=True)]


__all__ = ["END_TOL", "SAMPLES", "SLOPE_SAFETY", "compute_feasible_intervals"]
