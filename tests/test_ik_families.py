"""The closed-form families: the registry, each Family's facts, and no family leaks.

Every catalog robot gets its family (or none, with the reason); each Family's
facts agree with its solver (branch labels, redundancy parameter, packed
constants) and with the arm's joint axes (which axes are parallel, which meet);
and no module outside ``workbench/ik`` decides anything by a family's name or
finds a family by catching ``UnsupportedRobotError``.
"""

from __future__ import annotations

import ast
import itertools
from dataclasses import FrozenInstanceError
from pathlib import Path

import numpy as np
import pytest

import workbench.ik.families as families_module
from workbench import ik, load_robot
from workbench.errors import InputError
from workbench.ik.structure import axis_lines
from workbench.model.catalog import CATALOG

PACKAGE = Path(__file__).resolve().parents[1] / "workbench"

#: The family of each catalog robot that has one; every other has none.
EXPECTED = {
    "puma560": "opw",
    "puma560-kang": "opw",
    "kuka-kr6-r700": "opw",
    "abb-irb2400": "opw",
    "ur3": "ur",
    "ur3_gripper": "ur",
    "ur3_limited": "ur",
    "ur5": "ur",
    "ur5_gripper": "ur",
    "ur5_limited": "ur",
    "ur10": "ur",
    "ur10_limited": "ur",
    "z1": "ur",
    "iiwa14": "srs",
    "panda": "franka",
    "panda_collision": "franka",
    "xarm7": "franka",
}
#: One robot of each family, for the facts checked against the solvers.
ONE_OF_EACH = ("puma560", "puma560-kang", "ur5", "iiwa14", "panda", "xarm7")
FAMILY_NAMES = frozenset({"opw", "ur", "srs", "franka"})
#: Axes closer than this [m] meet; directions closer than this [rad] are parallel.
AXIS_TOL = 1e-5


# -- the registry -------------------------------------------------------------------


def test_registry_holds_the_four_families() -> None:
    assert set(ik.FAMILIES) == FAMILY_NAMES
    for name, family in ik.FAMILIES.items():
        assert isinstance(family, ik.Family) and family.name == name
        assert family.joint_count in (6, 7)
        assert len(family.branches) == 8 == len(set(family.branches))
        assert family.title


@pytest.mark.parametrize("name", sorted(CATALOG))
def test_every_catalog_robot_has_its_family(name: str) -> None:
    robot = load_robot(name)
    family = ik.get_family(robot)
    expected = EXPECTED.get(name)
    if expected is None:
        assert family is None
        reason = ik.get_family_refusal(robot)
        assert reason  # says why
        with pytest.raises(ik.UnsupportedRobotError) as err:
            ik.require_family(robot)
        assert str(err.value) == reason
    else:
        assert family is ik.FAMILIES[expected]
        assert ik.require_family(robot) is family
        assert ik.get_family_refusal(robot) is None
        assert family.joint_count == robot.nq


def test_no_family_says_why() -> None:
    robot = load_robot("generic6r")
    assert ik.get_family(robot) is None
    assert "no closed-form IK" in str(ik.get_family_refusal(robot))
    with pytest.raises(ik.UnsupportedRobotError, match="not OPW"):
        ik.get_solver(robot)


def test_the_registry_is_read_only() -> None:
    family = ik.FAMILIES["ur"]
    with pytest.raises(FrozenInstanceError):
        family.name = "other"  # type: ignore[misc]
    with pytest.raises(TypeError):
        ik.FAMILIES["other"] = family  # type: ignore[index]


def test_get_family_is_cached_per_robot(monkeypatch: pytest.MonkeyPatch) -> None:
    robot = load_robot("ur5").with_limits(velocity_limit=1.0)
    first = ik.get_family(robot)

    def refuse(robot):
        raise AssertionError("recognised twice")

    monkeypatch.setattr(families_module, "get_structure", refuse)
    assert ik.get_family(robot) is first is ik.FAMILIES["ur"]
    other = robot.with_limits(velocity_limit=2.0)
    with pytest.raises(AssertionError, match="recognised twice"):
        ik.get_family(other)  # another robot object: recognised on its own


# -- each family's facts against its solver ---------------------------------------


