"""Range extraction on synthetic waveforms: within one bin; first / last / strongest."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar import (
    DetectorOptions,
    PulseOptions,
    RangeOptions,
    TimeBins,
    expected_counts,
    extract_ranges,
    photon_counts,
    shape_waveform,
)

BINS = TimeBins.for_ranges(40.0, 60.0, 0.05)  # 400 bins of 5 cm
PULSE = PulseOptions(fwhm_s=1e-9, jitter_s=0.1e-9)


def _impulse(ranges, weights=None):
    """Impulse responses with their returns at ``ranges`` (m), split linearly between bins."""
    ranges = np.atleast_2d(ranges)
    w = np.ones_like(ranges) if weights is None else np.atleast_2d(weights)
    h = np.zeros((ranges.shape[0], BINS.count))
    x = (2 * ranges - BINS.start_opl) / BINS.bin_opl - 0.5  # fractional bin centre index
    i0 = np.floor(x).astype(int)
    f = x - i0
    for r in range(ranges.shape[0]):
        for j in range(ranges.shape[1]):
            h[r, i0[r, j]] += w[r, j] * (1 - f[r, j])
            h[r, i0[r, j] + 1] += w[r, j] * f[r, j]
    return h


@pytest.mark.parametrize("method, photons", [("matched", 40.0), ("peak", 200.0)])
def test_noisy_single_returns_within_one_bin(method, photons):
    rng = np.random.default_rng(0)
    truth = rng.uniform(42.0, 58.0, 300)
    sig = shape_waveform(_impulse(truth[:, None]), BINS, PULSE)
    det = DetectorOptions(signal_photons=photons, background_photons_per_s=5e8)
    counts = photon_counts(expected_counts(sig, 1.0, BINS, det), options=det, rng=1)
    res = extract_ranges(counts, BINS, pulse=PULSE, options=RangeOptions(method=method))
    assert res.valid.mean() > 0.98
    err = np.abs(res.range[res.valid] - truth[res.valid])
    assert np.quantile(err, 0.99) < BINS.bin_range
    assert res.photons[res.valid].mean() == pytest.approx(photons, rel=0.3)


def test_noise_free_reading_is_sub_bin():
    truth = np.linspace(45.0, 55.0, 37)
    sig = shape_waveform(_impulse(truth[:, None]), BINS, PULSE)
    res = extract_ranges(100 * sig, BINS, pulse=PULSE)
    assert np.abs(res.range - truth).max() < 0.25 * BINS.bin_range


def test_first_last_strongest_of_two_returns():
    truth = np.array([[47.0, 52.0]])
    sig = 100 * shape_waveform(_impulse(truth, [[0.3, 1.0]]), BINS, PULSE)
    for which, want in (("first", 47.0), ("last", 52.0), ("strongest", 52.0)):
        res = extract_ranges(sig, BINS, pulse=PULSE, options=RangeOptions(which=which))
        assert res.returns[0] == 2
        assert res.range[0] == pytest.approx(want, abs=BINS.bin_range)


def test_background_alone_gives_no_return():
    det = DetectorOptions(background_photons_per_s=2e9)
    lam = expected_counts(np.zeros((500, BINS.count)), 1.0, BINS, det)
    counts = photon_counts(lam, options=det, rng=5)
    res = extract_ranges(counts, BINS, pulse=PULSE)
    assert res.valid.mean() < 0.01
    assert np.isnan(res.range[~res.valid]).all()


def test_unknown_method_lists_the_valid_ones():
    with pytest.raises(ValueError, match="method must be one of 'matched', 'peak', got 'cfd'"):
        RangeOptions(method="cfd")


OFFSETS = (np.arange(10) + 0.05) / 10  # across one bin, away from its exact centre


def _sweep(photons, trials, rng, *, background=0.01, oversample=2):
    """Counts of a plane at every sub-bin offset (``trials`` each) through the fine-binned
    tent-splat + pulse + re-bin chain; returns (ranges (10, trials), truth (10, 1))."""
    from simlunar.lidar.waveform import splat_paths

    truth = 50.0 + OFFSETS[:, None] * BINS.bin_range
    fine = BINS.refined(oversample)
    lam = shape_waveform(splat_paths(2 * truth, 1.0, fine), BINS, PULSE, oversample=oversample)
    lam = photons * lam + background
    counts = rng.poisson(np.broadcast_to(lam[:, None, :], (10, trials, BINS.count)))
    res = extract_ranges(counts, BINS, pulse=PULSE)
    return np.where(res.valid, res.range, np.nan), truth


def test_no_staircase_noise_free():
    # expected counts, no noise: the ML fit reads every sub-bin offset to 0.05 mm (the
    # parabola's vertex alone is biased by up to 0.7 mm: a sine over the bin)
    from simlunar.lidar.waveform import splat_paths

    truth = 50.0 + OFFSETS * BINS.bin_range
    lam = shape_waveform(splat_paths(2 * truth[:, None], 1.0, BINS.refined(2)), BINS, PULSE,
                         oversample=2)  # fmt: skip
    ml = extract_ranges(1000 * lam + 0.01, BINS, pulse=PULSE).range
    assert np.abs(ml - truth).max() < 5e-5
    par = extract_ranges(1000 * lam + 0.01, BINS, pulse=PULSE, options=RangeOptions(fit="parabola"))
    assert 3e-4 < np.abs(par.range - truth).max() < 2e-3


def test_sub_bin_sweep_is_unbiased_at_1000_photons():
    got, truth = _sweep(1000.0, 400, np.random.default_rng(3))
    bias = np.nanmean(got - truth, axis=1)
    # CRLB 2.1 mm per reading: the standard error of each offset's mean is 0.1 mm
    assert np.abs(bias).max() < 1e-3


@pytest.mark.parametrize("photons, trials", [(10.0, 600), (100.0, 300), (1000.0, 300)])
def test_range_rms_reaches_the_cramer_rao_bound(photons, trials):
    from simlunar.lidar.bounds import range_crlb

    got, truth = _sweep(photons, trials, np.random.default_rng(int(photons)))
    assert np.isfinite(got).mean() > 0.95
    rms = np.sqrt(np.nanmean((got - truth) ** 2, axis=1))
    bound = range_crlb(photons, pulse=PULSE, bins=BINS, offset=OFFSETS, background=0.01)
    ratio = np.sqrt(np.mean(rms**2) / np.mean(bound**2))
    # measured 1.03-1.08 (10 photons: a Poisson count's E[1/n] > 1/E[n] adds 5-10 %)
    assert 0.85 < ratio < 1.3


def test_box_binned_returns_show_the_staircase():
    # the defect the tent splat removes: box bins put every path at its bin's centre
    truth = 50.0 + OFFSETS * BINS.bin_range
    box = np.zeros((10, BINS.count))
    box[np.arange(10), np.floor((2 * truth - BINS.start_opl) / BINS.bin_opl).astype(int)] = 1
    got = extract_ranges(1000 * shape_waveform(box, BINS, PULSE) + 0.01, BINS, pulse=PULSE).range
    assert np.abs(got - truth).max() > 0.02


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"threshold_sigma": -1.0}, "threshold_sigma must be >= 0, got -1.0"),
        ({"min_photons": -0.5}, "min_photons must be >= 0, got -0.5"),
        ({"threshold_sigma": float("nan")}, "threshold_sigma must be a finite number, got nan"),
    ],
)
def test_range_options_refuse_negative_or_nan_thresholds(kw, message):
    with pytest.raises(ValueError, match=message):
        RangeOptions(**kw)


def test_range_options_accept_zero_thresholds_and_name_bad_choices():
    o = RangeOptions(threshold_sigma=0.0, min_photons=0.0)
    assert (o.threshold_sigma, o.min_photons) == (0.0, 0.0)
    with pytest.raises(
        ValueError, match=r"which must be one of 'strongest', 'first', 'last', got 'middle'"
    ):
        RangeOptions(which="middle")


def test_photons_of_a_return_exclude_the_background_by_hand():
    """Noise-free: a return of 100 photons over 3 counts per bin of background. The window
    around the return holds the pulse (all of it but its far tails) plus 3 per bin of
    background, which the estimate takes off: about 100, never 100 + the background."""
    sig = shape_waveform(_impulse(np.array([[50.0]])), BINS, PULSE)
    assert sig.sum() == pytest.approx(1.0, rel=1e-6)
    res = extract_ranges(100 * sig + 3.0, BINS, pulse=PULSE)
    assert res.valid[0] and res.returns[0] == 1
    assert res.photons[0] == pytest.approx(100.0, rel=0.05)
    assert abs(res.range[0] - 50.0) < 0.25 * BINS.bin_range


def test_two_returns_closer_than_a_pulse_width_read_as_one():
    """Returns 5 cm apart (one bin) under a 1 ns pulse (15 cm FWHM in range) are one return
    between them; 1 m apart they are two."""
    close = shape_waveform(_impulse(np.array([[50.0, 50.05]])), BINS, PULSE)
    res = extract_ranges(100 * close, BINS, pulse=PULSE)
    assert res.returns[0] == 1
    assert 50.0 - BINS.bin_range < res.range[0] < 50.05 + BINS.bin_range
    apart = shape_waveform(_impulse(np.array([[50.0, 51.0]])), BINS, PULSE)
    assert extract_ranges(100 * apart, BINS, pulse=PULSE).returns[0] == 2


@pytest.mark.parametrize("method", ["matched", "peak"])
def test_noise_free_reading_interpolates_within_the_bin(method):
    """The parabola through the peak bin and its neighbours places a noise-free return to
    within a tenth of a bin (measured: 0.024 matched, 0.046 peak); the peak bin's centre
    alone is off by up to half a bin."""
    truth = np.linspace(45.0, 55.0, 37)
    sig = shape_waveform(_impulse(truth[:, None]), BINS, PULSE)
    res = extract_ranges(100 * sig, BINS, pulse=PULSE, options=RangeOptions(method=method))
    assert np.abs(res.range - truth).max() < 0.1 * BINS.bin_range


def test_a_flat_topped_return_is_one_return():
    """Raw-peak scoring of a return split evenly over two bins (50 and 50 counts over a
    background of 1): both bins are the window's maximum, and only the first of a run of
    equal scores is a peak, so there is one return, between the two bins."""
    counts = np.ones((1, BINS.count))
    counts[0, 200:202] = 50.0
    opts = RangeOptions(method="peak", fit="parabola")
    res = extract_ranges(counts, BINS, pulse=PULSE, options=opts)
    assert res.returns[0] == 1
    # bins 200 and 201 span ranges 50.00-50.05 and 50.05-50.10: their boundary is 50.05
    assert res.range[0] == pytest.approx(BINS.range_of(201.0), abs=0.5 * BINS.bin_range)


def test_last_return_with_the_parabola_alone_by_hand():
    """Returns at the centres of the bins of 47.00-47.05 m (weight 1) and 52.00-52.05 m
    (weight 0.3), noise free: the parabola's vertex alone (no ML refinement to pull a wrong
    bin back) reads each return to a quarter of a bin; a return read from the bin after
    its peak would be half a bin off (the vertex clipped to that bin's edge)."""
    truth = np.array([[47.025, 52.025]])
    sig = 100 * shape_waveform(_impulse(truth, [[1.0, 0.3]]), BINS, PULSE)
    for which, want in (("first", 47.025), ("last", 52.025), ("strongest", 47.025)):
        opts = RangeOptions(which=which, fit="parabola")
        res = extract_ranges(sig, BINS, pulse=PULSE, options=opts)
        assert res.returns[0] == 2
        assert abs(res.range[0] - want) < 0.25 * BINS.bin_range


def test_background_estimate_leaves_the_return_out():
    """Noise free, 100 photons over exactly 3 counts per bin: the background is the mean away
    from the return (3.000), so the photons of the return are the pulse's counts in the
    window of the kernel's width, 100 x (the kernel's mass there) = 99.9994, to 1e-6."""
    from simlunar.lidar.waveform import pulse_kernel

    sig = shape_waveform(_impulse(np.array([[50.0]])), BINS, PULSE)
    half = pulse_kernel(BINS, PULSE).size // 2
    peak = int(np.argmax(sig[0]))
    want = 100 * sig[0, peak - half : peak + half + 1].sum()
    res = extract_ranges(100 * sig + 3.0, BINS, pulse=PULSE)
    assert want == pytest.approx(100.0, abs=1e-3)
    assert res.photons[0] == pytest.approx(want, rel=1e-6)


def test_apd_detection_threshold_by_hand():
    """A linear-mode APD's window of 5 bins over 3 pulses with expected background 4 pe:
    variance F x 4 + 5 x 3 x 0.5^2 (excess noise, and the amplifier's per bin and pulse), the
    threshold 5 standard deviations above 4; the least signal is the APD's own threshold
    when it is above min_photons."""
    from simlunar.lidar.apd import ApdOptions
    from simlunar.lidar.ranging import _detection_threshold

    apd = ApdOptions(gain=100.0, ionisation_ratio=0.02, amplifier_noise_pe=0.5, threshold_pe=7.0)
    f = 0.02 * 100 + 0.98 * (2 - 1 / 100)  # McIntyre: 3.9502
    c_thr, least = _detection_threshold(np.array([4.0]), 5, RangeOptions(), apd, 3)
    np.testing.assert_allclose(c_thr, 4.0 + 5.0 * np.sqrt(f * 4.0 + 5 * 3 * 0.25), rtol=1e-12)
    assert least == 7.0
    _, least = _detection_threshold(np.array([4.0]), 5, RangeOptions(min_photons=9.0), apd, 3)
    assert least == 9.0


def test_a_wide_return_is_tested_in_a_window_of_its_own_width_by_hand():
    """A 4 ns pulse (sigma 5.09 bins) over 5 counts per bin, noise free: the significance
    window is +-ceil(1.5 sigma) = +-8 bins, 17 bins holding 0.905 of the pulse over 85
    background counts, whose 5-sigma Poisson quantile is 135. 70 photons give 85 + 63.3 =
    148.3 > 135: detected; 40 give 121.2: not. (A 3-bin window would hold 0.23 of the pulse:
    15 + 16.2 against its quantile 38, and miss both.)"""
    wide = PulseOptions(fwhm_s=4e-9)
    assert wide.sigma_bins(BINS) == pytest.approx(5.09, abs=0.01)
    sig = shape_waveform(_impulse(np.array([[50.0]])), BINS, wide)
    assert extract_ranges(70 * sig + 5.0, BINS, pulse=wide).valid[0]
    assert not extract_ranges(40 * sig + 5.0, BINS, pulse=wide).valid[0]


def _cut_returns(truth, photons=200.0):
    """Noise-free counts of returns at ``truth`` (m), the histogram cut at the window's edges
    (bins outside 40-60 m are not recorded): a return near an edge loses part of its pulse."""
    wide = TimeBins.for_ranges(35.0, 65.0, 0.05)
    ranges = np.atleast_1d(truth)
    x = (2 * ranges - wide.start_opl) / wide.bin_opl - 0.5
    h = np.zeros((len(ranges), wide.count))
    i0 = np.floor(x).astype(int)
    f = x - i0
    h[np.arange(len(ranges)), i0] = 1 - f
    h[np.arange(len(ranges)), i0 + 1] = f
    sig = shape_waveform(h, wide, PULSE)
    first = round((BINS.start_opl - wide.start_opl) / wide.bin_opl)
    return photons * sig[:, first : first + BINS.count] + 0.01


def test_a_return_cut_by_the_gate_s_edge_is_rejected_not_read_biased():
    # a 1 ns pulse (sigma 0.43 ns, 6.5 cm in range) centred 2 sigma before the window's start
    # leaves only its tail (5 of 200 photons, falling from the first bin): read without a
    # guard it is accepted at the window's edge, about 2 sigma (13 cm, 2.6 bins) from the
    # truth; with the guard it is rejected. Returns centred on the edge (+-0.5 sigma: half a
    # pulse) are read within 1 cm by the fit, but they too lie within the guard
    sigma_m = PULSE.sigma_s * 299_792_458.0 / 2
    truth = 40.0 + np.array([-2.0, -0.5, 0.0, 0.5]) * sigma_m
    counts = _cut_returns(truth)
    kept = extract_ranges(counts, BINS, pulse=PULSE)
    err = kept.range - truth
    assert kept.valid.all() and err[0] > 1.5 * sigma_m  # the bug: accepted, biased
    guarded = extract_ranges(counts, BINS, pulse=PULSE, options=RangeOptions(edge_sigma=3.0))
    assert not guarded.valid.any()
    assert np.isnan(guarded.range).all()
    # returns 4 sigma from either edge are kept and unbiased
    inside = np.array([40.0 + 4 * sigma_m, 50.0, 60.0 - 4 * sigma_m])
    res = extract_ranges(_cut_returns(inside), BINS, pulse=PULSE,
                         options=RangeOptions(edge_sigma=3.0))  # fmt: skip
    assert res.valid.all() and np.abs(res.range - inside).max() < 0.25 * BINS.bin_range
    # the far edge alike
    far = _cut_returns([60.0 + 2 * sigma_m])
    assert extract_ranges(far, BINS, pulse=PULSE).valid.all()
    assert not extract_ranges(
        far, BINS, pulse=PULSE, options=RangeOptions(edge_sigma=3)
    ).valid.any()


def test_no_accepted_return_near_an_edge_is_off_by_more_than_a_bin():
    # swept through the start of the window: with the guard every accepted range is within a
    # bin of the truth (without it the cut returns are accepted centimetres off)
    sigma_m = PULSE.sigma_s * 299_792_458.0 / 2
    truth = np.linspace(40.0 - 2 * sigma_m, 40.0 + 5 * sigma_m, 57)
    counts = _cut_returns(truth)
    res = extract_ranges(counts, BINS, pulse=PULSE, options=RangeOptions(edge_sigma=3.0))
    assert res.valid.any()
    assert np.abs(res.range[res.valid] - truth[res.valid]).max() < BINS.bin_range
    plain = extract_ranges(counts, BINS, pulse=PULSE)
    assert np.abs(plain.range[plain.valid] - truth[plain.valid]).max() > BINS.bin_range


@pytest.mark.parametrize("photons, background", [(1.0, 0.002), (0.5, 0.01), (2.0, 0.02)])
def test_detection_probability_matches_a_monte_carlo(photons, background):
    # the closed form of the detection test against 3000 simulated histograms at the pulses
    # it chooses for 90 %, and at half as many
    from simlunar.lidar.ranging import detection_probability, pulses_for_detection

    n = pulses_for_detection(photons, background, target=0.9, bins=BINS, pulse=PULSE)
    assert detection_probability(photons, background, n, bins=BINS, pulse=PULSE) >= 0.9
    assert detection_probability(photons, background, n - 1, bins=BINS, pulse=PULSE) < 0.9
    rng = np.random.default_rng(int(photons * 100))
    truth = rng.uniform(45.0, 55.0, 3000)
    sig = shape_waveform(_impulse(truth[:, None]), BINS, PULSE)
    for pulses in (n, max(1, n // 2)):
        lam = photons * sig + background
        counts = rng.poisson(lam * pulses)
        res = extract_ranges(counts, BINS, pulse=PULSE)
        hit = res.valid & (np.abs(res.range - truth) < 3 * BINS.bin_range)
        p = detection_probability(photons, background, pulses, bins=BINS, pulse=PULSE)
        assert hit.mean() == pytest.approx(float(p), abs=0.06), pulses


def test_pulses_for_detection_refuses_what_it_cannot_reach():
    from simlunar.lidar.ranging import pulses_for_detection

    with pytest.raises(ValueError, match=r"not detected with probability 0\.9"):
        pulses_for_detection(1e-4, 0.5, target=0.9, bins=BINS, pulse=PULSE, max_pulses=100)
    with pytest.raises(ValueError, match=r"target must be in \(0, 1\)"):
        pulses_for_detection(1.0, 0.0, target=1.0, bins=BINS, pulse=PULSE)
