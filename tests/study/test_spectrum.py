"""Variance share by wavelength (DCT power) and the grid-vs-random smoothness effect."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.study.spectrum import (
    dct_power,
    gaussian_field,
    random_grid_mse_ratio,
    sample_pitch,
    variance_share_above,
)


def _cos(shape, i, j):
    r = np.arange(shape[0])[:, None]
    c = np.arange(shape[1])[None, :]
    return np.cos(np.pi * i * (r + 0.5) / shape[0]) * np.cos(np.pi * j * (c + 0.5) / shape[1])


def test_parseval_and_frequencies():
    rng = np.random.default_rng(0)
    h = rng.standard_normal((30, 50)) + 3.0
    freq, power = dct_power(h, spacing=0.5)
    assert power.sum() == pytest.approx(h.var())
    # basis (i, j) has frequency hypot(i / 60, j / 100) / 0.5 cycles per metre
    assert freq[6, 0] == pytest.approx(0.2) and freq[0, 10] == pytest.approx(0.2)


def test_share_of_two_known_waves():
    # amplitude 2 at wavelength 2 * 64 / 2 = 64 cells, amplitude 1 at 2 * 64 / 16 = 8 cells:
    # variances 2 and 0.5 (a cos^2 averages 1/2), so 80 % of the variance lies above any
    # threshold between 8 and 64 cells
    shape = (64, 64)
    h = 2.0 * _cos(shape, 2, 0) + 1.0 * _cos(shape, 0, 16)
    assert variance_share_above(h, spacing=0.2, wavelength=0.2 * 20) == pytest.approx(0.8)
    assert variance_share_above(h, spacing=0.2, wavelength=0.2 * 7) == pytest.approx(1.0)
    assert variance_share_above(h, spacing=0.2, wavelength=0.2 * 70) == pytest.approx(0.0)
    # a plane (ramp) is long-wavelength variance and does not leak to short wavelengths
    ramp = np.add.outer(np.arange(64.0), np.zeros(64))
    assert variance_share_above(ramp, spacing=1, wavelength=16) > 0.99
    assert np.isnan(variance_share_above(np.ones((4, 4)), spacing=1, wavelength=2))
    with pytest.raises(ValueError):
        variance_share_above(h, spacing=1, wavelength=0)


def test_sample_pitch():
    assert sample_pitch(1 / 2048) == pytest.approx(45.2548, rel=1e-5)
    with pytest.raises(ValueError):
        sample_pitch(0)


def test_smooth_fields_favour_the_grid():
    # white noise: no sample layout helps (ratio about 1); a field smooth at the sample pitch
    # (8 cells): the grid's even coverage beats random's clumps and gaps by a factor > 2
    rough = gaussian_field((96, 96), 0, rng=1)
    smooth = gaussian_field((96, 96), 12, rng=1)
    assert smooth.std() == pytest.approx(1.0)
    r_rough = random_grid_mse_ratio(rough, 1 / 64, trials=3, rng=2)
    r_smooth = random_grid_mse_ratio(smooth, 1 / 64, trials=3, rng=2)
    assert 0.9 < r_rough < 1.15
    assert r_smooth > 2.0
