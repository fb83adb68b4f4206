"""Lit synthetic terrain for checking and timing the image-anchored reconstructions.

An fBm height field (random phases, power spectrum ~ f^-beta) with analytic slopes, rendered
as a Lambert surface under a distant sun and, optionally, under a co-located (camera-centred)
light seen from the nadir: ``I = albedo * max(0, n . s)``, ``n = (-h_r, -h_c, 1) / |.|`` in
grid coordinates (d_row, d_col, up). No cast shadows (attached shadows only).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LitTerrain", "fbm_heights", "jittered_samples", "lambert", "lit_terrain", "sun"]


def sun(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    """Unit vector towards the sun in (d_row, d_col, up); azimuth from +row towards +col."""
    e, a = np.radians(elevation_deg), np.radians(azimuth_deg)
    return np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])


def fbm_heights(shape, *, beta: float = 3.2, slope_rms: float = 0.25, rng=0):
    """A periodic fBm height field and its exact slopes (spectral derivatives).

    Parameters
    ----------
    shape : tuple of int
        (rows, cols).
    beta : float
        Power-spectrum exponent (``|H(f)|^2 ~ f^-beta``).
    slope_rms : float
        RMS of ``|grad h|`` after scaling (dz per cell).
    rng : seed or Generator

    Returns
    -------
    h, hr, hc : ndarray, shape (rows, cols)
        Heights and d h / d row, d h / d col (per cell), mean-zero heights.
    """
    g = np.random.default_rng(rng)
    rows, cols = (int(s) for s in shape)
    fr = np.fft.fftfreq(rows)[:, None]
    fc = np.fft.rfftfreq(cols)[None, :]
    f = np.hypot(fr, fc)
    f[0, 0] = np.inf
    amp = f ** (-beta / 2)
    spec = amp * np.exp(2j * np.pi * g.random(amp.shape)) * g.rayleigh(size=amp.shape)
    spec[0, 0] = 0
    # no Nyquist rows/columns: their derivative is not real (h and slopes would disagree)
    if rows % 2 == 0:
        spec[rows // 2, :] = 0
    if cols % 2 == 0:
        spec[:, -1] = 0
    h = np.fft.irfft2(spec, s=(rows, cols))
    hr = np.fft.irfft2(spec * (2j * np.pi * fr), s=(rows, cols))
    hc = np.fft.irfft2(spec * (2j * np.pi * fc), s=(rows, cols))
    scale = slope_rms / np.sqrt(np.mean(hr**2 + hc**2))
    return h * scale, hr * scale, hc * scale


def lambert(hr, hc, light, albedo=1.0) -> np.ndarray:
    """``albedo * max(0, n . light)`` of a height field with slopes (hr, hc) per cell."""
    s = np.asarray(light, dtype=np.float64)
    s = s / np.linalg.norm(s)
    ndot = (s[2] - s[0] * hr - s[1] * hc) / np.sqrt(1.0 + hr**2 + hc**2)
    return albedo * np.maximum(ndot, 0.0)


@dataclass(frozen=True, eq=False)
class LitTerrain:
    """Heights and what the camera sees (see :func:`lit_terrain`)."""

    heights: np.ndarray
    #: sun frame ``albedo * max(0, n . light)``
    image: np.ndarray
    #: the co-located frame seen from the nadir, ``albedo * n_up``
    flat: np.ndarray
    light: np.ndarray
    #: the albedo the frames were rendered with (after their common scaling)
    albedo: np.ndarray


def lit_terrain(
    shape,
    *,
    elevation_deg: float = 30.0,
    azimuth_deg: float = 40.0,
    slope_rms: float = 0.25,
    beta: float = 3.2,
    albedo_contrast: float = 0.0,
    albedo_beta: float = 1.0,
    rng=0,
) -> LitTerrain:
    """fBm terrain rendered under one sun and under a co-located light at the nadir.

    ``albedo_contrast``: the albedo is ``0.5 * (1 + contrast * a)`` with ``a`` an independent
    pattern in [-1, 1] of spectrum f^-albedo_beta (0: constant albedo). Images are scaled so the sun
    frame's maximum is at most 0.9 (no saturation at 1.0).
    """
    g = np.random.default_rng(rng)
    h, hr, hc = fbm_heights(shape, beta=beta, slope_rms=slope_rms, rng=g)
    a, _, _ = fbm_heights(shape, beta=albedo_beta, slope_rms=1.0, rng=g)
    a = a / max(np.abs(a).max(), 1e-300)
    albedo = 0.5 * (1.0 + albedo_contrast * a)
    s = sun(elevation_deg, azimuth_deg)
    image = lambert(hr, hc, s, albedo)
    flat = lambert(hr, hc, (0.0, 0.0, 1.0), albedo)
    k = 0.9 / max(image.max(), flat.max(), 1e-300)
    return LitTerrain(h, image * k, flat * k, s, albedo * k)


def jittered_samples(shape, density: float, *, rng=0) -> np.ndarray:
    """A uniform-ish layout: one random cell in each cell of a square grid of pitch
    ``density^-1/2``, plus the four corners (so the convex hull is the whole grid).

    Returns
    -------
    ndarray of int64, shape (k, 2)
        Distinct (row, col) cells, sorted.
    """
    g = np.random.default_rng(rng)
    rows, cols = (int(s) for s in shape)
    p = max(1.0, density**-0.5)
    r0 = np.arange(0.0, rows, p)
    c0 = np.arange(0.0, cols, p)
    rr, cc = np.meshgrid(r0, c0, indexing="ij")
    r = np.minimum(rr + g.random(rr.shape) * p, rows - 1).astype(np.int64).ravel()
    c = np.minimum(cc + g.random(cc.shape) * p, cols - 1).astype(np.int64).ravel()
    corners = np.array([[0, 0], [0, cols - 1], [rows - 1, 0], [rows - 1, cols - 1]])
    pts = np.unique(np.vstack([np.column_stack([r, c]), corners]), axis=0)
    return pts
