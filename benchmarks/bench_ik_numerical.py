"""Benchmark numerical IK: ``workbench.ik.numeric`` against peer solvers.

Targets are the tool poses of configurations drawn uniformly within the joint
limits (so every target is reachable). A solve succeeds when the pose error of
the returned q, measured with Pinocchio's FK of the same URDF, is <= 1e-9 m and
<= 1e-9 rad and q is within the position limits (1e-9 rad slack for peers).

Peers, each used as its documentation suggests, run only when importable:

* Robotics Toolbox for Python: ``ETS.ik_LM`` (C++) and ``ETS.ikine_LM``, with
  tolerance ``tol = 1e-19`` on their residual ``E = e.e / 2`` (so |e| < 4.5e-10);
* ikpy: ``Chain.inverse_kinematics`` with ``orientation_mode="all"``;
* pink (pin-pink): differential IK iterated (``solve_ik`` with dt = 1, OSQP)
  until |e| <= 1e-10 or 100 steps, from mid-range; it has no restarts.

Also listed: TRAC-IK's published figure for the Franka Emika Panda (it has none
for the PUMA 560 or the UR5): 99.70 % success, 0.38 ms average solve time, from
the table "IK success and average speed" of the TRAC-IK README (TRAC-IK tag
v1.4.6, Speed mode; 10,000 random reachable configurations, tolerance 1e-5 per
Cartesian axis, 5 ms timeout, seeded from mid-range), not run here and not the
same tolerance (1e-5, not 1e-9) nor the same statistic (mean, not median):
https://bitbucket.org/traclabs/trac_ik (README.md, "Some sample results").

Peers load a copy of the URDF without meshes. Solvers take turns on chunks of
25 targets, so that machine load hits all of them alike. Times are CPU time of
this process per call from Python (``time.process_time_ns``), including the
target validation of ``numeric``, so that other jobs on a shared machine
inflate them less than wall time would; a reference loop, ``sum(range(1000))``,
is timed the same way to calibrate the machine.

Further sections: ``numeric_batch`` throughput (targets per CPU second, one
core); the first ``numeric`` call in a fresh process with an empty Numba cache
and with a warm one (compilation and cache loading); the overhead of
``Robot.fk`` / ``Robot.jacobian`` over the Pinocchio calls underneath. Usage::

    python benchmarks/bench_ik_numerical.py [--targets 1000] [--slow-targets 100]

(``--slow-targets 0`` leaves the slow peers out.)
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import math
import os
import subprocess
import sys
import tempfile
import time
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin

from workbench import Robot, load_robot
from workbench.ik import numeric, numeric_batch

ATOL = 1e-9  # [m] and [rad]
ROBOTS = ("puma560", "ur5", "panda")

Solver = Callable[[pin.SE3, int], np.ndarray]


def kinematic_urdf(robot: Robot, folder: Path) -> Path:
    """Copy of the robot's URDF without visual/collision elements."""
    tree = ET.parse(robot.urdf_path)
    for link in tree.getroot().iter("link"):
        for tag in ("visual", "collision"):
            for element in link.findall(tag):
                link.remove(element)
    path = folder / f"{robot.name}.urdf"
    tree.write(path)
    return path


def chain_elements(path: Path, tip: str) -> list[str]:
    """[root link, joint, link, ..., tip] along the URDF tree (for ikpy)."""
    parent_of = {}
    for joint in ET.parse(path).getroot().findall("joint"):
        child = joint.find("child").get("link")
        parent_of[child] = (joint.get("name"), joint.find("parent").get("link"))
    elements = [tip]
    while elements[-1] in parent_of:
        elements += parent_of[elements[-1]]
    return elements[::-1]


class Ours:
    """``numeric`` with the default first guess; keeps its last result."""

    def __init__(self, robot: Robot, _: Path):
        self.robot = robot
        self.last = None

    def __call__(self, target: pin.SE3, seed: int) -> np.ndarray:
        self.last = numeric(self.robot, target, rng=seed)
        return self.last.q


