"""Fractal (fBm) base surfaces by spectral synthesis, and a low-frequency undulating bed.

Fractional Brownian surface with Hurst exponent H: its 2-D power spectrum falls as
``|k|**-(2H + 2)`` (Voss 1988, "Fractals in nature"; Saupe's spectral synthesis), so the radially
averaged spectrum has log-log slope ``-(2H + 2)``. Synthesised by filtering complex white noise in
the Fourier domain (one real FFT), so the cost is O(N log N) in the number of cells.
"""

from __future__ import annotations

import numpy as np
from scipy import fft as sfft

__all__ = ["fbm", "radial_power_spectrum", "undulating_bed"]


def _check_shape(shape) -> tuple[int, int]:
    if len(shape) != 2 or any(int(n) < 2 for n in shape):
        raise ValueError(f"shape must be (rows, cols) with at least 2 cells each, got {shape}")
    return int(shape[0]), int(shape[1])


def _spectral_noise(shape, spacing, amplitude_fn, rng) -> np.ndarray:
    rows, cols = shape
    ky = sfft.fftfreq(rows, d=spacing)[:, None]
    kx = sfft.rfftfreq(cols, d=spacing)[None, :]
    k = np.hypot(ky, kx)
    amp = amplitude_fn(k)
    amp[0, 0] = 0.0  # zero mean
    noise = rng.standard_normal((rows, cols))
    spec = sfft.rfft2(noise) * amp
    return sfft.irfft2(spec, s=(rows, cols))


def fbm(
    shape,
    *,
    spacing: float,
    hurst: float,
    rms: float,
    periodic: bool = True,
    rolloff_m: float | None = None,
    rng=None,
) -> np.ndarray:
    """Fractional Brownian surface with a given Hurst exponent and RMS height.

    Parameters
    ----------
    shape : (rows, cols)
    spacing : float
        Cell size in metres (> 0).
    hurst : float
        Hurst exponent H in (0, 1); the power spectrum falls as ``k**-(2H + 2)``.
    rms : float
        Root-mean-square height of the result in metres (>= 0); the mean is zero.
    periodic : bool
        If False, synthesise on a grid 1.5x larger and crop, so opposite edges do not match.
    rolloff_m : float, optional
        Wavelength (m) above which the spectrum is flat (no power-law growth), which keeps very
        large grids from being dominated by one tilt. ``None``: pure power law.
    rng : seed or Generator

    Returns
    -------
    (rows, cols) float64 heights in metres.
    """
    rows, cols = _check_shape(shape)
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"spacing must be a positive number of metres, got {spacing!r}")
    if not (np.isfinite(hurst) and 0.0 < hurst < 1.0):
        raise ValueError(f"hurst must be in (0, 1), got {hurst!r}")
    if not (np.isfinite(rms) and rms >= 0):
        raise ValueError(f"rms must be a non-negative number of metres, got {rms!r}")
    if rolloff_m is not None and not (np.isfinite(rolloff_m) and rolloff_m > 0):
        raise ValueError(f"rolloff_m must be a positive wavelength in metres, got {rolloff_m!r}")
    gen = np.random.default_rng(rng)
    if rms == 0:
        return np.zeros((rows, cols))
    beta = hurst + 1.0  # amplitude exponent: power = amplitude**2 ~ k**-(2H + 2)
    k0 = 0.0 if rolloff_m is None else 1.0 / rolloff_m

    def amplitude(k):
        with np.errstate(divide="ignore"):
            return np.maximum(k, k0) ** -beta if k0 > 0 else np.where(k > 0, k, 1.0) ** -beta

    if periodic:
        z = _spectral_noise((rows, cols), spacing, amplitude, gen)
    else:
        big = (int(np.ceil(rows * 1.5)), int(np.ceil(cols * 1.5)))
        z = _spectral_noise(big, spacing, amplitude, gen)
        r0, c0 = gen.integers(0, big[0] - rows + 1), gen.integers(0, big[1] - cols + 1)
        z = z[r0 : r0 + rows, c0 : c0 + cols]
    z = z - z.mean()
    s = z.std()
    return z * (rms / s) if s > 0 else z


def undulating_bed(
    shape, *, spacing: float, amplitude: float, wavelength: float, rng=None
) -> np.ndarray:
    """Smooth random bed: white noise low-passed at ``wavelength`` (Gaussian filter in k).

    Parameters
    ----------
    shape : (rows, cols)
    spacing : float
        Cell size (m).
    amplitude : float
        RMS height of the bed in metres (>= 0).
    wavelength : float
        Characteristic wavelength in metres (> 0): the spectral Gaussian has standard deviation
        ``1 / wavelength`` cycles per metre, so features narrower than about half of it vanish.
    rng : seed or Generator

    Returns
    -------
    (rows, cols) float64 heights, zero mean, RMS ``amplitude``. Non-periodic (cropped from a
    grid padded by one wavelength on each side).
    """
    rows, cols = _check_shape(shape)
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"spacing must be a positive number of metres, got {spacing!r}")
    if not (np.isfinite(amplitude) and amplitude >= 0):
        raise ValueError(
            f"bed amplitude must be a non-negative number of metres, got {amplitude!r}"
        )
    if not (np.isfinite(wavelength) and wavelength > 0):
        raise ValueError(f"bed wavelength must be a positive number of metres, got {wavelength!r}")
    gen = np.random.default_rng(rng)
    if amplitude == 0:
        return np.zeros((rows, cols))
    pad = int(min(np.ceil(wavelength / spacing), 4 * max(rows, cols)))
    big = (rows + 2 * pad, cols + 2 * pad)
    sig = 1.0 / wavelength
    z = _spectral_noise(big, spacing, lambda k: np.exp(-0.5 * (k / sig) ** 2), gen)
    z = z[pad : pad + rows, pad : pad + cols]
    z = z - z.mean()
    s = z.std()
    return z * (amplitude / s) if s > 0 else z


def radial_power_spectrum(z: np.ndarray, spacing: float, nbins: int = 40):
    """Radially averaged power spectrum of a surface.

    Returns
    -------
    k : (m,) float64 bin-centre spatial frequencies (cycles per metre)
    power : (m,) float64 mean |FFT|^2 in each annulus (empty bins dropped)
    """
    z = np.asarray(z, dtype=np.float64)
    rows, cols = z.shape
    p = np.abs(sfft.rfft2(z - z.mean())) ** 2
    k = np.hypot(sfft.fftfreq(rows, d=spacing)[:, None], sfft.rfftfreq(cols, d=spacing)[None, :])
    kmin = 1.0 / (spacing * max(rows, cols))
    kmax = 0.5 / spacing
    edges = np.geomspace(kmin, kmax, nbins + 1)
    idx = np.digitize(k.ravel(), edges) - 1
    ok = (idx >= 0) & (idx < nbins)
    s = np.bincount(idx[ok], weights=p.ravel()[ok], minlength=nbins)
    n = np.bincount(idx[ok], minlength=nbins)
    keep = n > 0
    centres = np.sqrt(edges[:-1] * edges[1:])
    return centres[keep], s[keep] / n[keep]
