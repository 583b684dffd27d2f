"""The singularity HTML report: self-contained, every figure embedded, key numbers."""

from __future__ import annotations

import base64
import json
import re
import subprocess
import sys
from html.parser import HTMLParser

import numpy as np
import pytest

from tests.conftest import run_cli
from workbench import load_robot
from workbench.reports import singularity_report
from workbench.reports.singularity_report import (
    build_singularity_report,
    write_singularity_report,
)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
DATA_URI = "data:image/png;base64,"
SMALL = {"grid_size": 60, "svd_grid_size": 16, "samples": 200}
REL_DET = 1e-9
#: Relative agreement of the report's SVD measures with numpy's SVD of
#: Pinocchio's Jacobians (the same numbers, computed again).
REL_MEASURE = 1e-12
NUMERIC_FIGURES = ("sigma_min_map", "manipulability_map", "condition_number_map")
#: Figures of a seven-axis arm without analytic conditions (the Panda).
SEVEN_AXIS_FIGURES = (*NUMERIC_FIGURES, "sigma_min_samples")
#: σmin of Pinocchio's J on an analytic locus (rank lost to rounding).
ATOL_SINGULAR = 1e-12


class _Sources(HTMLParser):
    """Collect every src/href attribute of the document."""

    def __init__(self) -> None:
        super().__init__()
        self.images: list[str] = []
        self.links: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for name, value in attrs:
            if name == "src":
                self.images.append(value or "")
            elif name == "href":
                self.links.append(value or "")


@pytest.fixture(scope="module")
def kang_report(tmp_path_factory):
    robot = load_robot("puma560-kang")
    t = np.linspace(0.0, 1.0, 21)
    q = np.tile(np.radians([0.0, 30.0, 40.0, 0.0, 20.0, 0.0]), (t.size, 1))
    q[:, 4] = np.radians(np.linspace(20.0, -20.0, t.size))
    path = tmp_path_factory.mktemp("report") / "kang.html"
    report = write_singularity_report(robot, path, trajectory=(t, q), **SMALL)
    return report, path.read_text(encoding="utf-8")


@pytest.mark.slow
def test_every_figure_is_an_embedded_png(kang_report) -> None:
    report, text = kang_report
    parser = _Sources()
    parser.feed(text)
    assert len(parser.images) == len(report.figures) >= 4
    for src in parser.images:
        assert src.startswith(DATA_URI)
        assert base64.b64decode(src[len(DATA_URI) :]).startswith(PNG_MAGIC)
    assert parser.links == []  # no stylesheet or script to fetch
    assert "<script" not in text
    assert set(report.summary["figures"]) >= {
        "det_j_map",
        "sigma_min_map",
        "trajectory",
    }


def test_key_numbers_appear(kang_report) -> None:
    report, text = kang_report
    summary = report.summary
    for value in ("+87.308°", "-92.692°", "+0.186657 m²"):
        assert value in text
    assert summary["elbow_theta3_deg"] == pytest.approx([87.308364, -92.691636])
    assert summary["elbow_theta3_within_limits"] == [True, False]
    assert summary["cross_check"]["max_relative_error"] <= REL_DET
    assert f"{summary['cross_check']['max_relative_error']:.2e}" in text
    assert summary["cross_check"]["subgrid_max_abs_error"] <= 1e-12
    assert "a2 c2 + a3 c23 + d4 s23" in text
    for record in summary["degenerate_directions"]:
        assert record["residual"] <= 1e-9
    assert summary["closest_approach"]["wrist"]["crossings"] == [pytest.approx(0.5)]


def test_degenerate_directions_and_arms_sections(kang_report) -> None:
    report, text = kang_report
    assert "Degenerate directions" in text
    assert text.count("<tr><td>") >= 5
    if "arms" in report.figures:  # needs workbench.plots.arm
        assert "arm in each singular configuration" in text