def rtb_solvers(robot: Robot, urdf: Path) -> dict[str, Solver]:
    import roboticstoolbox as rtb

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ets = rtb.Robot.URDF(str(urdf)).ets(end=robot.tool_frame)

    def ik_lm(target: pin.SE3, _: int) -> np.ndarray:
        return ets.ik_LM(target.homogeneous, tol=1e-19).q

    def ikine_lm(target: pin.SE3, seed: int) -> np.ndarray:
        return ets.ikine_LM(target.homogeneous, tol=1e-19, seed=seed).q

    return {"RTB ik_LM (C++)": ik_lm, "RTB ikine_LM": ikine_lm}


def ikpy_solver(robot: Robot, urdf: Path) -> Solver:
    import ikpy.chain

    elements = chain_elements(urdf, robot.tool_frame)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        chain = ikpy.chain.Chain.from_urdf_file(str(urdf), base_elements=elements)
        active = [link.joint_type != "fixed" for link in chain.links]
        chain = ikpy.chain.Chain.from_urdf_file(
            str(urdf), base_elements=elements, active_links_mask=active
        )
    mask = np.array(active)

    def solve(target: pin.SE3, _: int) -> np.ndarray:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            full = chain.inverse_kinematics(
                target.translation, target.rotation, orientation_mode="all"
            )
        return full[mask]

    return solve


def pink_solver(robot: Robot, _: Path) -> Solver:
    import pink
    from pink.tasks import FrameTask

    model = pin.Model(robot.model)  # pink may annotate its model: use a copy
    data = model.createData()
    start = 0.5 * (robot.lower + robot.upper)

    def solve(target: pin.SE3, _: int) -> np.ndarray:
        task = FrameTask(robot.tool_frame, position_cost=1.0, orientation_cost=1.0)
        task.set_target(target)
        configuration = pink.Configuration(model, data, start)
        for _step in range(100):
            if np.linalg.norm(task.compute_error(configuration)) <= 1e-10:
                break
            velocity = pink.solve_ik(
                configuration, [task], dt=1.0, solver="osqp", safety_break=False
            )
            configuration.integrate_inplace(velocity, 1.0)
        return configuration.q

    return solve


def pose_ok(robot: Robot, q: np.ndarray, target: pin.SE3) -> bool:
    q = np.asarray(q, dtype=float)
    if q.shape != (robot.nq,) or not np.all(np.isfinite(q)):
        return False
    if np.any(q < robot.lower - ATOL) or np.any(q > robot.upper + ATOL):
        return False
    pose = robot.fk(np.clip(q, robot.lower, robot.upper))
    position = np.linalg.norm(pose.translation - target.translation)
    rotation = np.linalg.norm(pin.log3(pose.rotation.T @ target.rotation))
    return bool(position <= ATOL and rotation <= ATOL)


@contextlib.contextmanager
def quiet():
    """Silence peers' warnings and log lines during their calls."""
    logging.disable(logging.CRITICAL)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            yield
        finally:
            logging.disable(logging.NOTSET)


def build_solvers(
    robot: Robot, urdf: Path, peers: bool
) -> tuple[dict[str, Solver], list[str]]:
    solvers = {"workbench numeric": Ours(robot, urdf)}
    notes = []
    for label, factory in (
        ()
        if not peers
        else (
            ("RTB", rtb_solvers),
            ("ikpy", ikpy_solver),
            ("pink", pink_solver),
        )
    ):
        try:
            with quiet():
                built = factory(robot, urdf)
        except Exception as err:  # optional peers: report, carry on
            notes.append(f"{label} unavailable for {robot.name}: {err!r:.120}")
            continue
        solvers |= built if isinstance(built, dict) else {label: built}
    return solvers, notes


SLOW = ("RTB ikine_LM", "ikpy", "pink")
CHUNK = 25
PEER = "RTB ik_LM (C++)"  # the ratios are against this solver

#: TRAC-IK's published figure (module docstring): robot -> (success, mean µs).
TRAC_IK_PUBLISHED = {"panda": (0.9970, 380.0)}

_clock = time.process_time_ns


