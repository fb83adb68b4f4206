"""Flat LIDAR scans joined one after the other: times run on across scans and gaps."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar.join import concat_scans, flat_scan, join_scans, subset_scan
from simlunar.lidar.returns import LidarScan


def scan(n, seconds):
    return LidarScan(np.ones(n), np.ones(n, bool), np.zeros((n, 3)), np.ones(n),
                     np.arange(n)[::-1], seconds, n, times=np.linspace(0, seconds, n))  # fmt: skip


def test_join_scans_runs_times_on_across_scans_and_gaps():
    j = join_scans([scan(2, 1.0), scan(3, 2.0)], [0.5])
    assert j.seconds == pytest.approx(3.5) and j.frames == 5
    np.testing.assert_allclose(j.times, [0.0, 1.0, 1.5, 2.5, 3.5])
    with pytest.raises(ValueError, match="gaps"):
        join_scans([scan(2, 1.0), scan(3, 2.0)], [0.5, 0.5])


def test_flat_subset_and_concat_keep_each_points_values_and_time():
    a, b = flat_scan(scan(3, 3.0)), flat_scan(scan(2, 1.0))
    np.testing.assert_array_equal(a.order, [0, 1, 2])
    np.testing.assert_array_equal(a.returns, [0, 0, 0])  # none given: filled with 0
    s = subset_scan(a, np.array([True, False, True]))
    np.testing.assert_allclose(s.times, [0.0, 3.0])
    c = concat_scans([a, b])
    assert c.seconds == 4.0 and c.frames == 5
    np.testing.assert_allclose(c.times, [0.0, 1.5, 3.0, 3.0, 4.0])  # b starts where a ended
