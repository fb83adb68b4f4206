"""Interior-only scoring: leave out the band near the image border where reconstructions extrapolate.

Outside the convex hull of the samples the reconstruction only extrapolates (nearest-sample fill
by default); a layout that leaves the border bare loses most of its score there. Scoring the
interior (cells farther than the sparsest sample pitch from the border) beside the full image
says how much of a table is border extrapolation. Use with ``metric(..., mask=interior_mask(...))``.
"""

from __future__ import annotations

import numpy as np

from simlunar.metrics.score import check_densities

__all__ = ["interior_mask", "sparsest_pitch"]


def sparsest_pitch(shape, densities) -> float:
    """Mean sample spacing (pixels) at the sparsest density: 1 / sqrt(min(densities)).

    Parameters
    ----------
    shape : tuple of int
        Grid (rows, cols), each >= 1 (checked; the pitch itself depends only on the density).
    densities : array_like of float, shape (n,)
        Sampling densities k / N, each in (0, 1].

    Returns
    -------
    float
        The pitch in pixels (>= 1).
    """
    rows, cols = (int(s) for s in shape)
    if rows < 1 or cols < 1:
        raise ValueError(f"shape must be (rows, cols) >= 1, got {tuple(shape)}")
    return float(1.0 / np.sqrt(check_densities(densities).min()))


def interior_mask(shape, pitch: float) -> np.ndarray:
    """Cells farther than ``pitch`` from the image border.

    The distance of cell (r, c) to the border is min(r, c, rows - 1 - r, cols - 1 - c) in index
    coordinates (the border cells themselves are at distance 0).

    Parameters
    ----------
    shape : tuple of int
        Grid (rows, cols).
    pitch : float, >= 0
        Border band width in pixels (e.g. :func:`sparsest_pitch`).

    Returns
    -------
    ndarray of bool, shape (rows, cols)
        True in the interior.

    Raises
    ------
    ValueError
        If the band leaves no interior cell.
    """
    rows, cols = (int(s) for s in shape)
    if rows < 1 or cols < 1:
        raise ValueError(f"shape must be (rows, cols) >= 1, got {tuple(shape)}")
    if not pitch >= 0:
        raise ValueError(f"pitch must be >= 0, got {pitch}")
    r = np.arange(rows)
    c = np.arange(cols)
    dr = np.minimum(r, rows - 1 - r)[:, None]
    dc = np.minimum(c, cols - 1 - c)[None, :]
    mask = np.minimum(dr, dc) > pitch
    if not mask.any():
        raise ValueError(
            f"a border band of {pitch} px leaves no interior cell in a {rows} x {cols} grid"
        )
    return mask
