"""Time bins and the pulse / jitter response."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.lidar import SPEED_OF_LIGHT, PulseOptions, TimeBins, pulse_kernel, shape_waveform


def test_bins_for_ranges():
    b = TimeBins.for_ranges(45.0, 60.0, 0.05)
    assert b.count == 300
    assert b.start_opl == 90.0
    assert b.bin_range == pytest.approx(0.05)
    assert b.bin_s == pytest.approx(0.1 / SPEED_OF_LIGHT)
    assert b.centres_range[0] == pytest.approx(45.025)


def test_pulse_kernel_has_the_combined_width():
    b = TimeBins(0.0, 0.03, 200)  # 0.1 ns bins
    p = PulseOptions(fwhm_s=2e-9, jitter_s=0.5e-9)
    k = pulse_kernel(b, p)
    x = np.arange(k.size) - k.size // 2
    assert k.sum() == pytest.approx(1.0)
    sd = np.sqrt(np.sum(k * x**2)) * b.bin_s
    # sigma^2 = (fwhm / 2.3548)^2 + jitter^2, plus 1/12 bin^2 of binning
    want = np.sqrt((2e-9 / 2.3548) ** 2 + 0.5e-9**2 + b.bin_s**2 / 12)
    assert sd == pytest.approx(want, rel=0.01)


def test_shaping_keeps_the_energy_and_the_centre():
    b = TimeBins(0.0, 0.03, 200)
    h = np.zeros((3, 200))
    h[:, 100] = 1.0
    out = shape_waveform(h, b, PulseOptions(fwhm_s=1e-9))
    assert out.sum(axis=1) == pytest.approx([1.0, 1.0, 1.0])
    assert (out.argmax(axis=1) == 100).all()
    assert np.array_equal(shape_waveform(h, b, PulseOptions(fwhm_s=0.0)), h)
    with pytest.raises(ValueError, match="bins"):
        shape_waveform(np.zeros(10), b, PulseOptions())


def test_splat_keeps_every_path_s_first_moment():
    from simlunar.lidar.waveform import splat_paths

    b = TimeBins(0.0, 0.1, 50)
    opl = np.array([[1.234, 2.5, 3.0001], [0.05, 4.95, 2.0]])  # second row: at both edges
    w = np.array([[1.0, 2.0, 0.5], [1.0, 1.0, 3.0]])
    h = splat_paths(opl, w, b)
    assert h[0].sum() == pytest.approx(3.5)
    centres = (np.arange(50) + 0.5) * 0.1
    assert np.sum(h[0] * centres) == pytest.approx(np.sum(w[0] * opl[0]))
    # 1.234 m lies 0.84 of the way from bin 11's centre (1.15) to bin 12's (1.25)
    one = splat_paths(np.array([1.234]), 1.0, b)
    assert one[11] == pytest.approx(0.16) and one[12] == pytest.approx(0.84)
    # a path in the first / last half bin keeps only the share inside the window
    assert h[1, 0] == pytest.approx(1.0) and h[1, 49] == pytest.approx(1.0)


def test_oversampled_shaping_rebins_to_the_output_bins():
    from simlunar.lidar.waveform import splat_paths

    b = TimeBins(0.0, 0.1, 100)
    fine = b.refined(4)
    assert (fine.count, fine.bin_opl, fine.start_opl) == (400, pytest.approx(0.025), 0.0)
    h = splat_paths(np.array([[5.0123]]), 1.0, fine)
    out = shape_waveform(h, b, PulseOptions(fwhm_s=1e-9), oversample=4)
    assert out.shape == (1, 100)
    assert out.sum() == pytest.approx(1.0)
    centres = (np.arange(100) + 0.5) * 0.1
    assert np.sum(out * centres) == pytest.approx(5.0123, abs=1e-6)
    with pytest.raises(ValueError, match="oversample"):
        shape_waveform(h, b, PulseOptions(), oversample=2)
    with pytest.raises(ValueError, match="oversample"):
        b.refined(0)
