r"""The arm angles at which each branch of an SRS arm is within its joint limits.

Shimizu et al. (IEEE T-RO 24(5), 2008, Section IV) write every joint of an SRS
arm as a function of the arm angle ψ. With R03 = A_s sin ψ + B_s cos ψ + C_s
and R47 = A_w sin ψ + B_w cos ψ + C_w (:mod:`workbench.ik._srs_kernel`), each
entry is a sinusoid :math:`a \sin\psi + b \cos\psi + c`, and

* θ1, θ3, θ5, θ7 are *tangent-type*, θ = atan2(N(ψ), D(ψ)) (both sinusoids,
  up to a common factor ± 1/|sin θ2| or ± 1/|sin θ6| that does not change
  where θ hits a value): θ1 from (R03[1,1], R03[0,1]), θ3 from
  (σ3 R03[2,2], R03[2,0]), θ5 from (R47[1,2], R47[0,2]), θ7 from
  (−R47[2,1], R47[2,0]);
* θ2 and θ6 are *cosine-type*, θ = ±acos(w(ψ)): cos θ2 = −σ1 σ2 σ3 R03[2,1],
  cos θ6 = −σ5 σ6 R47[2,2];
* θ4 does not depend on ψ.

A joint reaches a limit value θ_L (θ_L = s q_L + θ0 of the fitted chain) only
where θ(ψ) = θ_L, i.e. where N cos θ_L − D sin θ_L = 0 (tangent-type: that
also holds at θ_L + π, and where N = D = 0, the singular arm angle at which
θ jumps by π) or w = cos θ_L (cosine-type): all are roots of one equation
a sin ψ + b cos ψ + c = 0, at most two, in closed form
ψ = atan2(a, b) ± acos(−c / √(a² + b²)). Between two consecutive roots of all
joints no joint crosses a limit, so one test at the midpoint (the kernel's
``solve_batch`` at that ψ, its joint values against the limits) decides the
whole interval. A tangent-type joint whose θ(ψ) is not monotonic (Shimizu's
"stationary points", where Shimizu's own mapping of limits to ψ needs care)
needs nothing else here: every crossing of a limit, on either side of a
stationary point, is a root of the equation, and a stationary point that
touches a limit is a double root.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench.ik import _kernel_common as common
from workbench.ik import _srs_kernel as kernel
from workbench.ik._puma import LIMIT_TOL

FloatArray = npt.NDArray[np.float64]

#: Newton steps that polish each closed-form root of a sin ψ + b cos ψ + c.
_POLISH_STEPS = 2


def _rotations(geo, pose: FloatArray, cos_psi: float, sin_psi: float):
    """Per elbow (2), the sinusoid entries of R03 and R47 at one ψ (10,).

    Order: R03[1,1], R03[0,1], R03[2,1], R03[2,2], R03[2,0], R47[1,2],
    R47[0,2], R47[2,2], R47[2,1], R47[2,0]. ``None`` when out of reach.
    """
    tool, base = common.frames(geo)
    rot, sw = kernel._framed_target(geo, pose, tool, base, geo.based != 0.0)
    length2 = sw[0] ** 2 + sw[1] ** 2 + sw[2] ** 2
    c4 = kernel._elbow_cosine(geo, length2)
    if not abs(c4) <= 1.0 + geo.reach_tol:
        return None
    c4 = common.clip_unit(c4)
    s4 = common.clamped_root((1.0 - c4) * (1.0 + c4))
    col0, col1, col2, _ = kernel._reference(geo, sw, c4, s4)
    length = math.sqrt(length2)
    u = tuple(x / length for x in sw)
    turned = tuple(kernel._turn(u, c, cos_psi, sin_psi) for c in (col0, col1, col2))
    rows = []
    for e in (1.0, -1.0):
        c0, r47 = kernel._elbow_frames(geo, rot, turned, e, c4, s4)
        b1, c2 = turned[1], tuple(e * x for x in turned[2])
        rows.append(
            [b1[1], b1[0], b1[2], c2[2], c0[2], r47[5], r47[2], r47[8], r47[7], r47[6]]
        )
    return np.array(rows)


def _sinusoid_roots(a: float, b: float, c: float) -> list[float]:
    """The ψ in (−π, π] where a sin ψ + b cos ψ + c = 0 (none if identically)."""
    r = math.hypot(a, b)
    if r == 0.0 or abs(c) > r:
        return []
    gamma, delta = math.atan2(a, b), math.acos(max(-1.0, min(1.0, -c / r)))
    roots = []
    for psi in (gamma + delta, gamma - delta):
        for _ in range(_POLISH_STEPS):
            slope = a * math.cos(psi) - b * math.sin(psi)
            if abs(slope) <= 1e-8 * r:  # a double root: acos was as good
                break
            psi -= (a * math.sin(psi) + b * math.cos(psi) + c) / slope
        roots.append(common.remainder(psi))
    return roots


#: Per joint: ("tan", index of N, index of D, sign of N) or ("cos", index of
#: w, 0, sign of w) into the (10,) entries of :func:`_rotations`; None: θ4.
def _joint_forms(geo) -> list[tuple[str, int, int, float] | None]:
    s = geo.sigma
    return [
        ("tan", 0, 1, 1.0),
        ("cos", 2, 0, -s[0] * s[1] * s[2]),
        ("tan", 3, 4, s[2]),
        None,
        ("tan", 5, 6, 1.0),
        ("cos", 7, 0, -s[4] * s[5]),
        ("tan", 8, 9, -1.0),
    ]


def compute_feasible_intervals(
    geometry: np.ndarray, pose: FloatArray
) -> list[list[tuple[float, float]]]:
    """Per branch, the closed arm-angle intervals within the joint limits.

    Args:
        geometry: The arm's (1,) record (``_srs_kernel.pack_geometry``).
        pose: (4, 4) pose of the tool frame in the robot's base frame [m].

    Returns:
        Eight lists (branch order ``_srs_kernel.BRANCHES``) of sorted,
        disjoint (lo, hi) [rad] within [−π, π]: the branch reaches the pose
        and every joint is within its limits for ψ in them. All empty when
        the pose is out of reach (or not rigid: the caller checks first).
    """
    geo = geometry.view(np.recarray)[0]
    pose = np.ascontiguousarray(pose, dtype=float)
    f0 = _rotations(geo, pose, 1.0, 0.0)
    f1 = _rotations(geo, pose, 0.0, 1.0)
    f2 = _rotations(geo, pose, -1.0, 0.0)
    if f0 is None or f1 is None or f2 is None:  # (the reach does not depend on ψ)
        return [[] for _ in kernel.BRANCHES]
    const = 0.5 * (f0 + f2)  # f(ψ) = A sin ψ + B cos ψ + C
    cos_part = 0.5 * (f0 - f2)
    sin_part = f1 - const
    lower = np.asarray(geo.lower) + LIMIT_TOL
    upper = np.asarray(geo.upper) - LIMIT_TOL
    cuts: list[float] = []
    for j, form in enumerate(_joint_forms(geo)):
        if form is None or upper[j] - lower[j] >= common.TAU:
            continue
        kind, n, d, sign = form
        for limit in (lower[j], upper[j]):
            theta = geo.joint_sign[j] * limit + geo.theta_offset[j]
            ct, st = math.cos(theta), math.sin(theta)
            for e in range(2):
                a, b, c = sin_part[e], cos_part[e], const[e]
                if kind == "tan":  # N cos θL − D sin θL
                    coef = [sign * x[n] * ct - x[d] * st for x in (a, b, c)]
                else:  # w − cos θL
                    coef = [sign * a[n], sign * b[n], sign * c[n] - ct]
                cuts.extend(_sinusoid_roots(*coef))
    ends = np.unique(np.clip([-math.pi, *cuts, math.pi], -math.pi, math.pi))
    mids = 0.5 * (ends[:-1] + ends[1:])
    poses = np.ascontiguousarray(np.broadcast_to(pose, (mids.size, 4, 4)))
    q = np.empty((mids.size, 8, 7))
    valid = np.empty((mids.size, 8), dtype=bool)
    kernel.solve_batch(geometry, poses, mids, q, valid)
    within = valid & np.all((q >= lower) & (q <= upper), axis=2)
    out: list[list[tuple[float, float]]] = []
    for b in range(8):
        intervals: list[tuple[float, float]] = []
        for k in np.flatnonzero(within[:, b]):
            lo, hi = float(ends[k]), float(ends[k + 1])
            if intervals and intervals[-1][1] == lo:
                intervals[-1] = (intervals[-1][0], hi)
            else:
                intervals.append((lo, hi))
        out.append(intervals)
    return out


__all__ = ["compute_feasible_intervals"]