@pytest.mark.parametrize("name", ONE_OF_EACH)
def test_facts_agree_with_the_solver(name: str) -> None:
    robot = load_robot(name)
    family = ik.require_family(robot)
    assert (family.parameter is None) is (family.joint_count == 6)
    assert family.redundant is (family.joint_count == 7)
    assert (family.feasible_intervals is None) is (not family.redundant)
    solver = ik.get_solver(robot)
    assert solver.family is family  # the solver is built from its Family
    assert solver.branches == family.branches
    assert solver.parameter == family.parameter
    assert solver.nq == family.joint_count
    if not family.redundant:
        assert not family.parameter_periodic
        assert solver.parameter_range is None
        with pytest.raises(InputError, match="no redundancy"):
            solver.feasible(robot.fk(0.5 * (robot.lower + robot.upper)))
    else:
        pose = robot.fk(0.5 * (robot.lower + robot.upper))
        assert solver.feasible(pose).circular is family.parameter_periodic
        if family.parameter_periodic:
            assert solver.parameter_range == pytest.approx((-np.pi, np.pi))
        else:
            assert solver.parameter_range == (robot.lower[6], robot.upper[6])
    packed = family.pack(robot)
    assert packed.dtype == solver.geometry.dtype
    assert packed.tobytes() == solver.geometry.tobytes()


def _distance(p1, w1, p2, w2) -> float:
    """Distance [m] between two lines (point, unit direction)."""
    normal = np.cross(w1, w2)
    if np.linalg.norm(normal) <= AXIS_TOL:
        return float(np.linalg.norm(np.cross(p2 - p1, w1)))
    return abs(float((p2 - p1) @ normal)) / float(np.linalg.norm(normal))


def _meeting_point(points, directions) -> np.ndarray:
    """The least-squares point nearest every line [m]."""
    lhs = sum(np.eye(3) - np.outer(w, w) for w in directions)
    rhs = sum(
        (np.eye(3) - np.outer(w, w)) @ p
        for p, w in zip(points, directions, strict=True)
    )
    return np.linalg.solve(lhs, rhs)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_axis_facts_hold_on_the_model(name: str) -> None:
    robot = load_robot(name)
    family = ik.require_family(robot)
    w, p = axis_lines(robot)
    for i, j in itertools.pairwise(family.parallel_axes):
        assert np.linalg.norm(np.cross(w[i - 1], w[j - 1])) <= AXIS_TOL
    for axes in (family.shoulder_axes, family.elbow_axes, family.wrist_axes):
        if not axes:
            continue
        rows = [k - 1 for k in axes]
        point = _meeting_point(p[rows], w[rows])
        for k in rows:
            assert np.linalg.norm(np.cross(point - p[k], w[k])) <= AXIS_TOL
        for a, b in itertools.combinations(rows, 2):
            assert _distance(p[a], w[a], p[b], w[b]) <= AXIS_TOL
    assert family.spherical_wrist is (len(family.wrist_axes) == 3)


def test_franka_elbow_axes_do_not_meet() -> None:
    """Facts left empty are not true: the Panda's axes 3, 4 are offset (a3)."""
    robot = load_robot("panda")
    assert ik.require_family(robot).elbow_axes == ()
    w, p = axis_lines(robot)
    assert _distance(p[2], w[2], p[3], w[3]) > 0.05


@pytest.mark.parametrize("name", ONE_OF_EACH)
def test_reach_bounds_the_wrist_point(name: str) -> None:
    """``Family.reach``: the wrist point's largest distance from the shoulder.

    From axis 2, in the plane normal to it (six axes), or from the shoulder
    point S (seven axes), over sampled configurations of the fitted chain.
    """
    robot = load_robot(name)
    family = ik.require_family(robot)
    table = ik.get_structure(robot).table
    reach = family.reach(table)
    wrist = family.wrist_axes[0]  # DH frame whose origin is the wrist point
    largest = 0.0
    for q in np.random.default_rng(0).uniform(-np.pi, np.pi, (2000, robot.nq)):
        frames = table.frame_transforms(q)
        offset = frames[wrist][:3, 3] - frames[1][:3, 3]
        if not family.redundant:
            axis2 = frames[1][:3, 2]
            offset = offset - axis2 * float(axis2 @ offset)
        largest = max(largest, float(np.linalg.norm(offset)))
    assert largest <= reach + 1e-9
    assert largest >= 0.95 * reach


# -- no family leaks outside workbench/ik -----------------------------------------


def _is_family_expression(node: ast.AST) -> bool:
    """``family``, ``x.family``, ``some_family``: a value naming a family."""
    if isinstance(node, ast.Name):
        return node.id == "family" or node.id.endswith("_family")
    return isinstance(node, ast.Attribute) and node.attr == "family"


