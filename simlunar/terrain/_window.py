"""The grid window a feature of given reach covers (shared by crater and rock stamping)."""

from __future__ import annotations

import numpy as np


def feature_window(x, y, reach, shape, spacing, origin):
    """Cells within ``reach`` (m) of world point (x, y), clipped to the grid.

    Returns ``None`` when the window misses the grid, else ``(rows, cols, dx, dy)``: the
    slices of the window and the world offsets (m) from (x, y) of its cell centres, ``dx``
    (n_cols,) along +x and ``dy`` (n_rows,) along +y (rows run to -y; cell (r, c) centre is
    ``(x0 + (c + 0.5) s, y0 - (r + 0.5) s)``).
    """
    n_rows, n_cols = shape
    x0, y0 = origin
    cc = (x - x0) / spacing - 0.5
    rc = (y0 - y) / spacing - 0.5
    half = reach / spacing
    c_lo, c_hi = max(int(np.floor(cc - half)), 0), min(int(np.ceil(cc + half)) + 1, n_cols)
    r_lo, r_hi = max(int(np.floor(rc - half)), 0), min(int(np.ceil(rc + half)) + 1, n_rows)
    if c_lo >= c_hi or r_lo >= r_hi:
        return None
    dx = (np.arange(c_lo, c_hi) - cc) * spacing
    dy = (rc - np.arange(r_lo, r_hi)) * spacing
    return slice(r_lo, r_hi), slice(c_lo, c_hi), dx, dy
