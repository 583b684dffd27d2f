"""The serial chain of a robot, read from its Pinocchio model, for the compiled IK.

:class:`Chain` packs what the compiled kernels (``_chain_kernel``) need: the
joint placements, axes and kinds of the joints from the base to the tool
frame, the tool frame placement and the joint limits (layout in the
``_chain_kernel`` docstring), plus the first-guess candidates. It also maps
Pinocchio configurations ``q`` (nq,) to chain coordinates (one value per
joint of the chain: an angle for a continuous joint, whose ``q`` is
(cos, sin)) and back. Built once per robot object and cached (see
:func:`get_chain`); rebuilt when the robot's model, limits or tool frame are
replaced.

Supported joints: revolute (any axis, bounded or continuous) and prismatic
(any axis), i.e. every joint a URDF arm has; fixed joints are already merged
into the placements by Pinocchio. Joints off the path to the tool frame (a
tree) keep the values of the reference configuration.
"""

from __future__ import annotations

import itertools
import math
import threading
import weakref
from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench._compiled import get_built, is_interpreting
from workbench.errors import InputError
from workbench.ik import _chain_kernel as kernel
from workbench.model.per_robot import per_robot
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]

#: The weights of a full-pose target (every entry of the error counts); the
#: writable array ``numeric`` passes the kernel (one compiled signature).
FULL_POSE = np.ones(6)

SEED_COUNT = 512
"""Candidate first guesses (mid-range included) when no ``q0`` is given."""

SEED_POOL = 4096
"""Configurations drawn to choose the candidates from (see Chain._build_seeds)."""

SEED_SPREAD = 0.65
"""Candidates lie within this fraction of the half-range (<= pi) of mid-range."""

SEED_ROTATION_WEIGHT = 0.05
"""Weight of the rotation gap against the position gap [m^2] in choosing one."""

SEED_RNG = 20240
"""Fixed seed of the candidates: the first guess is the same in every process."""