def _names_a_family(node: ast.AST) -> bool:
    """A family name as a string, or a tuple/list/set holding one."""
    if isinstance(node, ast.Constant):
        return node.value in FAMILY_NAMES
    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        return any(_names_a_family(e) for e in node.elts)
    return False


#: The errors that say an arm is not of a family (or has no factorisation of
#: it): catching one to find out which arm it is, is a probe.
FAMILY_ERRORS = ("UnsupportedRobotError", "NotPumaTypeError", "NotSRSArmError")


def _catches_unsupported(handler: ast.ExceptHandler) -> bool:
    caught = handler.type
    kinds = caught.elts if isinstance(caught, ast.Tuple) else [caught]
    return any(
        (isinstance(k, ast.Name) and k.id in FAMILY_ERRORS)
        or (isinstance(k, ast.Attribute) and k.attr in FAMILY_ERRORS)
        for k in kinds
    )


def find_family_leaks(source: str, *, probes: bool = True) -> list[str]:
    """Where code decides by a family's name or probes by exception.

    Returns one ``"line N: what"`` per finding: comparisons of a family value
    (other than ``is None``) or of a family-name string,
    ``getattr(..., "family")``, a ``*_FAMILIES`` name and
    (``probes``) every ``except`` that catches one of :data:`FAMILY_ERRORS`.
    """
    found: list[str] = []
    for node in ast.walk(ast.parse(source)):
        line = getattr(node, "lineno", 0)
        if isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            against_none = all(isinstance(op, ast.Is | ast.IsNot) for op in node.ops)
            if any(_names_a_family(s) for s in sides):
                found.append(f"line {line}: compares a family name")
            elif not against_none and any(_is_family_expression(s) for s in sides):
                found.append(f"line {line}: compares a family")
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in ("getattr", "hasattr")
            and len(node.args) > 1
            and isinstance(node.args[1], ast.Constant)
            and node.args[1].value == "family"
        ):
            found.append(f"line {line}: getattr of a family")
        elif isinstance(node, ast.Name) and node.id.endswith("_FAMILIES"):
            found.append(f"line {line}: a list of family names ({node.id})")
        elif probes and isinstance(node, ast.ExceptHandler):
            if node.type is not None and _catches_unsupported(node):
                found.append(f"line {line}: probes the family by exception")
    return found


@pytest.mark.parametrize(
    "snippet",
    [
        'if fac.family == "ur": pass',
        "if structure.family != 'srs': pass",
        'ok = family in ("srs", "franka")',
        'ok = solver.family not in ("opw", "ur")',
        'ok = "franka" == robot_family',
        'periodic = solver.family is "srs"',
        'name = getattr(solver, "family")',
        "ok = name in REDUNDANT_FAMILIES",
        "try:\n    f()\nexcept UnsupportedRobotError:\n    pass",
        "try:\n    f()\nexcept ik.UnsupportedRobotError as err:\n    pass",
        "try:\n    f()\nexcept (InputError, UnsupportedRobotError):\n    pass",
        "try:\n    f()\nexcept NotPumaTypeError:\n    pass",
        "try:\n    f()\nexcept singularities.NotSRSArmError:\n    pass",
    ],
)
def test_the_leak_finder_finds_each_form(snippet: str) -> None:
    assert find_family_leaks(snippet)


@pytest.mark.parametrize(
    "snippet",
    [
        "if family is None: pass",
        "ok = family is not None and family.redundant",
        'print(f"{family.name.upper()} family")',
        'attrs = {"family": None if family is None else family.name}',
    ],
)
def test_the_leak_finder_lets_the_family_be_asked(snippet: str) -> None:
    assert find_family_leaks(snippet) == []


def _sources(*skip: str) -> dict[str, str]:
    return {
        str(path.relative_to(PACKAGE.parent)): path.read_text()
        for path in sorted(PACKAGE.rglob("*.py"))
        if path.relative_to(PACKAGE).parts[0] not in skip
    }


def test_no_family_name_is_compared_outside_ik() -> None:
    leaks = {
        path: found
        for path, text in _sources("ik").items()
        if (found := find_family_leaks(text, probes=False))
    }
    assert leaks == {}


def test_no_family_is_probed_by_exception_outside_ik_and_cli() -> None:
    probes = {
        path: found
        for path, text in _sources("ik", "cli").items()
        if (found := [f for f in find_family_leaks(text) if "exception" in f])
    }
    assert probes == {}
