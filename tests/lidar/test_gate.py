"""The range gate from the instrument's pose and a reference plane."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar.gate import GateOptions, gate_bins, plane_ranges


def test_plane_ranges_by_hand():
    o = np.array([1.0, 2.0, 50.0])
    d = np.array([[0.0, 0.0, -1.0], [np.sin(0.5), 0.0, -np.cos(0.5)], [1.0, 0.0, 0.0],
                  [0.0, 0.0, 1.0]])  # fmt: skip
    r = plane_ranges(o, d, datum_z=2.0, options=GateOptions(max_range_m=500.0))
    # 48 m above the plane: straight down 48, 0.5 rad off nadir 48 / cos 0.5; horizontal and
    # upward rays never meet it: gated at the largest range
    assert r == pytest.approx([48.0, 48.0 / np.cos(0.5), 500.0, 500.0])
    near = plane_ranges(o, d[:1], datum_z=49.99, options=GateOptions(min_range_m=0.5))
    assert near == pytest.approx([0.5])


def test_gate_bins_cover_the_predictions_with_margins():
    b = gate_bins(np.array([48.0, 55.0]), bin_range_m=0.05, margin_m=2.0)
    assert b.start_opl == pytest.approx(92.0)
    assert b.range_of(b.count) == pytest.approx(57.0, abs=0.05)


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"min_range_m": 10.0, "max_range_m": 5.0}, "min_range_m must be < max_range_m, got 10"),
        ({"min_range_m": -0.1}, "min_range_m must be >= 0, got -0.1"),
        ({"max_range_m": float("inf")}, "max_range_m must be a finite number, got inf"),
        ({"datum_z_m": float("nan")}, "datum_z_m must be a finite number, got nan"),
    ],
)
def test_bad_gate(kw, message):
    with pytest.raises(ValueError, match=message):
        GateOptions(**kw)
