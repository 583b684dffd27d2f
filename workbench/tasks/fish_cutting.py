r"""Kang's fish-cutting program (2007, Fig. 7) on a simulated fish, planned online.

The program, in the world frame of Fig. 7 (z up, the PUMA's base
:data:`~workbench.tasks.fish_program.KANG_BASE_HEIGHT` above the world origin;
another arm runs it in the cell scaled to its reach,
:func:`~workbench.tasks.fish_program.get_cell_scale`), with the fish stations
``S_0 .. S_{n-1}`` along the backbone (``S_0`` is Kang's start pose ``A``),
built by :func:`~workbench.tasks.fish_program.build_program`::

    PointToPoint(H -> S_0)                        # PTP(H, A)
    for each station i:
        VerticalDownCut(bone guess, retreat)      # VerticalDownCut(A, Ab, Ah, vi)
        StraightLine(-> S_i, end_at_speed)        # StraightLine(Ab, A, 0, 1)
        SemiCircleUp(-> S_i+1)                    # SemiCircleUp(A, B), not last
    StraightLine(-> above Q), StraightLine(-> Q)  # to the horizontal cut
    HorizontalCut(-> D, end_at_speed)             # HorizontalCut(Q, Dh, 0, 1)
    HorizontalCut(-> C, end_at_speed)             # HorizontalCut(Dh, Ch, 1, 1)
    StraightLine(-> above C), PointToPoint(-> H)  # PTP(A, H)

Every planning cycle the tool tip's commanded position is checked against the
fish (:meth:`SimulatedFish.get_contact`) and the active primitive reacts.

A seven-axis arm (``iiwa14``, ``panda``) starts at the home configuration of
the largest joint-limit margin and runs the program on that branch, its
redundancy parameter moved by the planner's ``redundancy`` policy
(``"keep"`` by default); the result holds the parameter's trace.
"""

from __future__ import annotations

import contextlib
import gc
import itertools
import math
import time
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InfeasibleError
from workbench.model.robot import Robot
from workbench.planning.online_planner import OnlinePlanner
from workbench.planning.redundancy_policy import (
    DEFAULT_MAX_REDUNDANCY_RATE,
    compute_limit_margin,
)
from workbench.planning.servo_interpolation import interpolate_servo
from workbench.tasks.fish import SimulatedFish
from workbench.tasks.fish_program import (
    FishCuttingSetup,
    build_program,
    check_waypoints,
    compute_home_configuration,
    get_cell_scale,
    get_world_transforms,
)
from workbench.trajectory.csv_io import JointTrajectorySamples

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class FishEvent:
    """A touch event the program reacted to.

    Attributes:
        t: Time [s] (planning cycle at which it was detected).
        kind: ``"flesh"`` or ``"bone"``.
        primitive: Name of the primitive that reacted.
        position: Tool-tip position (3,) [m], world frame.
    """

    t: float
    kind: str
    primitive: str
    position: FloatArray


@dataclass(frozen=True, slots=True)
class FishCuttingResult:
    """Everything a run produced; arrays over the K planning cycles.

    Attributes:
        t: (K,) [s]. position, velocity: (K, 3) tool tip, world frame.
        rotation: (K, 3, 3) tool orientation, angular_velocity: (K, 3) [rad/s],
            world frame.
        q, qd: (K, nq) joint commands [rad, rad/s]. damped: (K,) DLS used.
        branch: IK branch per cycle. primitive: Name of the primitive that
            produced each cycle's command. events: Touch events.
        latency_us: Time of each planning cycle [µs], one per cycle (K - 1).
        replanned: Per cycle (as ``latency_us``), True if a new motion was
            planned in it (``PlannerSample.replanned``).
        redundancy: (K,) the redundancy parameter of ``q`` [rad] (ψ or q7) on
            a seven-axis arm, NaN on a six-axis arm.
        redundancy_parameter: ``"arm angle"`` or ``"q7"``; None on a 6R arm.
        redundancy_policy: The planner's policy; None on a 6R arm.
        min_limit_margin: Smallest distance [rad] of a joint command to its
            limit over the run (``compute_limit_margin``).
        servo: Joint commands at the servo rate (Hermite interpolation).
        setup: The parameters. fish: The fish.
    """

    t: FloatArray
    position: FloatArray
    velocity: FloatArray
    rotation: FloatArray
    angular_velocity: FloatArray
    q: FloatArray
    qd: FloatArray
    damped: npt.NDArray[np.bool_]
    branch: tuple[str, ...]
    primitive: tuple[str, ...]
    events: tuple[FishEvent, ...]
    latency_us: FloatArray
    replanned: npt.NDArray[np.bool_]
    redundancy: FloatArray
    redundancy_parameter: str | None
    redundancy_policy: str | None
    min_limit_margin: float
    servo: JointTrajectorySamples
    setup: FishCuttingSetup
    fish: SimulatedFish = field(repr=False)

    @property
    def max_joint_speed(self) -> float:
        """Largest |joint speed| of the servo commands [rad/s]."""
        return float(np.max(np.abs(self.servo.qd)))

    @property
    def wrist_flips(self) -> int:
        """Planning steps where θ4 jumps by more than π/2 (Kang's flip; 0 wanted)."""
        return int(np.count_nonzero(np.abs(np.diff(self.q[:, 3])) > np.pi / 2))

    @property
    def branch_flips(self) -> int:
        """Planning steps where some joint jumps by more than π/2 (0 wanted)."""
        return int(
            np.count_nonzero((np.abs(np.diff(self.q, axis=0)) > np.pi / 2).any(1))
        )

    @property
    def branch_changes(self) -> int:
        """Times the IK branch label changed (continuously, at a singularity)."""
        return sum(a != b for a, b in itertools.pairwise(self.branch))

    @property
    def wrist_singularity_crossings(self) -> int:
        """Times the IK wrist label changed (no-flip <-> flip): θ5 crossed 0."""
        wrist = [b.rsplit("/", 1)[-1] for b in self.branch]
        return sum(a != b for a, b in itertools.pairwise(wrist))


