"""Kang's fish-cutting program (2007, Fig. 7): poses, parameters, primitives.

The scene is Kang's world frame (z up; the robot base :data:`KANG_BASE_HEIGHT`
above the origin). The program is the list of motion primitives that
:func:`workbench.tasks.fish_cutting.run_fish_cutting` executes online; see
that module for the sequence.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InfeasibleError
from workbench.ik.closed_form import analytic, nearest
from workbench.model.robot import Robot
from workbench.planning.cartesian_paths import CartesianLimits
from workbench.planning.motion_primitives import (
    MotionPrimitive,
    PointToPoint,
    SemiCircleUp,
    StraightLine,
)
from workbench.tasks.cuts import HorizontalCut, VerticalDownCut
from workbench.tasks.fish import SimulatedFish

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

#: Kang's home pose ``H`` of Fig. 7 (world frame): the wrist centre at
#: (0.4521, -0.1254, 0.24003) m, tool z down; the tip is ``tool_length`` lower.
KANG_HOME_ROTATION = np.diag([1.0, -1.0, -1.0])
KANG_HOME_WRIST_CENTER = np.array([0.4521, -0.1254, 0.24003])
KANG_HOME_ROTATION.setflags(write=False)
KANG_HOME_WRIST_CENTER.setflags(write=False)


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


def get_world_transforms(setup: FishCuttingSetup) -> tuple[pin.SE3, pin.SE3]:
    """``(transform_tip_to_tool, transform_base_to_world)`` of the scene."""
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
    tip, base = get_world_transforms(setup)
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


def compute_home_configuration(robot: Robot, setup: FishCuttingSetup) -> FloatArray:
    """The configuration of Kang's home pose ``H``, nearest zero, within limits.

    For ``puma560-kang`` this is q = 0 (Kang's home); for another PUMA-type
    model it is the same physical pose in that model's joint values, its base
    placed like Kang's (:data:`KANG_BASE_HEIGHT` above the world origin).

    Raises:
        InfeasibleError: If ``H`` has no IK solution within the limits.
    """
    _, base = get_world_transforms(setup)
    wrist = pin.SE3(KANG_HOME_ROTATION, KANG_HOME_WRIST_CENTER)
    target = base.inverse() * wrist
    zero = np.zeros(robot.nq)
    within = [s for s in analytic(robot, target, q_previous=zero) if s.within_limits]
    if not within:
        raise InfeasibleError(
            f"{robot.name}: Kang's home pose H has no IK solution within the limits"
        )
    return nearest(within, zero).q.copy()


__all__ = [
    "KANG_BASE_HEIGHT",
    "KANG_HOME_ROTATION",
    "KANG_HOME_WRIST_CENTER",
    "KANG_START_POSITION",
    "KANG_START_ROTATION",
    "FishCuttingSetup",
    "build_program",
    "check_waypoints",
    "compute_home_configuration",
    "compute_waypoints",
    "get_world_transforms",
]
