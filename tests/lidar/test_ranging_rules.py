"""The ranging rules a reader can check by hand: how far apart two returns must be to be two,
and which bins the background estimate reads."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar import extract_ranges, shape_waveform
from simlunar.lidar.waveform import pulse_kernel
from tests.lidar.test_ranging import BINS, PULSE, _impulse

#: the matched filter's half-width: 6 bins of 5 cm for a 1 ns pulse (sigma 1.31 bins)
HALF = pulse_kernel(BINS, PULSE).size // 2


def test_the_kernel_half_width_is_6_bins():
    assert HALF == 6


@pytest.mark.parametrize("bins_apart", [8, 9])
@pytest.mark.parametrize("start", [50.0, 50.0125, 50.025])
def test_returns_more_than_a_kernel_half_width_apart_are_two(bins_apart, start):
    # a return is the maximum of the filter output within +-HALF bins: two equal returns
    # 8 or 9 bins apart are each the maximum of their own window, wherever they fall in
    # their bins (a window of +-9 bins would merge them)
    truth = np.array([[start, start + bins_apart * BINS.bin_range]])
    sig = shape_waveform(_impulse(truth), BINS, PULSE)
    assert extract_ranges(100 * sig, BINS, pulse=PULSE).returns[0] == 2


def test_the_background_is_read_beyond_three_half_widths_of_the_return_by_hand():
    # noise free: 100 photons and, nowhere else but 19 to 24 bins after the return's bin,
    # 0.2 counts per bin (1.2 in all: no return of its own). The background is the mean of
    # the bins more than 3 x 6 = 18 bins from the strongest window: 6 x 0.2 counts over
    # 400 - 37 bins; the return's photons are its window's counts (13 bins) less 13 x that
    sig = 100 * shape_waveform(_impulse(np.array([[50.0]])), BINS, PULSE)
    top = int(np.argmax(sig[0]))
    counts = sig.copy()
    counts[0, top + 3 * HALF + 1 : top + 4 * HALF + 1] += 0.2
    bg = 6 * 0.2 / (BINS.count - (2 * 3 * HALF + 1))
    window = sig[0, top - HALF : top + HALF + 1].sum()
    res = extract_ranges(counts, BINS, pulse=PULSE)
    assert res.returns[0] == 1
    assert res.photons[0] == pytest.approx(window - (2 * HALF + 1) * bg, rel=1e-6)


def test_a_histogram_without_a_return_reports_no_range_and_no_photons():
    # documented: range NaN and photons 0 where no return is detected (a flat background
    # of 3 counts per bin has none), whatever the background's own counts
    res = extract_ranges(np.full((2, BINS.count), 3.0), BINS, pulse=PULSE)
    assert not res.valid.any() and (res.returns == 0).all()
    assert np.isnan(res.range).all()
    np.testing.assert_array_equal(res.photons, [0.0, 0.0])
