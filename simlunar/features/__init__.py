"""Image -> importance maps for image-directed range sampling (paper section 4.1).

``feature_map(name, image, **opts)`` returns a float64 (rows, cols) map >= 0; names are the keys
of ``FEATURES``: ``gradient``, ``entropy``, ``wavelet``, ``saliency``, and of
``TRAINED_FEATURES``: ``learned`` (a trained model, :mod:`simlunar.features.learned`).
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


# ---- maps that need a trained model, apart from the image-only maps above ---------------------
def _learned(image, *, model, density: float) -> np.ndarray:
    """``simlunar.features.learned.learned``, imported on use: that module imports
    scikit-learn and joblib, which every importer of this package (the planner, the studies,
    the runner) would otherwise load without a trained model to use them."""
    from simlunar.features.learned import learned

    return learned(image, model=model, density=density)


#: name -> map of a trained model; options ``model`` (a ``.joblib`` path) and ``density`` (k / N)
TRAINED_FEATURES: dict[str, Callable[..., np.ndarray]] = {"learned": _learned}


def feature_map(name: str, image, **opts) -> np.ndarray:
    """Compute the importance map ``name`` of ``image``.

    Parameters
    ----------
    name : str
        One of ``FEATURES`` or ``TRAINED_FEATURES`` (``learned``: options ``model``, a
        ``.joblib`` path, and ``density``, k / N).
    image : ndarray, shape (rows, cols) or (rows, cols, 3)
        Guide image (linear radiance or any intensity scale); must be finite.
    **opts
        Options of the chosen map (e.g. ``size``/``scale`` for entropy, ``levels`` for wavelet).

    Returns
    -------
    ndarray of float64, shape (rows, cols), >= 0
    """
    fn = FEATURES.get(name) if isinstance(name, str) else None
    if fn is None and isinstance(name, str) and name in TRAINED_FEATURES:
        missing = sorted({"model", "density"} - set(opts))
        if missing:
            raise ValueError(f"feature {name!r} needs option(s) {missing}")
        fn = TRAINED_FEATURES[name]
    if fn is None:
        valid = ", ".join([*FEATURES, *TRAINED_FEATURES])
        raise ValueError(f"unknown feature {name!r}; valid: {valid}")
    return fn(image, **opts)


__all__ = [
    "FEATURES",
    "TRAINED_FEATURES",
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