class Chain:
    """A robot's chain for the compiled kernels, with its coordinate maps.

    Attributes:
        robot: Weak reference to the robot the chain was read from.
        packed: (n + 1, CHAIN_WIDTH) read-only chain array (``_chain_kernel``).
        n: Number of joints on the path to the tool frame.
        idx_q, idx_v: (n,) where each joint of the chain starts in ``q`` and
            in the tangent vector (the Jacobian's columns).
        identity: True when chain coordinates are ``q`` itself (every joint
            is on the path and has one coordinate), so no mapping is needed.
        lower, upper: (nq,) limits of the robot when the chain was built.
        mid: (nq,) read-only middle of the limits (neutral for continuous
            joints, 0 where unbounded): the default pull reference.
        low, span: (n,) box restarts draw from, chain coordinates.
        seeds: The first-guess candidates: ``features`` (16, SEED_COUNT)
            float32, per candidate (column) 16 numbers whose dot product with
            the row-major target matrix is the squared position gap plus
            SEED_ROTATION_WEIGHT times the squared Frobenius rotation gap, up
            to terms that do not depend on the candidate; and ``starts``
            (SEED_COUNT, n), their coordinates. Read-only.
        no_seeds: The same, empty (when a first guess is given).
        run_inputs: Writable private copies of ``packed``, the mid-range
            chain coordinates and ``seeds``, and ``run_no_seeds`` of
            ``no_seeds``: the arguments :func:`numeric` passes to the kernel.
        run: ``kernel.run`` as :func:`numeric` calls it (see
            :func:`compiled_entry`).
        states: Fresh states of ``kernel.run`` for :func:`numeric`
            (:class:`StateBlocks`).
    """

    def __init__(self, robot: Robot) -> None:
        model = robot.model
        self.robot = weakref.ref(robot)
        self.model, self.frame_id = model, robot.tool_frame_id
        self.lower, self.upper = robot.lower, robot.upper
        frame = model.frames[self.frame_id]
        path = [j for j in model.supports[frame.parentJoint] if j > 0]
        self.n = n = len(path)
        self.idx_q = np.array([model.joints[j].idx_q for j in path], dtype=np.intp)
        self.idx_v = np.array([model.joints[j].idx_v for j in path], dtype=np.intp)
        self.unbounded = np.array([model.joints[j].nq == 2 for j in path])
        self.identity = n == model.nq and np.array_equal(self.idx_q, np.arange(n))
        packed = np.zeros((n + 1, kernel.CHAIN_WIDTH))
        for row, j in zip(packed[:n], path, strict=True):
            _pack_joint(row, model, j, robot.lower, robot.upper)
        _pack_placement(packed[n], frame.placement)
        packed.setflags(write=False)
        self.packed = packed
        mid = _mid_configuration(model, robot.lower, robot.upper)
        mid.setflags(write=False)
        self.mid = mid
        self.mid_values = self.to_chain(mid)
        self.mid_values.setflags(write=False)
        lo, hi = packed[:n, 16], packed[:n, 17]
        self.low = np.where(np.isfinite(lo), lo, -kernel.UNBOUNDED_SPAN)
        self.span = np.where(np.isfinite(hi), hi, kernel.UNBOUNDED_SPAN) - self.low
        self.seeds = self._build_seeds()
        self.no_start = np.empty((0, n))  # "no q0" for the batch kernel
        self.no_start.setflags(write=False)  # as a given q0: one signature
        # The state of a solve before its first run (see _chain_kernel.run).
        self.fresh_state = np.zeros(2 * n + kernel.N_STATS)
        self.fresh_state[2 * n + kernel.ERR2] = math.inf
        self.states = StateBlocks(self.fresh_state)
        # No candidates (when a q0 is given), read-only like the real ones.
        self.no_seeds = (np.empty((16, 0), np.float32), np.empty((0, n)))
        for array in self.no_seeds:
            array.setflags(write=False)
        # The arrays numeric passes to kernel.run (chain, mid-range reference,
        # candidates; no candidates), as private writable copies: should the
        # call go through Numba's dispatcher (see compiled_entry), it types a
        # writable array by a table lookup, a read-only one by a slower path.
        # The kernel takes them as read-only either way and never writes them.
        features, starts = self.seeds
        self.run_inputs = (
            packed.copy(),
            self.mid_values.copy(),
            features.copy(),
            starts.copy(),
        )
        self.run_no_seeds = (np.empty((16, 0), np.float32), np.empty((0, n)))
        # kernel.run's compiled code after the first call (numeric starts its
        # time budget after that call, which compiles or loads the kernel)
        self.run: Any = self._first_run

    def _first_run(self, *args: Any) -> Any:
        """``kernel.run``, then its compiled code for later calls (see ``run``)."""
        result = kernel.run(*args)
        if not is_interpreting():
            self.run = compiled_entry(kernel.run, args)
        return result

    def to_chain(self, q: FloatArray) -> FloatArray:
        """Chain coordinates (..., n) of configurations ``q`` (..., nq); new array."""
        if self.identity:
            return np.array(q)
        values = q[..., self.idx_q]
        if self.unbounded.any():
            sin = q[..., self.idx_q[self.unbounded] + 1]
            values[..., self.unbounded] = np.arctan2(sin, values[..., self.unbounded])
        return values

    def to_configuration(self, values: FloatArray, q_ref: FloatArray) -> FloatArray:
        """Configurations (..., nq) of chain coordinates ``values`` (..., n).

        Coordinates off the chain are copied from ``q_ref`` (nq,) or (..., nq).
        Returns ``values`` itself when the chain is the identity.
        """
        if self.identity:
            return values
        q = np.array(np.broadcast_to(q_ref, (*values.shape[:-1], q_ref.shape[-1])))
        plain = ~self.unbounded
        q[..., self.idx_q[plain]] = values[..., plain]
        angles = values[..., self.unbounded]
        q[..., self.idx_q[self.unbounded]] = np.cos(angles)
        q[..., self.idx_q[self.unbounded] + 1] = np.sin(angles)
        return q

    def _build_seeds(self) -> tuple[npt.NDArray[np.float32], FloatArray]:
        """The first-guess candidates (:attr:`seeds`), read-only.

        SEED_POOL configurations are drawn (mid-range first, then within
        SEED_SPREAD of the half-range around it); SEED_COUNT of them are kept,
        chosen greedily, each the farthest (by the score's metric) from those
        already kept: tool poses spread evenly over the reachable set, rather
        than clustered where the draws happen to cluster, so that the nearest
        candidate is nearer.
        """
        half = np.minimum(0.5 * self.span, kernel.UNBOUNDED_SPAN)
        draws = np.random.default_rng(SEED_RNG).uniform(
            -1.0, 1.0, (SEED_POOL - 1, self.n)
        )
        mid = self.to_chain(self.mid)
        pool = np.vstack((mid, mid + SEED_SPREAD * half * draws))
        np.clip(pool, self.packed[: self.n, 16], self.packed[: self.n, 17], pool)
        # Tool poses by Pinocchio's FK (not the compiled chain's: no compilation
        # for this), as points whose squared distance is the score's metric.
        points = np.empty((SEED_POOL, 12))
        model, data = self.model, self.model.createData()
        weight = math.sqrt(SEED_ROTATION_WEIGHT)
        for point, q in zip(points, self.to_configuration(pool, self.mid), strict=True):
            pin.forwardKinematics(model, data, q)
            pose = pin.updateFramePlacement(model, data, self.frame_id)
            point[:3] = pose.translation
            point[3:] = weight * pose.rotation.ravel()
        kept = _farthest_points(points, SEED_COUNT)
        starts, points = pool[kept], points[kept]
        # Score = |p - t|^2 + w |R - R_t|_F^2 - |t|^2 - 6 w, as dot products with
        # the row-major target matrix (its bottom row: 0, 0, 0, 1).
        features = np.zeros((SEED_COUNT, 4, 4))
        features[:, :3, :3] = (-2.0 * weight) * points[:, 3:].reshape(-1, 3, 3)
        features[:, :3, 3] = -2.0 * points[:, :3]
        features[:, 3, 3] = np.einsum("ij,ij->i", points[:, :3], points[:, :3])
        columns = np.ascontiguousarray(
            features.reshape(SEED_COUNT, 16).T, dtype=np.float32
        )
        columns.setflags(write=False)
        starts.setflags(write=False)
        return columns, starts


