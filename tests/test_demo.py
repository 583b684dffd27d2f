"""Angeles et al. Table II from Table III, and Section V end to end, via the API."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from workbench import ik, paper_data
from workbench.atomic_files import atomic_file
from workbench.demo.base_placement import (
    FIGURE,
    TOP,
    format_base_placement,
    run_base_placement_demo,
)
from workbench.demo.pick_and_place import (
    format_pick_and_place,
    run_pick_and_place_demo,
)
from workbench.demo.run import (
    _InSecondProcess,
    compare_table2,
    format_table2,
    round_for_json,
)
from workbench.errors import InputError
from workbench.workspace.placement import base_transform

ATOL_PRINTED = 1e-9


def test_table2_reproduced_to_printed_precision(puma) -> None:
    rows = compare_table2(puma)
    assert [r.pose for r in rows] == ["pick", "place"]
    for row in rows:
        np.testing.assert_allclose(row.rounded, row.printed, rtol=0, atol=ATOL_PRINTED)
        assert row.matches
        # and the unrounded values lie within half a printed unit
        assert np.all(np.abs(row.computed - row.printed) <= 0.005 + ATOL_PRINTED)


def test_table2_markdown_lists_every_coordinate(puma) -> None:
    text = format_table2(compare_table2(puma))
    for label in ("e_x sinφ", "cosφ", "p_z [mm]", "-470.55", "295.46"):
        assert label in text


def test_section5_end_to_end(puma, tmp_path) -> None:
    result = run_pick_and_place_demo(puma, tmp_path, plots=False)
    assert result["table3_violations"] == []
    # IK of the 2-decimal Table II puts joint 2 a hair above 45 deg at t = 0
    (v,) = result["violations"]
    assert (v["joint"], v["kind"], v["t"]) == ("joint2", "position", 0.0)
    assert 0 < np.rad2deg(v["value"] - v["limit"]) < 1e-3
    assert result["pick"]["branch"] == "right/elbow-down/no-flip"
    assert np.abs(result["place"]["minus_table3_deg"]).max() < 1.0
    assert len(result["ik_branches"]["pick"]) == 8
    assert result["table3_min_duration"] == pytest.approx(7.3304, abs=1e-4)
    assert result["time_optimal_ratio"] == pytest.approx(2.0, abs=1e-4)
    assert result["tool_end_rates_max"] <= 1e-9
    assert result["amplitude"] == pytest.approx(6.2968, abs=1e-4)
    text = format_pick_and_place(result)
    assert "joint2 position 45.0005 deg at t = 0 s" in text
    assert "time-optimal on the same path 3.6652 s (ratio 2.000)" in text


def test_paper_values_are_stored_as_printed(puma) -> None:
    pick = compare_table2(puma)[0]
    assert pick.printed[4:].tolist() == [-94.07, 125.4, -470.55]  # [mm], exact


def test_round_for_json_keeps_nine_significant_digits() -> None:
    value = {
        "a": np.array([-94.07000000000001, 1.0 / 3.0]),
        "b": (np.float64(2.0e-12 / 3.0), True, "text", None, 7),
        "c": [float("inf")],
    }
    assert round_for_json(value) == {
        "a": [-94.07, 0.333333333],
        "b": [6.66666667e-13, True, "text", None, 7],
        "c": [float("inf")],
    }


def _fail_in_child(parent: int) -> int:
    if os.getpid() != parent:
        raise RuntimeError("only in the second process")
    return os.getpid()


def test_second_process_returns_the_result(tmp_path: Path) -> None:
    section = _InSecondProcess(tmp_path, os.getpid)
    with section:
        pid = section.result()
    if sys.platform == "linux" and len(os.sched_getaffinity(0)) > 1:
        assert pid != os.getpid()  # it ran there
    else:
        assert pid == os.getpid()


def test_second_process_failure_makes_the_call_here(tmp_path: Path) -> None:
    # here the call succeeds (and would raise its own error if it failed)
    with _InSecondProcess(tmp_path, _fail_in_child, os.getpid()) as section:
        assert section.result() == os.getpid()
    start = time.perf_counter()
    with pytest.raises(InputError), _InSecondProcess(tmp_path, time.sleep, 60.0):
        raise InputError("raised here: the second process is stopped")
    assert time.perf_counter() - start < 30.0


def _write_forever(folder: Path) -> None:
    with atomic_file(folder / "slow.csv") as tmp:
        tmp.write_text("partial")
        time.sleep(60.0)


def test_second_process_ends_with_its_parent_and_leaves_no_file(
    tmp_path: Path,
) -> None:
    with (
        pytest.raises(InputError),
        _InSecondProcess(tmp_path, _write_forever, tmp_path),
    ):
        time.sleep(0.5)  # the child is writing now
        raise InputError("stops the child: SIGTERM, its temporary file removed")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_base_placement_of_table3(puma, tmp_path) -> None:
    """The demo's coarse map and placement: exact bases, none worse than the paper's."""
    result = run_base_placement_demo(puma, tmp_path, plots=True)
    assert result["candidates"] == 25 * 25 * 24
    assert 1 <= len(result["placements"]) <= TOP
    assert result["paper_base"]["all_reachable"] is True
    best = result["placements"][0]
    assert best["all_reachable"] and best["branch"] is not None
    assert best["min_dexterity"] >= result["paper_base"]["min_dexterity"]
    inverse = np.linalg.inv(base_transform(best["x"], best["y"], 0.0, best["yaw"]))
    for q_deg in (paper_data.ANGELES_PICK_Q_DEG, paper_data.ANGELES_PLACE_Q_DEG):
        pose = inverse @ puma.fk(np.deg2rad(q_deg)).homogeneous
        usable = [s for s in ik.analytic(puma, pose) if s.within_limits]
        assert best["branch"] in {s.branch for s in usable}
    assert (tmp_path / FIGURE).read_bytes()[:4] == b"\x89PNG"
    text = format_base_placement(result)
    assert "candidate bases" in text and "the paper's base" in text
