r"""Kang's fish-cutting program (2007, Fig. 7) on a simulated fish, planned online.

The program, in the world frame of Fig. 7 (z up, the robot base
:data:`KANG_BASE_HEIGHT` above the world origin), with the fish stations
``S_0 .. S_{n-1}`` along the backbone (``S_0`` is Kang's start pose ``A``)::

    PointToPoint(H -> S_0)                        # PTP(H, A)
    for each station i:
        VerticalDownCut(bone guess, retreat)      # VerticalDownCut(A, Ab, Ah, vi)
        StraightLine(-> S_i, end_at_speed)        # StraightLine(Ab, A, 0, 1)
        SemiCircleUp(-> S_i+1)                    # SemiCircleUp(A, B), not last
    StraightLine(-> above Q), StraightLine(-> Q)  # to the horizontal cut
    HorizontalCut(-> D, end_at_speed)             # HorizontalCut(Q, Dh, 0, 1)
    HorizontalCut(-> C)                           # HorizontalCut(Dh, Ch, 1, 1)
    StraightLine(-> above C), PointToPoint(-> H)  # PTP(A, H)

Every planning cycle the tool tip's commanded position is checked against the
fish (:meth:`SimulatedFish.get_contact`) and the active primitive reacts.
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InfeasibleError
from workbench.ik.closed_form import analytic, nearest
from workbench.robot import Robot
from workbench.tasks.cuts import HorizontalCut, VerticalDownCut
from workbench.tasks.fish import SimulatedFish
from workbench.trajectory.cartesian_paths import CartesianLimits
from workbench.trajectory.motion_primitives import (
    MotionPrimitive,
    PointToPoint,
    SemiCircleUp,
    StraightLine,
)
from workbench.trajectory.online_planner import OnlinePlanner
from workbench.trajectory.servo_interpolation import interpolate_servo
from workbench.trajectory_csv import JointTrajectorySamples

FloatArray = npt.NDArray[np.float64]

#: Height [m] of the robot base frame above Kang's world origin: Fig. 7 puts the
#: home wrist centre at world z = 0.24003 m (``H[2][3] + TOOL_LENGTH``), Table 1
#: at base z = -0.4318 m, so 0.24003 + 0.4318.
KANG_BASE_HEIGHT = 0.67183

#: Kang's start pose ``A`` of Fig. 7 (world frame): tool z down, x along world y.
KANG_START_ROTATION = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
KANG_START_POSITION = np.array([0.0, 0.25, 0.3])
KANG_START_ROTATION.setflags(write=False)
KANG_START_POSITION.setflags(write=False)


@dataclass(frozen=True, slots=True)
class FishCuttingSetup:
    """Parameters of the fish-cutting program (SI units).

    Kang gives the poses ``H`` and ``A`` but not the tool length, speeds or
    rates; the values here are assumptions that keep the PUMA 560 within its
    (assumed) joint speed limits.
    """

    tool_length: float = 0.05  # [m] tool tip beyond the wrist centre, along z6
    max_velocity: float = 0.15  # [m/s]
    max_acceleration: float = 1.0  # [m/s²]
    max_angular_velocity: float = 0.8  # [rad/s]
    max_angular_acceleration: float = 2.0  # [rad/s²]
    cutting_speed_ratio: float = 0.3  # Kang's "speed reducing rate"
    planning_rate: float = 100.0  # [Hz]
    servo_rate: float = 1000.0  # [Hz]
    stations: int = 4
    station_spacing: float = 0.08  # [m] along the fish (>= 2 v² / a for the arcs)
    clearance: float = 0.01  # [m] retreat height above the nominal flesh
    max_cycles: int = 20_000

    @property
    def limits(self) -> CartesianLimits:
        """The Cartesian bounds."""
        return CartesianLimits(
            self.max_velocity,
            self.max_acceleration,
            self.max_angular_velocity,
            self.max_angular_acceleration,
        )

    @property
    def cutting_speed(self) -> float:
        """Speed in the flesh [m/s]."""
        return self.cutting_speed_ratio * self.max_velocity


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
        q, qd: (K, nq) joint commands [rad, rad/s]. damped: (K,) DLS used.
        branch: IK branch per cycle. primitive: Name of the primitive that
            produced each cycle's command. events: Touch events.
        latency_us: (K,) time of each planning cycle [µs].
        servo: Joint commands at the servo rate (Hermite interpolation).
        setup: The parameters. fish: The fish.
    """

    t: FloatArray
    position: FloatArray
    velocity: FloatArray
    q: FloatArray
    qd: FloatArray
    damped: npt.NDArray[np.bool_]
    branch: tuple[str, ...]
    primitive: tuple[str, ...]
    events: tuple[FishEvent, ...]
    latency_us: FloatArray
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
    def wrist_singularity_crossings(self) -> int:
        """Times the IK wrist label changed (no-flip <-> flip): θ5 crossed 0."""
        wrist = [b.rsplit("/", 1)[-1] for b in self.branch]
        return sum(a != b for a, b in itertools.pairwise(wrist))