def _farthest_points(points: FloatArray, count: int) -> npt.NDArray[np.intp]:
    """Indices of ``count`` rows of ``points`` chosen greedily, farthest first.

    Row 0 first; then each time the row farthest (Euclidean) from those kept.
    Squared distances as |a|^2 + |b|^2 - 2 a.b: one matrix-vector product per
    row kept.
    """
    norm2 = np.einsum("ij,ij->i", points, points)
    kept = np.empty(count, dtype=np.intp)
    kept[0] = 0
    gap2 = norm2 + norm2[0] - 2.0 * (points @ points[0])
    for i in range(1, count):
        kept[i] = j = int(np.argmax(gap2))
        np.minimum(gap2, norm2 + norm2[j] - 2.0 * (points @ points[j]), out=gap2)
    return kept


class StateBlocks:
    """Fresh solve states, each handed out once, in blocks with a read-only view.

    ``numeric`` returns its best configuration as a read-only view of the state
    the kernel wrote. Marking each new state read-only costs a ``setflags`` call
    per solve, about 0.3 µs with warm caches and 3 µs with cold ones, as between
    the solves of a program that does other work, a tenth of a solve; here
    ``BLOCK`` states are allocated, initialised and viewed read-only at once,
    and a state is a row of the block, which the kernel takes with the row's
    index: the one array view a solve makes is its result's.
    Thread-safe: ``next`` on the block's counter is atomic, and a new block is
    made under a lock. A result keeps its block alive (``BLOCK`` states, about
    9 KB for six joints).

    Args:
        fresh: (width,) the state of a solve before its first run.
    """

    BLOCK = 64

    def __init__(self, fresh: FloatArray) -> None:
        self._fresh = fresh
        self._lock = threading.Lock()
        self._block = self._new_block()

    def _new_block(self) -> tuple[FloatArray, FloatArray, itertools.count[int]]:
        writable = np.empty((self.BLOCK, self._fresh.shape[0]))
        writable[:] = self._fresh
        read_only = writable.view()
        read_only.setflags(write=False)
        return writable, read_only, itertools.count()

    def take(self) -> tuple[FloatArray, FloatArray, int]:
        """A fresh state: ``(block, read-only view of it, row)``.

        Row ``row`` of the (BLOCK, width) C-contiguous ``block`` is the state,
        handed out to this caller only; the caller indexes it (an array view
        per solve would cost what the blocks save).
        """
        while True:
            block = self._block
            i = next(block[2])
            if i < self.BLOCK:
                return block[0], block[1], i
            with self._lock:  # used up: one thread makes the next block
                if self._block is block:
                    self._block = self._new_block()


