"""Closed-form IK exactness: FK residuals, agreement with EAIK and ik-geo, edge poses.

Run from the repository root: ``python -m benchmarks.bench_ik_agreement
[--poses N] [--edge-poses M] [--robots puma560,ur5,...]``.

Per model, clean (the catalog's URDF), rounded (the same URDF with every
nonzero ``rpy`` of a joint origin moved by 1.8e-9 rad and every nonzero ``xyz``
by 1e-9 m, as a file written with nine decimals is) and perturbed (the zeros
moved too: of its family only up to 1e-9; :func:`rounded_urdf`):

* the largest FK residual of every branch of ``analytic`` on N random poses,
  of EAIK's and of ik-geo's exact (not least-squares) answers: position
  |p(q) − p_T| [m] and rotation |log3(R_Tᵀ R(q))| [rad], by Pinocchio's FK;
* the largest joint difference (mod 2π) of each peer answer to the nearest of
  our branches, away from singularities (random poses);
* the poses of the edge families (:data:`EDGE_FAMILIES`, M each: stretched and
  folded elbows, θ5 → 0 and π, both, the wrist centre on the shoulder-singular
  surface, each at 0 and 1e-12 … 1e-4 from it) that ``analytic_batch``
  reports as not reached (false "out of reach": each pose is the FK of a
  configuration), and those for which a peer returns no exact answer.

EAIK and ik-geo get the model's own joint axes, as in
``bench_ik_closed_form.py`` (whose chain and peer builders are used here); a missing
peer is reported as such.
"""

from __future__ import annotations

import argparse
import importlib
import math
import tempfile
import xml.etree.ElementTree as ElementTree
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin

from benchmarks.bench_ik_closed_form import _chain, _ik_geo_peer
from workbench import Robot, load_robot
from workbench.ik import analytic, analytic_batch, get_structure
from workbench.model.catalog import CATALOG

#: How far a rounded URDF's nonzero joint-origin numbers are moved: ``rpy``
#: [rad] (π/2 written 1.570796325 is 1.8e-9 off) and ``xyz`` [m].
ROUNDING_RPY = 1.8e-9
ROUNDING_XYZ = 1e-9

#: Families of edge configurations (:func:`edge_configurations`).
EDGE_FAMILIES = ("stretched", "folded", "wrist", "stretched+wrist", "shoulder")

#: Offsets from an edge: 0 for a quarter of the draws, else ±10^u, u uniform
#: in [low, high] (elbow and shoulder: 1e-12 … 1e-4; wrist: 1e-12 … 1e-6).
ELBOW_EXPONENTS, WRIST_EXPONENTS = (-12.0, -4.0), (-12.0, -6.0)

#: Bisection steps that put the wrist centre on the shoulder-singular surface.
_BISECTIONS = 80

Peer = Callable[[np.ndarray], np.ndarray]


def rounded_urdf(
    name: str,
    folder: Path,
    *,
    zeros: bool = False,
    seed: int = 0,
    decimals: int | None = None,
) -> Robot:
    """The catalog robot ``name`` loaded from a copy of its URDF with rounded numbers.

    Every nonzero ``rpy`` value of a joint origin moves by ±(1…2) ×
    :data:`ROUNDING_RPY`, every nonzero ``xyz`` value by ±(1…2) ×
    :data:`ROUNDING_XYZ`; zeros stay zero, as a file's rounding leaves them,
    unless ``zeros``. (A UR arm's URDF turns its joints about their own axes,
    so rounding leaves it exactly of its family; moving its zeros too makes it
    UR-type only up to 1e-9.) With ``decimals``, every ``rpy`` and ``xyz``
    value is instead rounded to that many decimals, as a file written so is
    (4: π/2 written ``1.5708``, 3.67e-6 rad off, as example-robot-data's
    xArm7). The joints the catalog locks (a gripper's fingers), which a
    path cannot lock, are removed with their child links.

    Args:
        name: Catalog name (``"ur5"``, ``"kuka-kr6-r700"``, ``"iiwa14"``, ...).
        folder: Where the URDF copy is written.
        zeros: Move the zero values too (not with ``decimals``).
        seed: Seed of the perturbations.
        decimals: Round to this many decimals instead of perturbing.

    Returns:
        The robot, with the catalog's tool frame.
    """
    robot = load_robot(name)
    tree = ElementTree.parse(robot.urdf_path)
    root = tree.getroot()
    locked = CATALOG[name].locked_joints if name in CATALOG else ()
    for joint in [j for j in root.iter("joint") if j.get("name") in locked]:
        child = joint.find("child")
        root.remove(joint)
        for link in [k for k in root.iter("link") if child is not None
                     and k.get("name") == child.get("link")]:  # fmt: skip
            root.remove(link)
    rng = np.random.default_rng(seed)
    for joint in tree.getroot().iter("joint"):
        origin = joint.find("origin")
        if origin is None:
            continue
        for key, size in (("rpy", ROUNDING_RPY), ("xyz", ROUNDING_XYZ)):
            values = [float(v) for v in origin.get(key, "0 0 0").split()]
            if decimals is not None:
                origin.set(key, " ".join(f"{v:.{decimals}f}" for v in values))
                continue
            moved = [
                v + size * rng.uniform(1.0, 2.0) * rng.choice((-1.0, 1.0))
                if v or zeros
                else v
                for v in values
            ]
            origin.set(key, " ".join(repr(float(v)) for v in moved))
    kind = "perturbed" if zeros else "rounded"
    suffix = kind if decimals is None else f"rounded{decimals}"
    path = Path(folder) / f"{name}-{suffix}.urdf"
    tree.write(path)
    package = Path(robot.urdf_path).parent
    return load_robot(path, tool_frame=robot.tool_frame, package_dirs=[package])


