"""Geiger-mode SPAD: the event-level simulation, the exact expected histogram, pile-up and its
correction."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar import (
    DetectorOptions,
    PulseOptions,
    RangeOptions,
    TimeBins,
    shape_waveform,
    splat_paths,
)
from simlunar.lidar.spad import spad_correct, spad_counts, spad_expected

BINS = TimeBins.for_ranges(45.0, 55.0, 0.05)
PULSE = PulseOptions(fwhm_s=1e-9, jitter_s=0.1e-9)
DEAD = 1.5e-9  # 4.5 bins of 5 cm
TRUTH = 50.0123


def _shape():
    h = splat_paths(np.array([[2 * TRUTH]]), 1.0, BINS.refined(2))
    return shape_waveform(h, BINS, PULSE, oversample=2)[0]


def test_constant_rate_matches_the_dead_time_formula():
    # a constant rate r per bin, dead time D bins, armed at the start: after the first
    # detection (mean time 1 / r) the detections renew with period X = D + Exp(r), mean
    # mu = D + 1 / r and variance 1 / r^2, so the count in a long window of T bins is
    # (T - 1 / r) / mu + 1 + (1 / r^2 - mu^2) / (2 mu^2) (renewal theory): 31.01 here
    r, dead_bins = 0.5, 4.5
    mu = dead_bins + 1 / r
    lam = np.full(BINS.count, r)
    h = spad_counts(lam[None], BINS, dead_time_s=dead_bins * BINS.bin_s, pulses=4000, rng=0)
    per_pulse = h.sum() / 4000
    want = (BINS.count - 1 / r) / mu + 1 + (1 / r**2 - mu**2) / (2 * mu**2)
    assert want == pytest.approx(31.01, abs=0.01)
    assert per_pulse == pytest.approx(want, rel=0.01)
    e = spad_expected(lam, BINS, dead_time_s=dead_bins * BINS.bin_s, substeps=32).sum()
    assert e == pytest.approx(want, rel=0.01)
    # rounding the dead time up to whole bins (5) would undercount by 7 %
    assert (BINS.count - 2) / 7 + 1 + (4 - 49) / 98 < 0.95 * want


@pytest.mark.parametrize("photons", [0.5, 3.0, 10.0, 30.0])
def test_event_level_simulation_matches_the_expected_histogram(photons):
    lam = photons * _shape() + 0.01
    pulses = 50_000
    h = spad_counts(lam[None], BINS, dead_time_s=DEAD, pulses=pulses, rng=int(photons * 10))[0]
    e = spad_expected(lam, BINS, dead_time_s=DEAD, substeps=32) * pulses
    assert h.sum() == pytest.approx(e.sum(), rel=0.01)
    big = e > 0.02 * e.max()
    # per bin within 4 binomial sigmas plus 1 % (the sub-step discretisation)
    assert (np.abs(h - e)[big] < 4 * np.sqrt(e[big]) + 0.01 * e[big]).all()


def test_pile_up_biases_the_range_early_and_the_fit_removes_it():
    lam = 30.0 * _shape()
    pulses = 2000
    h = spad_counts(np.broadcast_to(lam, (6, BINS.count)), BINS, dead_time_s=DEAD,
                    pulses=pulses, rng=5)  # fmt: skip
    centres = BINS.centres_range
    raw = (h * centres).sum(1) / h.sum(1)
    # at 30 photons per pulse the first photon arrives on the leading edge: the uncorrected
    # centroid is early (by 3 cm, half the pulse's sigma); the model predicts it
    e = spad_expected(lam, BINS, dead_time_s=DEAD)
    predicted = (e * centres).sum() / e.sum()
    assert raw.mean() - TRUTH < -0.02
    assert raw.mean() == pytest.approx(predicted, abs=0.003)
    fit = spad_correct(h, BINS, pulses=pulses, dead_time_s=DEAD,
                       sigma_bins=PULSE.sigma_bins(BINS))  # fmt: skip
    assert np.abs(fit.range - TRUTH).max() < 0.005


@pytest.mark.parametrize("photons", [0.5, 3.0, 10.0, 30.0])
def test_corrected_signal_within_5_percent_up_to_30_photons(photons):
    bg = 0.002
    lam = photons * _shape() + bg
    pulses = 4000
    h = spad_counts(np.broadcast_to(lam, (8, BINS.count)), BINS, dead_time_s=DEAD,
                    pulses=pulses, rng=int(photons * 7))  # fmt: skip
    fit = spad_correct(h, BINS, pulses=pulses, dead_time_s=DEAD,
                       sigma_bins=PULSE.sigma_bins(BINS), background=bg)  # fmt: skip
    assert fit.photons.mean() == pytest.approx(photons, rel=0.05)
    assert np.abs(fit.photons / photons - 1).max() < 0.08
    # Coates' first-photon correction fails once the detector is rarely armed at the peak
    from simlunar.lidar import coates_correction

    if photons >= 10:
        coates = (coates_correction(h, pulses) - bg).clip(0).sum(1).mean()
        assert not coates == pytest.approx(photons, rel=0.2)


def test_bad_inputs():
    with pytest.raises(ValueError, match="dead_time_s"):
        spad_counts(np.ones((1, BINS.count)), BINS, dead_time_s=0.0, pulses=1)
    with pytest.raises(ValueError, match=">= 0"):
        spad_counts(-np.ones((1, BINS.count)), BINS, dead_time_s=1e-9, pulses=1)


def test_the_background_is_estimated_from_the_histogram_s_signal_free_bins():
    # 0.02 photons per bin and pulse of background, a 5-photon return at bin ~100 of 200:
    # the leading 80 bins see the background alone (a detection depends only on earlier
    # arrivals), so their sum inverts the exact expected histogram for the rate
    from simlunar.lidar.spad import spad_background

    b = 0.02
    lam = 5.0 * _shape() + b
    h = spad_counts(np.tile(lam, (6, 1)), BINS, dead_time_s=DEAD, pulses=4000, rng=7)
    est = spad_background(h, BINS, pulses=4000, dead_time_s=DEAD, free_bins=80)
    # 80 bins x 0.02 x 4000 = 6400 arrivals: about 1.3 % statistical error
    assert est == pytest.approx(np.full(6, b), rel=0.05)
    # bins holding the return are not signal-free: counting them would overestimate
    wrong = spad_background(h, BINS, pulses=4000, dead_time_s=DEAD, free_bins=140)
    assert (wrong > 1.3 * b).all()
    assert (spad_background(h, BINS, pulses=4000, dead_time_s=DEAD, free_bins=0) == 0).all()


def test_the_pile_up_correction_needs_no_true_background():
    # the scan hands read_ranges the render's background; with spad_background "histogram"
    # the correction ignores it (here deliberately wrong: none) and matches the correction
    # given the true background, while the "given" wrong one is biased
    from simlunar.lidar.returns import read_ranges

    b = 0.05  # photons per bin and pulse
    lam = 8.0 * _shape() + b
    h = spad_counts(np.tile(lam, (20, 1)), BINS, dead_time_s=DEAD, pulses=500, rng=11)
    rate = b / BINS.bin_s  # photons/s with background_photons_per_s 1 per unit luminance
    det = DetectorOptions(pulses=500, dead_time_s=DEAD, background_photons_per_s=1.0)
    truth_bg = read_ranges(h, rate, BINS, PULSE, det, RangeOptions())
    wrong_bg = read_ranges(h, 0.0, BINS, PULSE, det, RangeOptions())
    own = read_ranges(h, 0.0, BINS, PULSE, det, RangeOptions(spad_background="histogram"))
    assert own.valid.all() and truth_bg.valid.all()
    err_own = np.abs(own.range - TRUTH).mean()
    err_truth = np.abs(truth_bg.range - TRUTH).mean()
    err_wrong = np.abs(wrong_bg.range - TRUTH).mean()
    assert err_own < 1.5 * err_truth + 2e-3
    assert own.photons.mean() == pytest.approx(truth_bg.photons.mean(), rel=0.1)
    # the correction given no background puts the sun into the return: ~0.1 m off (measured
    # 116 mm, 925 photons instead of 8 per pulse)
    assert err_wrong > 10 * err_own and wrong_bg.photons.mean() > 10 * truth_bg.photons.mean()
    # whatever the caller hands it
    ten = read_ranges(h, 10 * rate, BINS, PULSE, det, RangeOptions(spad_background="histogram"))
    assert np.array_equal(ten.range, own.range)


def test_a_first_photon_receiver_is_corrected_in_a_reading():
    # one detection per pulse (infinite dead time) at 3 photons per pulse: the histogram piles
    # up towards the return's leading edge (the reading early by centimetres); the reading of
    # a scan refits it through the exact expected histogram as it does a SPAD's
    from simlunar.lidar import extract_ranges
    from simlunar.lidar.returns import read_ranges

    lam = 3.0 * _shape() + 1e-4
    h = spad_counts(np.tile(lam, (20, 1)), BINS, dead_time_s=np.inf, pulses=2000, rng=5)
    det = DetectorOptions(pulses=2000, dead_time_s=np.inf, background_photons_per_s=0.0)
    assert det.regime == "first_photon"
    raw = extract_ranges(h, BINS, pulse=PULSE)
    fixed = read_ranges(h, 0.0, BINS, PULSE, det, RangeOptions())
    off = read_ranges(h, 0.0, BINS, PULSE, det, RangeOptions(pileup_correction=False))
    assert np.array_equal(off.range, raw.range)
    bias_raw = np.mean(raw.range - TRUTH)
    bias_fixed = np.mean(fixed.range - TRUTH)
    assert bias_raw < -0.01  # early by more than a centimetre
    assert abs(bias_fixed) < 0.2 * abs(bias_raw) and abs(bias_fixed) < 0.003
    assert fixed.photons.mean() / 2000 == pytest.approx(3.0, rel=0.1)


def test_constant_rate_drawn_by_detections_matches_the_renewal_formula():
    # the detection-level draw (used above PHOTON_LEVEL_MAX photons per pulse) is the same
    # process as the photon-level one: the renewal count of the test above
    r, dead_bins = 0.5, 4.5
    mu = dead_bins + 1 / r
    lam = np.full(BINS.count, r)
    kw = {"dead_time_s": dead_bins * BINS.bin_s, "photon_level_max": 0.0}
    h = spad_counts(lam[None], BINS, pulses=4000, rng=1, **kw)
    want = (BINS.count - 1 / r) / mu + 1 + (1 / r**2 - mu**2) / (2 * mu**2)
    assert h.sum() / 4000 == pytest.approx(want, rel=0.01)
    # never two detections closer than the dead time: at a huge rate the first bin fires in
    # every pulse, then bin 4 (t = 4.5), never bins 1-3
    one = spad_counts(np.full((1, BINS.count), 1e9), BINS, pulses=7, rng=2, **kw)[0]
    assert one[0] == 7 and one[1:4].sum() == 0 and one[4] == 7


@pytest.mark.parametrize("photons", [0.5, 10.0, 30.0])
def test_detection_level_draw_matches_the_expected_histogram(photons):
    lam = photons * _shape() + 0.01
    pulses = 50_000
    h = spad_counts(lam[None], BINS, dead_time_s=DEAD, pulses=pulses, rng=7,
                    photon_level_max=0.0)[0]  # fmt: skip
    e = spad_expected(lam, BINS, dead_time_s=DEAD, substeps=32) * pulses
    assert h.sum() == pytest.approx(e.sum(), rel=0.01)
    big = e > 0.02 * e.max()
    assert (np.abs(h - e)[big] < 4 * np.sqrt(e[big]) + 0.01 * e[big]).all()


def test_the_documented_photon_cap_ends():
    # a SPAD at the schema's cap (1e12 photons per pulse) used to draw every photon: a hang.
    # At that rate the detector fires as soon as it is armed: the first detection where the
    # integrated rate reaches ~1 photon, then one every dead time to the window's end
    import time

    lam = 1e12 * _shape() + 0.01
    pulses = 2000
    t = time.perf_counter()
    h = spad_counts(lam[None], BINS, dead_time_s=DEAD, pulses=pulses, rng=3)[0]
    assert time.perf_counter() - t < 20.0
    dead_bins = DEAD / BINS.bin_s
    lit = np.flatnonzero(lam >= 1.0)  # bins of the pulse: at least a photon each
    first = int(np.searchsorted(np.cumsum(lam), 1.0))
    assert first <= lit[0] + 1
    # the leading edge fires in (nearly) every pulse; then one detection per dead time
    # inside the pulse (none can be closer, and the detector is never armed for long)
    # (unless a background photon, 0.01 per bin, blinded it within a dead time before: 4.5 %)
    assert h[first - 1 : first + 2].sum() >= 0.94 * pulses
    in_pulse = h[lit[0] : lit[-1] + 1].sum() / pulses
    span = lit[-1] + 1 - lit[0]
    assert np.floor(span / dead_bins) <= in_pulse <= np.ceil(span / dead_bins) + 1


def test_outlier_guards_drop_false_corrected_returns_and_keep_the_good_ones():
    # 10 ns dead time under a high background (2e8 photons/s: 0.07 per 5 cm bin and pulse),
    # 2 signal photons per pulse, 100 pulses, returns at 43-47 m in a 40-50 m window: the
    # detection takes pile-up ripples for returns and the corrected ranges hold outliers
    # (> 0.1 m off) metres early. The significance guard (the fit's likelihood ratio against
    # the dead time's background alone, 5 sigma) cuts them to a third or less and loses no
    # return that was within 0.1 m; a bound on the fitted range's standard error (5 cm) cuts
    # them as much, and a 2 cm bound is too tight (it loses good returns: the test can tell)
    from simlunar.lidar import DetectorOptions, RangeOptions
    from simlunar.lidar.returns import detect_counts, read_ranges

    bins = TimeBins.for_ranges(40.0, 50.0, 0.05)
    pulse = PulseOptions(fwhm_s=1e-9, jitter_s=0.1e-9)
    truth = np.random.default_rng(0).uniform(43.0, 47.0, 200)
    hist = splat_paths(2 * truth[:, None], 1.0, bins.refined(2))
    det = DetectorOptions(signal_photons=2.0, background_photons_per_s=2e8, pulses=100,
                          dead_time_s=10e-9)  # fmt: skip
    counts = detect_counts(hist, 1.0, bins, pulse, det, np.random.default_rng(1), 2)

    def read(**kw):
        res = read_ranges(counts, 1.0, bins, pulse, det,
                          RangeOptions(spad_background="histogram", **kw))  # fmt: skip
        bad = res.valid & (np.abs(res.range - truth) > 0.1)
        return res.valid, bad

    valid0, bad0 = read()
    good0 = valid0 & ~bad0
    assert bad0.sum() / valid0.sum() > 0.06  # the failure the guards are for
    for kw in ({"spad_min_significance": 5.0}, {"spad_max_sigma_m": 0.05}):
        valid, bad = read(**kw)
        assert bad.sum() <= bad0.sum() / 3 and not (good0 & ~valid).any()
    valid, _ = read(spad_max_sigma_m=0.02)
    assert (good0 & ~valid).mean() > 0.1
