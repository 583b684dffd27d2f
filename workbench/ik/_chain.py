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

import math
import weakref

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InputError
from workbench.ik import _chain_kernel as kernel
from workbench.model.robot import Robot

FloatArray = npt.NDArray[np.float64]

SEED_COUNT = 512
"""Candidate first guesses (mid-range included) when no ``q0`` is given."""

SEED_SPREAD = 0.65
"""Candidates lie within this fraction of the half-range (<= pi) of mid-range."""

SEED_ROTATION_WEIGHT = 0.05
"""Weight of the rotation gap against the position gap [m^2] in choosing one."""

SEED_RNG = 20240
"""Fixed seed of the candidates: the first guess is the same in every process."""


class Chain:
    """A robot's chain for the compiled kernels, with its coordinate maps.

    Attributes:
        packed: (n + 1, CHAIN_WIDTH) read-only chain array (``_chain_kernel``).
        n: Number of joints on the path to the tool frame.
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
    """

    def __init__(self, robot: Robot) -> None:
        model = robot.model
        self.model, self.frame_id = model, robot.tool_frame_id
        self.lower, self.upper = robot.lower, robot.upper
        frame = model.frames[self.frame_id]
        path = [j for j in model.supports[frame.parentJoint] if j > 0]
        self.n = n = len(path)
        self.idx_q = np.array([model.joints[j].idx_q for j in path], dtype=np.intp)
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
        # No candidates (when a q0 is given), read-only like the real ones.
        self.no_seeds = (np.empty((16, 0), np.float32), np.empty((0, n)))
        for array in self.no_seeds:
            array.setflags(write=False)
        # Load (or compile) the kernel now, not under a solve's time budget.
        # (Its arguments have the types of every later call: read-only chain,
        # reference and candidates, writable target and state.)
        warm_up = self.fresh_state.copy()
        kernel.run(
            packed, np.eye(4), self.mid_values, warm_up, 0.0, 0, False, *self.no_seeds,
            True,
        )  # fmt: skip

    def matches(self, robot: Robot) -> bool:
        """Whether ``robot`` still has this chain's model, limits and tool frame."""
        return (
            self.model is robot.model
            and self.lower is robot.lower
            and self.upper is robot.upper
            and self.frame_id == robot.tool_frame_id
        )

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
        """The first-guess candidates (:attr:`seeds`), read-only."""
        half = np.minimum(0.5 * self.span, kernel.UNBOUNDED_SPAN)
        draws = np.random.default_rng(SEED_RNG).uniform(
            -1.0, 1.0, (SEED_COUNT - 1, self.n)
        )
        mid = self.to_chain(self.mid)
        starts = np.vstack((mid, mid + SEED_SPREAD * half * draws))
        np.clip(starts, self.packed[: self.n, 16], self.packed[: self.n, 17], starts)
        features = np.zeros((SEED_COUNT, 4, 4))
        # Pinocchio's FK (not the compiled chain's): no compilation for this.
        model, data = self.model, self.model.createData()
        for row, q in zip(
            features, self.to_configuration(starts, self.mid), strict=True
        ):
            pin.forwardKinematics(model, data, q)
            pose = pin.updateFramePlacement(model, data, self.frame_id)
            position = pose.translation
            row[:3, :3] = (-2.0 * SEED_ROTATION_WEIGHT) * pose.rotation
            row[:3, 3] = -2.0 * position
            row[3, 3] = position.dot(position)
        columns = np.ascontiguousarray(
            features.reshape(SEED_COUNT, 16).T, dtype=np.float32
        )
        columns.setflags(write=False)
        starts.setflags(write=False)
        return columns, starts


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


_CHAINS: weakref.WeakKeyDictionary[Robot, Chain] = weakref.WeakKeyDictionary()


def get_chain(robot: Robot) -> Chain:
    """The cached :class:`Chain` of ``robot``, (re)built when stale.

    Raises:
        InputError: If a joint on the path to the tool frame is neither
            revolute nor prismatic.
    """
    chain = _CHAINS.get(robot)
    if chain is None or not chain.matches(robot):
        chain = _CHAINS[robot] = Chain(robot)
    return chain
