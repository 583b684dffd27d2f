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

Peers load a copy of the URDF without meshes. Solvers take turns on chunks of
25 targets, so that machine load hits all of them alike; times are wall-clock
per call from Python, including the target validation of ``numeric``. Usage::

    python benchmarks/bench_ik_numerical.py [--targets 1000] [--slow-targets 100]
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import tempfile
import time
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin

from workbench import Robot, load_robot
from workbench.ik import numeric
from workbench.poses import as_se3

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


def _time(function: Callable, *args) -> float:
    start = time.perf_counter()
    function(*args)
    return time.perf_counter() - start


def run_robot(
    name: str, targets: int, slow_targets: int, seed: int, folder: Path, peers: bool
):
    robot = load_robot(name)
    rng = np.random.default_rng(seed)
    poses = [robot.fk(rng.uniform(robot.lower, robot.upper)) for _ in range(targets)]
    seeds = rng.integers(0, 2**31, size=targets)
    solvers, notes = build_solvers(robot, kinematic_urdf(robot, folder), peers)
    times = {label: [] for label in solvers}
    steps, restarts = [], []  # of workbench numeric
    success = {label: 0 for label in solvers}
    errors = {label: 0 for label in solvers}
    validation = [_time(as_se3, target) for target in poses]
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
                    start = time.perf_counter()
                    try:
                        q = solve(poses[index], int(seeds[index]))
                    except Exception:  # a peer that raises has failed here
                        q = None
                        errors[label] += 1
                    elapsed = time.perf_counter() - start
                times[label].append(elapsed)
                if isinstance(solve, Ours):
                    steps.append(solve.last.iterations)
                    restarts.append(solve.last.restarts)
                success[label] += q is not None and pose_ok(robot, q, poses[index])
    rows = []
    for label in solvers:
        t = np.array(times[label]) * 1e6
        rows.append(
            (label, len(t), success[label] / len(t), *np.percentile(t, [50, 99]))
        )
        if errors[label]:
            notes.append(f"{label} on {name}: raised on {errors[label]} targets")
    steps, restarts = np.array(steps), np.array(restarts)
    notes.append(
        f"workbench numeric on {name}: steps median {np.median(steps):.0f}, "
        f"mean {steps.mean():.1f}, p99 {np.percentile(steps, 99):.0f}, "
        f"max {steps.max()}; restarts mean {restarts.mean():.2f}, "
        f"none in {np.mean(restarts == 0):.1%} of solves"
    )
    return rows, notes, float(np.median(validation) * 1e6)


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
    parser.add_argument("--no-peers", action="store_true", help="time ours only")
    args = parser.parse_args()

    header = (
        f"{'robot':8} {'solver':20} {'targets':>7} {'success':>8} "
        f"{'median µs':>10} {'p99 µs':>10} {'median ratio':>12}"
    )
    print(header)
    print("-" * len(header))
    all_notes = []
    with tempfile.TemporaryDirectory() as folder:
        for name in args.robots:
            rows, notes, validation = run_robot(
                name,
                args.targets,
                args.slow_targets,
                args.seed,
                Path(folder),
                not args.no_peers,
            )
            all_notes += notes
            reference = rows[0][3]
            for label, count, rate, median, p99 in rows:
                print(
                    f"{name:8} {label:20} {count:7d} {rate:8.1%} {median:10.0f} "
                    f"{p99:10.0f} {median / reference:11.1f}x"
                )
            all_notes.append(
                f"{name}: target validation (as_se3) alone, median {validation:.0f} µs"
            )
    print("\nratio = peer median time / workbench numeric median time")
    for note in all_notes:
        print(f"note: {note}")


if __name__ == "__main__":
    main()