def compiled_entry(dispatcher: Callable[..., Any], args: tuple[Any, ...]) -> Any:
    """The compiled code of ``dispatcher`` for arguments of the types of ``args``.

    Numba's dispatcher types every argument of every call to choose the
    compiled code to run: for the eleven of ``kernel.run``, about 0.6 µs of a
    call from Python when caches are warm and 2.5 µs when they are not (e.g.
    between calls of other code), a third of the cost of a call that takes no
    step. The entry point it would choose can be called directly, with
    arguments of exactly the dtypes, dimensions and layouts of its one
    signature (it does not check them): ``numeric`` passes only such arrays
    (float64, or the candidates' float32, all C-contiguous) and Python float,
    int and bool scalars.

    Returns:
        That entry point, if the dispatcher has compiled exactly one signature
        and ``args`` match it; else the dispatcher itself.
    """
    built = get_built(dispatcher)  # None: not compiled (nor Numba imported) yet
    signatures = getattr(built, "signatures", None)  # none without JIT
    if not signatures or len(signatures) != 1 or len(signatures[0]) != len(args):
        return dispatcher
    import numba

    for expected, value in zip(signatures[0], args, strict=True):
        actual = numba.typeof(value)
        if isinstance(expected, numba.types.Array):
            if not (
                isinstance(actual, numba.types.Array)
                and actual.dtype == expected.dtype
                and actual.ndim == expected.ndim
                and actual.layout == "C"
                and expected.layout in ("C", "A")
            ):
                return dispatcher
        elif numba.types.unliteral(actual) != expected:
            return dispatcher
    return built.get_overload(signatures[0])


def _pack_placement(row: FloatArray, placement: pin.SE3) -> None:
    row[0:9] = placement.rotation.ravel()
    row[9:12] = placement.translation


def _pack_joint(
    row: FloatArray, model: pin.Model, j: int, lower: FloatArray, upper: FloatArray
) -> None:
    """Fill the chain row of joint ``j``; raise if it is no revolute/prismatic joint."""
    joint = model.joints[j]
    kind = joint.shortname()
    motion = None
    if joint.nv == 1 and "Mimic" not in kind and "Helical" not in kind:
        data = joint.createData()
        joint.calc(data, pin.neutral(model)[joint.idx_q : joint.idx_q + joint.nq])
        motion = np.array(data.S).ravel()
    linear = angular = 0.0
    if motion is not None:
        linear = float(np.linalg.norm(motion[:3]))
        angular = float(np.linalg.norm(motion[3:]))
    if "Mimic" in kind:
        leader = next(
            i for i, k in enumerate(model.joints) if k.nv and k.idx_q == joint.idx_q
        )
        raise InputError(
            f"numerical IK does not support mimic joints: joint {model.names[j]!r} "
            f"follows {model.names[leader]!r}"
        )
    if motion is None or (linear > 0.0) == (angular > 0.0):
        raise InputError(
            f"numerical IK supports revolute, continuous and prismatic joints; "
            f"joint {model.names[j]!r} is a {kind}"
        )
    _pack_placement(row, model.jointPlacements[j])
    revolute = angular > 0.0
    row[12:15] = motion[3:] / angular if revolute else motion[:3] / linear
    row[15] = kernel.REVOLUTE if revolute else kernel.PRISMATIC
    aligned = np.flatnonzero(np.abs(row[12:15]) == 1.0)
    row[19] = aligned[0] if revolute and aligned.size == 1 else -1
    if joint.nq == 2:  # continuous: (cos, sin)
        row[16], row[17], row[18] = -math.inf, math.inf, kernel.WRAP_UNBOUNDED
        return
    lo, hi = lower[joint.idx_q], upper[joint.idx_q]
    row[16], row[17] = lo, hi
    full_turn = revolute and hi - lo >= 2.0 * math.pi
    row[18] = kernel.WRAP_FULL_TURN if full_turn else kernel.WRAP_NONE


def _mid_configuration(
    model: pin.Model, lower: FloatArray, upper: FloatArray
) -> FloatArray:
    """Middle of the limits; neutral for multi-coordinate joints, 0 if unlimited."""
    mid = 0.5 * (lower + upper)
    if model.nq != model.nv:
        neutral = pin.neutral(model)
        for joint in model.joints[1:]:
            if joint.nq != 1:
                span = slice(joint.idx_q, joint.idx_q + joint.nq)
                mid[span] = neutral[span]
    if not math.isfinite(mid.sum()):
        mid[~np.isfinite(mid)] = 0.0
    return mid


@per_robot
def get_chain(robot: Robot) -> Chain:
    """The :class:`Chain` of ``robot``, cached per robot object (weakly).

    Rebuilt when the robot's model, limits or tool frame were replaced.

    Raises:
        InputError: If a joint on the path to the tool frame is neither
            revolute nor prismatic.
    """
    return Chain(robot)
