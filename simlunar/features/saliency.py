"""Itti-Koch saliency map (Itti, Koch & Niebur, IEEE PAMI 20(11), 1998).

The model as in the Saliency Toolbox (Walther & Koch 2006) that the paper used for its SAL
metric: dyadic Gaussian pyramids of intensity, colour opponency (RGB input only) and Gabor
orientation (0, 45, 90, 135 degrees); centre-surround differences between centre levels
c in {2, 3, 4} and surround levels s = c + delta, delta in {3, 4}; the normalisation operator
N(.) (scale to [0, 1], multiply by (1 - mean of the other local maxima)^2); across-scale
addition at the coarsest centre level into conspicuity maps; saliency = mean of the normalised
conspicuity maps, resized to the input grid.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from simlunar.features.maps import check_image

__all__ = ["normalise", "saliency"]

_BINOMIAL = np.array([1.0, 4.0, 6.0, 4.0, 1.0]) / 16.0
_ANGLES = (0.0, np.pi / 4, np.pi / 2, 3 * np.pi / 4)


def _pyramid(img: np.ndarray, levels: int) -> list[np.ndarray]:
    """Dyadic Gaussian pyramid, level 0 = input.

    Each level is the 5-tap binomial low-pass of the previous one averaged over 2 x 2 blocks
    (odd sizes padded by edge replication), so pixel i of level l covers input pixels
    [2^l i, 2^l (i + 1)) and its centre agrees with :func:`_resize`'s pixel-centre alignment;
    plain [::2] decimation would shift level l by (2^l - 1) / 2 pixels.
    """
    pyr = [img]
    for _ in range(levels):
        low = ndimage.correlate1d(pyr[-1], _BINOMIAL, axis=0, mode="reflect")
        low = ndimage.correlate1d(low, _BINOMIAL, axis=1, mode="reflect")
        low = np.pad(low, ((0, low.shape[0] % 2), (0, low.shape[1] % 2)), mode="edge")
        pyr.append(0.25 * (low[0::2, 0::2] + low[1::2, 0::2] + low[0::2, 1::2] + low[1::2, 1::2]))
    return pyr


def _resize(a: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Bilinear resize with pixel-centre alignment (edge values held outside)."""
    if a.shape == tuple(shape):
        return a
    r = (np.arange(shape[0]) + 0.5) * a.shape[0] / shape[0] - 0.5
    c = (np.arange(shape[1]) + 0.5) * a.shape[1] / shape[1] - 0.5
    rr, cc = np.meshgrid(r, c, indexing="ij")
    return ndimage.map_coordinates(a, [rr, cc], order=1, mode="nearest")


def _gabor_kernels(size: int = 9, wavelength: float = 4.0, sigma: float = 2.0):
    """Quadrature pairs (even, odd) of Gabor kernels, one per orientation in ``_ANGLES``."""
    half = size // 2
    y, x = np.mgrid[-half : half + 1, -half : half + 1].astype(np.float64)
    env = np.exp(-(x**2 + y**2) / (2 * sigma**2))
    kernels = []
    for theta in _ANGLES:
        xr = x * np.cos(theta) + y * np.sin(theta)
        even = env * np.cos(2 * np.pi * xr / wavelength)
        even -= even.mean()  # zero DC so flat regions give no orientation energy
        odd = env * np.sin(2 * np.pi * xr / wavelength)
        kernels.append((even, odd))
    return kernels


def normalise(m: np.ndarray) -> np.ndarray:
    """Itti's N(.): scale to [0, 1], then weight by (1 - mean of the other local maxima)^2.

    Maps with one strong peak are promoted, maps with many comparable peaks suppressed.
    """
    lo, hi = float(m.min()), float(m.max())
    if hi - lo <= 1e-12 * max(abs(hi), 1.0):
        return np.zeros_like(m)
    m = (m - lo) / (hi - lo)
    peaks = (m == ndimage.maximum_filter(m, size=3, mode="constant", cval=-1.0)) & (m > 0.0)
    vals = m[peaks]
    # "other" maxima: all local maxima but one instance of the global maximum (value 1)
    mbar = float((vals.sum() - 1.0) / (vals.size - 1)) if vals.size > 1 else 0.0
    return m * (1.0 - mbar) ** 2


def _scales(n_levels: int) -> list[tuple[int, int]]:
    pairs = [(c, c + d) for c in (2, 3, 4) for d in (3, 4) if c + d <= n_levels]
    if not pairs:  # small images: the same model one or two octaves finer
        pairs = [(c, c + d) for c in (0, 1, 2) for d in (1, 2) if c + d <= n_levels]
    return pairs


def saliency(image) -> np.ndarray:
    """Itti-Koch saliency of a gray (rows, cols) or RGB (rows, cols, 3) image.

    Returns
    -------
    ndarray of float64, shape (rows, cols), >= 0
        The saliency map resized (bilinear) to the input grid; all zeros for a constant image.
    """
    img = check_image(image)
    rows, cols = img.shape[:2]
    # deepest level with at least 2 x 2 pixels
    n_levels = min(8, int(np.floor(np.log2(min(rows, cols)))) - 1)
    if n_levels < 1:
        raise ValueError(f"image too small for saliency: {img.shape[:2]} (need >= 4 x 4)")
    pairs = _scales(n_levels)
    out_level = max(c for c, _ in pairs)
    out_shape = None

    def centre_surround(pyr):
        nonlocal out_shape
        total = None
        for c, s in pairs:
            fm = np.abs(pyr[c] - _resize(pyr[s], pyr[c].shape))
            fm = _resize(normalise(fm), pyr[out_level].shape)
            total = fm if total is None else total + fm
        out_shape = total.shape
        return total

    if img.ndim == 3:
        r, g, b = img[..., 0], img[..., 1], img[..., 2]
        intensity = (r + g + b) / 3.0
    else:
        intensity = img
    ipyr = _pyramid(intensity, n_levels)
    conspicuity = [normalise(centre_surround(ipyr))]

    if img.ndim == 3:
        # Itti 1998: hue normalised by intensity where intensity > 1/10 of its maximum
        valid = intensity > 0.1 * intensity.max()
        denom = np.where(valid, intensity, 1.0)
        rn, gn, bn = (np.where(valid, ch / denom, 0.0) for ch in (r, g, b))
        R = rn - (gn + bn) / 2
        G = gn - (rn + bn) / 2
        B = bn - (rn + gn) / 2
        Y = np.maximum((rn + gn) / 2 - np.abs(rn - gn) / 2 - bn, 0.0)
        R, G, B = (np.maximum(x, 0.0) for x in (R, G, B))
        rg = _pyramid(R - G, n_levels)
        by = _pyramid(B - Y, n_levels)
        colour = centre_surround(rg) + centre_surround(by)
        conspicuity.append(normalise(colour))

    orient = None
    for even, odd in _gabor_kernels():
        opyr = [
            np.hypot(
                ndimage.convolve(lv, even, mode="reflect"),
                ndimage.convolve(lv, odd, mode="reflect"),
            )
            if i >= min(c for c, _ in pairs)
            else lv
            for i, lv in enumerate(ipyr)
        ]
        o = normalise(centre_surround(opyr))
        orient = o if orient is None else orient + o
    conspicuity.append(normalise(orient))

    sal = np.mean(conspicuity, axis=0)
    assert out_shape is not None
    return np.maximum(_resize(sal, (rows, cols)), 0.0)
