"""The sub-bin position of a return: the vertex of the parabola through the peak bin and its
neighbours by hand, and the maximum-likelihood fit exact on a noise-free return."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import erf

from simlunar.lidar.ranging import RangeOptions, _parabola_offset, extract_ranges
from simlunar.lidar.waveform import FWHM_PER_SIGMA, PulseOptions, TimeBins


def test_the_parabola_vertex_by_hand_and_the_bin_centre_without_curvature():
    """Through (-1, lo), (0, mid), (1, hi) the vertex is at 0.5 (lo - hi) / (lo - 2 mid + hi):
    1, 3, 1 -> 0 (symmetric); 1, 3, 2 -> 0.5 (-1) / (-3) = 1/6 towards the larger neighbour;
    2, 3, 1 -> -1/6. Three equal bins (no curvature) and a convex triple 0, 1, 3 (a minimum,
    not a maximum) have no peak vertex: the bin centre, 0. A vertex beyond the bin (0, 2, 3:
    0.5 (-3) / (-1) = 1.5) is clipped to the bin's edge, 0.5."""
    score = np.array(
        [
            [1.0, 3.0, 1.0],
            [1.0, 3.0, 2.0],
            [2.0, 3.0, 1.0],
            [2.0, 2.0, 2.0],
            [0.0, 1.0, 3.0],
            [0.0, 2.0, 3.0],
        ]
    )
    off = _parabola_offset(score, np.ones(6, int))
    np.testing.assert_allclose(off, [0.0, 1 / 6, -1 / 6, 0.0, 0.0, 0.5], atol=1e-15)


@pytest.mark.parametrize(("tau", "amplitude", "sigma"), [(17.3, 200.0, 1.5), (41.72, 1000.0, 2.5)])
def test_a_noise_free_return_is_ranged_exactly_by_the_ml_fit(tau, amplitude, sigma):
    """The histogram a return of A photons at bin position tau would produce on average, A
    times the bin-integrated Gaussian [Phi((i + 1 - tau) / s) - Phi((i - tau) / s)], no
    background, is the Poisson likelihood's own maximum: the fit (Fisher scoring, Newton-like,
    quadratic near the solution) finds tau to rounding (1e-11 bin) from the parabola's vertex."""
    bins = TimeBins(0.0, 0.3, 64)
    pulse = PulseOptions(fwhm_s=sigma * FWHM_PER_SIGMA * bins.bin_s)
    i = np.arange(64)
    root = sigma * np.sqrt(2.0)
    counts = amplitude * 0.5 * (erf((i + 1 - tau) / root) - erf((i - tau) / root))
    res = extract_ranges(counts, bins, pulse=pulse)
    assert bool(res.valid)
    bin_range = bins.bin_opl / 2  # a bin is half its round-trip path in range
    assert abs(float(res.range) - float(bins.range_of(tau))) < 1e-11 * bin_range


@pytest.mark.parametrize(("spike_bin", "kept"), [(0, False), (1, True), (62, True), (63, False)])
def test_the_edge_guard_keeps_a_return_exactly_at_its_distance_from_the_ends(spike_bin, kept):
    """A pulse of 0.2 bin (the parabola's vertex alone) in one bin of 64: the return sits at
    the bin's centre, spike_bin + 0.5. edge_sigma = 7.5 guards 7.5 x 0.2 = 1.5 bins at each
    end: a return at 1.5 or 62.5 (= 64 - 1.5) is on the guard and kept, one at 0.5 or 63.5 is
    inside it and dropped."""
    bins = TimeBins(0.0, 0.3, 64)
    pulse = PulseOptions(fwhm_s=0.2 * FWHM_PER_SIGMA * bins.bin_s)
    counts = np.zeros(64)
    counts[spike_bin] = 100.0
    res = extract_ranges(counts, bins, pulse=pulse, options=RangeOptions(edge_sigma=7.5))
    assert bool(res.valid) is kept
    if kept:
        assert float(res.range) == pytest.approx(float(bins.range_of(spike_bin + 0.5)), abs=1e-12)
