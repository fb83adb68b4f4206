"""Triangle mesh of a height grid: one vertex per cell centre (NumPy only).

Used by the renderer (``simlunar.render.mesh``) and by mesh export, so both see the same
triangles. Vertex index of cell (r, c) is ``r * cols + c``. Each grid square between four cell
centres is split along the same diagonal into two counter-clockwise (seen from +z) triangles.
Triangles touching a nodata (NaN) cell are dropped; NaN vertices are kept (unreferenced) so the
vertex numbering stays ``r * cols + c``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["grid_faces", "grid_uv", "grid_vertices"]


def grid_vertices(heights: np.ndarray, spacing: float, origin=(0.0, 0.0)) -> np.ndarray:
    """(rows * cols, 3) float64 world positions of cell centres."""
    rows, cols = heights.shape
    x = origin[0] + (np.arange(cols) + 0.5) * spacing
    y = origin[1] - (np.arange(rows) + 0.5) * spacing
    X, Y = np.meshgrid(x, y)
    return np.stack([X.ravel(), Y.ravel(), np.asarray(heights, float).ravel()], axis=1)


def grid_faces(shape: tuple[int, int], nodata: np.ndarray | None = None) -> np.ndarray:
    """(n_faces, 3) int64 vertex indices, counter-clockwise seen from above (+z)."""
    rows, cols = shape
    if rows < 2 or cols < 2:
        raise ValueError(f"a mesh needs at least 2x2 cells, got {rows}x{cols}")
    idx = np.arange(rows * cols).reshape(rows, cols)
    a = idx[:-1, :-1].ravel()  # (r, c)      north-west
    b = idx[:-1, 1:].ravel()  # (r, c+1)    north-east
    c = idx[1:, :-1].ravel()  # (r+1, c)    south-west
    d = idx[1:, 1:].ravel()  # (r+1, c+1)  south-east
    # rows run to -y: (a, c, b) and (b, c, d) are counter-clockwise in the x-y plane
    faces = np.concatenate([np.stack([a, c, b], 1), np.stack([b, c, d], 1)])
    if nodata is not None and np.any(nodata):
        bad = np.asarray(nodata).ravel()
        faces = faces[~bad[faces].any(axis=1)]
    return faces


def grid_uv(shape: tuple[int, int]) -> np.ndarray:
    """(rows * cols, 2) texture coordinates placing texel (r, c) exactly at vertex (r, c).

    u = (c + 0.5) / cols, v = (r + 0.5) / rows: with nearest filtering the albedo grid maps
    exactly onto cells (row 0 at v near 0; renderers that flip v must flip the texture too).
    """
    rows, cols = shape
    u = (np.arange(cols) + 0.5) / cols
    v = (np.arange(rows) + 0.5) / rows
    U, V = np.meshgrid(u, v)
    return np.stack([U.ravel(), V.ravel()], axis=1)
