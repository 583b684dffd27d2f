"""SRDFs: the self-collision pairs a robot's own SRDF leaves out are honoured.

MotionBenchMaker's Panda (``tests/data/motionbenchmaker/panda``, its URDF
with ``panda.srdf`` beside it, unchanged from the vamp-planner sdist) is
loaded with its SRDF found beside the URDF; the filter then leaves out the
SRDF's pairs and the links on one joint, and nothing else.
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

import pytest

from tests.conftest import run_cli
from workbench import load_robot
from workbench.collision import CollisionChecker, compute_self_collision_filter
from workbench.errors import URDFLoadError
from workbench.model.srdf_files import find_srdf, read_disabled_collisions
from workbench.workspace import get_robot_spec, load_spec_robot, make_pose_grid
from workbench.workspace._partial import map_attributes

PANDA = Path(__file__).parent / "data" / "motionbenchmaker" / "panda"
URDF, SRDF = PANDA / "panda.urdf", PANDA / "panda.srdf"


def _pairs_in_file(path: Path) -> set[tuple[str, str]]:
    """The link pairs of the file's entries, read here with a regular expression."""
    found = re.findall(
        r'<disable_collisions link1="([^"]+)" link2="([^"]+)"', path.read_text()
    )
    return {(min(a, b), max(a, b)) for a, b in found}


def test_the_disabled_pairs_are_read_as_written() -> None:
    entries = read_disabled_collisions(SRDF)
    assert {(a, b) for a, b, _ in entries} == _pairs_in_file(SRDF)
    assert len(entries) == len(_pairs_in_file(SRDF)) > 0
    assert list(entries) == sorted(entries)
    assert all(a < b for a, b, _ in entries)
    assert {reason for _, _, reason in entries} <= {"Adjacent", "Never", "Default"}


def test_an_srdf_beside_the_urdf_is_honoured() -> None:
    robot = load_robot(URDF)
    assert find_srdf(URDF) == SRDF and robot.srdf_path == SRDF.resolve()
    chosen = compute_self_collision_filter(robot)
    links = set(chosen.links)
    expected = {(a, b) for a, b in _pairs_in_file(SRDF) if {a, b} <= links}
    rigid = {(d.link_a, d.link_b) for d in chosen.disabled if d.reason == "Rigid"}
    assert {(d.link_a, d.link_b) for d in chosen.disabled} == expected | rigid
    checker = CollisionChecker(robot)
    checked = {
        (min(p.body_a, p.body_b), max(p.body_a, p.body_b))
        for p in checker.pairs
        if p.kind == "self"
    }
    assert checked == set(chosen.get_checked_pairs())
    assert not checked & expected
    assert "read from the robot's SRDF" in chosen.to_srdf()


def test_an_srdf_given_replaces_the_computed_pairs(tmp_path: Path) -> None:
    computed = compute_self_collision_filter(load_robot("panda"))
    assert computed.srdf is None
    srdf = tmp_path / "none.srdf"
    srdf.write_text('<robot name="panda"/>')
    bare = compute_self_collision_filter(load_robot("panda", srdf=srdf))
    assert {d.reason for d in bare.disabled} <= {"Rigid"}
    assert len(bare.disabled) < len(computed.disabled)
    again = tmp_path / "again.srdf"
    again.write_text(computed.to_srdf())  # the computed filter, written and read
    read = compute_self_collision_filter(load_robot("panda", srdf=again))
    assert [(d.link_a, d.link_b) for d in read.disabled] == [
        (d.link_a, d.link_b) for d in computed.disabled
    ]


def test_worker_specs_carry_the_srdf() -> None:
    robot = load_robot(URDF)
    spec = get_robot_spec(robot)
    assert spec.srdf == str(SRDF.resolve())
    assert load_spec_robot(spec).disabled_collisions == robot.disabled_collisions


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("<robot", "not valid XML"),
        ("<srdf/>", "the root element is <srdf>, not <robot>"),
        ('<robot><disable_collisions link1="a"/></robot>', "needs link1 and link2"),
    ],
)
def test_a_bad_srdf_is_refused_in_one_line(tmp_path, text, message) -> None:
    srdf = tmp_path / "bad.srdf"
    srdf.write_text(text)
    with pytest.raises(URDFLoadError, match=message):
        load_robot("ur5", srdf=srdf)


def test_the_command_line_takes_an_srdf(tmp_path, capsys) -> None:
    code, out, err = run_cli(
        capsys, "urdf", "srdf", "--robot", "panda", "--srdf", str(tmp_path / "no.srdf")
    )
    assert code == 2 and err.count("\n") == 1 and "SRDF file not found" in err
    code, out, err = run_cli(capsys, "urdf", "srdf", "--robot", str(URDF))
    assert code == 0 and "read from the robot's SRDF" in out
    code, out, err = run_cli(
        capsys, "urdf", "srdf", "--robot", "panda", "--srdf", str(SRDF)
    )
    assert code == 0 and "read from the robot's SRDF" in out


def test_a_map_records_the_srdf() -> None:
    """A workspace map names the SRDF its collision counts were made with."""
    for robot, digest in (
        (load_robot(URDF), hashlib.sha256(SRDF.read_bytes()).hexdigest()),
        (load_robot("panda"), None),
    ):
        grid = make_pose_grid(robot, resolution=0.5, orientations=1)
        attrs = map_attributes(robot, get_robot_spec(robot), grid, None, None, 64, 1)
        assert attrs["srdf_sha256"] == digest
