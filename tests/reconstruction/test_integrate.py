"""Frankot-Chellappa on the mirror-extended grid and the DCT Gaussian: round trips, planes,
agreement with scipy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from simlunar.reconstruction.integrate import (
    central_gradient,
    frankot_chellappa,
    gaussian_smooth,
)


def _reference_fc(gr, gc, u, w):
    """The weighted Frankot-Chellappa solved on the explicit 2R x 2C mirror extension with
    numpy's FFT (what the quarter-size transforms of the library compute)."""
    u = np.asarray(u, float) / np.hypot(*u)
    t = np.array([-u[1], u[0]])
    rows, cols = gr.shape

    def ext(m, n):  # m odd about the row edges, n about the column edges
        top = np.hstack([m + n, (m - n)[:, ::-1]])
        return np.vstack([top, np.hstack([(n - m)[::-1], -(m + n)[::-1, ::-1]])])

    kr = np.sin(2 * np.pi * np.fft.fftfreq(2 * rows))[:, None]
    kc = np.sin(2 * np.pi * np.fft.rfftfreq(2 * cols))[None, :]
    a, b = u[0] * kr + u[1] * kc, t[0] * kr + t[1] * kc
    den = a * a + w * b * b
    num = -1j * (a * np.fft.rfft2(ext(u[0] * gr, u[1] * gc))
                 + w * b * np.fft.rfft2(ext(t[0] * gr, t[1] * gc)))  # fmt: skip
    small = den <= 1e-12
    den[small] = 1.0
    num /= den
    num[small] = 0.0
    z = np.fft.irfft2(num, s=(2 * rows, 2 * cols))[:rows, :cols]
    return z - z.mean()


@pytest.mark.parametrize("shape", [(6, 9), (37, 29), (64, 80)])
@pytest.mark.parametrize("along, w", [((1.0, 0.0), 1.0), ((0.6, 0.8), 0.05), ((-0.3, 1.0), 0.3)])
def test_quarter_transforms_equal_the_fft_of_the_mirror_extension(rng, shape, along, w):
    gr, gc = rng.normal(size=shape), rng.normal(size=shape)  # any field, not integrable
    ours = frankot_chellappa(gr, gc, along=along, across_weight=w, detrend=False)
    ref = _reference_fc(gr, gc, along, w)
    np.testing.assert_allclose(ours, ref, atol=1e-12 * np.abs(ref).max())


def _field(rng, shape):
    return ndimage.gaussian_filter(rng.normal(size=shape), 2.0) * 10 + rng.normal(size=shape)


@pytest.mark.parametrize("shape", [(32, 48), (37, 29), (2, 5)])
def test_central_gradient_integrates_back_exactly(rng, shape):
    # any field (rough, odd sizes): its mirrored central differences are in the range of the
    # operator the integrator inverts, so the round trip is exact up to the mean
    z = _field(rng, shape)
    gr, gc = central_gradient(z)
    back = frankot_chellappa(gr, gc, detrend=False)
    np.testing.assert_allclose(back, z - z.mean(), atol=1e-9 * np.abs(z).max())


@pytest.mark.parametrize("along, w", [((0.6, 0.8), 0.05), ((1.0, 0.0), 0.3), ((-1.0, 2.0), 1.0)])
def test_consistent_slopes_integrate_back_for_any_across_weight(rng, along, w):
    # the weighted problem has the same exact solution when the slopes are consistent
    z = _field(rng, (40, 56))
    gr, gc = central_gradient(z)
    back = frankot_chellappa(gr, gc, along=along, across_weight=w, detrend=False)
    np.testing.assert_allclose(back, z - z.mean(), atol=1e-8 * np.abs(z).max())


def test_mirror_symmetric_cosine_from_its_analytic_slopes():
    # a surface whose mirror extension is smooth: cos(pi k (i + 1/2) / R); its analytic slope
    # integrates back to O(h^2) (central differences of a cosine: sin(w) / w)
    rows, cols = 64, 96
    i = (np.arange(rows) + 0.5)[:, None]
    j = (np.arange(cols) + 0.5)[None, :]
    kr, kc = 3, 5
    wr, wc = np.pi * kr / rows, np.pi * kc / cols
    z = np.cos(wr * i) * np.cos(wc * j)
    # the discrete response is sin(w): scaling the analytic slope by sin(w) / w is exact
    gr = -np.sin(wr * i) * np.cos(wc * j) * np.sin(wr)
    gc = -np.cos(wr * i) * np.sin(wc * j) * np.sin(wc)
    np.testing.assert_allclose(frankot_chellappa(gr, gc, detrend=False), z, atol=1e-12)
    # the analytic slope itself: error of order w^2 / 6
    raw = frankot_chellappa(
        -np.sin(wr * i) * np.cos(wc * j) * wr, -np.cos(wr * i) * np.sin(wc * j) * wc
    )
    assert np.abs(raw - z).max() < wc**2


def test_constant_slopes_give_the_exact_plane():
    rows, cols = 30, 41
    r, c = np.mgrid[0:rows, 0:cols]
    plane = 0.3 * r - 1.7 * c
    out = frankot_chellappa(np.full((rows, cols), 0.3), np.full((rows, cols), -1.7),
                            along=(0.3, 0.9), across_weight=0.05)  # fmt: skip
    np.testing.assert_allclose(out, plane - plane.mean(), atol=1e-12 * np.abs(plane).max())


def test_small_across_weight_keeps_detail_along_the_direction(rng):
    # slopes along u exact, across u left out (zero): the isotropic projection keeps cos^2 of
    # each mode (half of an isotropic field), a small weight across keeps nearly all of it
    z = ndimage.gaussian_filter(rng.normal(size=(128, 128)), 3.0, mode="wrap")
    gr, gc = central_gradient(z)
    u = np.array([1.0, 1.0]) / np.sqrt(2)
    pu = u[0] * gr + u[1] * gc
    kept = {}
    for w in (1.0, 1e-3):
        out = frankot_chellappa(pu * u[0], pu * u[1], along=u, across_weight=w)
        zc, oc = (z - z.mean())[16:-16, 16:-16], out[16:-16, 16:-16]
        kept[w] = float((oc * zc).sum() / (zc * zc).sum())
    assert 0.35 < kept[1.0] < 0.65
    assert kept[1e-3] > 0.85


def test_gaussian_smooth_matches_scipy_reflect(rng):
    a = _field(rng, (50, 70))
    for sigma in (1.5, 4.0):
        ref = ndimage.gaussian_filter(a, sigma, mode="reflect", truncate=8.0)
        np.testing.assert_allclose(gaussian_smooth(a, sigma), ref, atol=2e-3 * np.abs(a).max())
    np.testing.assert_array_equal(gaussian_smooth(a, 0), a)


def test_bad_input():
    with pytest.raises(ValueError, match="same shape"):
        frankot_chellappa(np.zeros((3, 4)), np.zeros((4, 3)))
    with pytest.raises(ValueError, match="across_weight"):
        frankot_chellappa(np.zeros((3, 4)), np.zeros((3, 4)), across_weight=0)
    with pytest.raises(ValueError, match="along"):
        frankot_chellappa(np.zeros((3, 4)), np.zeros((3, 4)), along=(0, 0))
    with pytest.raises(ValueError, match="NaN"):
        frankot_chellappa(np.full((3, 4), np.nan), np.zeros((3, 4)))
    with pytest.raises(ValueError, match="sigma"):
        gaussian_smooth(np.zeros((3, 4)), -1)
