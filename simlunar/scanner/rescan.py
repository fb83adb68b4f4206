"""Rescan planners that rank pixels by a coded scan itself rather than by the guide image
(the ``ambiguity_enhancement`` mode only: they need the scan)."""

from __future__ import annotations

import numpy as np

__all__ = ["SCAN_PLANNERS", "low_contrast_pixels"]


#: rescan planners that rank pixels by the gray-code scan itself rather than by the guide
#: image (``ambiguity_enhancement`` only: they need the scan)
SCAN_PLANNERS = ("low_contrast",)


def low_contrast_pixels(gray, k: int, *, rng) -> np.ndarray:
    """The ``k`` guide pixels the gray-code scan saw with the least contrast: (k, 2) (row, col).

    Each projector pixel (= guide pixel) gets the lowest ``white - black`` contrast of the lit
    camera pixels whose gray code decodes to it (whether or not every bit was reliable: a
    dim pixel's code is what it is, and a wrong code puts a wrong depth at the pixel it names);
    the ``k`` lowest are rescanned, ties in random order. Projector pixels no lit camera pixel
    decodes to come last: the camera cannot see a dot there either. The threshold ablation
    (docs/scanner.md) finds most of the gray code's squared error in its lowest-contrast
    pixels.
    """
    dec = gray.decode
    if dec.contrast is None:
        raise ValueError("low_contrast needs a decode with its contrast (GrayDecoder.result)")
    H, W = dec.proj_shape
    if not 1 <= int(k) <= H * W:
        raise ValueError(f"k must be in 1..{H * W}, got {k}")
    col, row = dec.decoded_index()
    ok = dec.lit & (col < W) & (row < H)
    lowest = np.full(H * W, np.inf)
    np.minimum.at(lowest, (row[ok] * W + col[ok]).ravel(), dec.contrast[ok].ravel())
    tie = np.random.default_rng(rng).random(H * W)
    order = np.lexsort((tie, lowest))[: int(k)]
    return np.stack([order // W, order % W], axis=-1).astype(np.int64)
