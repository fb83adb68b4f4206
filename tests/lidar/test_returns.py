"""What every LIDAR acquisition shares, on arrays (no rendering): the rendering options' bounds,
the instrument's photon scales, impulse responses -> photon counts -> ranges, a scan's depth."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simlunar.geometry import Camera, Intrinsics, Pose
from simlunar.lidar import DetectorOptions, PulseOptions, RangeOptions, TimeBins, extract_ranges
from simlunar.lidar.hardware import LidarHardware
from simlunar.lidar.returns import (
    LidarScan,
    ReturnOptions,
    TransientOptions,
    detect_counts,
    read_ranges,
)
from simlunar.lidar.waveform import splat_paths


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"spp": 0}, "spp must be >= 1"),
        ({"seed": -1}, "seed must be >= 0, got -1"),
        ({"oversample": 0}, "oversample must be >= 1"),
        ({"max_depth": 1}, "max_depth must be >= 2"),  # depth 1 never sees the laser
        ({"max_depth": -1}, "max_depth must be >= 2"),
        ({"max_depth": 17}, "max_depth must be <= 16"),
        ({"laser_intensity": 0.0}, "laser_intensity must be > 0"),
    ],
)
def test_transient_options_refuse_what_cannot_render(kwargs, match):
    with pytest.raises(ValueError, match=match):
        TransientOptions(**kwargs)


def test_photon_detector_is_the_expert_override_without_hardware():
    det = DetectorOptions(signal_photons=7.0, background_photons_per_s=3.0, pulses=2)
    opts = ReturnOptions(detector=det)
    assert opts.photon_detector() is det
    assert opts.photon_detector(pulses=5) == dataclasses.replace(det, pulses=5)


def test_photon_detector_takes_the_photon_scales_of_the_hardware():
    # the instrument's lidar equation (LidarHardware.detector) at the rendered laser intensity
    # and sun replaces the expert scales; the pulses per reading stay the options'
    hw = LidarHardware(pulse_energy_j=1e-6, dark_count_rate_hz=50.0)
    opts = ReturnOptions(
        detector=DetectorOptions(signal_photons=1.0, pulses=3),
        transient=TransientOptions(laser_intensity=2.0),
        hardware=hw,
    )
    got = opts.photon_detector(sun_irradiance=1361.0)
    want = hw.detector(laser_intensity=2.0, sun_irradiance=1361.0)
    assert got.signal_photons == want.signal_photons
    assert got.background_photons_per_s == want.background_photons_per_s
    assert got.dark_count_rate_hz == 50.0 and got.pulses == 3
    # the expected signal photons scale inversely with the rendered laser intensity
    half = dataclasses.replace(opts, transient=TransientOptions(laser_intensity=4.0))
    assert half.photon_detector().signal_photons == pytest.approx(got.signal_photons / 2)


def _impulses(ranges, bins: TimeBins, oversample: int) -> np.ndarray:
    """Rendered returns of unit weight at ``ranges`` (n,) m on ``oversample`` finer bins."""
    fine = bins.refined(oversample)
    return splat_paths(2.0 * np.asarray(ranges, float)[:, None], 1.0, fine).astype(np.float32)


def test_counts_have_the_expected_mean():
    # Poisson counts over many readings: their mean per reading is pulses x (signal photons x
    # the pulse-shaped return + background rate x bin duration), summed over the bins
    bins = TimeBins.for_ranges(10.0, 12.0, 0.05)
    det = DetectorOptions(signal_photons=20.0, background_photons_per_s=1e8, pulses=4)
    hist = np.repeat(_impulses([11.0], bins, 2), 4000, axis=0)
    counts = detect_counts(hist, 0.5, bins, PulseOptions(fwhm_s=1e-9), det,
                           np.random.default_rng(0), oversample=2)  # fmt: skip
    assert counts.shape == (4000, bins.count)
    per_reading = 4 * (20.0 + 0.5 * 1e8 * bins.bin_s * bins.count)
    # the pulse keeps the return's area (the kernel sums to 1) inside the window
    sem = np.sqrt(per_reading / 4000)
    assert counts.sum(axis=1).mean() == pytest.approx(per_reading, abs=4 * sem)


def test_ranges_of_noise_free_returns_are_the_true_ranges():
    # 200 signal photons per pulse and no background: the read range is the rendered one
    # within a tenth of a bin (5 cm bins, 1 ns pulse)
    bins = TimeBins.for_ranges(10.0, 14.0, 0.05)
    truth = np.array([10.5, 11.234, 13.01])
    det = DetectorOptions(signal_photons=200.0, background_photons_per_s=0.0, pulses=8)
    pulse = PulseOptions(fwhm_s=1e-9)
    counts = detect_counts(_impulses(truth, bins, 2), 0.0, bins, pulse, det,
                           np.random.default_rng(1), oversample=2)  # fmt: skip
    res = read_ranges(counts, 0.0, bins, pulse, det, RangeOptions())
    assert res.valid.all()
    assert res.range == pytest.approx(truth, abs=0.1 * bins.bin_range)
    # photon counting: read_ranges is the range extraction itself
    ref = extract_ranges(counts, bins, pulse=pulse, options=RangeOptions(), pulses=det.pulses)
    assert np.array_equal(res.range, ref.range)


def test_spad_pileup_is_refitted():
    # 30 photons per pulse on a SPAD with a 1.5 ns dead time: the first photon comes on the
    # pulse's leading edge, so the raw peak reads early; the refit through the dead time
    # removes that bias (the same physics as the rendered check in tests/lidar/test_scan.py)
    bins = TimeBins.for_ranges(10.0, 14.0, 0.05)
    truth = np.full(200, 12.0)
    det = DetectorOptions(signal_photons=30.0, background_photons_per_s=0.0, pulses=50,
                          dead_time_s=1.5e-9)  # fmt: skip
    pulse = PulseOptions(fwhm_s=1e-9)
    counts = detect_counts(_impulses(truth, bins, 2), 0.0, bins, pulse, det,
                           np.random.default_rng(2), oversample=2)  # fmt: skip
    raw = read_ranges(counts, 0.0, bins, pulse, det, RangeOptions(pileup_correction=False))
    fit = read_ranges(counts, 0.0, bins, pulse, det, RangeOptions())
    assert raw.valid.all() and fit.valid.all()
    raw_bias, fit_bias = np.mean(raw.range - 12.0), np.mean(fit.range - 12.0)
    assert raw_bias < -0.01  # early by more than a centimetre
    assert abs(fit_bias) < abs(raw_bias) / 3


def test_scan_depth_is_along_the_optical_axis():
    # a nadir camera 10 m up: points on z = 0 are 10 m deep wherever they are; NaN stays NaN
    cam = Camera(Intrinsics.from_fov(8, 8, 30.0), Pose.look_at([1.0, 2.0, 10.0], [1.0, 2.0, 0.0]))
    pts = np.array([[1.0, 2.0, 0.0], [4.0, -3.0, 0.0], [np.nan] * 3, [1.0, 2.0, 2.5]])
    scan = LidarScan(
        ranges=np.zeros(4),
        valid=np.array([True, True, False, True]),
        points=pts,
        photons=np.zeros(4),
        order=np.arange(4),
        seconds=0.0,
        frames=1,
    )
    depth = scan.depth(cam)
    assert depth[[0, 1, 3]] == pytest.approx([10.0, 10.0, 7.5])
    assert np.isnan(depth[2])
