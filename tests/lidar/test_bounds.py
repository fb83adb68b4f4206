"""The range Cramer-Rao bound: closed form, binning, background, Monte Carlo."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar import SPEED_OF_LIGHT, PulseOptions, TimeBins
from simlunar.lidar.bounds import range_crlb

PULSE = PulseOptions(fwhm_s=1e-9, jitter_s=0.1e-9)


def test_closed_form_65_4_mm_over_sqrt_n():
    # by hand: sigma_t = sqrt((1 ns / 2.35482)^2 + (0.1 ns)^2) = 0.43628 ns;
    # c / 2 x sigma_t = 0.149896 m/ns x 0.43628 ns = 65.40 mm
    assert range_crlb(1.0, pulse=PULSE) == pytest.approx(0.06540, abs=5e-6)
    assert range_crlb([1.0, 100.0], pulse=PULSE) == pytest.approx([0.06540, 0.006540], rel=1e-3)


def test_fine_bins_approach_the_unbinned_bound_and_coarse_bins_cost():
    fine = TimeBins.for_ranges(0.0, 10.0, 0.001)
    assert range_crlb(100.0, pulse=PULSE, bins=fine) == pytest.approx(0.00654, rel=1e-3)
    coarse = TimeBins.for_ranges(0.0, 10.0, 0.05)
    c = range_crlb(100.0, pulse=PULSE, bins=coarse, offset=np.linspace(0, 1, 11))
    assert (c > 0.00654).all() and (c < 1.1 * 0.00654).all()
    # a bin as wide as 3 sigma: a return at a bin's centre is located worse than at its edge
    wide = TimeBins.for_ranges(0.0, 10.0, 0.2)
    centre, edge = range_crlb(100.0, pulse=PULSE, bins=wide, offset=[0.5, 0.0])
    assert centre > edge


def test_background_raises_the_bound():
    b = TimeBins.for_ranges(0.0, 10.0, 0.05)
    lo, hi = range_crlb(50.0, pulse=PULSE, bins=b, background=[0.0, 5.0])
    assert hi > 1.2 * lo


def test_monte_carlo_of_the_mean_arrival_time_meets_the_bound():
    # without background the ML estimate of a Gaussian's location is the mean arrival time:
    # its standard deviation is sigma_t / sqrt(N) for N photons (the bound, attained)
    rng = np.random.default_rng(0)
    t = rng.normal(0.0, PULSE.sigma_s, (20000, 25))
    sd = t.mean(axis=1).std() * SPEED_OF_LIGHT / 2
    assert sd == pytest.approx(range_crlb(25.0, pulse=PULSE), rel=0.02)


def test_bad_inputs():
    b = TimeBins.for_ranges(0.0, 10.0, 0.05)
    with pytest.raises(ValueError, match="photons"):
        range_crlb(0.0, pulse=PULSE)
    with pytest.raises(ValueError, match="unbinned"):
        range_crlb(10.0, pulse=PULSE, background=1.0)
    with pytest.raises(ValueError, match="zero width"):
        range_crlb(10.0, pulse=PulseOptions(fwhm_s=0.0), bins=b)