def fk_residuals(robot: Robot, qs: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """FK residuals (N, 2) of configurations (N, 6): position [m], rotation [rad].

    Pinocchio's FK; position |p(q) − p_T|, rotation |log3(R_Tᵀ R(q))|.
    """
    model, data, frame = robot.model, robot.model.createData(), robot.tool_frame_id
    out = np.empty((len(qs), 2))
    for row, q, target in zip(out, qs, targets, strict=True):
        pin.framesForwardKinematics(model, data, q)
        pose = data.oMf[frame]
        row[0] = np.linalg.norm(pose.translation - target[:3, 3])
        row[1] = np.linalg.norm(pin.log3(target[:3, :3].T @ pose.rotation))
    return out


def _dh_frames(table, theta: np.ndarray) -> np.ndarray:
    """Poses (N, 7, 4, 4) of DH frames 0..6 at DH angles ``theta`` (N, 6)."""
    n = len(theta)
    frames = np.empty((n, 7, 4, 4))
    frames[:, 0] = np.eye(4)
    for k, joint in enumerate(table.joints):
        c, s = np.cos(theta[:, k]), np.sin(theta[:, k])
        ca, sa = math.cos(joint.alpha), math.sin(joint.alpha)
        link = np.zeros((n, 4, 4))
        link[:, 0] = np.stack([c, -s * ca, s * sa, joint.a * c], axis=1)
        link[:, 1] = np.stack([s, c * ca, -c * sa, joint.a * s], axis=1)
        link[:, 2, 1:] = sa, ca, joint.d
        link[:, 3, 3] = 1.0
        frames[:, k + 1] = frames[:, k] @ link
    return frames


def _set_dh_angle(robot: Robot, qs: np.ndarray, joint: int, theta: np.ndarray) -> None:
    """Set joint ``joint`` of ``qs`` (N, 6) to DH angles ``theta`` (N,), wrapped."""
    structure = get_structure(robot)
    sign = structure.joint_sign[joint]
    offset = structure.table.joints[joint].theta_offset
    qs[:, joint] = np.remainder(sign * (theta - offset) + np.pi, 2.0 * np.pi) - np.pi


def _offsets(rng: np.random.Generator, count: int, exponents) -> np.ndarray:
    """0 for a quarter of ``count`` draws, else ±10^u, u uniform in ``exponents``."""
    size = rng.choice((-1.0, 1.0), count) * 10.0 ** rng.uniform(*exponents, count)
    return np.where(rng.uniform(size=count) < 0.25, 0.0, size)


def elbow_angles(robot: Robot) -> tuple[float, float]:
    """DH θ3 [rad] of the stretched and the folded elbow."""
    structure = get_structure(robot)
    if structure.family == "ur":
        return 0.0, math.pi
    j3, j4 = structure.table.joints[2], structure.table.joints[3]
    beta = math.atan2(-math.copysign(1.0, j3.alpha) * j4.d, j3.a)
    return -beta, math.pi - beta


def edge_configurations(
    robot: Robot, family: str, count: int, rng: np.random.Generator
) -> np.ndarray:
    """Configurations (count, 6) [rad] at or next to an edge of the closed form.

    Args:
        robot: An OPW or UR-type arm.
        family: One of :data:`EDGE_FAMILIES`: ``"stretched"`` / ``"folded"``
            (DH θ3 at the elbow's reach boundaries, plus an offset of
            :data:`ELBOW_EXPONENTS`), ``"wrist"`` (DH θ5 at 0 or π plus
            :data:`WRIST_EXPONENTS`), ``"stretched+wrist"`` (both),
            ``"shoulder"`` (the wrist centre on the surface where the right
            and left arms meet, the base axis when the shoulder offset is 0,
            then moved by an elbow offset along joint 2).
        count: Number of configurations.
        rng: Random generator; the other joints are uniform within the limits.
    """
    qs = rng.uniform(robot.lower, robot.upper, size=(count, 6))
    stretched, folded = elbow_angles(robot)
    if family in ("stretched", "stretched+wrist"):
        theta = stretched + _offsets(rng, count, ELBOW_EXPONENTS)
        _set_dh_angle(robot, qs, 2, theta)
    if family == "folded":
        _set_dh_angle(robot, qs, 2, folded + _offsets(rng, count, ELBOW_EXPONENTS))
    if family in ("wrist", "stretched+wrist"):
        base = rng.choice((0.0, math.pi), count)
        _set_dh_angle(robot, qs, 4, base + _offsets(rng, count, WRIST_EXPONENTS))
    if family == "shoulder":
        qs = _on_shoulder_surface(robot, qs)
        qs[:, 1] += _offsets(rng, count, ELBOW_EXPONENTS)
    return qs


def _on_shoulder_surface(robot: Robot, qs: np.ndarray) -> np.ndarray:
    """``qs`` with joint 2 moved so the wrist centre is shoulder-singular.

    The wrist centre's coordinate along x1, from the base axis, is brought to
    0 by bisection on q2 over its limits (configurations with no sign change
    there are drawn again from the others).
    """
    structure = get_structure(robot)
    signs, table = np.asarray(structure.joint_sign), structure.table
    which = 5 if structure.family == "ur" else 4  # frame whose origin it is
    a1 = table.joints[0].a

    def along_x1(q2: np.ndarray) -> np.ndarray:
        q = qs.copy()
        q[:, 1] = q2
        theta = q * signs + [j.theta_offset for j in table.joints]
        frames = _dh_frames(table, theta)
        point = frames[:, which, :3, 3] - frames[:, 1, :3, 3]
        return np.einsum("ij,ij->i", frames[:, 1, :3, 0], point) + a1

    grid = np.linspace(robot.lower[1], robot.upper[1], 61)
    values = np.array([along_x1(np.full(len(qs), g)) for g in grid])
    change = np.sign(values[:-1]) != np.sign(values[1:])
    found = change.any(axis=0)
    first = np.argmax(change, axis=0)
    low, high = grid[first], grid[first + 1]
    f_low = values[first, np.arange(len(qs))]
    for _ in range(_BISECTIONS):
        mid = 0.5 * (low + high)
        f_mid = along_x1(mid)
        left = np.sign(f_mid) == np.sign(f_low)
        low, f_low = np.where(left, mid, low), np.where(left, f_mid, f_low)
        high = np.where(left, high, mid)
    qs = qs.copy()
    qs[:, 1] = 0.5 * (low + high)
    keep = qs[found]
    return keep[np.arange(len(qs)) % len(keep)]


def eaik_solver(robot: Robot) -> Peer | str:
    """EAIK's exact answers (k, 6) for a target (4, 4), or why it is missing."""
    try:
        hp = importlib.import_module("eaik.IK_HP")
    except ImportError as err:
        return f"not importable ({err})"
    directions, offsets, rotation0 = _chain(robot)
    try:
        peer = hp.HPRobot(directions, offsets)
        peer.IK(robot.fk(np.zeros(6)).homogeneous)
    except RuntimeError as err:  # no subproblem decomposition of the axes
        return f"refuses the chain ({err})"

    def solve(target: np.ndarray) -> np.ndarray:
        pose = target.copy()
        pose[:3, :3] = target[:3, :3] @ rotation0.T
        solution = peer.IK(pose)
        exact = ~np.asarray(solution.is_LS, dtype=bool)
        return np.asarray(solution.Q).reshape(-1, 6)[exact]

    return solve


def ik_geo_solver(robot: Robot) -> Peer | str:
    """ik-geo's exact answers (k, 6) for a target (4, 4), or why it is missing."""
    try:
        ik_geo = importlib.import_module("ik_geo")
    except ImportError as err:
        return f"not importable ({err})"
    peer, rotation0 = _ik_geo_peer(ik_geo, robot)

    def solve(target: np.ndarray) -> np.ndarray:
        rotation = (target[:3, :3] @ rotation0.T).T  # get_ik reads columns
        answers = peer.get_ik(rotation, target[:3, 3])
        exact = [q for q, least_squares in answers if not least_squares]
        return np.array(exact).reshape(-1, 6)

    return solve


def _wrapped(d: np.ndarray) -> np.ndarray:
    return np.remainder(d + np.pi, 2.0 * np.pi) - np.pi


def agreement(robot: Robot, peers: dict[str, Peer | str], poses: int) -> dict:
    """Residuals of ours and the peers and the peers' distance to our branches."""
    rng = np.random.default_rng(0)
    qs = rng.uniform(robot.lower, robot.upper, size=(poses, 6))
    targets = np.array([robot.fk(q).homogeneous for q in qs])
    ours = [np.array([s.q for s in analytic(robot, t)]) for t in targets]
    row: dict[str, float | str] = {}
    row["ours"] = max(
        fk_residuals(robot, q, [t] * len(q)).max()
        for q, t in zip(ours, targets, strict=True)
    )
    for name, peer in peers.items():
        if isinstance(peer, str):
            row[name] = row[f"{name} dq"] = peer
            continue
        residual = distance = 0.0
        for q_ours, target in zip(ours, targets, strict=True):
            theirs = peer(target)
            if len(theirs):
                residual = max(
                    residual, fk_residuals(robot, theirs, [target] * len(theirs)).max()
                )
                steps = np.abs(_wrapped(theirs[:, None] - q_ours[None])).max(axis=2)
                distance = max(distance, steps.min(axis=1).max())
        row[name], row[f"{name} dq"] = residual, distance
    return row


def edge_misses(robot: Robot, peers: dict[str, Peer | str], count: int) -> dict:
    """Per edge family: poses (FK of configurations) reported as not reached."""
    rng = np.random.default_rng(1)
    out: dict[str, dict[str, int | str]] = {}
    for family in EDGE_FAMILIES:
        qs = edge_configurations(robot, family, count, rng)
        targets = np.array([robot.fk(q).homogeneous for q in qs])
        _, valid = analytic_batch(robot, targets)
        counts: dict[str, int | str] = {"ours": int((~valid.any(axis=1)).sum())}
        for name, peer in peers.items():
            counts[name] = (
                "—"
                if isinstance(peer, str)
                else sum(len(peer(t)) == 0 for t in targets)
            )
        out[family] = counts
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=500, help="random poses")
    parser.add_argument("--edge-poses", type=int, default=10_000, help="per family")
    parser.add_argument(
        "--robots", default="puma560,kuka-kr6-r700,abb-irb2400,ur5,ur10"
    )
    args = parser.parse_args()
    header = (
        "| model | ours residual | EAIK residual | ik-geo residual | "
        "max dq to EAIK [rad] | max dq to ik-geo [rad] | "
        + " | ".join(f"unreached {f} (ours/EAIK/ik-geo)" for f in EDGE_FAMILIES)
        + " |"
    )
    print(header)
    print("|---" * (6 + len(EDGE_FAMILIES)) + "|")
    with tempfile.TemporaryDirectory() as folder:
        for name in args.robots.split(","):
            for label, robot in (
                (name, load_robot(name)),
                (f"{name} rounded", rounded_urdf(name, Path(folder))),
                (f"{name} perturbed", rounded_urdf(name, Path(folder), zeros=True)),
            ):
                peers = {"EAIK": eaik_solver(robot), "ik-geo": ik_geo_solver(robot)}
                row = agreement(robot, peers, args.poses)
                misses = edge_misses(robot, peers, args.edge_poses)
                cells = [_cell(row[k]) for k in ("ours", "EAIK", "ik-geo")]
                cells += [_cell(row["EAIK dq"]), _cell(row["ik-geo dq"])]
                cells += [
                    "/".join(str(misses[f][k]) for k in ("ours", "EAIK", "ik-geo"))
                    for f in EDGE_FAMILIES
                ]
                print(f"| {label} | " + " | ".join(cells) + " |", flush=True)


def _cell(value: float | str) -> str:
    return value if isinstance(value, str) else f"{value:.1e}"


if __name__ == "__main__":
    main()
