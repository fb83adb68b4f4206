"""Image -> importance maps for image-directed range sampling (paper section 4.1).

``feature_map(name, image, **opts)`` returns a float64 (rows, cols) map >= 0; names are the keys
of ``FEATURES``: ``gradient``, ``entropy``, ``wavelet``, ``saliency``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from simlunar.features.maps import (
    check_image,
    entropy,
    gradient,
    to_gray,
    to_uint8,
    wavelet,
    wavelet_levels,
)
from simlunar.features.saliency import saliency

FEATURES: dict[str, Callable[..., np.ndarray]] = {
    "gradient": gradient,
    "entropy": entropy,
    "wavelet": wavelet,
    "saliency": saliency,
}


def feature_map(name: str, image, **opts) -> np.ndarray:
    """Compute the importance map ``name`` of ``image``.

    Parameters
    ----------
    name : str
        One of ``FEATURES``.
    image : ndarray, shape (rows, cols) or (rows, cols, 3)
        Guide image (linear radiance or any intensity scale); must be finite.
    **opts
        Options of the chosen map (e.g. ``size``/``scale`` for entropy, ``levels`` for wavelet).

    Returns
    -------
    ndarray of float64, shape (rows, cols), >= 0
    """
    try:
        fn = FEATURES[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown feature {name!r}; valid: {', '.join(FEATURES)}") from None
    return fn(image, **opts)


__all__ = [
    "FEATURES",
    "check_image",
    "entropy",
    "feature_map",
    "gradient",
    "saliency",
    "to_gray",
    "to_uint8",
    "wavelet",
    "wavelet_levels",
]
