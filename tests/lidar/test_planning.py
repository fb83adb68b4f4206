"""Sensor-aware planning rules: scan-time fit, receiver cap, first-frame tile scores."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar.planning import (
    choose_tiles,
    fit_to_budget,
    fit_to_time,
    receiver_capped_plan,
    receiver_cells,
    tile_range_scores,
)


def test_fit_to_time_takes_the_largest_k_that_fits():
    # scan time 0.1 s per point + 1 s: a 10 s budget holds k = 90 exactly
    calls = []

    def place(k):
        calls.append(k)
        return np.zeros((k, 2), int)

    rc, s = fit_to_time(place, lambda rc: 1.0 + 0.1 * len(rc), 10.0, k_max=400)
    assert len(rc) == 90 and s == pytest.approx(10.0)
    assert len(calls) < 15  # a bisection, not a sweep
    # everything fits: k_max; nothing fits: k_min (over budget, said by its seconds)
    assert len(fit_to_time(place, lambda rc: 0.0, 1.0, k_max=7)[0]) == 7
    rc, s = fit_to_time(place, lambda rc: 5.0 + len(rc), 1.0, k_max=7, k_min=2)
    assert len(rc) == 2 and s > 1.0
    with pytest.raises(ValueError, match="budget_s"):
        fit_to_time(place, len, 0.0, k_max=3)


def test_fit_to_budget_finds_the_largest_k_from_any_start_without_placing_k_max():
    # cost 3 per sample: a budget of 100 holds k = 33 exactly, found from below (k = 1: by
    # doubling) and from above (k = 5000: by halving); neither search places the whole guide
    calls = []

    def place(k):
        calls.append(k)
        return np.zeros((k, 2), int)

    for start in (1, 33, 40, 5000):
        calls.clear()
        rc, c = fit_to_budget(place, lambda rc: 3.0 * len(rc), 100.0, k_start=start, k_max=10_000)
        assert len(rc) == 33 and c == 99.0
        assert max(calls) <= max(2 * 33, start) and len(calls) < 20
    # everything fits: k_max; nothing fits: one sample (over budget, said by its cost)
    assert len(fit_to_budget(place, lambda rc: 0.0, 1.0, k_start=3, k_max=7)[0]) == 7
    rc, c = fit_to_budget(place, lambda rc: 5.0 + len(rc), 1.0, k_start=4, k_max=7)
    assert len(rc) == 1 and c == 6.0
    # a smallest count: a budget under it gets that plan, over budget
    rc, c = fit_to_budget(place, lambda rc: 3.0 * len(rc), 5.0, k_start=40, k_max=100, k_min=3)
    assert len(rc) == 3 and c == 9.0
    with pytest.raises(ValueError, match="budget"):
        fit_to_budget(place, len, 0.0, k_start=1, k_max=3)


def test_fit_to_time_with_a_steered_beam_tour_stays_in_budget():
    # the real tour time (nn + 2-opt under a gimbal) of uniform random points: the fitted plan
    # never exceeds the budget and one more point would (within the bisection's resolution)
    from simlunar.lidar import SteeringOptions, order_scan, scan_timing

    steer = SteeringOptions(pulses_per_point=4)
    pts = np.random.default_rng(0).uniform(0, 0.6, (600, 2))

    def seconds(rc):
        a = pts[rc[:, 0]]
        return scan_timing(a, order_scan(a, steering=steer), options=steer).total_s

    def place(k):
        return np.c_[np.arange(k), np.zeros(k, int)]

    budget = seconds(place(300)) * 0.7
    rc, s = fit_to_time(place, seconds, budget, k_max=600)
    assert s <= budget and seconds(place(len(rc) + 1)) > budget * 0.97
    assert 100 < len(rc) < 300


def test_receiver_capped_plan_never_puts_two_dots_in_a_receiver_pixel_per_frame():
    # 64 x 64 guide, 16 x 16 receiver (4 x 4 guide px each); a map piled into one corner
    h = w = 64
    weights = np.zeros((h, w))
    weights[:16, :16] = 1.0
    weights += 1e-3
    for k, frames in ((200, 1), (256, 1), (300, 2), (700, 3)):
        rc = receiver_capped_plan(weights, k, shape=(h, w), receiver_shape=(16, 16), frames=frames,
                                  rng=0)  # fmt: skip
        assert rc.shape == (k, 2)
        assert len({tuple(x) for x in rc}) == k  # distinct pixels
        per_cell = np.bincount(receiver_cells(rc, (h, w), (16, 16)), minlength=256)
        assert per_cell.max() <= frames
    # the map still steers it: with one frame the corner cells are all full first
    rc = receiver_capped_plan(weights, 100, shape=(h, w), receiver_shape=(16, 16), rng=1)
    corner = np.bincount(receiver_cells(rc, (h, w), (16, 16)), minlength=256).reshape(16, 16)
    assert corner[:4, :4].sum() == 16
    # and inside a cell it picks the heavy pixels: a map lit on one pixel per cell
    one = np.zeros((h, w))
    one[1::4, 2::4] = 1.0
    rc = receiver_capped_plan(one, 256, shape=(h, w), receiver_shape=(16, 16), rng=2)
    assert (rc[:, 0] % 4 == 1).all() and (rc[:, 1] % 4 == 2).all()
    with pytest.raises(ValueError, match="do not fit 1 per receiver pixel"):
        receiver_capped_plan(None, 257, shape=(h, w), receiver_shape=(16, 16), frames=1)


def test_receiver_capped_plan_matches_the_micromirror_frame_count():
    # the micromirror sensor's own frame assignment fires exactly `frames` frames
    from simlunar.geometry import Camera, Intrinsics, Pose
    from simlunar.lidar.flash import micromirror_frames

    cam = Camera(Intrinsics.from_fov(64, 64, 40.0), Pose.look_at([0, 0, 50.0], [0, 0, 0.0]))
    for k, frames in ((256, 1), (500, 2)):
        rc = receiver_capped_plan(None, k, shape=(64, 64), receiver_shape=(16, 16), rng=3)
        f = micromirror_frames(rc[:, ::-1] + 0.5, cam, (16, 16))
        assert int(f.max()) + 1 == frames


def test_tile_range_scores_find_the_rough_tile():
    # a 16 x 16 receiver over a tilted plane (rough nowhere) with a 1 m box in tile (2, 1)
    r, c = np.mgrid[0:16, 0:16].astype(float)
    z = 0.3 * c - 0.1 * r
    z[9:11, 5:7] += 1.0  # tile (2, 1) of a 4 x 4 grid: rows 8-11, cols 4-7
    pts = np.stack([c, r, z], -1)
    ok = np.ones((16, 16), bool)
    s = tile_range_scores(pts, ok, 4)
    assert s.shape == (4, 4)
    assert np.unravel_index(np.argmax(s), s.shape) == (2, 1)
    assert np.delete(s.ravel(), 2 * 4 + 1).max() < 1e-9  # planes fit exactly
    # a tile the first frame could not measure counts as the roughest
    ok[0:4, 12:16] = False
    s2 = tile_range_scores(np.where(ok[..., None], pts, np.nan), ok, 4)
    assert s2[0, 3] >= s2.max() - 1e-12


def test_choose_tiles_mixes_the_plan_and_the_ranges():
    plan = np.zeros((4, 4))
    plan[0, 0] = 10.0
    rough = np.zeros((4, 4))
    rough[3, 3] = 1.0
    assert choose_tiles(plan, rough, 1, range_weight=0.0).tolist() == [[0, 0]]
    assert choose_tiles(plan, rough, 1, range_weight=1.0).tolist() == [[3, 3]]
    assert sorted(choose_tiles(plan, rough, 2).tolist()) == [[0, 0], [3, 3]]
    assert choose_tiles(None, rough, 1).tolist() == [[3, 3]]
    with pytest.raises(ValueError, match="needs plan_counts"):
        choose_tiles(None, None, 1)


def test_receiver_capped_layout_moves_only_the_dots_over_the_cap():
    from simlunar.lidar.planning import receiver_capped_layout

    # 8 x 8 guide, 4 x 4 receiver (2 x 2 guide px each). Dots at (0,0) and (0,1) share
    # receiver pixel 0; (5,5) is alone. With one frame, one of the pair moves to the nearest
    # free pixel of a receiver pixel with room: (0,1) -> (0,2) (distance 1, receiver pixel 1)
    rc = np.array([[0, 0], [0, 1], [5, 5]])
    out = receiver_capped_layout(rc, shape=(8, 8), receiver_shape=(4, 4), frames=1)
    assert out.tolist() == [[0, 0], [0, 2], [5, 5]]
    # a layout already within the cap is returned unchanged
    same = receiver_capped_layout(out, shape=(8, 8), receiver_shape=(4, 4), frames=1)
    assert np.array_equal(same, out)
    # two frames hold the pair: nothing moves
    two = receiver_capped_layout(rc, shape=(8, 8), receiver_shape=(4, 4), frames=2)
    assert np.array_equal(two, rc)


def test_receiver_capped_layout_keeps_a_clustered_layout_close():
    from simlunar.lidar.planning import receiver_capped_layout

    # a 64 x 64 guide, 16 x 16 receiver: 200 distinct dots piled into the top-left 20 x 20
    g = np.random.default_rng(4)
    flat = g.choice(20 * 20, 200, replace=False)
    rc = np.stack([flat // 20, flat % 20], -1)
    before = np.bincount(receiver_cells(rc, (64, 64), (16, 16)), minlength=256)
    for frames in (1, 2):
        out = receiver_capped_layout(rc, shape=(64, 64), receiver_shape=(16, 16), frames=frames)
        assert out.shape == rc.shape
        assert len({tuple(x) for x in out}) == len(out)  # distinct
        per_cell = np.bincount(receiver_cells(out, (64, 64), (16, 16)), minlength=256)
        assert per_cell.max() <= frames
        # dots in receiver pixels within the cap never move
        cell = receiver_cells(rc, (64, 64), (16, 16))
        stay = before[cell] <= frames
        assert np.array_equal(out[stay], rc[stay])
    with pytest.raises(ValueError, match="do not fit 1 per receiver pixel"):
        receiver_capped_layout(np.argwhere(np.ones((64, 64)))[:257], shape=(64, 64),
                               receiver_shape=(16, 16), frames=1)  # fmt: skip
    with pytest.raises(ValueError, match="distinct"):
        receiver_capped_layout([[1, 1], [1, 1]], shape=(64, 64), receiver_shape=(16, 16))


def test_receiver_capped_layout_undoes_a_small_displacement_by_one_pixel():
    from simlunar.lidar.planning import receiver_capped_layout

    # one dot per receiver pixel of a 16 x 16 receiver on a 64 x 64 guide, at (4i+1, 4j+1);
    # ten dots pushed 3 rows down, to (4i+4, 4j+1): each now shares receiver pixel (i+1, j)
    # (rows 4i+4 .. 4i+7) with the dot there, and left (i, j) empty. The nearest free pixel
    # with room for the pushed dot is (4i+3, 4j+1) in its old receiver pixel, 1 px away (the
    # other dot of the pair is 2 px from it): exactly the pushed dots move, each by 1 px.
    i, j = np.mgrid[0:16, 0:16]
    rc = np.stack([4 * i.ravel() + 1, 4 * j.ravel() + 1], -1)
    even = np.flatnonzero(i.ravel() % 2 == 0)  # rows 0, 2, ..., 14: no pushed dot lands on another
    pushed = np.random.default_rng(5).choice(even, 10, replace=False)
    rc[pushed, 0] += 3
    out = receiver_capped_layout(rc, shape=(64, 64), receiver_shape=(16, 16), frames=1)
    moved = np.flatnonzero((out != rc).any(1))
    assert sorted(moved) == sorted(pushed)
    assert np.array_equal(out[pushed], rc[pushed] - [1, 0])
