"""SamplePlan: k distinct in-bounds pixels; flat, (row, col) and mask views agree."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.planner.types import SamplePlan


def test_views_of_a_hand_made_plan():
    p = SamplePlan([0, 2, 1], [3, 0, 1], (3, 4))
    assert p.k == len(p) == 3
    assert p.shape == (3, 4)
    np.testing.assert_array_equal(p.flat, [3, 8, 5])  # r * 4 + c
    np.testing.assert_array_equal(p.rc, [[0, 3], [2, 0], [1, 1]])
    mask = p.mask()
    assert mask.dtype == bool and mask.shape == (3, 4) and mask.sum() == 3
    assert mask[0, 3] and mask[2, 0] and mask[1, 1]


def test_from_flat_round_trips(rng):
    flat = rng.choice(7 * 5, size=12, replace=False)
    p = SamplePlan.from_flat(flat, (7, 5))
    np.testing.assert_array_equal(p.flat, flat)
    np.testing.assert_array_equal(p.rows, flat // 5)
    np.testing.assert_array_equal(p.cols, flat % 5)


def test_the_plan_is_int64_read_only_and_a_copy():
    rows = np.array([0, 1], dtype=np.int32)
    p = SamplePlan(rows, [0, 0], [2.0, 1.0])
    assert p.rows.dtype == np.int64 and p.shape == (2, 1)
    rows[0] = 1  # the caller's array is not the plan's
    assert p.rows[0] == 0
    with pytest.raises(ValueError, match="read-only"):
        p.rows[0] = 1


def test_an_empty_plan():
    p = SamplePlan([], [], (2, 2))
    assert p.k == 0 and not p.mask().any()


@pytest.mark.parametrize(
    ("rows", "cols", "shape", "message"),
    [
        ([0], [0], (0, 3), r"SamplePlan shape must be \(rows, cols\) > 0, got \(0, 3\)"),
        ([0], [0], (3,), r"SamplePlan shape must be \(rows, cols\) > 0, got \(3,\)"),
        ([0, 1], [0], (2, 2), "SamplePlan rows and cols differ in length: 2 vs 1"),
        ([2], [0], (2, 2), r"SamplePlan has pixels outside the grid \(2, 2\)"),
        ([0], [-1], (2, 2), r"SamplePlan has pixels outside the grid \(2, 2\)"),
        ([1, 1], [0, 0], (2, 2), "SamplePlan pixels must be distinct"),
    ],
)
def test_bad_plans_are_refused(rows, cols, shape, message):
    with pytest.raises(ValueError, match=f"^{message}$"):
        SamplePlan(rows, cols, shape)
