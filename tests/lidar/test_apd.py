"""Linear-mode APD: excess noise, amplifier noise, detection threshold, against an event-level
simulation (one avalanche per photoelectron)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar import PulseOptions, TimeBins, extract_ranges, shape_waveform, splat_paths
from simlunar.lidar.apd import ApdOptions, apd_waveform


def test_mcintyre_excess_noise_by_hand():
    # Si, k = 0.02, M = 100: F = 0.02 x 100 + 0.98 x (2 - 0.01) = 3.9502
    assert ApdOptions(gain=100, ionisation_ratio=0.02).excess_noise == pytest.approx(3.9502)
    # k = 0: F -> 2 at high gain; k = 1: F = M
    assert ApdOptions(gain=1e4, ionisation_ratio=0.0).excess_noise == pytest.approx(2.0, 1e-3)
    assert ApdOptions(gain=50, ionisation_ratio=1.0).excess_noise == pytest.approx(50.0)


def test_waveform_matches_an_event_level_simulation():
    # event level: every photoelectron's avalanche drawn on its own (mean M, variance
    # (F - 1) M^2, Gamma), summed, divided by M, plus amplifier noise per pulse
    apd = ApdOptions(gain=100, ionisation_ratio=0.02, amplifier_noise_pe=0.7)
    lam, pulses, n = 2.5, 4, 40_000
    rng = np.random.default_rng(1)
    f1 = apd.excess_noise - 1
    events = np.empty(n)
    for i in range(n):
        pe = rng.poisson(lam * pulses)
        events[i] = rng.gamma(1 / f1, f1 * apd.gain, pe).sum() / apd.gain
    events += rng.normal(0, apd.amplifier_noise_pe, (n, pulses)).sum(1)
    model = apd_waveform(np.full(n, lam), options=apd, pulses=pulses, rng=2)
    want_var = apd.excess_noise * lam * pulses + pulses * 0.7**2
    for x in (events, model):
        assert x.mean() == pytest.approx(lam * pulses, rel=0.02)
        assert x.var() == pytest.approx(want_var, rel=0.04)
    # the same distribution: quantiles agree
    q = [0.05, 0.25, 0.5, 0.75, 0.95]
    assert np.quantile(model, q) == pytest.approx(np.quantile(events, q), abs=0.3)


def test_threshold_sets_detection_and_ranges_stay_unbiased():
    bins = TimeBins.for_ranges(45.0, 55.0, 0.05)
    pulse = PulseOptions(fwhm_s=1e-9, jitter_s=0.1e-9)
    shape = shape_waveform(splat_paths(np.array([[100.0246]]), 1.0, bins.refined(2)), bins,
                           pulse, oversample=2)[0]  # fmt: skip
    apd = ApdOptions(gain=100, ionisation_ratio=0.02, amplifier_noise_pe=0.3, threshold_pe=20)
    rng = np.random.default_rng(3)
    lam = np.broadcast_to(shape * 60.0 + 0.01, (500, bins.count))
    strong = extract_ranges(apd_waveform(lam, options=apd, pulses=1, rng=rng), bins,
                            pulse=pulse, apd=apd)  # fmt: skip
    assert strong.valid.mean() > 0.98
    assert np.nanmean(strong.range) == pytest.approx(50.0123, abs=0.003)
    weak = np.broadcast_to(shape * 8.0 + 0.01, (500, bins.count))
    res = extract_ranges(apd_waveform(weak, options=apd, pulses=1, rng=rng), bins,
                         pulse=pulse, apd=apd)  # fmt: skip
    assert res.valid.mean() < 0.1  # 8 photoelectrons < the 20 pe threshold
    noise = np.full((500, bins.count), 0.01)
    res = extract_ranges(apd_waveform(noise, options=apd, pulses=1, rng=rng), bins,
                         pulse=pulse, apd=apd)  # fmt: skip
    assert res.valid.mean() < 0.01


def test_bad_options():
    with pytest.raises(ValueError, match=r"gain must be >= 1, got 0\.5"):
        ApdOptions(gain=0.5)
    with pytest.raises(ValueError, match=r"ionisation_ratio must be <= 1, got 2\.0"):
        ApdOptions(ionisation_ratio=2.0)
    with pytest.raises(ValueError, match=r"amplifier_noise_pe must be >= 0, got -0\.1"):
        ApdOptions(amplifier_noise_pe=-0.1)
    with pytest.raises(ValueError, match="threshold_pe must be a finite number, got nan"):
        ApdOptions(threshold_pe=float("nan"))
    from simlunar.lidar import DetectorOptions

    with pytest.raises(ValueError, match="no dead time"):
        DetectorOptions(apd=ApdOptions(), dead_time_s=1e-9)
    assert DetectorOptions(apd=ApdOptions()).regime == "linear_apd"
    assert DetectorOptions(dead_time_s=1e-9).regime == "spad"


def test_a_saturated_return_is_flat_topped_at_the_full_scale_per_pulse():
    # 2.5e6 photoelectrons in one bin (a descent's APD) against a 1000 pe full scale: each of
    # 4 pulses clips at 1000, so the bin reads exactly 4000 whatever its noise; a bin far below
    # the full scale reads as without it (mean 4 x 10, Poisson with F = 1: no excess noise)
    from simlunar.lidar.apd import ApdOptions, apd_waveform

    opts = ApdOptions(gain=1.0, ionisation_ratio=0.0, amplifier_noise_pe=0.0, full_scale_pe=1000.0)
    assert opts.excess_noise == pytest.approx(1.0)
    lam = np.zeros((2000, 3))
    lam[:, 0], lam[:, 1] = 2.5e6, 10.0
    w = apd_waveform(lam, options=opts, pulses=4, rng=0)
    assert (w[:, 0] == 4000.0).all()
    assert w[:, 1].mean() == pytest.approx(40.0, rel=0.02)
    assert w[:, 1].var() == pytest.approx(40.0, rel=0.1)
    assert (w[:, 2] == 0).all()
    # the ideal receiver (no full scale) keeps every photoelectron
    ideal = apd_waveform(lam, options=ApdOptions(gain=1.0, ionisation_ratio=0.0,
                                                 amplifier_noise_pe=0.0), pulses=4, rng=0)  # fmt: skip
    assert ideal[:, 0].mean() == pytest.approx(1e7, rel=1e-3)


def test_the_digitiser_rounds_to_its_steps_with_the_uniform_quantisation_noise():
    # 8 bits over 256 pe: 1 pe steps; a bin of mean 20.3 pe with 3 pe amplifier noise: every
    # reading a whole number, the variance F n + sigma^2 + step^2 / 12 (Widrow's model)
    from simlunar.lidar.apd import ApdOptions, apd_waveform

    opts = ApdOptions(gain=1.0, ionisation_ratio=0.0, amplifier_noise_pe=3.0,
                      full_scale_pe=256.0, bits=8)  # fmt: skip
    w = apd_waveform(np.full((40_000, 1), 20.3), options=opts, pulses=1, rng=1)
    assert np.array_equal(w, np.round(w))
    assert w.mean() == pytest.approx(20.3, abs=0.05)
    assert w.var() == pytest.approx(20.3 + 9.0 + 1.0 / 12.0, rel=0.03)
    with pytest.raises(ValueError, match="bits: a digitiser's resolution needs its full_scale_pe"):
        ApdOptions(bits=12)


def test_poisson_counts_exact_below_the_limit_and_normal_above():
    # below POISSON_NORMAL_ABOVE the draws are NumPy's Poisson draws of the same generator
    # (so every earlier histogram keeps its numbers); above it, the normal limit
    from simlunar.lidar.apd import MAX_COUNT, POISSON_NORMAL_ABOVE, poisson_counts

    mean = np.array([0.0, 0.5, 3.0, 1e6])
    got = poisson_counts(mean, np.random.default_rng(4))
    np.testing.assert_array_equal(got, np.random.default_rng(4).poisson(mean))
    # NumPy refuses a mean of 1e20 ("lam value too large"): the normal limit has mean m and
    # standard deviation sqrt(m) (1e10 here), so 200 draws' mean is within 4 sigma / sqrt(200)
    m = 1e17
    draws = poisson_counts(np.full(200, m), np.random.default_rng(5)).astype(float)
    assert abs(draws.mean() - m) < 4 * np.sqrt(m) / np.sqrt(200)
    assert 0.7 * np.sqrt(m) < draws.std() < 1.3 * np.sqrt(m)
    huge = poisson_counts(np.array([1e30, 2.0 * POISSON_NORMAL_ABOVE]), np.random.default_rng(6))
    assert huge.dtype == np.int64 and huge[0] == MAX_COUNT and huge[1] > POISSON_NORMAL_ABOVE
