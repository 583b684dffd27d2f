r"""The joint-space singularity map: analytic factors and σ_min at many configurations.

The pose maps of this package say where the tool can go; this map says how
close the arm is to a singularity over its joint space, for configurations
drawn at random within the limits (from a seed) or on a regular grid:

* the analytic factors of an OPW or UR-type arm,
  :math:`\det J = K\,s\,e\,w` (:mod:`workbench.singularities.conditions`):
  shoulder :math:`s` [m], elbow :math:`e` [1], wrist :math:`w` [1], and the
  :func:`~workbench.workspace.measures.singularity_margin` of the atlas;
* the singular values of the 6 × nv tool Jacobian of any arm (compiled
  chain Jacobians, :func:`workbench.ik.compute_jacobians_local`, and the
  compiled SVD, :func:`workbench.singularities.measures.compute_singular_values`):
  :math:`\sigma_{\min}` and Yoshikawa's :math:`\prod_i \sigma_i`, which
  equals :math:`|\det J|` for six joints.

The configurations are cut into chunks of :data:`CHUNK`; chunk c of a random
map draws its configurations from ``numpy.random.default_rng([seed, c])``,
so the map does not depend on how many threads computed it (the kernels run
without the GIL: ``workers`` threads share the chunks), bit for bit.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError
from workbench.ik import compute_jacobians_local
from workbench.model.robot import Robot
from workbench.singularities.conditions import (
    PumaFactorisation,
    compute_conditions,
    find_factorisation,
)
from workbench.singularities.measures import compute_singular_values
from workbench.workspace.measures import get_core_count, singularity_margin

FloatArray = npt.NDArray[np.float64]
#: ``progress(done, total)`` in configurations, after each chunk.
ProgressCallback = Callable[[int, int], None]

#: Configurations per chunk: the unit of the random draws and of the work
#: shared between threads (6 × 6 Jacobians of a chunk take 19 MB).
CHUNK = 65_536
#: Configurations of the default map.
DEFAULT_SAMPLES = 1_000_000
#: Most configurations of one map (its arrays take about 100 bytes each).
MAX_CONFIGURATIONS = 20_000_000


@dataclass(frozen=True, slots=True)
class JointSpaceMap:
    r"""Singularity measures at N configurations of one arm.

    Attributes:
        robot: Robot name.
        q: Configurations, shape (N, nq) [rad or m].
        sigma_min: Smallest singular value of the tool Jacobian, (N,) [mixed
            units, SI].
        manipulability: Yoshikawa's :math:`\prod_i \sigma_i = \sqrt{\det(J
            J^T)}`, (N,) [m³ for six revolute joints].
        det_j: :math:`\det J` [m³], (N,): :math:`K s e w` for an OPW or
            UR-type arm, else LAPACK's determinant; None unless nv = 6.
        shoulder: Signed shoulder distance :math:`s` [m], (N,); None without
            an analytic factorisation (neither family).
        elbow: Signed elbow sine :math:`e` [1], (N,); None likewise.
        wrist: :math:`\sin\theta_5` [1], (N,); None likewise.
        singularity_margin: min(|s|/SHOULDER_TOL, |e|/ELBOW_TOL,
            |w|/WRIST_TOL) [1], (N,); below 1: near-singular. None likewise.
        sampling: ``"random"`` or ``"grid"``.
        seed: Seed of a random map; None for a grid.
        points_per_joint: Grid points per joint; None for a random map.
        workers: Threads that computed it.
        seconds: Wall time [s].
    """

    robot: str
    q: FloatArray
    sigma_min: FloatArray
    manipulability: FloatArray
    det_j: FloatArray | None
    shoulder: FloatArray | None
    elbow: FloatArray | None
    wrist: FloatArray | None
    singularity_margin: FloatArray | None
    sampling: str
    seed: int | None
    points_per_joint: int | None
    workers: int
    seconds: float

    @property
    def count(self) -> int:
        """Number of configurations N."""
        return int(self.q.shape[0])

    def near_singular_fraction(self) -> float | None:
        """Fraction of the configurations with singularity margin < 1 (None if none)."""
        if self.singularity_margin is None:
            return None
        return float(np.mean(self.singularity_margin < 1.0))


def compute_joint_space_map(
    robot: Robot,
    *,
    samples: int | None = None,
    seed: int = 0,
    points_per_joint: int | None = None,
    workers: int | None = None,
    progress: ProgressCallback | None = None,
) -> JointSpaceMap:
    """Singularity measures at random or grid configurations within the limits.

    Args:
        robot: Any serial arm with one coordinate per joint and finite limits.
        samples: Random configurations, uniform within the limits
            (default :data:`DEFAULT_SAMPLES` when ``points_per_joint`` is
            not given).
        seed: Seed of the random configurations (module docstring).
        points_per_joint: Instead of random ones, a regular grid of this many
            values per joint, limits included (``points_per_joint ** nq``
            configurations, the last joint varying fastest).
        workers: Threads (default: the machine's cores).
        progress: Called as ``progress(done, total)`` after each chunk.

    Returns:
        The map (:class:`JointSpaceMap`).

    Raises:
        InputError: If a count is not a positive integer (``seed``: not a
            non-negative one), ``samples`` and ``points_per_joint`` are both
            given, the map would exceed :data:`MAX_CONFIGURATIONS`, the robot
            has a joint of two coordinates (continuous) or an infinite limit,
            or a joint the compiled chain does not model.
    """
    if samples is not None and points_per_joint is not None:
        raise InputError("give samples or points_per_joint, not both")
    if points_per_joint is None:
        samples = DEFAULT_SAMPLES if samples is None else samples
        total = _count(samples, "samples")
    else:
        points = _count(points_per_joint, "points_per_joint")
        total = points**robot.nq
    if total > MAX_CONFIGURATIONS:
        raise InputError(
            f"{total:,} configurations is more than {MAX_CONFIGURATIONS:,} in one map"
        )
    seed = _count(seed, "seed", minimum=0)
    threads = get_core_count() if workers is None else workers
    threads = _count(threads, "workers")
    if robot.nq != robot.nv:
        raise InputError(
            f"{robot.name}: the joint-space map needs one coordinate per joint "
            f"(nq = {robot.nq}, nv = {robot.nv}: a continuous joint)"
        )
    low, high = robot.lower, robot.upper
    if not (np.all(np.isfinite(low)) and np.all(np.isfinite(high))):
        raise InputError(f"{robot.name}: the joint-space map needs finite limits")
    factors: PumaFactorisation | None = find_factorisation(robot)
    start = time.perf_counter()
    compute_jacobians_local(robot, np.zeros((0, robot.nq)))  # chain, kernel loaded
    out = _allocate(total, robot.nq, robot.nv, factors is not None)
    axes = None
    if points_per_joint is not None:
        axes = [
            np.linspace(lo, hi, points_per_joint)
            for lo, hi in zip(low, high, strict=True)
        ]

    def run(chunk: int) -> int:
        begin = chunk * CHUNK
        stop = min(begin + CHUNK, total)
        if axes is None:
            rng = np.random.default_rng([seed, chunk])
            q = rng.uniform(low, high, size=(stop - begin, robot.nq))
        else:
            index = np.unravel_index(np.arange(begin, stop), (len(axes[0]),) * robot.nq)
            q = np.stack([axis[i] for axis, i in zip(axes, index, strict=True)], axis=1)
        _measure(robot, factors, q, {k: v[begin:stop] for k, v in out.items()})
        return stop - begin

    chunks = range(math.ceil(total / CHUNK))
    done = 0
    with ThreadPoolExecutor(max_workers=threads) as pool:
        for future in as_completed([pool.submit(run, c) for c in chunks]):
            done += future.result()
            if progress is not None:
                progress(done, total)
    return JointSpaceMap(
        robot=robot.name,
        q=out["q"],
        sigma_min=out["sigma_min"],
        manipulability=out["manipulability"],
        det_j=out.get("det_j"),
        shoulder=out.get("shoulder"),
        elbow=out.get("elbow"),
        wrist=out.get("wrist"),
        singularity_margin=out.get("singularity_margin"),
        sampling="random" if axes is None else "grid",
        seed=seed if axes is None else None,
        points_per_joint=points_per_joint,
        workers=threads,
        seconds=time.perf_counter() - start,
    )


def _count(value: int, name: str, *, minimum: int = 1) -> int:
    """``value`` as an int >= ``minimum``, else InputError."""
    if (
        isinstance(value, bool)
        or not isinstance(value, int | np.integer)
        or value < minimum
    ):
        kind = "a positive" if minimum == 1 else "a non-negative"
        raise InputError(f"{name} must be {kind} integer, got {value!r}")
    return int(value)


def _allocate(total: int, nq: int, nv: int, factorised: bool) -> dict[str, FloatArray]:
    """The map's arrays, empty: q, sigma_min, manipulability and the optional ones."""
    out: dict[str, FloatArray] = {"q": np.empty((total, nq))}
    names = ["sigma_min", "manipulability"]
    names += ["det_j"] if nv == 6 else []
    names += ["shoulder", "elbow", "wrist", "singularity_margin"] if factorised else []
    out |= {name: np.empty(total) for name in names}
    return out


def _measure(
    robot: Robot,
    factors: PumaFactorisation | None,
    q: FloatArray,
    out: dict[str, FloatArray],
) -> None:
    """Fill the views ``out`` (one chunk of the map's arrays) at configurations q."""
    out["q"][:] = q
    jac = compute_jacobians_local(robot, q)
    sv = compute_singular_values(jac)
    out["sigma_min"][:] = sv[:, -1]
    out["manipulability"][:] = np.prod(sv, axis=1)
    if factors is None:
        if "det_j" in out:
            out["det_j"][:] = np.linalg.det(jac)
        return
    c = compute_conditions(robot, q)
    out["shoulder"][:], out["elbow"][:], out["wrist"][:] = c.shoulder, c.elbow, c.wrist
    out["det_j"][:] = factors.constant * c.shoulder * c.elbow * c.wrist
    out["singularity_margin"][:] = singularity_margin(c.shoulder, c.elbow, c.wrist)