def _world_to_base(setup: FishCuttingSetup) -> tuple[pin.SE3, pin.SE3]:
    tip = pin.SE3(np.eye(3), np.array([0.0, 0.0, setup.tool_length]))
    base = pin.SE3(np.eye(3), np.array([0.0, 0.0, KANG_BASE_HEIGHT]))
    return tip, base


def compute_waypoints(
    fish: SimulatedFish, setup: FishCuttingSetup
) -> dict[str, FloatArray]:
    """Named program waypoints (3,) [m], world frame, from the *nominal* fish.

    Station ``i`` is ``KANG_START_POSITION`` moved ``i * station_spacing`` along
    y. The bone guess is at the table (below any bone), the retreat point just
    above the nominal flesh; the horizontal cut runs at the nominal backbone
    height, from the last station back to the first.
    """
    a = KANG_START_POSITION
    top = fish.table_z + fish.thickness + setup.clearance
    points: dict[str, FloatArray] = {}
    for i in range(setup.stations):
        s = a + np.array([0.0, i * setup.station_spacing, 0.0])
        points[f"S{i}"] = s
        points[f"S{i}_bone_guess"] = np.array([s[0], s[1], fish.table_z])
        points[f"S{i}_retreat"] = np.array([s[0], s[1], top])
    cut_z = fish.table_z + fish.bone_height
    last, first = points[f"S{setup.stations - 1}"], points["S0"]
    points["Q_above"] = np.array([last[0], last[1], top])
    points["Q"] = np.array([last[0], last[1], cut_z])
    points["D"] = np.array([last[0], 0.5 * (last[1] + first[1]), cut_z])
    points["C"] = np.array([first[0], first[1], cut_z])
    points["C_above"] = np.array([first[0], first[1], top])
    return points


def build_program(
    fish: SimulatedFish, setup: FishCuttingSetup, home: pin.SE3
) -> list[MotionPrimitive]:
    """Kang's Fig. 7 program as primitives (see the module docstring).

    Args:
        fish: The fish (only its nominal sizes are used).
        setup: Program parameters.
        home: Tool-tip home pose ``H``, world frame.
    """
    p = compute_waypoints(fish, setup)
    rot, cut = KANG_START_ROTATION, setup.cutting_speed
    program: list[MotionPrimitive] = [PointToPoint(p["S0"], rot)]
    for i in range(setup.stations):
        s = p[f"S{i}"]
        last = i == setup.stations - 1
        program += [
            VerticalDownCut(
                p[f"S{i}_bone_guess"], p[f"S{i}_retreat"], cutting_speed=cut
            ),
            StraightLine(s, end_at_speed=not last),
        ]
        if not last:
            program.append(SemiCircleUp(p[f"S{i + 1}"]))
    step = cut / setup.planning_rate
    program += [
        StraightLine(p["Q_above"]),
        StraightLine(p["Q"]),
        HorizontalCut(p["D"], cutting_speed=cut, step_height=step, end_at_speed=True),
        HorizontalCut(p["C"], cutting_speed=cut, step_height=step),
        StraightLine(p["C_above"]),
        PointToPoint(home.translation, home.rotation),
    ]
    return program


