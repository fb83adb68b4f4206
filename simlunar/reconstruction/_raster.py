"""Compiled per-triangle rasteriser behind :func:`simlunar.reconstruction.reconstruct`.

Kept in its own module so the Numba compilation (cached on disk) happens only when the
reconstruction is first used.
"""

from __future__ import annotations

import numba
import numpy as np

# Barycentric tolerance: a cell whose barycentric coordinates are all >= -_EPS is inside.
# Cells on an edge shared by two triangles are written twice with values equal to rounding.
_EPS = 1e-10


@numba.njit(cache=True, nogil=True)
def rasterise_linear(pts, vals, tris, out, covered):  # pragma: no cover - compiled
    """Linear interpolation of ``vals`` over triangles ``tris`` onto every covered cell.

    ``pts`` (k, 2) float64 (row, col) index coordinates, ``vals`` (k,), ``tris`` (m, 3) int,
    ``out`` (rows, cols) float64 written in place, ``covered`` (rows, cols) bool set in place.
    """
    nr, nc = out.shape
    for t in range(tris.shape[0]):
        i0, i1, i2 = tris[t, 0], tris[t, 1], tris[t, 2]
        r0, c0 = pts[i0, 0], pts[i0, 1]
        r1, c1 = pts[i1, 0], pts[i1, 1]
        r2, c2 = pts[i2, 0], pts[i2, 1]
        det = (r1 - r0) * (c2 - c0) - (r2 - r0) * (c1 - c0)
        if det == 0.0:
            continue
        inv = 1.0 / det
        v0, v1, v2 = vals[i0], vals[i1], vals[i2]
        rlo = max(int(np.ceil(min(r0, r1, r2) - 1e-9)), 0)
        rhi = min(int(np.floor(max(r0, r1, r2) + 1e-9)), nr - 1)
        clo = max(int(np.ceil(min(c0, c1, c2) - 1e-9)), 0)
        chi = min(int(np.floor(max(c0, c1, c2) + 1e-9)), nc - 1)
        for r in range(rlo, rhi + 1):
            dr = r - r0
            for c in range(clo, chi + 1):
                dc = c - c0
                # barycentric coordinates of (r, c) with respect to vertices 1 and 2
                b1 = (dr * (c2 - c0) - (r2 - r0) * dc) * inv
                b2 = ((r1 - r0) * dc - dr * (c1 - c0)) * inv
                b0 = 1.0 - b1 - b2
                if b0 >= -_EPS and b1 >= -_EPS and b2 >= -_EPS:
                    out[r, c] = b0 * v0 + b1 * v1 + b2 * v2
                    covered[r, c] = True
