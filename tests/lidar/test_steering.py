"""Steering mechanics: move, settle and dwell times by hand."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.geometry import Pose
from simlunar.lidar import (
    SteeringOptions,
    axis_move_time,
    move_time,
    pointing_angles,
    raster_order,
    scan_timing,
)

# v = 1 rad/s, a = 10 rad/s^2: the axis reaches full speed after v^2/a = 0.1 rad
OPTS = SteeringOptions(
    max_rate_rad_s=1.0,
    max_accel_rad_s2=10.0,
    settle_s=0.01,
    pulse_rate_hz=100.0,
    pulses_per_point=2,
)


def test_axis_move_time_triangle_and_trapezoid():
    # 0.1 rad: triangle, 2 sqrt(0.1 / 10) = 0.2 s; 0.4 rad: 0.4 / 1 + 1 / 10 = 0.5 s
    assert axis_move_time([0.1, -0.4, 0.0], OPTS) == pytest.approx([0.2, 0.5, 0.0])
    assert axis_move_time(0.025, OPTS) == pytest.approx(0.1)


def test_both_axes_move_at_once():
    a = np.array([[0.0, 0.0]])
    b = np.array([[0.1, 0.4]])
    assert move_time(a, b, OPTS) == pytest.approx([0.5 + 0.01])
    assert move_time(a, a, OPTS) == pytest.approx([0.0])  # no move, no settle


def test_scan_time_by_hand():
    pts = np.array([[0.0, 0.0], [0.1, 0.0], [0.1, 0.4], [0.1, 0.4]])
    t = scan_timing(pts, options=OPTS)
    # moves: 0.2 s (0.1 rad), 0.5 s (0.4 rad), none; 2 settles; 4 dwells of 2 / 100 s
    assert t.move_s == pytest.approx(0.7)
    assert t.settle_s == pytest.approx(0.02)
    assert t.dwell_s == pytest.approx(0.08)
    assert t.total_s == pytest.approx(0.8)
    # from a start pointing, the first move counts too; an order permutes the points
    t2 = scan_timing(pts, [1, 0, 2, 3], options=OPTS, start=[0.1, 0.0])
    assert t2.total_s == pytest.approx((0.0 + 0.2 + 0.5) + 2 * 0.01 + 0.08)


def test_raster_scan_time_by_hand():
    # 2 x 3 grid, pitch 0.1 rad: serpentine = 5 moves of 0.1 rad (0.2 s each, +0.01 settle)
    az, el = np.meshgrid([0.0, 0.1, 0.2], [0.1, 0.0])
    pts = np.stack([az.ravel(), el.ravel()], axis=1)[[4, 0, 5, 2, 1, 3]]  # shuffled
    order = raster_order(pts, 0.1)
    ordered = pts[order]
    assert np.allclose(ordered[:, 1], [0.1, 0.1, 0.1, 0.0, 0.0, 0.0])
    assert np.allclose(ordered[:, 0], [0.0, 0.1, 0.2, 0.2, 0.1, 0.0])
    assert scan_timing(pts, order, options=OPTS).total_s == pytest.approx(5 * 0.21 + 6 * 0.02)


def test_pointing_angles_of_a_nadir_gimbal():
    pose = Pose.look_at([0.0, 0.0, 50.0], [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    right = pose.rotation[:, 0]
    up = -pose.rotation[:, 1]
    d = np.stack(
        [
            pose.forward,
            np.cos(0.1) * pose.forward + np.sin(0.1) * right,
            np.cos(0.2) * pose.forward + np.sin(0.2) * up,
        ]
    )
    ang = pointing_angles(d, pose)
    assert ang == pytest.approx(np.array([[0, 0], [0.1, 0], [0, 0.2]]), abs=1e-12)


def test_bad_mechanics_are_rejected():
    with pytest.raises(ValueError, match="max_rate_rad_s"):
        SteeringOptions(max_rate_rad_s=0.0)
    with pytest.raises(ValueError, match="shape"):
        scan_timing(np.zeros((3, 3)), options=OPTS)


def test_point_times_add_up_to_the_scan_time():
    from simlunar.lidar import point_times

    opts = SteeringOptions(max_rate_rad_s=1.0, max_accel_rad_s2=10.0, settle_s=1e-3,
                           pulse_rate_hz=1000.0, pulses_per_point=4)  # fmt: skip
    ang = np.array([[0.0, 0.0], [0.1, 0.0], [0.1, 0.05], [0.0, 0.0]])
    order = np.array([0, 2, 1, 3])
    t = point_times(ang, order, options=opts)
    total = scan_timing(ang, order, options=opts).total_s
    assert t[order[-1]] + opts.dwell_s == pytest.approx(total)
    # by hand: point 0 at once; then 0.1 rad (move 2 sqrt(0.1 / 10) = 0.2 s) + settle, after
    # one dwell of 4 ms
    assert t[0] == 0.0
    assert t[2] == pytest.approx(0.004 + 0.2 + 0.001)
    assert np.all(np.diff(t[order]) > 0)


def test_galvanometer_moves_are_rate_plus_step_response():
    # inertia-free: 0.1 rad at 1 rad/s = 0.1 s (+ 0.01 s step response); the gimbal takes 0.2 s
    g = SteeringOptions(**{**OPTS.__dict__, "model": "galvanometer"})
    assert axis_move_time([0.1, -0.4], g) == pytest.approx([0.1, 0.4])
    a, b = np.array([[0.0, 0.0]]), np.array([[0.1, 0.05]])
    assert move_time(a, b, g) == pytest.approx([0.11])
    p = np.array([[0.0, 0.0], [0.1, 0.0], [0.1, 0.3]])
    # moves 0.11 + 0.31, dwells 3 x 2 / 100
    assert scan_timing(p, options=g).total_s == pytest.approx(0.42 + 0.06)


def test_continuous_raster_time_by_hand():
    from simlunar.lidar.steering import raster_sweep

    # v = 1 rad/s, a = 10: turnaround 0.2 s; lines 0.01 rad apart; a step of 0.02 rad takes
    # 2 sqrt(0.002) = 0.0894 s + 0.01 settle < 0.2: the turnaround sets it
    r = SteeringOptions(**{**OPTS.__dict__, "model": "continuous_raster", "line_pitch_rad": 0.01})
    # two lines (el 0.02 and 0.0), azimuth span 0.4 rad: 2 sweeps of 0.4 s + one turnaround
    p = np.array([[0.0, 0.02], [0.4, 0.02], [0.2, 0.02], [0.1, 0.0], [0.3, 0.0]])
    s = raster_sweep(p, options=r)
    assert (s.sweeps, s.lines) == (2, 2)
    assert s.timing.total_s == pytest.approx(0.8 + 0.2 + 0.0)
    # first line forwards, second backwards (serpentine)
    assert s.times == pytest.approx([0.0, 0.4, 0.2, 0.6 + 0.3, 0.6 + 0.1])
    assert scan_timing(p, options=r).total_s == pytest.approx(s.timing.total_s)
    assert point_times_of(p, r) == pytest.approx(s.times)
    # two points closer than v x dwell = 0.02 rad on one line: that line is swept twice
    q = np.array([[0.0, 0.0], [0.01, 0.0], [0.4, 0.0]])
    s2 = raster_sweep(q, options=r)
    # the point at 0.01 rad fires on the way back at 0.6 + 0.39 s; its dwell (0.02 s) ends
    # 0.01 s after the second sweep
    assert s2.sweeps == 2 and s2.timing.total_s == pytest.approx(0.4 + 0.2 + 0.4 + 0.01)


def point_times_of(p, options):
    from simlunar.lidar import point_times

    return point_times(p, options=options)


def test_continuous_raster_makes_the_grid_the_cheapest_pattern():
    from simlunar.lidar.steering import raster_sweep

    r = SteeringOptions(max_rate_rad_s=2.0, max_accel_rad_s2=50.0, settle_s=1e-3,
                        pulse_rate_hz=1e4, pulses_per_point=4, model="continuous_raster",
                        line_pitch_rad=0.005)  # fmt: skip
    g = np.mgrid[0:16, 0:16].reshape(2, -1).T * 0.04  # 256 points on 16 lines
    rand = np.random.default_rng(0).uniform(0, 0.6, (256, 2))
    tg, tr = raster_sweep(g, options=r).timing.total_s, raster_sweep(rand, options=r).timing.total_s
    assert tg < 0.5 * tr
    gim = SteeringOptions(max_rate_rad_s=2.0, max_accel_rad_s2=50.0, settle_s=1e-3,
                          pulse_rate_hz=1e4, pulses_per_point=4)  # fmt: skip
    assert scan_timing(g, options=gim).total_s > tg  # stop-and-stare pays for every stop


def test_continuous_raster_needs_its_line_pitch():
    with pytest.raises(ValueError, match="line_pitch_rad"):
        scan_timing(np.zeros((2, 2)), options=SteeringOptions(model="continuous_raster"))
    with pytest.raises(
        ValueError,
        match="model must be one of 'gimbal', 'galvanometer', 'continuous_raster', got 'resonant'",
    ):
        SteeringOptions(model="resonant")
    with pytest.raises(ValueError, match=r"line_pitch_rad must be > 0, got -0\.01"):
        SteeringOptions(model="continuous_raster", line_pitch_rad=-0.01)
    with pytest.raises(ValueError, match="pulses_per_point must be >= 1, got 0"):
        SteeringOptions(pulses_per_point=0)


@pytest.mark.parametrize("bad", [np.zeros((4, 3)), np.zeros(4), np.zeros((2, 2, 2))])
def test_timings_refuse_angles_that_are_not_n_by_2(bad):
    from simlunar.lidar.steering import raster_sweep

    raster = SteeringOptions(model="continuous_raster", line_pitch_rad=0.01)
    for call in (
        lambda: scan_timing(bad, options=SteeringOptions()),
        lambda: raster_sweep(bad, options=raster),
    ):
        with pytest.raises(ValueError, match=r"angles must have shape \(n, 2\), got"):
            call()