@pytest.mark.slow
def test_angeles_report_has_its_own_elbow_angles_and_progress() -> None:
    stages: dict[str, tuple[int, int]] = {}
    report = build_singularity_report(
        load_robot("puma560"),
        **SMALL,
        progress=lambda stage, done, total: stages.__setitem__(stage, (done, total)),
    )
    assert "+87.474°" in report.html and "-92.526°" in report.html
    assert report.summary["det_j_constant"] < 0.0
    assert stages == {"det J map": (3600, 3600), "σmin map": (256, 256)}


def test_report_of_a_robot_without_dh_table() -> None:
    report = build_singularity_report(
        load_robot("generic6r"), grid_size=12, svd_grid_size=8, samples=10
    )
    assert report.summary["elbow_theta3_deg"] is None
    assert report.summary["puma_type"] is False
    assert set(report.figures) == {"det_j_map", *NUMERIC_FIGURES}
    assert "numeric measures only" in report.html


def grid_jacobians(robot, size: int) -> np.ndarray:
    """Pinocchio's Jacobians over the report's (θ2, θ3) grid, shape (size², 6, nv)."""
    q_fixed = singularity_report._fixed_joints(robot, None, 0)
    x, y = (np.linspace(*singularity_report._window(robot, j), size) for j in (1, 2))
    jacobians = []
    for theta3 in y:
        for theta2 in x:
            q = q_fixed.copy()
            q[1], q[2] = theta2, theta3
            jacobians.append(robot.jacobian(q))
    return np.array(jacobians)


@pytest.mark.slow
def test_report_of_a_seven_axis_arm_has_the_numeric_maps_and_no_det() -> None:
    robot = load_robot("panda")
    size = 9
    stages: dict[str, tuple[int, int]] = {}
    report = build_singularity_report(
        robot,
        grid_size=size,
        svd_grid_size=size,
        samples=10,
        progress=lambda stage, done, total: stages.__setitem__(stage, (done, total)),
    )
    summary = report.summary
    assert summary["det_j_map"] is None and summary["elbow_theta3_deg"] is None
    assert summary["sigma_min_map"]["shape"] == [size, size]
    assert stages == {"σmin map": (size * size, size * size)}
    assert summary["figures"] == list(report.figures) == list(SEVEN_AXIS_FIGURES)
    for name in SEVEN_AXIS_FIGURES:
        assert report.figures[name].startswith(PNG_MAGIC)
    parser = _Sources()
    parser.feed(report.html)
    assert len(parser.images) == len(SEVEN_AXIS_FIGURES)
    assert "srs" not in summary and "no analytic singularity conditions" in report.html
    for heading in ("σmin over", "Manipulability over", "Condition number over"):
        assert heading in report.html
    assert "no determinant" in report.html and "det J map" not in report.html
    sv = np.linalg.svd(grid_jacobians(robot, size), compute_uv=False)
    expected = {
        "sigma_min": sv[:, -1],
        "manipulability": np.prod(sv, axis=1),
        "condition_number": sv[:, 0] / sv[:, -1],
    }
    assert set(summary["map_ranges"]) == set(expected)
    for name, values in expected.items():
        np.testing.assert_allclose(
            summary["map_ranges"][name],
            [values.min(), values.max()],
            rtol=REL_MEASURE,
            atol=0,
        )


