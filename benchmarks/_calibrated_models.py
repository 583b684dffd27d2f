"""Calibrated copies of catalog URDFs, as a robot calibration writes them.

:func:`calibrated_urdf` moves every joint origin of a catalog arm by
calibration-sized deltas (seeded uniform 1e-4…1e-3 rad on each ``rpy`` value,
0.1…1 mm on each ``xyz`` value, either sign); :func:`off_axis_iiwa` writes the
iiwa 14 with its joint 2 and joint 4 origins 0.436 mm off axis, as
ROS-Industrial's ``kuka_lbr_iiwa_14_r820`` URDF has them (``xyz="-0.00043624 0
0.36"`` and ``xyz="0 -0.00043624 0.42"`` in its frames). Both load the copy with
the catalog's tool frame; the benchmarks and ``tests/test_ik_calibrated.py``
use them.
"""

from __future__ import annotations

import xml.etree.ElementTree as ElementTree
from pathlib import Path

import numpy as np
import pinocchio as pin

from workbench import Robot, load_robot
from workbench.ik import get_solver
from workbench.model.catalog import CATALOG

#: Range of the calibration deltas: ``rpy`` [rad] and ``xyz`` [m].
CALIBRATION_RPY = (1e-4, 1e-3)
CALIBRATION_XYZ = (1e-4, 1e-3)
#: Step [rad] of the central differences of the arm angle ψ(q).
PARAMETER_STEP = 1e-6
#: How far ROS-Industrial's iiwa 14 R820 URDF has its joint 2 and 4 origins
#: off axis [m].
IIWA_OFF_AXIS = 0.43624e-3


def _write(robot: Robot, tree: ElementTree.ElementTree, path: Path) -> Robot:
    root = tree.getroot()
    locked = CATALOG[robot.name].locked_joints if robot.name in CATALOG else ()
    for joint in [j for j in root.iter("joint") if j.get("name") in locked]:
        child = joint.find("child")
        root.remove(joint)
        for link in [k for k in root.iter("link") if child is not None
                     and k.get("name") == child.get("link")]:  # fmt: skip
            root.remove(link)
    tree.write(path)
    package = Path(robot.urdf_path).parent
    return load_robot(path, tool_frame=robot.tool_frame, package_dirs=[package])


def calibrated_urdf(
    name: str, folder: Path, *, seed: int = 0, scale: float = 1.0
) -> Robot:
    """The catalog arm ``name`` with calibration deltas on its joint origins.

    Every ``rpy`` and ``xyz`` value of every revolute joint's origin moves by
    ``scale`` times a seeded uniform draw in :data:`CALIBRATION_RPY` [rad] or
    :data:`CALIBRATION_XYZ` [m], either sign (zeros too: a calibration moves
    them).

    Args:
        name: Catalog name (``"ur5"``, ``"puma560"``, ...).
        folder: Where the URDF copy is written.
        seed: Seed of the deltas.
        scale: Factor on both ranges (1: a calibration's size).

    Returns:
        The robot, with the catalog's tool frame (and no DH table: the copy is
        read as any URDF).
    """
    robot = load_robot(name)
    tree = ElementTree.parse(robot.urdf_path)
    rng = np.random.default_rng(seed)
    for joint in tree.getroot().iter("joint"):
        if joint.get("type") not in ("revolute", "continuous"):
            continue
        origin = joint.find("origin")
        if origin is None:
            origin = ElementTree.SubElement(joint, "origin")
        for key, (low, high) in (("rpy", CALIBRATION_RPY), ("xyz", CALIBRATION_XYZ)):
            values = [float(v) for v in origin.get(key, "0 0 0").split()]
            moved = [
                v + scale * rng.uniform(low, high) * rng.choice((-1.0, 1.0))
                for v in values
            ]
            origin.set(key, " ".join(repr(float(v)) for v in moved))
    return _write(robot, tree, Path(folder) / f"{name}-calibrated-{seed}.urdf")


def off_axis_iiwa(folder: Path, *, offset: float = IIWA_OFF_AXIS) -> Robot:
    """The iiwa 14 with its joint 2 and 4 origins ``offset`` [m] off axis.

    Each origin moves by ``offset`` along the x of its parent frame, normal to
    the joint's axis and to the axis before it, so that axes 1, 2, 3 and axes
    3, 4, 5 miss their common points by ``offset``, as in ROS-Industrial's URDF.
    """
    robot = load_robot("iiwa14")
    tree = ElementTree.parse(robot.urdf_path)
    for joint in tree.getroot().iter("joint"):
        if joint.get("name") not in ("joint2", "joint4"):
            continue
        origin = joint.find("origin")
        if origin is None:
            origin = ElementTree.SubElement(joint, "origin")
        x, y, z = (float(v) for v in origin.get("xyz", "0 0 0").split())
        origin.set("xyz", f"{x + offset!r} {y!r} {z!r}")
    return _write(robot, tree, Path(folder) / f"iiwa14-off-axis-{offset:g}.urdf")


def calibrated_arm(name: str, folder: Path) -> Robot:
    """``"iiwa14"``: :func:`off_axis_iiwa`; else :func:`calibrated_urdf` (seed 0)."""
    if name == "iiwa14":
        return off_axis_iiwa(folder)
    return calibrated_urdf(name, folder, seed=0)


def wrapped(a: np.ndarray) -> np.ndarray:
    """|a| with each angle wrapped to [0, π] [rad]."""
    return np.abs(np.angle(np.exp(1j * a)))


def fk_residuals(robot: Robot, qs: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """(N, 2) position [m] and rotation [rad] residuals by Pinocchio's FK."""
    model, data = robot.model, robot.model.createData()
    out = np.empty((len(qs), 2))
    for row, q, target in zip(out, qs, targets, strict=True):
        pin.framesForwardKinematics(model, data, q)
        pose = data.oMf[robot.tool_frame_id]
        row[0] = np.linalg.norm(pose.translation - target[:3, 3])
        row[1] = np.linalg.norm(pin.log3(target[:3, :3].T @ pose.rotation))
    return out


def least_singular(robot: Robot, q: np.ndarray) -> float:
    """Least singular value of the system a solve at held redundancy inverts.

    A 6R arm: the tool Jacobian (LOCAL, 6 × 6); a Franka arm at held q7: its
    first six columns; an SRS arm at held arm angle ψ: [J; ∇ψ] (7 × 7, ∇ψ by
    central differences of ``Solver.parameter_of``), whose rank also drops
    where ψ is degenerate (the wrist centre near axis 1). Small near the
    singularities where a solve may miss solutions [m or rad per rad].
    """
    jac = robot.jacobian_local(q)
    solver = get_solver(robot)
    if robot.nq == 6 or not solver.family.parameter_periodic:
        return float(np.linalg.svd(jac[:, :6], compute_uv=False)[-1])
    gradient = np.empty(7)
    for k in range(7):
        up, down = q.copy(), q.copy()
        up[k] += PARAMETER_STEP
        down[k] -= PARAMETER_STEP
        step = float(solver.parameter_of(up)) - float(solver.parameter_of(down))
        gradient[k] = np.angle(np.exp(1j * step)) / (2 * PARAMETER_STEP)
    square = np.vstack([jac, gradient])
    return float(np.linalg.svd(square, compute_uv=False)[-1])
