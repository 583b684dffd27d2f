"""Robot.fk and Robot.jacobian*: the cheap input check is exact; Pinocchio's values."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from workbench import DimensionError, NonFiniteError, Robot

ATOL_EXACT = 1e-12
"""Same quantity computed twice."""

JACOBIANS = (
    ("jacobian", pin.ReferenceFrame.LOCAL_WORLD_ALIGNED),
    ("jacobian_local", pin.ReferenceFrame.LOCAL),
    ("jacobian_world", pin.ReferenceFrame.WORLD),
)


def test_fk_and_jacobians_are_pinocchios(puma: Robot, rng) -> None:
    model, data = puma.model, puma.model.createData()
    for q in rng.uniform(puma.lower, puma.upper, (20, puma.nq)):
        pin.forwardKinematics(model, data, q)
        for frame, frame_id in ((None, puma.tool_frame_id), ("link3", None)):
            frame_id = puma.get_frame_id(frame) if frame_id is None else frame_id
            expected = pin.updateFramePlacement(model, data, frame_id)
            pose = puma.fk(q, frame)
            np.testing.assert_allclose(
                pose.homogeneous, expected.homogeneous, rtol=0, atol=ATOL_EXACT
            )
            for name, reference in JACOBIANS:
                jac = pin.computeFrameJacobian(model, data, q, frame_id, reference)
                np.testing.assert_allclose(
                    getattr(puma, name)(q, frame), jac, rtol=0, atol=ATOL_EXACT
                )


def test_fk_returns_a_copy(puma: Robot) -> None:
    first = puma.fk(np.zeros(6))
    puma.fk(np.full(6, 0.5))
    np.testing.assert_allclose(
        first.homogeneous, puma.fk(np.zeros(6)).homogeneous, rtol=0, atol=0
    )


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("method", ["fk", "jacobian", "jacobian_local"])
def test_non_finite_float_arrays_are_rejected(puma: Robot, bad, method) -> None:
    q = np.zeros(6)
    q[3] = bad
    with pytest.raises(NonFiniteError, match="must be finite"):
        getattr(puma, method)(q)


def test_huge_finite_values_pass(puma: Robot) -> None:
    q = np.full(6, 1e300)
    expected = pin.SE3(puma.fk(np.array(q)))
    assert np.isfinite(puma.fk(q).homogeneous).all()
    np.testing.assert_array_equal(puma.fk(q).homogeneous, expected.homogeneous)
    assert puma.jacobian(q).shape == (6, 6)


@pytest.mark.parametrize(
    "q",
    [np.zeros(5), np.zeros(7), np.zeros((6, 1)), np.zeros((1, 6)), np.float64(0.0)],
)
def test_wrong_shapes_are_rejected(puma: Robot, q) -> None:
    with pytest.raises(DimensionError):
        puma.fk(q)
    with pytest.raises(DimensionError):
        puma.jacobian(q)


def test_other_input_types_are_converted(puma: Robot) -> None:
    expected = puma.fk(np.zeros(6)).homogeneous
    for q in ([0, 0, 0, 0, 0, 0], np.zeros(6, dtype=np.int64), np.zeros(6, np.float32),
              np.zeros(12)[::2]):  # fmt: skip
        np.testing.assert_array_equal(puma.fk(q).homogeneous, expected)
