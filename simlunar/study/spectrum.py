"""How a height field's variance splits over wavelengths, and what that does to grid sampling.

A reconstruction from k samples resolves wavelengths longer than about twice the sample pitch
``spacing * sqrt(N / k)``; variance at shorter wavelengths is lost whatever the sample layout.
:func:`variance_share_above` measures how much of a terrain's height variance lies above such
a wavelength; :func:`gaussian_field` and :func:`random_grid_mse_ratio` reproduce the effect on
fields of known smoothness (the smoother the field, the more a grid's even coverage beats
random's clumps and gaps).
"""

from __future__ import annotations

import numpy as np

from simlunar.planner import plan
from simlunar.reconstruction import reconstruct

__all__ = [
    "dct_power",
    "gaussian_field",
    "random_grid_mse_ratio",
    "sample_pitch",
    "variance_share_above",
]


def _heights(heights) -> np.ndarray:
    h = np.asarray(heights, dtype=np.float64)
    if h.ndim != 2 or min(h.shape) < 2:
        raise ValueError(f"heights must have shape (rows, cols) with both >= 2, got {h.shape}")
    if not np.all(np.isfinite(h)):
        raise ValueError("heights contain NaN or infinite values")
    return h


def dct_power(heights, *, spacing: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Variance per spatial frequency from the orthonormal 2-D DCT-II, mean removed.

    The DCT is the Fourier transform of the field's mirror extension, which has no step at the
    borders, so a non-periodic terrain does not leak edge power into every frequency.

    Parameters
    ----------
    heights : array_like (rows, cols)
    spacing : float
        Cell size (m per cell).

    Returns
    -------
    freq : ndarray (rows, cols)
        Radial spatial frequency (cycles per metre) of each coefficient: basis (i, j) is
        ``cos(pi i (r + 1/2) / rows) cos(pi j (c + 1/2) / cols)``, frequency
        ``hypot(i / (2 rows), j / (2 cols)) / spacing``.
    power : ndarray (rows, cols)
        Squared coefficients / N: they sum to the field's variance (Parseval).
    """
    from scipy.fft import dctn

    h = _heights(heights)
    if not spacing > 0:
        raise ValueError(f"spacing must be > 0, got {spacing}")
    rows, cols = h.shape
    c = dctn(h - h.mean(), type=2, norm="ortho")
    fy = np.arange(rows)[:, None] / (2.0 * rows)
    fx = np.arange(cols)[None, :] / (2.0 * cols)
    return np.hypot(fy, fx) / spacing, c**2 / h.size


def variance_share_above(heights, *, spacing: float, wavelength: float) -> float:
    """Share of the height variance at wavelengths longer than ``wavelength``.

    Parameters
    ----------
    heights : array_like (rows, cols)
        A height field (m), finite.
    spacing : float
        Cell size (m).
    wavelength : float
        Threshold (m), e.g. twice the sample pitch ``2 * spacing * sqrt(N / k)``.

    Returns
    -------
    float
        In [0, 1]; NaN for a constant field.
    """
    if not wavelength > 0:
        raise ValueError(f"wavelength must be > 0, got {wavelength}")
    freq, power = dct_power(heights, spacing=spacing)
    total = power.sum()
    if total <= 0:
        return float("nan")
    return float(power[freq < 1.0 / wavelength].sum() / total)


def sample_pitch(density: float) -> float:
    """Mean spacing of k = density * N samples on a grid, in cells: ``sqrt(1 / density)``."""
    if not 0 < density <= 1:
        raise ValueError(f"density must lie in (0, 1], got {density}")
    return float(np.sqrt(1.0 / density))


def gaussian_field(shape, length: float, *, rng) -> np.ndarray:
    """Unit-variance Gaussian random field with a Gaussian correlation of ``length`` cells.

    White noise smoothed by a Gaussian kernel of standard deviation ``length`` (cells; 0 =
    white noise), rescaled to zero mean and unit variance.
    """
    from scipy import ndimage

    rng = np.random.default_rng(rng)
    f = rng.standard_normal(shape)
    if length > 0:
        f = ndimage.gaussian_filter(f, length, mode="wrap")
    f -= f.mean()
    return f / f.std()


def random_grid_mse_ratio(field, density: float, *, trials: int = 4, rng) -> float:
    """MSE of random sampling over MSE of the shifted grid at one density (same k).

    Both use simlunar's planners (``random``, ``grid``) and Delaunay-linear reconstruction;
    errors are averaged over ``trials`` independent plans before the ratio.
    """

    f = _heights(field)
    rng = np.random.default_rng(rng)
    k = max(3, round(density * f.size))
    errs = {"random": [], "grid": []}
    for _ in range(trials):
        for name in errs:
            p = plan(name, k, shape=f.shape, rng=rng)
            rec = reconstruct(p.rc, f[p.rows, p.cols], f.shape)
            errs[name].append(float(np.mean((rec - f) ** 2)))
    return float(np.mean(errs["random"]) / np.mean(errs["grid"]))
