"""Scan ordering: never longer than the planner's order, near the exact tour."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar import (
    OrderOptions,
    SteeringOptions,
    exact_order,
    nearest_neighbour_order,
    order_scan,
    scan_timing,
)

STEER = SteeringOptions(max_rate_rad_s=1.0, max_accel_rad_s2=10.0, settle_s=0.005)


def _time(p, order):
    return scan_timing(p, order, options=STEER).total_s


@pytest.mark.parametrize("seed", range(5))
def test_nine_points_within_ten_percent_of_the_exact_tour(seed):
    p = np.random.default_rng(seed).uniform(-0.3, 0.3, (9, 2))
    exact = exact_order(p, steering=STEER)
    best = _time(p, exact)
    ours = order_scan(p, steering=STEER)
    assert sorted(ours) == list(range(9)) and ours[0] == 0
    assert _time(p, ours) <= 1.10 * best
    assert _time(p, ours) <= _time(p, np.arange(9)) + 1e-12
    assert _time(p, ours) >= best - 1e-12  # the brute force is exact


def test_ordered_scan_is_never_longer_than_the_planner_order():
    rng = np.random.default_rng(7)
    for n in (5, 50, 2000):
        p = rng.uniform(-0.5, 0.5, (n, 2))
        # the planner's order is already good here (a sorted sweep): must still not lose
        planner = np.lexsort((p[:, 0], np.round(p[:, 1], 1)))
        p = p[planner]
        ours = order_scan(p, steering=STEER)
        assert np.array_equal(np.sort(ours), np.arange(n))
        assert _time(p, ours) <= _time(p, np.arange(n)) + 1e-9


def test_two_opt_improves_on_nearest_neighbour_and_raster():
    p = np.random.default_rng(3).uniform(-0.5, 0.5, (3000, 2))
    nn = nearest_neighbour_order(p, 0)
    assert np.array_equal(np.sort(nn), np.arange(3000))
    ours = order_scan(p, steering=STEER)
    raster = order_scan(p, steering=STEER, options=OrderOptions(method="raster"))
    assert _time(p, ours) < _time(p, nn)
    assert _time(p, ours) < _time(p, raster)
    assert _time(p, ours) < 0.2 * _time(p, np.arange(3000))


def test_exact_order_refuses_large_cases():
    with pytest.raises(ValueError, match="n = 11"):
        exact_order(np.zeros((11, 2)), steering=STEER)
    with pytest.raises(ValueError, match="nn2opt"):
        OrderOptions(method="tsp")


def test_ordered_scan_time_by_hand():
    # four points on one azimuth line given out of order; the ordered scan sweeps them:
    # moves of 0.1, 0.1, 0.2 rad = 0.2 + 0.2 + 0.3 s (v = 1 rad/s, a = 10 rad/s^2), 3 settles
    steer = SteeringOptions(
        max_rate_rad_s=1.0,
        max_accel_rad_s2=10.0,
        settle_s=0.01,
        pulse_rate_hz=1000.0,
        pulses_per_point=10,
    )
    p = np.array([[0.0, 0.0], [0.2, 0.0], [0.4, 0.0], [0.1, 0.0]])
    order = order_scan(p, steering=steer)
    assert list(order) == [0, 3, 1, 2]
    t = scan_timing(p, order, options=steer)
    assert t.total_s == pytest.approx(0.7 + 3 * 0.01 + 4 * 0.01)
    # the planner's order: 0.2 + 0.2 (trapezoid 0.2 / 1 + 0.1 = 0.3 each) + 0.3 rad
    assert scan_timing(p, options=steer).total_s == pytest.approx(0.3 + 0.3 + 0.4 + 0.07)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"method": "tsp"}, "method must be one of 'nn2opt', 'raster', 'given', got 'tsp'"),
        ({"neighbours": 0}, "neighbours must be >= 1, got 0"),
        ({"max_passes": -1}, "max_passes must be >= 0, got -1"),
        ({"line_pitch_rad": 0.0}, r"line_pitch_rad must be > 0, got 0\.0"),
    ],
)
def test_order_options_refuse_bad_values(kw, match):
    with pytest.raises(ValueError, match=match):
        OrderOptions(**kw)
    assert OrderOptions(max_passes=0, line_pitch_rad=None).max_passes == 0
