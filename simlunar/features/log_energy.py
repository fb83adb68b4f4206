"""Laplacian-of-Gaussian (LoG) energy: an importance map of blobs and ridges at several scales.

The map is the sum over scales sigma_i = ``sigma_px`` * 2^i (i = 0 .. ``scales`` - 1) of the
squared scale-normalised Laplacian sigma^2 (nabla^2 G_sigma * I) of the gray image
(Lindeberg 1998, "Feature detection with automatic scale selection", IJCV 30(2): 79-116: the
normalisation by t = sigma^2 makes responses at different scales comparable, and the response
to a blob of size s peaks at sigma = s). Rocks and crater rims, whose size sets the error of a
linear reconstruction between samples, light it at their own scale; a uniform slope (a ramp)
gives zero, unlike the gradient map.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from simlunar.features.maps import to_gray
from simlunar.registry import Options, option

__all__ = ["LogEnergyOptions", "log_energy"]


@dataclass(frozen=True)
class LogEnergyOptions(Options):
    """Options of the LoG energy map (:func:`log_energy`)."""

    sigma_px: float = option(1.0, doc="LoG map: finest Gaussian scale", unit="px", gt=0, le=64)
    scales: int = option(3, doc="LoG map: scales sigma_px * 2^i summed, i < scales", ge=1, le=8)

    def __post_init__(self):
        super().__post_init__()
        if isinstance(self.scales, bool) or int(self.scales) != self.scales:
            raise ValueError(f"scales must be an integer, got {self.scales!r}")


def log_energy(image, *, sigma_px: float = 1.0, scales: int = 3) -> np.ndarray:
    """Multi-scale LoG energy sum_i (sigma_i^2 nabla^2 (G_sigma_i * I))^2 of the gray image.

    Parameters
    ----------
    image : ndarray, shape (rows, cols) or (rows, cols, 3)
        Guide image (any intensity scale); must be finite.
    sigma_px : float
        Finest scale (px), > 0.
    scales : int
        Number of scales sigma_px * 2^i, >= 1.

    Returns
    -------
    ndarray of float64, shape (rows, cols), >= 0
        Borders reflected (``scipy.ndimage`` mode ``"reflect"``).
    """
    LogEnergyOptions(sigma_px, scales)  # the options' own checks
    g = to_gray(image)
    out = np.zeros_like(g)
    for i in range(int(scales)):
        s = sigma_px * 2.0**i
        # the 5-point Laplacian of the smoothed image: exactly zero on constants and planes
        # (scipy's sampled second-derivative-of-Gaussian kernel is not zero-mean)
        smooth = ndimage.gaussian_filter(g, s, mode="reflect")
        out += (s * s * ndimage.laplace(smooth, mode="reflect")) ** 2
    return out
