"""The range gate from the instrument's pose and a reference plane."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simlunar.lidar.gate import GateOptions, gate_bins, plane_ranges, prior_ranges, read_datum


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


# --- the gate's prior: a datum read with its error, a slope bound -------------------------


def test_prior_of_a_datum_error_by_hand():
    # 50 m above the datum read, 1 m error at 3 sigmas: straight down 47 .. 53 m, 0.4 rad off
    # nadir (47 .. 53) / cos 0.4
    o = np.array([0.0, 0.0, 50.0])
    d = np.array([[0.0, 0.0, -1.0], [np.sin(0.4), 0.0, -np.cos(0.4)]])
    opts = GateOptions(datum_sigma_m=1.0, prior_sigmas=3.0)
    lo, hi = prior_ranges(o, d, datum_z=0.0, boresight=[0, 0, -1], options=opts)
    assert lo == pytest.approx([47.0, 47.0 / np.cos(0.4)], rel=1e-12)
    assert hi == pytest.approx([53.0, 53.0 / np.cos(0.4)], rel=1e-12)
    # no prior: both ends are the plane's range
    lo0, hi0 = prior_ranges(o, d, datum_z=0.0, boresight=[0, 0, -1], options=GateOptions())
    assert np.array_equal(lo0, hi0) and lo0 == pytest.approx([50.0, 50.0 / np.cos(0.4)])


def test_prior_of_a_slope_by_hand():
    # a nadir boresight from 50 m meets the datum at the origin; a ray a off nadir towards +x
    # meets the plane z = g x at 50 / (cos a + g sin a), g = +-tan(theta): the window runs from
    # 50 cos(theta) / cos(a - theta) to 50 cos(theta) / cos(a + theta)
    a, th = 0.3, np.radians(15.0)
    d = np.array([[np.sin(a), 0.0, -np.cos(a)], [0.0, 0.0, -1.0]])
    opts = GateOptions(max_slope_rad=th)
    lo, hi = prior_ranges([0, 0, 50.0], d, datum_z=0.0, boresight=[0, 0, -1], options=opts)
    assert lo[0] == pytest.approx(50 * np.cos(th) / np.cos(a - th), rel=1e-12)
    assert hi[0] == pytest.approx(50 * np.cos(th) / np.cos(a + th), rel=1e-12)
    # the boresight's own footprint does not move with the tilt
    assert lo[1] == pytest.approx(50.0) and hi[1] == pytest.approx(50.0)
    # a tilt that turns the plane away from a grazing ray: its far end is the largest range
    far = prior_ranges([0, 0, 50.0], [[np.sin(1.2), 0, -np.cos(1.2)]], datum_z=0.0,
                       boresight=[0, 0, -1], options=GateOptions(max_slope_rad=0.5))  # fmt: skip
    assert far[1][0] == GateOptions().max_range_m


def test_read_datum_draws_its_error_seeded():
    opts = GateOptions(datum_z_m=2.0, datum_sigma_m=0.5)
    assert read_datum(GateOptions(datum_z_m=2.0), rng=0) == 2.0  # no error: no draw
    assert read_datum(opts, rng=7) == read_datum(opts, rng=7)
    z = np.array([read_datum(opts, rng=np.random.default_rng(s)) for s in range(4000)])
    # mean 2 and standard deviation 0.5 (standard errors 0.008 and 0.006)
    assert z.mean() == pytest.approx(2.0, abs=0.03)
    assert z.std() == pytest.approx(0.5, abs=0.025)


def test_steered_beam_windows_hold_the_prior():
    # a steered beam's batch windows take the prior's largest half-width on top of margin_m:
    # straight down from 50 m with a 1 m datum error at 3 sigmas, 47 .. 53 m: centre 50 m,
    # margin 1 + 3 m; a window of 8 m cannot hold 2 x 4 m
    from simlunar.lidar.scan import SteeredBeamOptions, _predict

    gate = GateOptions(datum_sigma_m=1.0)
    opts = SteeredBeamOptions(margin_m=1.0, window_m=10.0, gate=gate)
    pred, margin = _predict(np.array([0, 0, 50.0]), np.array([[0, 0, -1.0]]), 0.0,
                            np.array([0, 0, -1.0]), opts)  # fmt: skip
    assert pred == pytest.approx([50.0]) and margin == pytest.approx(4.0)
    with pytest.raises(ValueError, match="window_m must exceed 8 m"):
        _predict(np.array([0, 0, 50.0]), np.array([[0, 0, -1.0]]), 0.0, np.array([0, 0, -1.0]),
                 dataclasses.replace(opts, window_m=8.0))  # fmt: skip
