"""A projector's optics: how a digital pattern becomes the emitted image (NumPy/SciPy only).

A digital pattern (projector shape (H, W), values in [0, 1]) is, in order:

1. pre-compensated for the display response when asked (``p ** (1 / gamma)``), quantised to
   the projector's ``bits`` and shown through its response ``p ** gamma`` (a video-driven
   projector's gamma; the pre-compensation is the usual inverse look-up table, exact but for
   the quantisation);
2. emitted by each pixel's mirror: a centred square of side ``sqrt(fill_factor)`` pitch, dark
   between the mirrors, formed on a grid of ``supersample`` x ``supersample`` sub-pixels per
   projector pixel (area-weighted at the mirror's edges);
3. blurred by the lens: a Gaussian point-spread function of ``psf_sigma`` projector px (the
   lens's resolving power, independent of depth) and, when ``f_number`` > 0, a defocus disc
   whose diameter follows the thin lens: a point at depth ``s`` of a lens of focal length
   ``f`` and aperture diameter ``A = f / N`` focused at ``s_f`` blurs into a circle of diameter
   ``c = A f |s - s_f| / (s (s_f - f))`` on the micromirror array (e.g. Hecht, *Optics*, 5th
   ed., section 5.7.3, depth of field), ``c / pitch`` projector px with ``f = f_x pitch`` from
   the projector's focal length ``f_x`` in pixels. The disc's diameter varies across the
   pattern with the depth each projector pixel sees: the image is blurred at a few diameters
   and interpolated linearly between them per sub-pixel (a layered defocus).

The defaults are those of a TI DLP5500 DMD (0.55-inch XGA, 1024 x 768; the DMD of the DLP
LightCommander structured-light kit): micromirror pitch 10.8 um with a gap of about 1 um
between mirrors (TI E2E forum, "DMD chip", TI's answer: pitch 10.8 um, gap ~1 um, square
mirrors), so a fill factor of (9.8 / 10.8)^2 = 0.82; mirrors tilt +-12 deg, which sets the
illumination and projection cone to f/2.4 (1 / (2 sin 12 deg); TI DLPA044 "Geometric Optics
for DLP", aperture); a Gaussian lens PSF of 0.5 px (a modulation of exp(-2 pi^2 0.5^2 0.5^2)
= 0.29 at the pixel grid's Nyquist frequency, a typical projection lens); display gamma 2.2
(a video-driven projector; a DMD's pulse-width modulation itself is linear) with its
pre-compensation on (the usual bench practice) and 8-bit patterns.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from simlunar.registry import Options, option

__all__ = [
    "DLP5500_PITCH_M",
    "ProjectorOptics",
    "defocus_diameter_px",
    "emit",
    "pixel_aperture",
]

#: micromirror pitch of the TI DLP5500 (m)
DLP5500_PITCH_M = 10.8e-6

#: most disc diameters the layered defocus blurs at (the image is interpolated between them)
_DEFOCUS_LAYERS = 8


@dataclass(frozen=True)
class ProjectorOptics(Options):
    """The projector's response, pixel aperture and lens (module docstring; defaults: a
    TI DLP5500 projector)."""

    supersample: int = option(
        4, doc="sub-pixels per projector pixel along each axis of the emitted image", ge=1, le=16
    )
    fill_factor: float = option(
        0.82, doc="lit share of a pixel's area (DLP5500: 9.8 um mirrors at 10.8 um)", gt=0, le=1
    )
    psf_sigma: float = option(
        0.5, doc="Gaussian lens point-spread sigma (0: none)", unit="px", ge=0, le=16
    )
    f_number: float = option(
        0.0,
        doc="lens f-number for the thin-lens defocus disc (0: in focus everywhere; DLP5500: 2.4)",
        ge=0,
        le=64,
    )
    focus_distance: float | None = option(
        None, doc="depth the lens is focused at (None: the median depth it lights)", unit="m", gt=0
    )
    pixel_pitch: float = option(
        DLP5500_PITCH_M, doc="micromirror pitch (sets the focal length f = f_x pitch)", unit="m",
        gt=0,
    )  # fmt: skip
    gamma: float = option(2.2, doc="display response: emitted = value ** gamma", gt=0, le=5)
    precompensate: bool = option(
        True, doc="patterns pre-compensated by value ** (1 / gamma) before quantisation"
    )
    bits: int = option(8, doc="bits per pattern value the projector shows", ge=1, le=16)


def pixel_aperture(supersample: int, fill_factor: float) -> np.ndarray:
    """(S, S) float64 lit share of each sub-pixel of one projector pixel: a centred square of
    side ``sqrt(fill_factor) S`` sub-pixels, area-weighted at its edges (sums to
    ``fill_factor S^2``)."""
    S = int(supersample)
    a = np.sqrt(float(fill_factor)) * S
    lo, hi = (S - a) / 2, (S + a) / 2
    edges = np.arange(S + 1, dtype=np.float64)
    prof = np.clip(np.minimum(edges[1:], hi) - np.maximum(edges[:-1], lo), 0.0, 1.0)
    return np.outer(prof, prof)


def defocus_diameter_px(depth, *, fx: float, options: ProjectorOptics, focus: float) -> np.ndarray:
    """Thin-lens defocus disc diameter (projector px) of points at ``depth`` (m): ``A f |s -
    s_f| / (s (s_f - f)) / pitch``, ``f = fx pitch``, ``A = f / N``; 0 where ``depth`` is not
    finite or ``f_number`` is 0."""
    o = options
    s = np.asarray(depth, np.float64)
    if o.f_number <= 0:
        return np.zeros(s.shape)
    f = float(fx) * o.pixel_pitch
    if not focus > f:
        raise ValueError(f"the focus distance {focus:g} m is not beyond the focal length {f:g} m")
    A = f / o.f_number
    with np.errstate(invalid="ignore", divide="ignore"):
        c = A * f * np.abs(s - focus) / (s * (focus - f)) / o.pixel_pitch
    return np.where(np.isfinite(c) & (s > 0), c, 0.0)


def _disc(diameter: float) -> np.ndarray:
    """Normalised pillbox of ``diameter`` sub-px, its edge area-weighted (8 x 8 samples per
    kernel pixel); a delta below one sub-pixel."""
    r = diameter / 2
    if r < 0.5:
        return np.ones((1, 1))
    n = int(np.ceil(r))
    off = (np.arange(8) + 0.5) / 8 - 0.5
    x = np.arange(-n, n + 1)[:, None] + off[None, :]  # (2n + 1, 8) sample positions
    d2 = x[:, None, :, None] ** 2 + x[None, :, None, :] ** 2
    k = (d2 <= r * r).mean(axis=(2, 3))
    return k / k.sum()


def _layered_defocus(img: np.ndarray, diam: np.ndarray) -> np.ndarray:
    """``img`` blurred by a disc whose diameter (sub-px) varies per pixel as ``diam``: blurred at
    up to :data:`_DEFOCUS_LAYERS` diameters spanning ``diam``, interpolated linearly."""
    lo, hi = float(diam.min()), float(diam.max())
    if hi < 1.0:
        return img
    levels = np.linspace(lo, hi, _DEFOCUS_LAYERS) if hi - lo > 0.25 else np.array([hi])
    blurred = [ndimage.convolve(img, _disc(d), mode="constant") for d in levels]
    if len(levels) == 1:
        return blurred[0]
    t = np.clip((diam - lo) / (levels[1] - levels[0]), 0, len(levels) - 1)
    i = np.minimum(np.floor(t).astype(int), len(levels) - 2)
    w = t - i
    stack = np.stack(blurred)
    rr, cc = np.indices(img.shape)
    return (1 - w) * stack[i, rr, cc] + w * stack[i + 1, rr, cc]


def emit(patterns, options: ProjectorOptics, *, defocus_px=None) -> np.ndarray:
    """The emitted images of digital ``patterns`` (module docstring).

    Parameters
    ----------
    patterns : (n, H, W) array in [0, 1]
    options : ProjectorOptics
    defocus_px : (H, W) array, optional
        Defocus disc diameter (projector px) at each projector pixel
        (:func:`defocus_diameter_px` of the depth it lights); None: no defocus.

    Returns
    -------
    (n, S H, S W) float32 >= 0, ``S = options.supersample``
    """
    o = options
    p = np.clip(np.asarray(patterns, np.float64), 0.0, 1.0)
    if p.ndim != 3:
        raise ValueError(f"patterns must be (n, H, W), got shape {p.shape}")
    if o.precompensate:
        p = p ** (1.0 / o.gamma)
    top = (1 << int(o.bits)) - 1
    p = (np.rint(p * top) / top) ** o.gamma
    S = int(o.supersample)
    ap = pixel_aperture(S, o.fill_factor)
    diam = None
    if defocus_px is not None:
        diam = np.kron(np.asarray(defocus_px, np.float64), np.ones((S, S))) * S
    out = np.empty((len(p), p.shape[1] * S, p.shape[2] * S), np.float32)
    for i, x in enumerate(p):
        img = np.kron(x, ap)
        if o.psf_sigma > 0:
            img = ndimage.gaussian_filter(img, o.psf_sigma * S, mode="constant")
        if diam is not None:
            img = _layered_defocus(img, diam)
        out[i] = np.maximum(img, 0.0)
    return out