def run_robot(
    name: str, targets: int, slow_targets: int, seed: int, folder: Path, peers: bool
):
    """Rows (label, count, success rate, median, p99, max [µs]) and notes."""
    robot = load_robot(name)
    rng = np.random.default_rng(seed)
    poses = [robot.fk(rng.uniform(robot.lower, robot.upper)) for _ in range(targets)]
    seeds = rng.integers(0, 2**31, size=targets)
    solvers, notes = build_solvers(robot, kinematic_urdf(robot, folder), peers)
    if slow_targets <= 0:  # no targets for the slow peers: no rows for them
        solvers = {label: s for label, s in solvers.items() if label not in SLOW}
    times = {label: [] for label in solvers}
    steps, restarts = [], []  # of workbench numeric
    success = {label: 0 for label in solvers}
    errors = {label: 0 for label in solvers}
    for solve in solvers.values():  # warm up: compilation, caches
        with quiet(), contextlib.suppress(Exception):
            solve(poses[0], 0)
    # Chunks of targets, each solved by every solver in turn: warm caches
    # within a chunk, and load changes spread evenly over the solvers.
    for first in range(0, targets, CHUNK):
        chunk = range(first, min(first + CHUNK, targets))
        for label, solve in solvers.items():
            limit = slow_targets if label in SLOW else targets
            for index in chunk:
                if index >= limit:
                    break
                with quiet():
                    start = _clock()
                    try:
                        q = solve(poses[index], int(seeds[index]))
                    except Exception:  # a peer that raises has failed here
                        q = None
                        errors[label] += 1
                    elapsed = _clock() - start
                times[label].append(elapsed)
                if isinstance(solve, Ours):
                    steps.append(solve.last.iterations)
                    restarts.append(solve.last.restarts)
                success[label] += q is not None and pose_ok(robot, q, poses[index])
    rows = []
    for label in solvers:
        t = np.array(times[label]) * 1e-3
        if t.size == 0:  # no targets (--targets 0)
            continue
        rate = success[label] / len(t)
        rows.append((label, len(t), rate, *np.percentile(t, [50, 99]), t.max()))
        if errors[label]:
            notes.append(f"{label} on {name}: raised on {errors[label]} targets")
    if name in TRAC_IK_PUBLISHED:
        rate, mean = TRAC_IK_PUBLISHED[name]
        rows.append(("TRAC-IK (published)", 10_000, rate, mean, math.nan, math.nan))
    if not steps:
        return rows, notes
    steps, restarts = np.array(steps), np.array(restarts)
    notes.append(
        f"workbench numeric on {name}: steps median {np.median(steps):.0f}, "
        f"mean {steps.mean():.1f}, p99 {np.percentile(steps, 99):.0f}, "
        f"max {steps.max()}; restarts mean {restarts.mean():.2f}, "
        f"none in {np.mean(restarts == 0):.1%} of solves"
    )
    return rows, notes


def batch_rate(name: str, count: int, seed: int) -> tuple[float, float]:
    """(targets per CPU second of numeric_batch, success rate) on FK targets."""
    robot = load_robot(name)
    rng = np.random.default_rng(seed)
    q = rng.uniform(robot.lower, robot.upper, (count, robot.nq))
    targets = np.array([robot.fk(row).homogeneous for row in q])
    numeric_batch(robot, targets[:2])  # warm up
    start = _clock()
    result = numeric_batch(robot, targets)
    elapsed = (_clock() - start) * 1e-9
    return count / elapsed, float(result.success.mean())


_FIRST_CALL = """
import time
start = time.perf_counter()
import numpy as np
from workbench import load_robot
from workbench.ik import numeric
robot = load_robot("ur5")
loaded = time.perf_counter()
result = numeric(robot, robot.fk(np.full(6, 0.3)))
solved = time.perf_counter()
again = numeric(robot, robot.fk(np.full(6, 0.4)))
print(loaded - start, solved - loaded, time.perf_counter() - solved, result.success)
"""


def first_call_times() -> list[tuple[str, list[float]]]:
    """Wall times of a fresh process: import + load, first numeric, second one."""
    rows = []
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        for label in ("empty Numba cache", "warm Numba cache"):
            out = subprocess.run(
                [sys.executable, "-c", _FIRST_CALL],
                env=env,
                capture_output=True,
                text=True,
                check=True,
            ).stdout.split()
            rows.append((label, [float(x) for x in out[:3]]))
    return rows


