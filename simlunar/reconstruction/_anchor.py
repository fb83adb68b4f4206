"""What the image-anchored reconstructions share: the linear reconstruction with its hull,
the sample pitch, and re-anchoring a detail field to the samples."""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from simlunar.reconstruction.delaunay import SampleMesh, _check_inputs
from simlunar.reconstruction.integrate import central_gradient

__all__ = [
    "LinearField",
    "at_points",
    "cell_indices",
    "linear_field",
    "reanchored_detail",
    "sample_pitch",
]


class LinearField:
    """The Delaunay-linear reconstruction of the samples and where it interpolates.

    Attributes
    ----------
    points : ndarray, shape (k, 2)
        The samples (row, col) as float64.
    values : ndarray, shape (k,)
    shape : tuple of int
    heights : ndarray, shape (rows, cols)
        Linear inside the samples' convex hull, the nearest sample's value outside
        (exactly what the registry's ``linear`` returns).
    hull : ndarray of bool, shape (rows, cols)
        Cells inside the convex hull (those the triangles cover).
    pitch : float
        ``density^(-1/2)`` cells, density = k / (rows cols).
    mesh : SampleMesh
        The samples' triangles, made once: every interpolation at these samples reuses them.
    """

    def __init__(self, points_rc, values, shape):
        pts, vals, shape = _check_inputs(points_rc, values, shape)
        self.points, self.values, self.shape = pts, vals, shape
        self.mesh = SampleMesh(pts, shape)
        # one rasterisation: NaN outside the triangles (the hull), then the nearest fill
        heights, covered, mesh_vals = self.mesh.rasterised(vals)
        self.hull = np.isfinite(heights)
        if not self.hull.all():
            self.mesh.fill_nearest(heights, covered, mesh_vals)
        self.heights = heights
        self.pitch = sample_pitch(len(pts), shape)
        self._slopes = None

    def slopes(self) -> tuple[np.ndarray, np.ndarray]:
        """``integrate.central_gradient(heights)`` (per cell), made once (read-only)."""
        if self._slopes is None:
            gr, gc = central_gradient(self.heights)
            gr.setflags(write=False)
            gc.setflags(write=False)
            self._slopes = (gr, gc)
        return self._slopes

    def interpolate(self, at_samples) -> np.ndarray:
        """Linear interpolation of other values at the same samples (same triangles):
        ``delaunay.reconstruct(points, at_samples, shape, outside="nearest")``."""
        return self.mesh.interpolate(at_samples, outside="nearest")


def linear_field(points_rc, values, shape) -> LinearField:
    """:class:`LinearField` of the samples (input checks of :func:`.delaunay.reconstruct`)."""
    return LinearField(points_rc, values, shape)


def sample_pitch(k: int, shape) -> float:
    """Mean sample spacing in cells: ``density^(-1/2)`` with density = k / (rows cols)."""
    return math.sqrt(shape[0] * shape[1] / max(int(k), 1))


def cell_indices(points: np.ndarray, shape) -> tuple[np.ndarray, np.ndarray] | None:
    """``(rows, cols)`` integer indices of (row, col) points when every one sits on a cell
    centre inside a grid of ``shape``; None otherwise (such points are read bilinearly)."""
    r, c = points[:, 0], points[:, 1]
    ri, ci = np.rint(r), np.rint(c)
    if not (np.array_equal(ri, r) and np.array_equal(ci, c)):
        return None
    if (ri < 0).any() or (ri >= shape[0]).any() or (ci < 0).any() or (ci >= shape[1]).any():
        return None
    return ri.astype(np.intp), ci.astype(np.intp)


def at_points(field: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Values of ``field`` at (row, col) points: a lookup on integer points, bilinear (edge
    values beyond the grid) otherwise."""
    cells = cell_indices(points, field.shape)
    if cells is not None:
        return field[cells]
    return ndimage.map_coordinates(field, [points[:, 0], points[:, 1]], order=1, mode="nearest")


def reanchored_detail(field: np.ndarray, lin: LinearField) -> np.ndarray:
    """``z_a - z_lin`` for ``z_a = field + linear_interp(samples of (z - field))``.

    By linearity of the interpolation this is ``field - linear_interp(field at the samples)``:
    zero at every sample, and zero everywhere inside the hull when ``field`` is linear
    (a plane).
    """
    return field - lin.interpolate(at_points(field, lin.points))
