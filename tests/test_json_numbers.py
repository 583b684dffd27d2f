"""JSON-ready numbers: builtins, vectors' rounding noise as 0, nothing else changed."""

from __future__ import annotations

import json
import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from tests.conftest import run_cli
from workbench import load_robot, paper_data
from workbench.demo.run import round_for_json
from workbench.json_numbers import FLOAT64_DIGITS, to_json_ready
from workbench.poses import angeles7_from_se3

#: Half a unit of the 15th significant digit, relative to a vector's largest entry.
NOISE_STEP = 0.5 * 10.0 ** (1 - FLOAT64_DIGITS)

finite = st.floats(allow_nan=False, allow_infinity=False, width=64)


def test_float64_holds_fifteen_digits() -> None:
    assert FLOAT64_DIGITS == 15


def test_numpy_types_become_builtins_and_negative_zero_zero() -> None:
    value = {
        "q": np.array([4.04456009e-15, -180.0, 90.0]),
        "n": np.int64(3),
        "x": np.float64(-0.0),
        "record": (np.float64(1e-16), 7, True, "text", None),
        "lone": 1.2e-16,
        "inf": [math.inf, 1e-30, 1.0],
    }
    ready = to_json_ready(value)
    assert ready == {
        "q": [0.0, -180.0, 90.0],
        "n": 3,
        "x": 0.0,
        "record": [1e-16, 7, True, "text", None],  # mixed: not a vector
        "lone": 1.2e-16,  # a scalar is a measurement
        "inf": [math.inf, 0.0, 1.0],
    }
    assert type(ready["n"]) is int and math.copysign(1.0, ready["x"]) == 1.0
    json.dumps(ready)


@given(st.lists(finite, min_size=2, max_size=8))
def test_only_noise_below_the_largest_entrys_last_digit_changes(values) -> None:
    ready = to_json_ready(np.array(values))
    largest = max(abs(v) for v in values)
    for before, after in zip(values, ready, strict=True):
        if abs(before) < NOISE_STEP * largest:
            assert after == 0.0
        else:
            assert after == before  # full precision, bit for bit


@given(st.lists(finite, min_size=2, max_size=8))
def test_nine_digits_zero_below_the_ninth(values) -> None:
    ready = round_for_json(values)
    largest = max(abs(v) for v in values)
    for before, after in zip(values, ready, strict=True):
        if abs(before) < 0.5e-8 * largest:
            assert after == 0.0
        else:
            assert after == float(f"{before:.9g}")


def test_ik_json_prints_the_pick_joint_at_zero(capsys) -> None:
    """Angeles' pick has θ1 = 0; the closed form returns it as rounding noise."""
    pose = load_robot("puma560").fk(np.radians(paper_data.ANGELES_PICK_Q_DEG))
    pose7 = [repr(float(x)) for x in angeles7_from_se3(pose)]
    code, out, _ = run_cli(
        capsys, "ik", "--robot", "puma560", "--angeles7", *pose7, "--all", "--json"
    )
    assert code == 0
    rows = json.loads(out)["solutions"]
    solution = min(  # Table III's branch
        rows,
        key=lambda row: np.abs(
            np.array(row["q_deg"]) - paper_data.ANGELES_PICK_Q_DEG
        ).max(),
    )
    assert solution["q"][0] == 0.0 and solution["q_deg"][0] == 0.0
    np.testing.assert_allclose(
        solution["q_deg"], paper_data.ANGELES_PICK_Q_DEG, rtol=0, atol=1e-9
    )
