"""The lit synthetic terrain: Lambert by hand, spectral slopes, the sample layout."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.reconstruction.integrate import central_gradient
from simlunar.reconstruction.synthetic import (
    fbm_heights,
    jittered_samples,
    lambert,
    lit_terrain,
    sun,
)


def test_sun_and_lambert_by_hand():
    s = sun(30.0, 90.0)  # towards +col, 30 deg up
    np.testing.assert_allclose(s, [0.0, np.sqrt(3) / 2, 0.5], atol=1e-15)
    # a plane rising towards +col with slope 1 (45 deg) faces away from that sun: n = (0,-1,1)/sqrt2
    np.testing.assert_allclose(
        lambert(0.0, 1.0, s, 0.5), 0.5 * max(0, (0.5 - np.sqrt(3) / 2)) / 2**0.5
    )
    # falling towards the sun: n . s = (sqrt(3)/2 + 1/2) / sqrt(2)
    np.testing.assert_allclose(lambert(0.0, -1.0, s, 1.0), (np.sqrt(3) / 2 + 0.5) / 2**0.5)


def test_fbm_slopes_are_the_heights_derivatives():
    h, hr, hc = fbm_heights((64, 96), beta=6.0, slope_rms=0.3, rng=0)
    assert np.sqrt(np.mean(hr**2 + hc**2)) == pytest.approx(0.3)
    # the spectral derivative, computed independently with the full complex FFT
    spec = np.fft.fft2(h)
    fr, fc = np.fft.fftfreq(64)[:, None], np.fft.fftfreq(96)[None, :]
    np.testing.assert_allclose(np.fft.ifft2(spec * 2j * np.pi * fr).real, hr, atol=1e-12)
    np.testing.assert_allclose(np.fft.ifft2(spec * 2j * np.pi * fc).real, hc, atol=1e-12)
    # central differences of this smooth a field are within 5 % (RMS) of it
    gr, gc = central_gradient(h)
    inner = (slice(2, -2), slice(2, -2))
    assert np.std((gr - hr)[inner]) < 0.05 * np.std(hr)
    assert np.std((gc - hc)[inner]) < 0.05 * np.std(hc)


def test_lit_terrain_frames():
    t = lit_terrain((32, 40), elevation_deg=45.0, azimuth_deg=0.0, albedo_contrast=0.5, rng=1)
    assert t.image.max() <= 0.9 + 1e-12 and t.flat.max() <= 0.9 + 1e-12
    _, hr, hc = fbm_heights((32, 40), beta=3.2, slope_rms=0.25, rng=np.random.default_rng(1))
    np.testing.assert_allclose(t.flat, t.albedo / np.sqrt(1 + hr**2 + hc**2))
    np.testing.assert_allclose(t.image, lambert(hr, hc, t.light, t.albedo))


def test_jittered_samples():
    pts = jittered_samples((100, 160), 1 / 64, rng=0)
    assert len(np.unique(pts, axis=0)) == len(pts)
    # one per 8 x 8 cell of a 13 x 20 lattice, plus the corners not already drawn
    assert 13 * 20 <= len(pts) <= 13 * 20 + 4
    for corner in ([0, 0], [0, 159], [99, 0], [99, 159]):
        assert (pts == corner).all(axis=1).any()
    assert pts.min() >= 0 and pts[:, 0].max() < 100 and pts[:, 1].max() < 160