@contextlib.contextmanager
def _cyclic_gc_paused() -> Iterator[None]:
    """Pause Python's cyclic garbage collector, as a real-time loop does.

    The planning cycle makes no reference cycles (reference counting frees
    all it allocates), but the collector, triggered by allocation counts,
    would scan the run's growing sample list inside some cycle (70-150 µs).
    """
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def run_fish_cutting(
    robot: Robot,
    fish: SimulatedFish | None = None,
    setup: FishCuttingSetup | None = None,
    *,
    q_home: npt.ArrayLike | None = None,
    redundancy: str | None = None,
    max_redundancy_rate: float = DEFAULT_MAX_REDUNDANCY_RATE,
) -> FishCuttingResult:
    """Run the fish-cutting program online, cycle by cycle.

    Args:
        robot: An arm with closed-form IK (default use: ``puma560-kang``).
        fish: The fish; default ``SimulatedFish(seed=0).scaled(setup.scale)``.
        setup: Program parameters; default Kang's cell scaled to the arm,
            ``FishCuttingSetup().scaled(get_cell_scale(robot))`` (Kang's
            :class:`FishCuttingSetup` itself for the PUMA models).
        q_home: Start (and end) configuration; default
            :func:`compute_home_configuration` (zeros for ``puma560-kang``).
        redundancy: Seven-axis arms: the planner's redundancy policy
            (``OnlinePlanner(redundancy=...)``, default ``"keep"``).
        max_redundancy_rate: Seven-axis arms: largest rate of the redundancy
            parameter's policy moves [rad/s].

    Returns:
        The run: planning-rate commands, events, latencies, servo commands.

    Raises:
        InfeasibleError: A waypoint out of reach or limits, a joint command
            beyond its limits (``JointLimitError``), or a program that does
            not finish within ``setup.max_cycles``.
        InputError: Bad parameters, a robot without closed-form IK, or a
            redundancy policy for a six-axis arm.
    """
    setup = setup or FishCuttingSetup().scaled(get_cell_scale(robot))
    fish = fish or SimulatedFish().scaled(setup.scale)
    if q_home is None:
        q0 = compute_home_configuration(robot, setup, fish)
    else:
        q0 = robot.check_configuration(q_home)
    check_waypoints(robot, fish, setup, q0)
    tip, base = get_world_transforms(robot, setup)
    planner = OnlinePlanner(
        robot,
        q0,
        setup.limits,
        planning_rate=setup.planning_rate,
        servo_rate=setup.servo_rate,
        transform_tip_to_tool=tip,
        transform_base_to_world=base,
        redundancy=redundancy,
        max_redundancy_rate=max_redundancy_rate,
    )
    start_value = planner.redundancy
    home = pin.SE3(planner.state.rotation, planner.state.position)
    planner.append(*build_program(fish, setup, home))
    first = planner.state
    samples, events, latency, names = [], [], [], []
    clock = time.perf_counter
    contact = None  # what the tool touched at the last commanded pose (the sensor)
    t_last, p_last = 0.0, first.position
    with _cyclic_gc_paused():
        while not planner.done:
            if planner.cycle >= setup.max_cycles:
                raise InfeasibleError(
                    f"the program did not finish within {setup.max_cycles} cycles"
                )
            reacting = type(planner.active).__name__
            start = clock()  # one planning cycle: react (replan), then step
            kind = planner.notify(contact)
            sample = planner.step()
            latency.append(clock() - start)
            if kind is not None:  # a reaction to the state commanded last cycle
                events.append(FishEvent(t_last, kind, reacting, p_last.copy()))
            samples.append(sample)
            names.append(type(planner.active).__name__)
            contact = fish.get_contact(sample.position)
            t_last, p_last = sample.t, sample.position
    t = np.array([0.0] + [s.t for s in samples])
    q = np.array([q0] + [s.q for s in samples])
    qd = np.array([np.zeros(robot.nv)] + [s.qd for s in samples])
    m = round(setup.servo_rate / setup.planning_rate)
    return FishCuttingResult(
        t=t,
        position=np.array([first.position] + [s.position for s in samples]),
        velocity=np.array([first.velocity] + [s.velocity for s in samples]),
        rotation=np.array([first.rotation] + [s.rotation for s in samples]),
        angular_velocity=np.array(
            [first.angular_velocity] + [s.angular_velocity for s in samples]
        ),
        q=q,
        qd=qd,
        damped=np.array([False] + [s.damped for s in samples]),
        branch=tuple(s.branch for s in samples[:1] + samples),
        primitive=tuple(names[:1] + names),
        events=tuple(events),
        latency_us=np.array(latency) * 1e6,
        replanned=np.array([s.replanned for s in samples]),
        redundancy=np.array(
            [math.nan if start_value is None else start_value]
            + [s.redundancy for s in samples]
        ),
        redundancy_parameter=planner.redundancy_parameter,
        redundancy_policy=planner.redundancy_policy,
        min_limit_margin=min(
            compute_limit_margin(row, robot.lower, robot.upper) for row in q
        ),
        servo=interpolate_servo(t, q, qd, m),
        setup=setup,
        fish=fish,
    )


