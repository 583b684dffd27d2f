"""The command line's contract under bad input, drawn by hypothesis.

Every input class of ``tests/_cli_fuzz.py`` (unwritable or input-clobbering
output paths, malformed JSON and CSV files, sizes beyond the stated maxima,
numbers in every notation, contradictory flags): the exit code is 0, 2 or 3,
a failure prints one line on stderr and no traceback, and a failed run leaves
every existing file byte-identical. A few cases also run as a real process.
``python -m tests.run_cli_robustness`` runs hundreds of cases per class.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests._cli_fuzz import (
    CLASSES,
    IK_AT,
    IK_SEVEN,
    OLD,
    PICK,
    PLACE,
    PLACE_ON_MAP,
    PLAN,
    SMALL_MAP,
    VIEW_SEVEN,
    WORKSPACE_CLASSES,
    contract_violations,
    run_case,
    write_inputs,
)

EXAMPLES_PER_CLASS = 8
#: Per ``workspace`` class: each case copies a small map (a few ms).
WORKSPACE_EXAMPLES_PER_CLASS = 12
ATOL_IK = 1e-9  # [m, rad] FK residual of the IK of an FK pose printed with repr()


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(CLASSES))
def test_bad_input_keeps_the_contract(name: str) -> None:
    @settings(
        max_examples=EXAMPLES_PER_CLASS,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )
    @given(case=CLASSES[name])
    def check(case: tuple[list[str], bytes]) -> None:
        argv, bad = case
        with tempfile.TemporaryDirectory() as folder:
            write_inputs(Path(folder))
            outcome = run_case(argv, Path(folder), bad)
        assert contract_violations(outcome) == [], (argv, outcome)

    check()


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(WORKSPACE_CLASSES))
def test_bad_workspace_input_keeps_the_contract(name: str) -> None:
    @settings(
        max_examples=WORKSPACE_EXAMPLES_PER_CLASS,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
        deadline=None,
    )
    @given(case=WORKSPACE_CLASSES[name])
    def check(case: tuple[list[str], bytes]) -> None:
        argv, bad = case
        with tempfile.TemporaryDirectory() as folder:
            write_inputs(Path(folder), workspace=True)
            outcome = run_case(argv, Path(folder), bad)
        assert contract_violations(outcome) == [], (argv, outcome)

    check()


def _run_in(
    tmp_path: Path, *argv: str, workspace: bool = False
) -> tuple[int, str, str]:
    write_inputs(tmp_path, workspace=workspace)
    outcome = run_case(list(argv), tmp_path)
    assert contract_violations(outcome) == [], outcome
    return outcome.code, outcome.stdout, outcome.stderr


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["urdf", "from-dh", "t.json", "--out", "t.json"], "also an input"),
        (
            ["view", "--robot", "ur5", "--scene", "scene.json", "--html", "scene.json"],
            "also an input",
        ),
        ([*PLAN, "--csv", "old.csv", "--plot", "o.xyz"], "unknown figure format"),
        ([*PLAN, "--csv", "nodir/o.csv"], "does not exist"),
        ([*PLAN, "--plot", "nodir/o.png"], "does not exist"),
        (
            ["report", "singularities", "--robot", "puma560", "--out", "dir"],
            "is a folder",
        ),
        (["demo", "--out", "old.txt"], "not a folder"),
        ([*PLAN, "--rate", "1e9"], "at most 100000 Hz"),
        (["fishcut", "--seed", "-1"], "--seed: must be 0.."),
        ([*PLAN, "--scene", "scene.json", "--no-collision"], "contradict"),
        ([*IK_AT, "1e308", "1e308", "1e308", "--mm"], "at most 1e+06 m"),
        ([*IK_AT, "0.4", "0", "0.4", "--redundancy", "1"], "no redundancy"),
        ([*IK_SEVEN, "--redundancy", "1e308"], "at most 1000 rad"),
        ([*VIEW_SEVEN, "--redundancy-sweep", "65"], "must be 1..64"),
    ],
)
def test_found_cases_exit_2(tmp_path: Path, argv: list[str], fragment: str) -> None:
    code, out, err = _run_in(tmp_path, *argv)
    assert (code, out) == (2, "") and fragment in err, err
    assert (tmp_path / "old.csv").read_text() == OLD


@pytest.mark.parametrize(
    ("key", "value", "fragment"),
    [
        ("tool_frame", 'a"b<c>&', "'tool_frame' must be letters"),
        ("tool_frame", "link1", "name of a generated link"),
        ("name", "arm-->x", "without '--'"),
    ],
)
def test_dh_names_that_break_the_urdf_exit_2(
    tmp_path: Path, key: str, value: str, fragment: str
) -> None:
    table = {"name": "t", "joints": [{"alpha": 0.0, "a": 0.1, "d": 0.2}] * 6}
    (tmp_path / "n.json").write_text(json.dumps({**table, key: value}))
    code, _, err = _run_in(tmp_path, "urdf", "from-dh", "n.json", "--out", "o.urdf")
    assert code == 2 and fragment in err
    assert not (tmp_path / "o.urdf").exists()


def test_numbers_in_any_notation_are_values(tmp_path: Path) -> None:
    code, out, _ = _run_in(
        tmp_path, "fk", "--robot", "ur5", "--rad", "-1", "1", "0", "-1.25", "-1e-10",
        "0", "--json",
    )  # fmt: skip
    assert code == 0
    pose = json.loads(out)
    matrix = np.eye(4)
    matrix[:3, :3], matrix[:3, 3] = pose["rotation"], pose["position"]
    typed = [repr(float(x)) for x in matrix.ravel()]  # as pasted from fk's output
    code, out, err = _run_in(
        tmp_path, "ik", "--robot", "ur5", "--matrix", *typed, "--json"
    )
    assert code == 0, err
    assert any(-1e-9 < x < 0.0 for x in matrix.ravel())  # e.g. -2.9e-11
    residual = json.loads(out)["solutions"][0]["residual"]
    assert residual <= ATOL_IK


def test_infeasible_ik_prints_its_json(tmp_path: Path) -> None:
    code, out, err = _run_in(
        tmp_path, "ik", "--robot", "ur5", "--xyz-quat-wxyz", "5", "5", "5", "1", "0",
        "0", "0", "--json",
    )  # fmt: skip
    result = json.loads(out)
    assert code == 3 and result["feasible"] is False and result["solutions"] == []
    assert "out of reach" in result["error"] and err.count("\n") == 1


@pytest.mark.slow
def test_plan_writes_an_infeasible_result_and_nothing_on_bad_input(
    tmp_path: Path,
) -> None:
    code, _, _ = _run_in(
        tmp_path, *PLAN, "--duration", "0.5", "--csv", "old.csv", "--plot", "old.png"
    )
    assert code == 3  # too fast: the CSV and plot are written, exit 3 after
    assert (tmp_path / "old.csv").read_text() != OLD
    (tmp_path / "old.csv").write_text(OLD)
    code, _, _ = _run_in(tmp_path, *PLAN, "--csv", "old.csv", "--plot", "nodir/p.png")
    assert code == 2 and (tmp_path / "old.csv").read_text() == OLD


def test_export_checks_what_plan_checks(tmp_path: Path) -> None:
    code, out, err = _run_in(
        tmp_path, "export", "--format", "csv", "--pick-place", "--out", "old.csv",
        "--json",
    )  # fmt: skip
    assert code == 3 and "collision of" in err
    assert json.loads(out)["feasible"] is False
    assert (tmp_path / "old.csv").read_text() == OLD
    plan_code, _, _ = _run_in(
        tmp_path, "plan", "pick-place", "--robot", "puma560", "--pick-deg", *PICK,
        "--place-deg", *PLACE, "--duration", "10", "--rate", "100",
    )  # fmt: skip
    assert plan_code == 3


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize(
    ("argv", "code"),
    [
        (["fk", "--robot", "ur5", "--rad", "-1", "1", "0", "-1.25", "-1e-10", "0"], 0),
        (["urdf", "from-dh", "t.json", "--out", "t.json"], 2),
        ([*IK_AT, "5", "5", "5", "--json"], 3),
    ],
)
def test_as_a_process(tmp_path: Path, argv: list[str], code: int) -> None:
    write_inputs(tmp_path)
    done = subprocess.run(
        [sys.executable, "-m", "workbench", *argv],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == code, done.stderr
    assert "Traceback" not in done.stderr
    assert len(done.stderr.splitlines()) == (code != 0)
    if code == 3:
        assert json.loads(done.stdout)["feasible"] is False


@given(st.sampled_from(["-1e-10", "-2.5E+3", "-.5", "-7", "-1.", "-0e0"]))
@settings(max_examples=6)
def test_negative_number_pattern(text: str) -> None:
    from workbench.cli import _NUMBER

    assert _NUMBER.match(text) and float(text) <= 0.0


def test_fishcut_prints_json_when_the_run_fails(tmp_path: Path) -> None:
    code, out, err = _run_in(
        tmp_path, "fishcut", "--max-velocity", "0.6", "--csv", "old.csv", "--json"
    )
    result = json.loads(out)
    assert code == 3 and result["command"] == "fishcut"
    assert result["feasible"] is False and "velocity" in result["error"]
    assert err.count("\n") == 1 and (tmp_path / "old.csv").read_text() == OLD


_VIEW = ["workspace", "view", "map.zarr", "--html"]
_REPORT = ["workspace", "report", "map.zarr", "--out"]


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        ([*_REPORT, "map.zarr/zarr.json"], "inside the input folder map.zarr"),
        ([*_VIEW, "map.zarr/reached/zarr.json"], "inside the input folder"),
        ([*_REPORT, "map.zarr"], "is a folder"),
        (["workspace", "view", "trunc.zarr", "--html", "v.html"], "damaged"),
        (["workspace", "report", "trunc.zarr", "--out", "r.html"], "damaged"),
        ([*PLACE_ON_MAP, "--map", "trunc.zarr", "--targets", "task.csv"], "damaged"),
        (["workspace", "view", "nodone.zarr", "--html", "v.html"], "no array 'done'"),
        (["workspace", "report", "m.zarr.partial", "--out", "r.html"], "unfinished"),
        ([*SMALL_MAP, "old.csv"], "already exists"),
        ([*SMALL_MAP, "nodir/m.zarr"], "does not exist"),
        ([*SMALL_MAP, "x.zarr", "--cone", "0", "0", "0", "30"], "nonzero vector"),
        (
            [
                *PLACE_ON_MAP,
                "--targets",
                "task.csv",
                "--region",
                "0",
                "1e300",
                "0",
                "1e300",
                "--resolution",
                "0.001",
            ],
            "1e+303 × 1e+303 × 4 candidates",
        ),
    ],
)
def test_found_workspace_cases_exit_2(
    tmp_path: Path, argv: list[str], fragment: str
) -> None:
    code, out, err = _run_in(tmp_path, *argv, workspace=True)
    assert (code, out) == (2, "") and fragment in err, err
    assert (tmp_path / "map.zarr" / "zarr.json").read_text().startswith("{")


def test_found_workspace_truncated_chunks_of_a_queried_array(tmp_path: Path) -> None:
    write_inputs(tmp_path, workspace=True)
    for chunk in (tmp_path / "map.zarr" / "dexterity").rglob("c/**/*"):
        if chunk.is_file():
            chunk.write_bytes(b"\0")
    outcome = run_case([*PLACE_ON_MAP, "--targets", "task.csv"], tmp_path)
    assert contract_violations(outcome) == []
    assert outcome.code == 2 and "array 'dexterity'" in outcome.stderr


def test_cone_axis_of_huge_components_is_a_direction(tmp_path: Path) -> None:
    code, _, err = _run_in(
        tmp_path, *SMALL_MAP, "x.zarr", "--cone", "1e308", "1e308", "0", "30",
        workspace=True,
    )  # fmt: skip
    assert code == 0, err
    attrs = json.loads((tmp_path / "x.zarr" / "zarr.json").read_text())["attributes"]
    half = np.sqrt(0.5)
    assert attrs["orientation_set"]["axis"] == pytest.approx([half, half, 0.0])


def test_infeasible_placement_prints_its_json(tmp_path: Path) -> None:
    code, out, err = _run_in(
        tmp_path, *PLACE_ON_MAP, "--targets", "task.csv", "--region", "5", "6", "5",
        "6", "--json", workspace=True,
    )  # fmt: skip
    result = json.loads(out)
    assert code == 3 and result["feasible"] is False
    assert "no base placement reaches all 1 task poses" in result["error"]
    assert result["robot"] == "puma560" and result["poses"] == 1
    assert all(not p["all_reachable"] for p in result["placements"])
    assert err.count("\n") == 1 and result["error"] in err


#: An output that is one of the command's inputs, or inside an input folder, in
#: every command that writes files: refused (exit 2, one line), the input unchanged.
#: ``puma.urdf`` is the catalog PUMA's URDF, ``link.urdf`` a symbolic link to it.
OUTPUT_IS_INPUT = [
    ["workspace", "view", "map.zarr", "--robot", "puma.urdf", "--html", "puma.urdf"],
    ["workspace", "view", "map.zarr", "--robot", "puma.urdf", "--html", "link.urdf"],
    ["workspace", "view", "map.zarr", "--html", "map.zarr/view.html"],
    ["workspace", "report", "map.zarr", "--out", "map.zarr/zarr.json"],
    ["view", "--robot", "puma.urdf", "--deg", *["0"] * 6, "--html", "puma.urdf"],
    ["plan", "pick-place", "--robot", "puma.urdf", "--pick-deg", *["0"] * 6,
     "--place-deg", *["10"] * 6, "--duration", "5", "--csv", "link.urdf"],
    ["plan", "pick-place", "--robot", "puma560", "--pick-deg", *["0"] * 6,
     "--place-deg", *["10"] * 6, "--duration", "5", "--scene", "scene.json",
     "--plot", "scene.json"],
    ["fishcut", "--robot", "puma.urdf", "--html", "puma.urdf"],
    ["export", "--format", "csv", "--trajectory", "traj.csv", "--out", "traj.csv"],
    ["report", "singularities", "--robot", "puma.urdf", "--out", "puma.urdf"],
    [*SMALL_MAP, "map.zarr/inner.zarr"],  # a map inside a map
]  # fmt: skip


@pytest.mark.parametrize("argv", OUTPUT_IS_INPUT, ids=lambda a: " ".join(a[:2]))
def test_no_output_overwrites_an_input(tmp_path: Path, argv: list[str]) -> None:
    from workbench import load_robot

    write_inputs(tmp_path, workspace=True)
    puma = tmp_path / "puma.urdf"
    puma.write_bytes(Path(load_robot("puma560").urdf_path).read_bytes())
    (tmp_path / "link.urdf").symlink_to(puma)
    before = {
        p: p.read_bytes()
        for p in tmp_path.rglob("*")
        if p.is_file() and not p.is_symlink()
    }
    outcome = run_case(argv, tmp_path)
    assert contract_violations(outcome) == [], outcome
    assert outcome.code == 2 and outcome.stdout == "", outcome
    said = ("also an input", "inside the input", "inside the store")
    assert any(words in outcome.stderr for words in said), outcome.stderr
    after = {p: p.read_bytes() for p in before}
    assert after == before  # no input changed