def check_waypoints(
    robot: Robot, fish: SimulatedFish, setup: FishCuttingSetup, q_home: FloatArray
) -> None:
    """Check every waypoint has an IK solution within the joint limits.

    Raises:
        InfeasibleError: Naming the first waypoint out of reach or limits.
    """
    tip, base = _world_to_base(setup)
    q = q_home
    for name, point in compute_waypoints(fish, setup).items():
        target = base.inverse() * pin.SE3(KANG_START_ROTATION, point) * tip.inverse()
        try:
            solutions = analytic(robot, target, q_previous=q)
        except InfeasibleError as err:
            raise InfeasibleError(f"waypoint {name} {point.tolist()}: {err}") from err
        within = [s for s in solutions if s.within_limits]
        if not within:
            raise InfeasibleError(
                f"waypoint {name} {point.tolist()} [m] has no IK solution within "
                "the joint limits"
            )
        q = nearest(within, q).q


def run_fish_cutting(
    robot: Robot,
    fish: SimulatedFish | None = None,
    setup: FishCuttingSetup | None = None,
    *,
    q_home: npt.ArrayLike | None = None,
) -> FishCuttingResult:
    """Run the fish-cutting program online, cycle by cycle.

    Args:
        robot: A PUMA-type robot (default use: ``puma560-kang``).
        fish: The fish; default ``SimulatedFish(seed=0)``.
        setup: Program parameters; default :class:`FishCuttingSetup`.
        q_home: Start (and end) configuration; default zeros (Kang's home).

    Returns:
        The run: planning-rate commands, events, latencies, servo commands.

    Raises:
        InfeasibleError: A waypoint out of reach or limits, a joint command
            beyond its limits (``JointLimitError``), or a program that does
            not finish within ``setup.max_cycles``.
        InputError: Bad parameters or a robot without closed-form IK.
    """
    fish = fish or SimulatedFish()
    setup = setup or FishCuttingSetup()
    q0 = robot.check_configuration(np.zeros(robot.nq) if q_home is None else q_home)
    check_waypoints(robot, fish, setup, q0)
    tip, base = _world_to_base(setup)
    planner = OnlinePlanner(
        robot,
        q0,
        setup.limits,
        planning_rate=setup.planning_rate,
        servo_rate=setup.servo_rate,
        transform_tip_to_tool=tip,
        transform_base_to_world=base,
    )
    home = pin.SE3(planner.state.rotation, planner.state.position)
    planner.append(*build_program(fish, setup, home))
    first = planner.state
    samples, events, latency, names = [], [], [], []
    clock = time.perf_counter
    contact = None  # what the tool touched at the last commanded pose (the sensor)
    t_last, p_last = 0.0, first.position
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
        q=q,
        qd=qd,
        damped=np.array([False] + [s.damped for s in samples]),
        branch=tuple(s.branch for s in samples[:1] + samples),
        primitive=tuple(names[:1] + names),
        events=tuple(events),
        latency_us=np.array(latency) * 1e6,
        servo=interpolate_servo(t, q, qd, m),
        setup=setup,
        fish=fish,
    )


__all__ = [
    "KANG_BASE_HEIGHT",
    "KANG_START_POSITION",
    "KANG_START_ROTATION",
    "FishCuttingResult",
    "FishCuttingSetup",
    "FishEvent",
    "build_program",
    "check_waypoints",
    "compute_waypoints",
    "run_fish_cutting",
]
