"""Linear-mode APD: excess noise, amplifier noise, detection threshold, against an event-level
simulation (one avalanche per photoelectron)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simlunar.lidar import PulseOptions, TimeBins, extract_ranges, shape_waveform, splat_paths
from simlunar.lidar.apd import ApdOptions, agc_energy, apd_waveform


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
    with pytest.raises(ValueError, match="agc_target: the gain control needs"):
        ApdOptions(agc_target=0.5)
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


# --- automatic pulse-energy control --------------------------------------------------------


def test_agc_energy_by_hand():
    # probe waveforms at 1e-3 of the full energy: background 2 pe per bin, the brightest
    # return 2 + 40 pe at its peak; full scale 1000 pe, target half of it: the frame's energy
    # is 1e-3 x 0.5 x 1000 / 40 = 0.0125 (the digitiser is linear below its full scale)
    apd = ApdOptions(full_scale_pe=1000.0, agc_target=0.5)
    w = np.full((3, 50), 2.0)
    w[0, 20], w[1, 10] = 42.0, 12.0
    w += np.random.default_rng(0).normal(0.0, 0.1, w.shape)  # a little noise: significant
    # the receiver read without firing: the 2 pe background and its noise alone
    quiet = 2.0 + np.random.default_rng(2).normal(0.0, 0.1, w.shape)
    energy, again = agc_energy(w, quiet, 1e-3, options=apd)
    assert energy == pytest.approx(1e-3 * 0.5 * 1000 / 40.0, rel=0.02) and not again
    # a saturated probe: the next is 100x weaker
    w[2, 30] = 1000.0
    assert agc_energy(w, quiet, 1e-3, options=apd) == (1e-5, True)
    # a probe of noise alone saw no return: 100x stronger, then the full energy and no more
    noise = 2.0 + np.random.default_rng(1).normal(0.0, 0.5, (3, 50))
    assert agc_energy(noise, quiet, 1e-3, options=apd) == (pytest.approx(0.1), True)
    assert agc_energy(noise, quiet, 1.0, options=apd) == (1.0, False)
    # a return too weak for the target at full energy gets the full energy
    weak = np.full((1, 50), 2.0)
    weak[0, 5] = 202.0
    assert agc_energy(weak, quiet[:1], 1.0, options=apd) == (1.0, False)


def _plane_frame(signal, apd, *, pulses=16, n=8, background_per_s=0.0):
    """A n x n flash receiver 50 m over a plane, its rendered returns and options (the sun's
    background, if any, ``background_per_s`` photons per second into every pixel)."""
    from types import SimpleNamespace

    from simlunar.geometry import Camera, Intrinsics, Pose
    from simlunar.lidar import DetectorOptions
    from simlunar.lidar.flash import FlashOptions, flash_window

    pose = Pose.look_at([0.0, 0.0, 50.0], [0.0, 0.0, 0.0], up=(0.0, 1.0, 0.0))
    cam = Camera(Intrinsics.from_fov(n, n, 10.0), pose)
    det = DetectorOptions(signal_photons=signal, background_photons_per_s=background_per_s,
                          pulses=pulses, apd=apd)  # fmt: skip
    opts = FlashOptions(detector=det, pulse=PulseOptions(fwhm_s=1e-9), pulse_rate_hz=20.0)
    bins = flash_window(cam, options=opts)
    truth = 50.0 / -cam.rays(cam.pixel_centers())[1][..., 2]
    hist = splat_paths(2.0 * truth[..., None], 1.0, bins.refined(2)).reshape(n, n, -1)
    sun = np.ones((n, n)) if background_per_s else None
    frame = SimpleNamespace(histograms=hist.astype(np.float32), sun=sun, bins=bins,
                            oversample=2, sun_irradiance=1.0)  # fmt: skip
    return cam, opts, frame, truth


def test_agc_puts_a_saturating_return_at_its_target_for_a_probe_pulse():
    # 2.5e6 photons per pulse into a 1000 pe digitiser: without control every pixel clips
    # (its photons read ~pulses x full scale per bin); with agc_target 0.5 one probe at 1e-3
    # of the energy (the brightest peak then ~750 pe, linear) sets the energy to 0.5 x 1000 /
    # P, P the brightest pixel's noise-free peak per pulse at full energy: the photons read
    # are that share of the unsaturated receiver's, the frame costs one pulse more
    from simlunar.lidar.flash import read_flash, receiver_solid_angles
    from simlunar.lidar.returns import detect_counts

    fs, s = 1000.0, 2.5e6
    cam, ideal, frame, truth = _plane_frame(s, ApdOptions())
    w = receiver_solid_angles(cam) / receiver_solid_angles(cam).max()
    hist = frame.histograms * w[..., None]
    peak = s * shape_waveform(hist, frame.bins, ideal.pulse, oversample=2).max()
    energy = 0.5 * fs / peak
    _, agc, _, _ = _plane_frame(s, ApdOptions(full_scale_pe=fs, bits=12, agc_target=0.5))
    _, clip, _, _ = _plane_frame(s, ApdOptions(full_scale_pe=fs, bits=12))
    free = read_flash(frame, cam, options=ideal, rng=0)
    ctrl = read_flash(frame, cam, options=agc, rng=0)
    sat = read_flash(frame, cam, options=clip, rng=0)
    assert ctrl.valid.all() and np.abs(ctrl.ranges - truth).max() < 0.01
    # the probe (the read's second draw after the background slot, redrawn here from the same
    # seed) measures the peak
    # with the APD's noise (7 % at ~750 pe, F = 3.95) and its maximum over the pixels is
    # biased up: the energy set is agc_energy's of that probe, 0.8-1.0x the noise-free one
    rng = np.random.default_rng(0)
    quiet_det = dataclasses.replace(agc.detector, pulses=1, signal_photons=0.0)
    quiet = detect_counts(hist, 0.0, frame.bins, agc.pulse, quiet_det, rng, 2)
    probe_det = dataclasses.replace(agc.detector, pulses=1, signal_photons=s * 1e-3)
    probe = detect_counts(hist, 0.0, frame.bins, agc.pulse, probe_det, rng, 2)
    set_energy, again = agc_energy(probe, quiet, 1e-3, options=agc.detector.apd)
    assert not again and 0.8 * energy < set_energy <= 1.0 * energy
    ratio = ctrl.photons / free.photons
    assert np.median(ratio) == pytest.approx(set_energy, rel=0.03)
    # without control the waveform clips at the full scale: the photons read are under 1 %
    # of the return's, whatever it is
    assert sat.photons.max() < 0.01 * free.photons.min()
    # the control took two pulse slots (the background read and one probe)
    assert ctrl.seconds == pytest.approx(18 / 20.0) and sat.seconds == pytest.approx(16 / 20.0)
    # and fired the probe's 1e-3 of the full energy, then 16 pulses at the energy it set: the
    # laser energy in full-energy pulses (the quiet slot fires nothing)
    from simlunar.lidar.flash import read_frame

    fired = read_frame(frame, cam, agc, np.random.default_rng(0)).energy_pulses
    assert fired == pytest.approx(1e-3 + 16 * set_energy, rel=1e-12)
    assert read_frame(frame, cam, clip, np.random.default_rng(0)).energy_pulses is None
    # a dim return (the target out of reach at full energy) keeps the full energy
    _, dim, _, _ = _plane_frame(20.0, ApdOptions(full_scale_pe=fs, agc_target=0.5))
    _, full, _, _ = _plane_frame(20.0, ApdOptions(full_scale_pe=fs))
    a, b = (read_flash(frame, cam, options=o, rng=3) for o in (dim, full))
    assert np.median(a.photons) == pytest.approx(np.median(b.photons), rel=0.1)


def test_agc_probe_of_background_photons_alone_is_no_return():
    # a probe that saw only the sun: 0.05 background photons per bin and pixel through a
    # gain-100 APD (F = 3.96), 4096 pixels x 200 bins. The waveforms' MAD is set by the
    # amplifier's noise (under 1 pe), while single photons multiplied by the gain reach tens of
    # pe in the frame: judged against the MAD such a photon looked like a return and set the
    # energy ~1e-3 x 500 / 30 (the frame then starved: 2 % of a rendered frame's pixels
    # valid); judged against the background read without firing it is no return: 100x stronger
    apd = ApdOptions(gain=100.0, ionisation_ratio=0.02, full_scale_pe=1000.0, agc_target=0.5)
    w = apd_waveform(np.full((4096, 200), 0.05), options=apd, pulses=1, rng=0)
    quiet = apd_waveform(np.full((4096, 200), 0.05), options=apd, pulses=1, rng=1)
    mad = 1.4826 * np.median(np.abs(w - np.median(w, -1, keepdims=True)))
    peak = (w.max(-1) - np.median(w, -1)).max()
    assert mad < 1.0 and peak > 16.0 > 8 * mad  # the photon that fooled the MAD
    assert agc_energy(w, quiet, 1e-3, options=apd) == (pytest.approx(0.1), True)
    # the same sun with a return of 60 pe in every pixel: a return
    w[:, 100] += 60.0
    assert agc_energy(w, quiet, 1e-3, options=apd)[1] is False


def test_agc_aims_at_the_quantile_pixel_not_the_brightest():
    # 1000 pixels: the ground's return peaks at 40 pe in the probe, 5 rocks (0.5 %) at 400 pe,
    # one saturated: the energy puts the 99 % pixel (the ground, 40 pe) at half the 1000 pe
    # full scale, the rocks clip; aimed at the brightest, the whole frame would sit at 5 %
    apd = ApdOptions(full_scale_pe=1000.0, agc_target=0.5)
    rng = np.random.default_rng(0)
    w = np.full((1000, 50), 2.0) + rng.normal(0.0, 0.1, (1000, 50))
    quiet = np.full((1000, 50), 2.0) + rng.normal(0.0, 0.1, (1000, 50))
    w[:, 20] += 40.0
    w[:5, 20] += 360.0
    w[5, 20] = 1000.0
    energy, again = agc_energy(w, quiet, 1e-3, options=apd)
    assert not again and energy == pytest.approx(1e-3 * 0.5 * 1000 / 40.0, rel=0.02)
    # more than 1 - q of the pixels saturated: the next probe is 100x weaker
    w[:20, 20] = 1000.0
    assert agc_energy(w, quiet, 1e-3, options=apd) == (1e-5, True)
    # agc_quantile 1.0 is the brightest pixel's rule
    one = ApdOptions(full_scale_pe=1000.0, agc_target=0.5, agc_quantile=1.0)
    w[:20, 20] = 42.0
    w[:5, 20] = 402.0
    energy, _ = agc_energy(w, quiet, 1e-3, options=one)
    assert energy == pytest.approx(1e-3 * 0.5 * 1000 / 400.0, rel=0.02)


def test_agc_keeps_a_starved_frame_under_sunlight_at_full_energy():
    # a 32 x 32 receiver over a plane, 20 photons per pixel and pulse under a sun of 1e9
    # photons / s: the brightest return stays far below the full scale, so the control must
    # fire at full energy and keep the pixels the uncontrolled frame keeps (judged against the
    # MAD it kept 0.5 %; on the rendered frame of the receiver bench 2 %)
    from simlunar.lidar.flash import read_flash

    kw = {"n": 32, "background_per_s": 1e9}
    apd = {"gain": 100.0, "ionisation_ratio": 0.02, "full_scale_pe": 1000.0, "bits": 12}
    cam, free, frame, truth = _plane_frame(20.0, ApdOptions(**apd), **kw)
    _, agc, _, _ = _plane_frame(20.0, ApdOptions(**apd, agc_target=0.5), **kw)
    a = read_flash(frame, cam, options=free, rng=5)
    b = read_flash(frame, cam, options=agc, rng=5)
    assert a.valid.mean() > 0.9
    assert b.valid.mean() >= a.valid.mean() - 0.02
    assert np.median(b.photons) == pytest.approx(np.median(a.photons), rel=0.1)
    assert np.median(np.abs(b.ranges - truth)[b.valid]) < 0.05
