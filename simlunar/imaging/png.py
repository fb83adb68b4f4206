"""8-bit sRGB PNG previews of linear radiance images (colour-science encoding, Pillow writer)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from simlunar.atomic import atomic_write

__all__ = [
    "AUTO_KEY",
    "AUTO_PERCENTILE",
    "AUTO_TARGET",
    "auto_exposure",
    "to_srgb8",
    "write_png_preview",
]

#: auto exposure maps the median of the positive pixel values to photographic middle grey
#: (the "key" 0.18 of Reinhard et al. 2002, "Photographic tone reproduction for digital images",
#: SIGGRAPH), as a camera's averaging meter does ...
AUTO_KEY = 0.18
#: ... unless that would push this percentile ...
AUTO_PERCENTILE = 99.0
#: ... above this linear value (before the sRGB curve): high-contrast scenes keep their highlights
AUTO_TARGET = 0.9


def auto_exposure(image: np.ndarray) -> float:
    """Scale factor of a preview: the median of finite, positive values to middle grey (0.18),
    or the 99th percentile to 0.9 where that is the smaller factor.

    Mapping the 99th percentile alone washed low-contrast lunar scenes out (the quickstart
    render's median came out at 211/255); the regolith is dark (albedo about 0.12), and a metered
    photograph shows it mid-grey. Returns 1.0 for an image with no positive finite value (all
    black stays black).
    """
    a = np.asarray(image, dtype=np.float64)
    vals = a[np.isfinite(a) & (a > 0)]
    if vals.size == 0:
        return 1.0
    median, p = np.percentile(vals, [50.0, AUTO_PERCENTILE])
    return float(min(AUTO_KEY / median, AUTO_TARGET / p))


def to_srgb8(image: np.ndarray, *, exposure: float | None = None) -> np.ndarray:
    """Linear radiance -> 8-bit sRGB.

    Parameters
    ----------
    image : (rows, cols) or (rows, cols, 3) array
        Linear values (any unit); NaN and negative values show as black.
    exposure : float, optional
        Multiplier applied before encoding; ``None`` picks :func:`auto_exposure`.

    Returns
    -------
    (rows, cols) or (rows, cols, 3) uint8 array
    """
    import colour

    a = np.asarray(image, dtype=np.float64)
    if not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] == 3)):
        raise ValueError(f"a preview image must be (rows, cols) or (rows, cols, 3), got {a.shape}")
    k = auto_exposure(a) if exposure is None else float(exposure)
    if not (np.isfinite(k) and k > 0):
        raise ValueError(f"exposure must be a positive number, got {exposure}")
    lin = np.clip(np.nan_to_num(a * k, nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0)
    enc = colour.cctf_encoding(lin, function="sRGB")
    return np.round(np.clip(enc, 0.0, 1.0) * 255.0).astype(np.uint8)


def write_png_preview(path, image: np.ndarray, *, exposure: float | None = None) -> Path:
    """Write a linear radiance image as an 8-bit sRGB PNG, atomically.

    Parameters
    ----------
    path : str or Path
        Target ``.png`` file; its folder must exist.
    image : (rows, cols) or (rows, cols, 3) array
        Linear radiance (grey or RGB).
    exposure : float, optional
        Linear multiplier; ``None``: :func:`auto_exposure` (median to middle grey, the 99th
        percentile at most 0.9).

    Returns
    -------
    Path
        The written path.
    """
    from PIL import Image

    path = Path(path)
    px = to_srgb8(image, exposure=exposure)
    atomic_write(path, lambda tmp: Image.fromarray(px).save(tmp, format="PNG"))
    return path
