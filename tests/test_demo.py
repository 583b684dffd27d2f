"""Angeles et al. Table II from Table III through the Python API."""

from __future__ import annotations

import numpy as np

from workbench.demo import compare_table2, format_table2

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