def summarize_fish_cutting(result: FishCuttingResult, robot_name: str) -> dict:
    """JSON-ready summary of a run (the keys of ``workbench fishcut --json``)."""
    latency = result.latency_us
    setup = result.setup
    return {
        "robot": robot_name,
        "scale": setup.scale,
        "cycles": len(result.t) - 1,
        "servo_rate_hz": setup.servo_rate,
        "planning_rate_hz": setup.planning_rate,
        "duration": float(result.t[-1]),
        "events": [
            {"t": e.t, "kind": e.kind, "primitive": e.primitive, "position": e.position}
            for e in result.events
        ],
        "latency_us": {
            "median": float(np.median(latency)),
            "p99": float(np.percentile(latency, 99)),
        },
        "max_joint_speed": result.max_joint_speed,
        "wrist_flips": result.wrist_flips,
        "wrist_singularity_crossings": result.wrist_singularity_crossings,
        "dls_cycles": int(np.count_nonzero(result.damped)),
        "seed": result.fish.seed,
        "servo_samples": len(result.servo.t),
        "branch_flips": result.branch_flips,
        "redundancy": summarize_redundancy(result),
    }


def summarize_redundancy(result: FishCuttingResult) -> dict | None:
    """The redundancy trace of a seven-axis run (``redundancy`` in the JSON).

    Returns:
        None on a six-axis arm; else ``parameter`` (``"arm angle"`` or
        ``"q7"``), ``policy``, the parameter's ``start``, ``end``, ``min``,
        ``max`` [rad] (ψ's trace unwrapped: continuous across ±π, from its
        start in (−π, π]), ``travel`` (the sum of its steps' sizes) [rad],
        ``max_rate`` [rad/s], ``moving_cycles`` (cycles that changed it),
        ``branch`` (the label, or the labels in order if it changed),
        ``branch_changes`` and ``min_limit_margin`` [rad] (the smallest
        distance of a joint command to its limit over the run).
    """
    if result.redundancy_parameter is None:
        return None
    values = result.redundancy
    if result.redundancy_parameter == "arm angle":
        values = np.unwrap(values)
    steps = np.diff(values)
    period = 1.0 / result.setup.planning_rate
    labels = [result.branch[0]] + [
        b for a, b in itertools.pairwise(result.branch) if a != b
    ]
    return {
        "parameter": result.redundancy_parameter,
        "policy": result.redundancy_policy,
        "start": float(values[0]),
        "end": float(values[-1]),
        "min": float(values.min()),
        "max": float(values.max()),
        "travel": float(np.abs(steps).sum()),
        "max_rate": float(np.abs(steps).max() / period) if len(steps) else 0.0,
        "moving_cycles": int(np.count_nonzero(steps)),
        "branch": labels[0] if len(labels) == 1 else labels,
        "branch_changes": result.branch_changes,
        "min_limit_margin": result.min_limit_margin,
    }


__all__ = [
    "FishCuttingResult",
    "FishEvent",
    "run_fish_cutting",
    "summarize_fish_cutting",
]