def fk_overhead(name: str = "ur5", number: int = 20_000) -> list[tuple[str, float]]:
    """Median CPU µs per call: Robot.fk / jacobian and the Pinocchio calls inside."""
    robot = load_robot(name)
    model, data, frame = robot.model, robot.data, robot.tool_frame_id
    q = 0.5 * (robot.lower + robot.upper)
    world_aligned = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

    def pin_fk():
        pin.forwardKinematics(model, data, q)
        return pin.updateFramePlacement(model, data, frame).copy()

    calls = (
        ("Pinocchio forwardKinematics + updateFramePlacement", pin_fk),
        ("Robot.fk", lambda: robot.fk(q)),
        (
            "Pinocchio computeFrameJacobian",
            lambda: pin.computeFrameJacobian(model, data, q, frame, world_aligned),
        ),
        ("Robot.jacobian", lambda: robot.jacobian(q)),
    )
    return [(label, _median_us(call, number)) for label, call in calls]


def _median_us(call: Callable[[], object], number: int, repeat: int = 7) -> float:
    call()
    samples = []
    for _ in range(repeat):
        start = _clock()
        for _ in range(number):
            call()
        samples.append((_clock() - start) * 1e-3 / number)
    return float(np.median(samples))


def _ratio(value: float) -> str:
    """A ratio to ik_LM: one decimal from 1 up, else two significant digits."""
    return f"{value:.1f}x" if value >= 1.0 else f"{value:.2g}x"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--targets", type=int, default=1000, help="per robot")
    parser.add_argument(
        "--slow-targets",
        type=int,
        default=100,
        help="targets for the slow peers (RTB ikine_LM, ikpy, pink)",
    )
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS))
    parser.add_argument("--seed", type=int, default=2024)
    parser.add_argument("--batch", type=int, default=20_000, help="batch targets")
    parser.add_argument("--no-peers", action="store_true", help="time ours only")
    args = parser.parse_args()

    reference = _median_us(lambda: sum(range(1000)), 2000, repeat=15)
    print("Numerical IK, one core, CPU time per call from Python")
    print(f"machine reference: sum(range(1000)) = {reference:.1f} µs\n")
    header = (
        f"{'robot':8} {'solver':20} {'targets':>7} {'success':>8} {'median µs':>10} "
        f"{'p99 µs':>9} {'max µs':>9} {'median vs ik_LM':>16} {'p99 vs ik_LM':>13}"
    )
    print(header)
    print("-" * len(header))
    all_notes = []
    with tempfile.TemporaryDirectory() as folder:
        for name in args.robots:
            rows, notes = run_robot(
                name,
                args.targets,
                args.slow_targets,
                args.seed,
                Path(folder),
                not args.no_peers,
            )
            all_notes += notes
            peer = next((row for row in rows if row[0] == PEER), None)
            for label, count, rate, median, p99, worst in rows:
                print(
                    f"{name:8} {label:20} {count:7d} {rate:8.1%} {median:10.0f} ",
                    end="",
                )
                if math.isnan(p99):  # a published figure: a mean, not comparable
                    print(f"{'—':>9} {'—':>9}   (published mean, not run)")
                    continue
                ratios = ("", "")
                if peer is not None and label != PEER:
                    ratios = (_ratio(peer[3] / median), _ratio(peer[4] / p99))
                print(f"{p99:9.0f} {worst:9.0f} {ratios[0]:>16} {ratios[1]:>13}")
    print("\nratio = ik_LM's time / this solver's time (> 1: faster than ik_LM)")
    for note in all_notes:
        print(f"note: {note}")

    print(f"\nnumeric_batch, {args.batch} FK targets, one core, CPU time")
    for name in args.robots:
        rate, ok = batch_rate(name, args.batch, args.seed)
        print(f"{name:8} {rate:12,.0f} targets/s  success {ok:.2%}")

    print("\nFirst numeric call (ur5) in a fresh process, wall time [s]")
    print(f"{'':20} {'import + load':>14} {'first call':>11} {'second call':>12}")
    for label, (load, first, second) in first_call_times():
        print(f"{label:20} {load:14.2f} {first:11.3f} {second:12.6f}")

    print("\nRobot.fk / Robot.jacobian (ur5), median CPU µs per call")
    for label, us in fk_overhead():
        print(f"{label:52} {us:6.2f}")
    again = _median_us(lambda: sum(range(1000)), 2000)
    print(f"machine reference again: sum(range(1000)) = {again:.1f} µs")


if __name__ == "__main__":
    main()