@pytest.mark.slow
def test_cli_report_of_a_seven_axis_arm(capsys, tmp_path) -> None:
    html = tmp_path / "panda.html"
    argv = ["--robot", "panda", "--out", str(html), "--svd-grid", "6", "--no-progress"]
    code, out, err = run_cli(capsys, "report", "singularities", *argv, "--json")
    assert (code, err) == (0, "")
    summary = json.loads(out)
    assert summary["det_j_map"] is None
    assert summary["figures"] == list(SEVEN_AXIS_FIGURES)
    assert "Manipulability over" in html.read_text(encoding="utf-8")
    code, out, err = run_cli(capsys, "report", "singularities", *argv)
    assert (code, err) == (0, "")
    assert "σmin map 6×6" in out and "det J" not in out
    assert "(numeric only: no analytic conditions)" in out


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ur5", "kuka-kr6-r700"])
def test_report_of_any_closed_form_arm_classifies(name: str) -> None:
    report = build_singularity_report(
        load_robot(name), grid_size=12, svd_grid_size=8, samples=300
    )
    summary = report.summary
    assert summary["family"] in ("opw", "ur") and summary["puma_type"] is False
    assert summary["cross_check"]["max_relative_error"] <= REL_DET
    assert sum(summary["classes"].values()) >= 300
    assert "recognised from the joint axes" in report.html
    assert "classes of those" in report.html
    assert "Degenerate directions" in report.html and "arms" in report.figures
    records = summary["degenerate_directions"]
    assert len(records) == 5
    for record in records:
        assert max(record["residual"], record["tool_residual"]) <= 1e-9
    assert len(summary["elbow_theta3_deg"]) == 2
    if name == "ur5":
        assert summary["elbow_theta3_deg"] == pytest.approx([0.0, 180.0], abs=1e-6)


@pytest.mark.slow
@pytest.mark.subprocess
def test_core_modules_do_not_import_matplotlib() -> None:
    code = (
        "import sys, workbench.singularities, "
        "workbench.cli.singularities, workbench.cli.report, workbench.reports; "
        "bad = [m for m in sys.modules if re.match('matplotlib|meshcat', m)]; "
        "assert not bad, bad"
    )
    result = subprocess.run(
        [sys.executable, "-c", "import re; " + code],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 0, result.stderr


def test_html_has_title_and_units(kang_report) -> None:
    _, text = kang_report
    assert re.search(r"<title>Singularities of puma560-kang</title>", text)
    assert "det J [m³]" not in text or "m³" in text
    assert "[m/s; rad/s]" in text


@pytest.mark.slow
def test_report_of_an_srs_arm_checks_its_conditions_against_pinocchio() -> None:
    """iiwa14: det(J Jᵀ), the loci and the sweeps against Pinocchio's J (numpy SVD)."""
    robot = load_robot("iiwa14")
    report = build_singularity_report(robot, grid_size=8, svd_grid_size=8, samples=300)
    summary = report.summary
    srs = summary["srs"]
    assert srs["cross_check"]["samples"] == 300
    assert srs["cross_check"]["max_relative_error"] < REL_DET
    assert [locus["kind"] for locus in srs["loci"]] == [
        "elbow",
        "shoulder",
        "wrist",
        "shoulder_wrist",
    ]
    for locus in srs["loci"]:
        q = np.radians(locus["q_deg"])
        sigma = np.linalg.svd(robot.jacobian(q), compute_uv=False)[-1]
        assert sigma < ATOL_SINGULAR and locus["sigma_min"] < ATOL_SINGULAR
        assert abs(locus["condition"]) < ATOL_SINGULAR
        assert locus["residual"] < ATOL_SINGULAR
    for sweep in srs["sweeps"].values():
        assert sweep["sigma_min_at_locus"] < ATOL_SINGULAR
        assert sweep["sigma_min_elsewhere"] > 1e-5  # rank only lost on the locus
    sampled = summary["sigma_min_samples"]
    assert 0.0 < sampled["min"] <= sampled["median"] <= sampled["max"]
    assert summary["figures"] == [
        *SEVEN_AXIS_FIGURES[:3],
        "sigma_min_samples",
        "srs_sweeps",
    ]
    assert "SRS: analytic conditions of the 6 × 7 Jacobian" in report.html
    assert "SRS seven-axis arm" in report.html


@pytest.mark.slow
def test_cli_report_of_an_srs_arm(capsys, tmp_path) -> None:
    html = tmp_path / "iiwa.html"
    argv = ["--robot", "iiwa14", "--out", str(html), "--svd-grid", "6", "--no-progress"]
    code, out, err = run_cli(capsys, "report", "singularities", *argv)
    assert (code, err) == (0, "")
    assert "SRS det(J Jᵀ) analytic vs Pinocchio" in out
    assert out.count("locus: σmin") == 4
