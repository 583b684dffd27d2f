"""Kang's fish-cutting program (2007, Fig. 7): poses, parameters, primitives.

The scene is Kang's world frame (z up; the PUMA's base, which is its
shoulder, :data:`KANG_BASE_HEIGHT` above the origin). The program is the list
of motion primitives that :func:`workbench.tasks.fish_cutting.run_fish_cutting`
executes online; see that module for the sequence.

Any arm with a closed form runs it in Kang's cell scaled to its size: the
cell scale ``s`` (:func:`get_cell_scale`, the arm's reach over the PUMA's,
1 for both PUMA models) multiplies every length of the cell (Kang's poses,
the fish, the table, the tool, the station spacing and clearance) and the
linear speed and acceleration limits (:meth:`FishCuttingSetup.scaled`), and
the arm's shoulder is put where the scaled PUMA's shoulder is
(:func:`get_base_placement`). The tool-tip path is then the PUMA's path
times ``s``, on the same time line.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from workbench.errors import InfeasibleError, InputError
from workbench.ik import (
    get_solver,
    get_structure,
    require_family,
    select,
)
from workbench.model.robot import Robot
from workbench.planning.cartesian_paths import CartesianLimits
from workbench.planning.motion_primitives import (
    MotionPrimitive,
    PointToPoint,
    SemiCircleUp,
    StraightLine,
)
from workbench.tasks.cuts import HorizontalCut, VerticalDownCut
from workbench.tasks.fish import SimulatedFish, check_scale_factor

FloatArray = npt.NDArray[np.float64]


#: Height [m] of the robot base frame above Kang's world origin: Fig. 7 puts the
#: home wrist centre at world z = 0.24003 m (``H[2][3] + TOOL_LENGTH``), Table 1
#: at base z = -0.4318 m, so 0.24003 + 0.4318. The PUMA's base frame is its
#: shoulder; another arm's shoulder goes ``scale`` times this high
#: (:func:`get_base_placement`).
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

#: Reach [m] of Kang's PUMA (Table 1), as :func:`get_arm_reach` measures it:
#: upper arm a2 plus forearm sqrt(a3² + d4²), shoulder axis to wrist centre.
KANG_REACH = 0.4318 + math.hypot(0.0203, 0.4318)

#: Distance [m] from the shoulder of Kang's PUMA to its wrist centre at the
#: start pose ``A`` (the wrist centre 0.05 m, the default tool length, above
#: ``A``): about the nearest the program brings them (the arcs between the
#: stations come about 1 % nearer).
KANG_START_FOLD = math.hypot(KANG_START_POSITION[1], KANG_BASE_HEIGHT - 0.35)

#: Margin [rad] that a seven-axis arm's elbow (joint 4) keeps inside its
#: limits at Kang's start pose, which sets its smallest cell scale
#: (:func:`get_cell_scale`).
FOLD_MARGIN = 0.1

#: The cell scale is rounded to this many decimals (1 %): models of one arm
#: whose lengths differ by a fraction of a millimetre (the two PUMA tables:
#: a3 = 20.3 mm and 19.05 mm) share one cell, exactly Kang's.
CELL_SCALE_DECIMALS = 2


@dataclass(frozen=True, slots=True)
class FishCuttingSetup:
    """Parameters of the fish-cutting program (SI units).

    Kang gives the poses ``H`` and ``A`` but not the tool length, speeds or
    rates; the values here are assumptions that keep the PUMA 560 within its
    (assumed) joint speed limits. The defaults are Kang's cell (``scale`` 1);
    :meth:`scaled` gives the cell of another arm (:func:`get_cell_scale`).

    ``scale`` multiplies Kang's poses ``A`` and ``H`` and the shoulder height
    :data:`KANG_BASE_HEIGHT`; the other lengths and the linear limits are
    held as they are used, already scaled. The semicircles between stations
    need ``station_spacing >= 2 max_velocity² / max_acceleration`` (radius
    above v² / a); scaling keeps it, since both sides scale by the factor.

    Raises:
        InputError: If ``scale`` is not a positive finite number.
    """

    tool_length: float = 0.05  # [m] tool tip beyond the tool frame, along its z
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
    scale: float = 1.0  # cell size over Kang's PUMA cell (get_cell_scale)

    def __post_init__(self) -> None:
        check_scale_factor(self.scale, "setup scale")

    def scaled(self, factor: float) -> FishCuttingSetup:
        """The setup of a cell ``factor`` times as large (``scale`` multiplied).

        Lengths (tool length, station spacing, clearance) and the linear
        speed and acceleration limits are multiplied by ``factor``; angular
        limits, rates and the cycle budget are kept. Times are unchanged: the
        tool-tip path is the same path, ``factor`` times larger.

        Raises:
            InputError: If ``factor`` is not a positive finite number.
        """
        f = check_scale_factor(factor, "cell scale")
        return dataclasses.replace(
            self,
            tool_length=f * self.tool_length,
            max_velocity=f * self.max_velocity,
            max_acceleration=f * self.max_acceleration,
            station_spacing=f * self.station_spacing,
            clearance=f * self.clearance,
            scale=f * self.scale,
        )

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


def get_arm_reach(robot: Robot) -> float:
    """Reach [m] of an arm: shoulder axis to wrist point, arm stretched.

    The wrist point is where the last wrist axes meet: the wrist centre of an
    OPW arm (axes 4, 5, 6), the point of axes 5 and 6 of a UR arm. Its
    largest distance from axis 2, in the plane normal to axis 2, is, with
    ``a_k``, ``d_k`` of DH row k (1-based) of the fitted table
    (:attr:`workbench.ik.Family.reach`):

    * OPW: ``|a2| + hypot(a3, d4)`` (upper arm, then elbow to wrist centre);
    * UR: ``|a2| + |a3| + |d5|`` (upper arm, forearm, then wrist 1 to the
      wrist point, which joint 4 turns into line with them).

    Offsets along axis 2 (the PUMA's d3, the UR's d4) and the flange length
    are left out, as in the makers' "reach to the wrist point". A seven-axis
    arm (SRS, Franka) reaches from its shoulder point S (axes 1, 2, 3 meet)
    to its wrist point (axes 5 and 6 meet), both segments normal to axis 4,
    which stretches them into line: ``hypot(a3, d3) + hypot(a4, d5)``
    (``d3 + d5`` for an SRS arm, whose offsets a3, a4 are zero).

    Raises:
        UnsupportedRobotError: If the robot has no closed-form IK.
    """
    return require_family(robot).reach(get_structure(robot).table)


def get_shortest_fold(robot: Robot) -> float:
    """Shortest distance [m] from shoulder to wrist point of a seven-axis arm.

    The distance from S (axes 1, 2, 3 meet) to the wrist point (axes 5 and 6
    meet) depends on joint 4 alone: on the fitted DH chain, with θ = θ4 −
    θ0_4, ``|SW|² = A + C cos θ + D sin θ`` (rows 3 to 5), minimised exactly
    over joint 4's limits narrowed by :data:`FOLD_MARGIN` on each side.

    Raises:
        UnsupportedRobotError: If the robot has no closed-form IK.
        InputError: If it is not a seven-axis arm.
    """
    if not require_family(robot).redundant:
        raise InputError(f"robot {robot.name!r} is not a seven-axis arm")
    structure = get_structure(robot)

    def fold2(theta: float) -> float:
        x = np.zeros(7)
        x[3] = theta
        links = structure.table.link_transforms(x)
        return float(np.sum((links[2] @ links[3] @ links[4])[:3, 3] ** 2))

    zero, half, full = fold2(0.0), fold2(0.5 * math.pi), fold2(math.pi)
    a, c = 0.5 * (zero + full), 0.5 * (zero - full)
    d = half - a
    sign = structure.joint_sign[3]
    ends = sorted(
        [
            sign * (robot.lower[3] + FOLD_MARGIN),
            sign * (robot.upper[3] - FOLD_MARGIN),
        ]
    )
    best = math.atan2(-d, -c)  # where A + C cos + D sin is least
    best += 2.0 * math.pi * math.ceil((ends[0] - best) / (2.0 * math.pi))
    thetas = [*ends, best] if best <= ends[1] else ends
    return math.sqrt(min(a + c * math.cos(t) + d * math.sin(t) for t in thetas))


def get_cell_scale(robot: Robot) -> float:
    """Scale of Kang's cell for ``robot``: its reach over the PUMA's.

    ``round(get_arm_reach(robot) / KANG_REACH, 2)``: 1.0 for both PUMA
    models, 0.63 for the UR3, 1.06 for the UR5, 1.5 for the UR10, 0.79 for
    the KUKA KR 6 R700, 1.7 for the ABB IRB 2400 (the table in
    ``docs/closed-form-ik.md``, section 6). A seven-axis arm's cell is at
    least so large that its wrist point, as near its shoulder as the PUMA's
    at Kang's start pose (:data:`KANG_START_FOLD` times the scale), leaves
    joint 4 :data:`FOLD_MARGIN` inside its limits
    (``get_shortest_fold / KANG_START_FOLD``): 0.83 for the Panda (its reach),
    1.09 for the iiwa14 (its elbow folds to ±120° only; reach 0.95). The arcs
    between stations bring the wrist a little nearer than ``A`` (the iiwa14's
    elbow keeps 0.05 rad at the top of the first).

    Raises:
        UnsupportedRobotError: If the robot has no closed-form IK.
    """
    ratio = get_arm_reach(robot) / KANG_REACH
    if require_family(robot).redundant:
        ratio = max(ratio, get_shortest_fold(robot) / KANG_START_FOLD)
    return round(ratio, CELL_SCALE_DECIMALS)


def get_base_placement(robot: Robot, setup: FishCuttingSetup) -> pin.SE3:
    """Pose of the robot's base frame in Kang's world frame (scaled cell).

    The arm's shoulder, the point of axis 1 level with axis 2 (DH frame 0
    moved ``d1`` along axis 1), is put where the PUMA's shoulder is in the
    scaled cell: ``setup.scale * KANG_BASE_HEIGHT`` above the world origin,
    axis 1 vertical, DH frame 0's x along the world x. Arms differ in where
    their base frame is: the PUMA's is its shoulder; a UR's ``base_link`` is
    d1 below it, the KUKA KR 6 R700's 0.4 m below (axis 2 a further 25 mm
    out, a1). For the PUMA models this is ``KANG_BASE_HEIGHT`` straight up.

    A seven-axis arm's tool frame is far beyond its wrist point (the iiwa14's
    flange 0.126 m, the Panda's hand TCP 0.210 m), where the PUMA's is the
    wrist centre itself: its shoulder goes that much higher (``d7`` plus the
    tool frame's offset along axis 7), so that with the tool pointing down,
    as in every pose of the program, its wrist point moves as the scaled
    PUMA's wrist centre relative to the shoulder (the Panda's wrist point,
    where axes 5 and 6 meet, is a further a6 = 0.088 m aside of axis 7).

    Raises:
        UnsupportedRobotError: If the robot has no closed-form IK.
    """
    structure = get_structure(robot)
    height = setup.scale * KANG_BASE_HEIGHT - structure.table.joints[0].d
    if require_family(robot).redundant:
        height += structure.table.joints[6].d + structure.tool[2, 3]
    frame0 = pin.SE3(np.eye(3), np.array([0.0, 0.0, height]))  # in the world
    return frame0 * pin.SE3(structure.base).inverse()


def get_world_transforms(
    robot: Robot, setup: FishCuttingSetup
) -> tuple[pin.SE3, pin.SE3]:
    """``(transform_tip_to_tool, transform_base_to_world)`` of the scene.

    The tool tip is ``setup.tool_length`` along z of the robot's tool frame
    (the wrist centre of the PUMA models, the flange of the others); the
    base is placed by :func:`get_base_placement`.
    """
    tip = pin.SE3(np.eye(3), np.array([0.0, 0.0, setup.tool_length]))
    return tip, get_base_placement(robot, setup)


def compute_waypoints(
    fish: SimulatedFish, setup: FishCuttingSetup
) -> dict[str, FloatArray]:
    """Named program waypoints (3,) [m], world frame, from the *nominal* fish.

    Station ``i`` is ``setup.scale * KANG_START_POSITION`` moved
    ``i * station_spacing`` along y. The bone guess is at the table (below any
    bone), the retreat point just above the nominal flesh; the horizontal cut
    runs at the nominal backbone height, from the last station back to the
    first.
    """
    a = setup.scale * KANG_START_POSITION
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
        # Fig. 7: HorizontalCut(Q, Dh, 0, 1); HorizontalCut(Dh, Ch, 1, 1): both end
        # at the cutting speed (the flags; the second line's comment is a slip,
        # docs/errata-kang-orientation.md item 5). The lift then slows the
        # horizontal velocity to zero.
        HorizontalCut(p["D"], cutting_speed=cut, step_height=step, end_at_speed=True),
        HorizontalCut(p["C"], cutting_speed=cut, step_height=step, end_at_speed=True),
        StraightLine(p["C_above"]),
        PointToPoint(home.translation, home.rotation),
    ]
    return program


def is_redundant(robot: Robot) -> bool:
    """True for a seven-axis arm of a family with a closed form (SRS, Franka).

    Raises:
        UnsupportedRobotError: If the robot has no closed-form IK.
    """
    return require_family(robot).redundant


def check_waypoints(
    robot: Robot, fish: SimulatedFish, setup: FishCuttingSetup, q_home: FloatArray
) -> None:
    """Check every waypoint has an IK solution within the joint limits.

    On a seven-axis arm: on the branch of ``q_home`` (the online planner
    keeps it), for some value of the redundancy parameter
    (``workbench.ik.Solver.feasible``).

    Raises:
        InfeasibleError: Naming the first waypoint out of reach or limits.
    """
    tip, base = get_world_transforms(robot, setup)
    q = q_home
    branch = None  # of q_home, on a seven-axis arm
    if is_redundant(robot):
        value = float(get_solver(robot).parameter_of(q))
        branch = select(robot, robot.fk(q), q_near=q, redundancy=value).branch
    for name, point in compute_waypoints(fish, setup).items():
        target = base.inverse() * pin.SE3(KANG_START_ROTATION, point) * tip.inverse()
        if branch is not None:
            _check_redundant_waypoint(robot, target, branch, f"{name} {point.tolist()}")
            continue
        try:  # the solution within the limits nearest the last one
            q = select(robot, target, q_near=q).q
        except InfeasibleError as err:
            raise InfeasibleError(
                f"waypoint {name} {point.tolist()} [m]: {err}"
            ) from err


def _check_redundant_waypoint(
    robot: Robot, target: pin.SE3, branch: str, name: str
) -> None:
    """A seven-axis arm reaches ``target`` within limits on ``branch``.

    Raises:
        InfeasibleError: Naming the waypoint.
    """
    try:
        feasible = get_solver(robot).feasible(target)
    except InfeasibleError as err:
        raise InfeasibleError(f"waypoint {name}: {err}") from err
    if not feasible.intervals[feasible.branches.index(branch)]:
        raise InfeasibleError(
            f"waypoint {name} [m] has no IK solution within the joint limits on "
            f"the branch {branch} of the home configuration"
        )


def compute_home_configuration(
    robot: Robot, setup: FishCuttingSetup, fish: SimulatedFish | None = None
) -> FloatArray:
    """The configuration of Kang's home pose ``H``, nearest zero, within limits.

    ``H`` scaled: the robot's tool frame at ``setup.scale`` times Kang's wrist
    centre :data:`KANG_HOME_WRIST_CENTER` (world frame), with Kang's
    orientation :data:`KANG_HOME_ROTATION` (tool z down), the base placed by
    :func:`get_base_placement`. For ``puma560-kang`` this is q = 0 (Kang's
    home); for the other PUMA model it is the same physical pose in that
    model's joint values; for another six-axis arm, the IK solution within
    its limits nearest q = 0; for a seven-axis arm, the solution of the
    largest joint-limit margin (``workbench.ik.choose_redundancy``) over the
    values of the redundancy parameter and the branches that reach ``H`` and
    every waypoint of ``fish`` (default the nominal fish of the scaled cell)
    within the limits (the planner keeps the branch).

    Raises:
        InfeasibleError: If ``H`` has no IK solution within the limits.
        UnsupportedRobotError: If the robot has no closed-form IK.
    """
    _, base = get_world_transforms(robot, setup)
    wrist = pin.SE3(KANG_HOME_ROTATION, setup.scale * KANG_HOME_WRIST_CENTER)
    target = base.inverse() * wrist
    if is_redundant(robot):
        return _redundant_home(robot, setup, fish, target)
    try:
        return select(robot, target, q_near=np.zeros(robot.nq)).q.copy()
    except InfeasibleError as err:
        raise InfeasibleError(f"{robot.name}: Kang's home pose H: {err}") from err


def _redundant_home(
    robot: Robot, setup: FishCuttingSetup, fish: SimulatedFish | None, home: pin.SE3
) -> FloatArray:
    """Home of a seven-axis arm: see :func:`compute_home_configuration`."""
    fish = fish or SimulatedFish().scaled(setup.scale)
    tip, base = get_world_transforms(robot, setup)
    targets = [home] + [
        base.inverse() * pin.SE3(KANG_START_ROTATION, point) * tip.inverse()
        for point in compute_waypoints(fish, setup).values()
    ]
    try:
        solver = get_solver(robot)
        feasible = [solver.feasible(target) for target in targets]
    except InfeasibleError as err:
        raise InfeasibleError(
            f"{robot.name}: Kang's cell out of reach ({err})"
        ) from err
    labels = feasible[0].branches
    branches = [
        label for i, label in enumerate(labels) if all(f.intervals[i] for f in feasible)
    ]
    if not branches:
        raise InfeasibleError(
            f"{robot.name}: no branch reaches Kang's home pose H and every waypoint "
            "within the joint limits"
        )
    # per branch the value of largest limit margin (ik.select), the best of them
    choices = [select(robot, home, branch=label) for label in branches]
    scores = [-math.inf if c.score is None else c.score for c in choices]
    return choices[int(np.argmax(scores))].q.copy()  # the first on a tie


__all__ = [
    "CELL_SCALE_DECIMALS",
    "FOLD_MARGIN",
    "KANG_BASE_HEIGHT",
    "KANG_HOME_ROTATION",
    "KANG_HOME_WRIST_CENTER",
    "KANG_REACH",
    "KANG_START_FOLD",
    "KANG_START_POSITION",
    "KANG_START_ROTATION",
    "FishCuttingSetup",
    "build_program",
    "check_waypoints",
    "compute_home_configuration",
    "compute_waypoints",
    "get_arm_reach",
    "get_base_placement",
    "get_cell_scale",
    "get_shortest_fold",
    "get_world_transforms",
    "is_redundant",
]
