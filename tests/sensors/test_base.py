"""The sensor interface's Acquisition: a NaN-holed map to samples and back, the one-line
NothingMeasured error; the ideal sampler satisfies the Sensor protocol."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.errors import NothingMeasuredError, SimlunarError
from simlunar.sensors.base import Acquisition, NothingMeasured, Sensor
from simlunar.sensors.ideal import IdealSampler


def test_from_map_keeps_the_finite_cells_in_row_major_order():
    m = np.array([[np.nan, 1.5, np.nan], [2.0, np.inf, 3.0]])
    a = Acquisition.from_map(m, frames=4, seconds=0.5, detail="scan")
    np.testing.assert_array_equal(a.rc, [[0, 1], [1, 0], [1, 2]])
    assert a.rc.dtype == np.float64  # index coordinates, as reconstruct takes them
    np.testing.assert_array_equal(a.values, [1.5, 2.0, 3.0])
    assert (a.shape, a.frames, a.seconds, a.detail) == ((2, 3), 4, 0.5, "scan")


def test_measured_map_round_trips(rng):
    m = rng.normal(size=(5, 7))
    m[rng.random((5, 7)) < 0.4] = np.nan
    m[0, 0] = 1.0
    back = Acquisition.from_map(m).measured_map()
    np.testing.assert_array_equal(back, m)  # NaN where nothing was measured


def test_defaults():
    a = Acquisition(np.array([[0, 0]]), np.array([1.0]), (1, 1))
    assert (a.frames, a.seconds, a.detail) == (0, 0.0, None)


def test_nothing_measured_is_a_one_line_user_error():
    assert NothingMeasured is NothingMeasuredError
    assert issubclass(NothingMeasured, SimlunarError) and issubclass(NothingMeasured, ValueError)
    with pytest.raises(
        NothingMeasured, match=r"^the scan measured no pixel \(nothing decoded"
    ) as info:
        Acquisition.from_map(np.full((3, 3), np.nan))
    assert "\n" not in str(info.value)


def test_the_ideal_sampler_is_a_sensor():
    s: Sensor = IdealSampler(np.zeros((2, 2)))
    assert s.name == "ideal" and s.needs_plan is True
    assert isinstance(s.acquire(np.array([[0, 1]])), Acquisition)
