"""The projector's optics: pixel aperture, response and pre-compensation, Gaussian PSF,
thin-lens defocus by hand; the fringe staircase of a pixel-grid projector gone with the
optics, and phase shifting's decoding error down to its noise formula."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from simlunar.imaging.projector_optics import (
    ProjectorOptics,
    _disc,
    _layered_defocus,
    defocus_diameter_px,
    emit,
    pixel_aperture,
)
from simlunar.scanner import rigs
from simlunar.scanner.codings import make_coding
from simlunar.scanner.fringes import phase_noise_std
from simlunar.scanner.phase_shift import coord_scores
from tests.scanner._synthetic import PlaneCapture

PLAIN = dict(fill_factor=1.0, psf_sigma=0.0, gamma=1.0, precompensate=False, bits=16)


def test_pixel_aperture_is_a_centred_square_of_the_fill_factor():
    ap = pixel_aperture(4, 0.81)  # side 0.9 x 4 = 3.6 sub-px: edges 0.2 and 3.8
    assert ap.sum() == pytest.approx(0.81 * 16)
    np.testing.assert_allclose(ap[0], [0.64, 0.8, 0.8, 0.64])
    np.testing.assert_array_equal(ap, ap.T)
    np.testing.assert_array_equal(pixel_aperture(3, 1.0), np.ones((3, 3)))


def test_plain_optics_emit_the_pixel_grid_supersampled():
    p = np.random.default_rng(0).random((2, 3, 5))
    em = emit(p, ProjectorOptics(supersample=4, **PLAIN))
    assert em.shape == (2, 12, 20) and em.dtype == np.float32
    np.testing.assert_allclose(em, np.kron(p, np.ones((4, 4)))[:, :, :], atol=2e-5)


def test_response_and_its_precompensation():
    p = np.linspace(0, 1, 11)[None, None]
    raw = emit(p, ProjectorOptics(supersample=1, **{**PLAIN, "gamma": 2.2}))
    np.testing.assert_allclose(raw[0, 0], p[0, 0] ** 2.2, atol=1e-4)
    pre = ProjectorOptics(supersample=1, **{**PLAIN, "gamma": 2.2, "precompensate": True})
    np.testing.assert_allclose(emit(p, pre)[0, 0], p[0, 0], atol=1e-4)
    # at 8 bits the pre-compensated curve keeps the quantisation of p ** (1 / 2.2)
    pre8 = ProjectorOptics(
        supersample=1, **{**PLAIN, "gamma": 2.2, "precompensate": True, "bits": 8}
    )
    want = (np.rint(p ** (1 / 2.2) * 255) / 255) ** 2.2
    np.testing.assert_allclose(emit(p, pre8)[0, 0], want[0, 0], atol=1e-6)


def test_gaussian_psf_spreads_a_pixel_by_its_sigma_and_the_aperture():
    # one lit pixel: the emitted image's variance is sigma^2 plus the aperture's, a^2 / 12
    # with a = sqrt(fill) px (the box of the mirror), in projector px
    S, sigma, fill = 8, 0.7, 0.64
    p = np.zeros((1, 15, 15))
    p[0, 7, 7] = 1.0
    em = emit(
        p, ProjectorOptics(supersample=S, **{**PLAIN, "psf_sigma": sigma, "fill_factor": fill})
    )[0]
    x = (np.arange(em.shape[1]) + 0.5) / S
    w = em.sum(axis=0)
    mean = (w * x).sum() / w.sum()
    var = (w * (x - mean) ** 2).sum() / w.sum()
    assert mean == pytest.approx(7.5, abs=1e-6)
    assert var == pytest.approx(sigma**2 + fill / 12, rel=0.01)
    assert em.sum() / S**2 == pytest.approx(fill, rel=1e-3)  # the gap's light is lost


def test_defocus_diameter_by_the_thin_lens_by_hand():
    # fx 1000 px, pitch 10 um: f = 10 mm; f/2: A = 5 mm; focused at 1 m, a point at 2 m:
    # c = A f |s - s_f| / (s (s_f - f)) = 5e-3 * 1e-2 * 1 / (2 * 0.99) m = 2.525 px
    o = ProjectorOptics(f_number=2.0, pixel_pitch=10e-6)
    c = defocus_diameter_px(np.array([2.0, 1.0, np.nan]), fx=1000.0, options=o, focus=1.0)
    np.testing.assert_allclose(c, [5e-5 / 1.98 / 1e-5, 0.0, 0.0])
    assert np.all(defocus_diameter_px([2.0], fx=1000.0, options=ProjectorOptics(), focus=1.0) == 0)
    with pytest.raises(ValueError, match="not beyond the focal length"):
        defocus_diameter_px([2.0], fx=1000.0, options=o, focus=0.005)


def test_layered_defocus_blurs_each_region_by_its_own_disc():
    img = np.zeros((64, 64))
    img[::8, ::8] = 1.0  # point sources
    diam = np.full(img.shape, 3.0)
    diam[:, 32:] = 9.0
    out = _layered_defocus(img, diam)
    left = ndimage.convolve(img, _disc(3.0), mode="constant")
    right = ndimage.convolve(img, _disc(9.0), mode="constant")
    np.testing.assert_allclose(out[:, :24], left[:, :24], atol=1e-12)
    np.testing.assert_allclose(out[:, 40:], right[:, 40:], atol=1e-12)
    assert _disc(0.5).shape == (1, 1) and _disc(9.0).sum() == pytest.approx(1.0)


def _fringe_scan(optics, noise, seed=0):
    rig = rigs.moonyard_rig(proj_size=(64, 48), cam_size=(256, 192))
    cap = PlaneCapture(rig, (0.25, -0.1, 1.0), 0.0, ss=2, noise=noise, rng=seed, optics=optics)
    coding = make_coding("phase_shift", {"steps": 8, "period_px": 8.0, "min_modulation": 0.05})
    scan = coding.scan(cap, rig)
    uv = cap.true_uv()
    truth = {"uv": uv, "lit": np.isfinite(uv[..., 0]) & cap.ok.all(axis=-1)}
    return scan.decode, truth


def _flatness(dec):
    frac = np.mod(dec.u[dec.valid], 1.0)
    h, _ = np.histogram(frac, bins=10, range=(0.0, 1.0))
    return np.abs(h / h.mean() - 1).max()


def test_the_psf_removes_the_fringe_staircase():
    # a pixel-grid projector shows each fringe as a staircase: the decoded positions bunch
    # where the steps are (histogram of u within the projector pixel far from flat); through
    # the DLP5500 optics (0.5 px PSF, 0.82 fill factor, 4x supersampled) the histogram is flat
    # to 10 % per tenth of a pixel (about 30 000 positions: 3 % sampling scatter per bin)
    grid, _ = _fringe_scan(None, 0.0)
    optics, _ = _fringe_scan(ProjectorOptics(), 0.0)
    assert optics.valid.sum() > 25_000
    assert _flatness(grid) > 0.5
    assert _flatness(optics) < 0.1


def test_phase_shift_decoding_error_falls_to_its_noise_formula():
    # with the optics the error against the continuous truth is the frame noise's:
    # sigma_u = p / (2 pi) sqrt(2 / N) sigma_I / B (B each pixel's measured modulation)
    # (away from the projector image's border: within a few PSF widths of it the blur
    # mixes the fringe with the dark outside, 0.035 px RMS over all pixels noise-free, 0.0045
    # px over these)
    sigma_i = 0.01
    dec, truth = _fringe_scan(ProjectorOptics(), sigma_i, seed=3)
    uv = truth["uv"]
    inner = (uv[..., 0] > 4) & (uv[..., 0] < 60) & (uv[..., 1] > 4) & (uv[..., 1] < 44)
    scores = coord_scores(dec, truth, inner)
    m = dec.valid & truth["lit"] & inner
    sigma_u = 8.0 / (2 * np.pi) * phase_noise_std(8, sigma_i, dec.modulation[m])
    predicted = float(np.sqrt(np.mean(sigma_u**2)))
    assert scores["coord_err_rate"] == 0.0
    assert scores["coord_rmse_px"] == pytest.approx(predicted, rel=0.15)
    # without the optics the staircase, not the noise, dominates the error
    dec, truth = _fringe_scan(None, sigma_i, seed=3)
    assert coord_scores(dec, truth, inner)["coord_rmse_px"] > 3 * predicted
