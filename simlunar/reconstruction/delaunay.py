"""Delaunay triangulation of scattered samples and linear interpolation back to the grid.

This is the reconstruction of the paper's sampling protocol (section 4.1): the k sampled depths
are Delaunay-triangulated and linearly interpolated to every cell of the native grid.

Fast path: the triangulation comes from Shewchuk's Triangle (the ``triangle`` package,
divide and conquer, exact predicates) and each triangle is filled by a compiled rasteriser
(:mod:`._raster`), instead of locating every one of the rows * cols cells in the triangulation
as scipy's ``LinearNDInterpolator`` does (measured by ``benchmarks/bench_sampling.py``; numbers in
``docs/benchmarks.md``).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree
from triangle.core import triang

from simlunar.reconstruction._raster import rasterise_linear, scan_points

__all__ = [
    "EXACT_INTEGER_EXTENT",
    "OUTSIDE_POLICIES",
    "SampleMesh",
    "loo_residuals",
    "reconstruct",
    "triangulate",
    "trim_hull",
]

OUTSIDE_POLICIES = ("nearest", "nan")


def _check_inputs(points_rc, values, shape):
    pts = np.ascontiguousarray(points_rc, dtype=np.float64)
    vals = np.asarray(values, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"points_rc must have shape (k, 2), got {pts.shape}")
    if vals.shape != (pts.shape[0],):
        raise ValueError(
            f"values must have shape ({pts.shape[0]},) to match points_rc, got {vals.shape}"
        )
    if pts.shape[0] == 0:
        raise ValueError("points_rc is empty: at least one sample is needed")
    if not np.isfinite(vals).all():
        raise ValueError("values contains NaN or infinite entries")
    try:
        rows, cols = (int(s) for s in shape)
    except (TypeError, ValueError):
        raise ValueError(f"shape must be (rows, cols), got {shape!r}") from None
    if rows < 1 or cols < 1:
        raise ValueError(f"shape must be positive, got {shape!r}")
    return pts, vals, (rows, cols)


#: Largest coordinate extent for which Triangle's floating-point predicates are exact on
#: integer points: the incircle determinant is a sum of three products of integers bounded by
#: 2 W^2 each, so every intermediate is an integer below 12 W^4 < 2^53 for W <= 5234.
EXACT_INTEGER_EXTENT = 4096


def _triangle_switches(integer: bool, extent: float) -> str:
    """Triangle's switches for points that are all ``integer`` (or not) with this extent.

    ``Q`` quiet, ``z`` zero-based, ``B`` and ``N`` skip the boundary markers and the copy of
    the vertices, ``l`` divide and conquer with vertical cuts only (alternating cuts cost about
    1.8x more on pixel-lattice points). ``X`` turns off the adaptive exact arithmetic; it is
    only used on integer points of extent at most :data:`EXACT_INTEGER_EXTENT`, where plain
    double arithmetic already computes both predicates exactly (so the triangulation is the
    one exact arithmetic gives), which covers every sample plan. Together 3x faster at
    k = 800 k on a 1000 x 1600 grid (0.55 -> 0.18 s).
    """
    if integer and extent <= EXACT_INTEGER_EXTENT:
        return "QzBNlX"
    return "QzBNl"


def triangulate(points_rc) -> np.ndarray:
    """Delaunay triangles of the points (Triangle, exact predicates).

    Parameters
    ----------
    points_rc : ndarray, shape (k, 2)
        Distinct points (row, col).

    Returns
    -------
    ndarray of int32, shape (m, 3)
        Vertex indices of each triangle; empty (0, 3) when the points are collinear or k < 3.
    """
    pts = np.ascontiguousarray(points_rc, dtype=np.float64)
    if len(pts) < 3:
        return np.empty((0, 3), dtype=np.int32)
    finite, _, _, integer, extent = scan_points(pts)
    if not finite:
        raise ValueError("points_rc contains NaN or infinite coordinates")
    return _triangulate(pts, _triangle_switches(integer, extent))


def _triangulate(pts: np.ndarray, switches: str) -> np.ndarray:
    out, _ = triang({"pointlist": pts}, switches)
    tris = out.get("trianglelist")
    if tris is None:
        return np.empty((0, 3), dtype=np.int32)
    return np.ascontiguousarray(tris, dtype=np.int32)


def trim_hull(points_rc, tris: np.ndarray, ratio: float) -> np.ndarray:
    """The triangles left after peeling long hull triangles: a triangle with an edge on the
    hull whose longest edge exceeds ``ratio`` x the median edge length of the triangulation is
    removed, and the peeling repeats on the new hull until none is left (``ratio`` <= 0: the
    triangles unchanged).

    Samples off their lattice by a fraction of a pixel at the border (a moving platform's) make
    the Delaunay hull fill the border strip with slivers whose longest edge spans many samples;
    their cells then take the nearest sample's value (``reconstruct``'s outside policy)
    instead of a value interpolated along the sliver.
    """
    if ratio <= 0 or len(tris) == 0:
        return tris
    pts = np.asarray(points_rc, dtype=np.float64)
    t = np.asarray(tris, dtype=np.int64)
    a, b, c = pts[t[:, 0]], pts[t[:, 1]], pts[t[:, 2]]
    lengths = np.stack([np.hypot(*(b - a).T), np.hypot(*(c - b).T), np.hypot(*(a - c).T)], 1)
    limit = ratio * float(np.median(lengths))
    long = lengths.max(axis=1) > limit
    alive = np.ones(len(t), bool)
    edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    _, edge_id, edge_count = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
    edge_id = edge_id.reshape(3, len(t)).T  # (m, 3) edge ids of each triangle
    count = edge_count.copy()
    while True:
        on_hull = (count[edge_id] == 1).any(axis=1)
        peel = alive & long & on_hull
        if not peel.any():
            break
        alive &= ~peel
        np.subtract.at(count, edge_id[peel].ravel(), 1)
    return np.ascontiguousarray(tris[alive])


def reconstruct(
    points_rc, values, shape, *, outside: str = "nearest", hull_edge_ratio: float = 0.0
) -> np.ndarray:
    """Delaunay-linear reconstruction of scattered samples on a (rows, cols) grid.

    Coordinate convention: ``points_rc`` are (row, col) *index* coordinates, so the cell (r, c)
    sits at (r, c); this is the pixel centre (u, v) = (c + 0.5, r + 0.5) of the project-wide
    convention. Integer sample plans (``SamplePlan.rc``) pass directly. Non-integer points are
    allowed (e.g. triangulated scanner points projected to the grid).

    Parameters
    ----------
    points_rc : array_like, shape (k, 2)
        Sample positions (row, col), any real values (samples outside the grid still shape the
        triangulation).
    values : array_like, shape (k,)
        Sample values (e.g. depth in m).
    shape : tuple of int
        Output grid (rows, cols).
    outside : {"nearest", "nan"}
        Policy for cells outside the convex hull of the samples: ``"nearest"`` (default) takes
        the value of the nearest sample (Euclidean, ties broken by the k-d tree), ``"nan"`` leaves
        NaN (the metrics then exclude those cells). The same policy applies to every strategy.
    hull_edge_ratio : float
        Border treatment (:func:`trim_hull`): hull triangles whose longest edge exceeds this
        many times the median edge are peeled off and their cells treated as outside; 0 (the
        default) keeps the whole Delaunay hull.

    Returns
    -------
    ndarray of float64, shape (rows, cols)

    Notes
    -----
    - Duplicated positions are merged into one sample with the mean of their values.
    - Collinear (or fewer than three distinct) samples span no triangle: every cell counts as
      outside the hull, so ``"nearest"`` fills the grid from the nearest sample and ``"nan"``
      returns all NaN.
    - Inside the hull the result equals scipy's ``LinearNDInterpolator`` to rounding whenever the
      Delaunay triangulation is unique. Integer points are often co-circular (four points of a
      lattice square): both triangulations are then valid but may pick different diagonals, and
      values inside such a square differ by up to the difference of the two planes.
    - Float points that are nearly collinear (lattice points off by rounding, as projected
      sensor points are) make sliver triangles: the rasteriser draws those under 1e-9 cells
      high last, only into cells no other triangle covered and with the value along their
      longest edge, and clamps thin ones to their vertices' values, so the result stays
      within the samples' range.
    """
    if outside not in OUTSIDE_POLICIES:
        raise ValueError(
            f"unknown outside policy {outside!r}; valid: {', '.join(OUTSIDE_POLICIES)}"
        )
    pts, vals, shape = _check_inputs(points_rc, values, shape)
    return SampleMesh(pts, shape, hull_edge_ratio=hull_edge_ratio).interpolate(
        vals, outside=outside
    )


class SampleMesh:
    """The Delaunay triangles of fixed sample positions on a grid, made once and filled with
    any values at those samples: :meth:`interpolate` equals :func:`reconstruct` of the same
    points to the bit (the same order, merge, triangles, rasteriser and nearest fill), without
    triangulating again or querying the nearest samples again.

    Parameters
    ----------
    points_rc : ndarray of float64, shape (k, 2)
        Sample positions (row, col), as :func:`reconstruct` takes them (checked there).
    shape : tuple of int
        Output grid (rows, cols).
    hull_edge_ratio : float
        :func:`reconstruct`'s border treatment (:func:`trim_hull`); 0 keeps the whole hull.
    """

    def __init__(self, points_rc, shape, *, hull_edge_ratio: float = 0.0):
        pts = np.ascontiguousarray(points_rc, dtype=np.float64)
        self.shape = (int(shape[0]), int(shape[1]))
        self.k = len(pts)
        # Lexicographic (row, col) order keeps the rasteriser's vertex and cell accesses local
        # (about 4x faster at k = 400 k) and puts duplicates next to each other; sorted input
        # (e.g. a SamplePlan) skips the sort.
        finite, lex_sorted, duplicates, integer, extent = scan_points(pts)
        if not finite:
            raise ValueError("points_rc contains NaN or infinite coordinates")
        self._order = None
        if not lex_sorted:
            self._order = np.lexsort((pts[:, 1], pts[:, 0]))
            pts = pts[self._order]
            duplicates = bool(np.any(np.all(pts[1:] == pts[:-1], axis=1)))
        self._merge = None
        if duplicates:
            pts, inverse, counts = np.unique(pts, axis=0, return_inverse=True, return_counts=True)
            self._merge = (inverse.reshape(-1), counts)
        self.points = pts
        if len(pts) >= 3:
            self.tris = _triangulate(pts, _triangle_switches(integer, extent))
            self.tris = trim_hull(pts, self.tris, hull_edge_ratio)
        else:
            self.tris = np.empty((0, 3), dtype=np.int32)
        self._nearest = None  # (cells outside the triangles, their nearest sample): geometry

    def _mesh_values(self, values) -> np.ndarray:
        """The values at :attr:`points` (sorted; duplicates merged into their mean)."""
        vals = np.asarray(values, dtype=np.float64)
        if vals.shape != (self.k,):
            raise ValueError(
                f"values must have shape ({self.k},) to match points_rc, got {vals.shape}"
            )
        if not np.isfinite(vals).all():
            raise ValueError("values contains NaN or infinite entries")
        if self._order is not None:
            vals = vals[self._order]
        if self._merge is not None:
            inverse, counts = self._merge
            vals = np.bincount(inverse, weights=vals, minlength=len(counts)) / counts
        return vals

    def rasterised(self, values) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(grid, covered, mesh_values)``: the linear interpolation on every cell the
        triangles cover (NaN elsewhere), those cells, and the values at :attr:`points`."""
        vals = self._mesh_values(values)
        out = np.full(self.shape, np.nan)
        covered = np.zeros(self.shape, dtype=bool)
        if len(self.tris):
            rasterise_linear(self.points, vals, self.tris, out, covered)
        return out, covered, vals

    def fill_nearest(self, out: np.ndarray, covered: np.ndarray, vals: np.ndarray) -> None:
        """Give every cell the triangles do not cover its nearest sample's value, in place
        (Euclidean, ties broken by the k-d tree)."""
        if covered.all():
            return
        if self._nearest is None:  # the covered cells depend on the positions alone
            cols = self.shape[1]
            holes = np.flatnonzero(~covered.ravel())
            cells = np.column_stack((holes // cols, holes % cols)).astype(np.float64)
            # an unbalanced tree builds ~4x faster (175 -> 47 ms at k = 800 k) and the
            # queries (few cells at dense k) are as fast
            tree = cKDTree(self.points, leafsize=64, balanced_tree=False, compact_nodes=False)
            self._nearest = (holes, tree.query(cells)[1])
        holes, nearest = self._nearest
        out.ravel()[holes] = vals[nearest]

    def interpolate(self, values, *, outside: str = "nearest") -> np.ndarray:
        """:func:`reconstruct` of ``values`` at these samples (same ``outside`` policies)."""
        if outside not in OUTSIDE_POLICIES:
            raise ValueError(
                f"unknown outside policy {outside!r}; valid: {', '.join(OUTSIDE_POLICIES)}"
            )
        out, covered, vals = self.rasterised(values)
        if outside == "nearest":
            self.fill_nearest(out, covered, vals)
        return out


def loo_residuals(points_rc, values) -> np.ndarray:
    """Leave-one-out residual of each sample against the plane through its Delaunay neighbours.

    Parameters
    ----------
    points_rc : ndarray, shape (n, 2)
        Distinct sample positions (row, col).
    values : ndarray, shape (n,)
        Measured values.

    Returns
    -------
    ndarray of float64, shape (n,)
        value_i - plane_i(position_i), the plane the least-squares fit to the neighbours of i
        in the Delaunay triangulation of all samples; 0 where the fit is degenerate (fewer than
        three neighbours, or all collinear).
    """
    pts = np.asarray(points_rc, dtype=np.float64)
    z = np.asarray(values, dtype=np.float64)
    tris = triangulate(pts)
    out = np.zeros(len(pts))
    if len(tris) == 0:
        return out
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]).astype(np.int64)
    e = np.unique(np.sort(e, axis=1), axis=0)
    i, j = np.concatenate((e[:, 0], e[:, 1])), np.concatenate((e[:, 1], e[:, 0]))
    dr, dc, dz = pts[j, 0] - pts[i, 0], pts[j, 1] - pts[i, 1], z[j] - z[i]
    n = len(pts)

    def total(x):
        return np.bincount(i, weights=x, minlength=n)

    cnt = np.bincount(i, minlength=n).astype(np.float64)
    srr, scc, src = total(dr * dr), total(dc * dc), total(dr * dc)
    sr, sc = total(dr), total(dc)
    m = np.stack(
        [np.stack([cnt, sr, sc], -1), np.stack([sr, srr, src], -1), np.stack([sc, src, scc], -1)],
        axis=1,
    )
    rhs = np.stack([total(dz), total(dz * dr), total(dz * dc)], -1)
    det = np.linalg.det(m)
    scale = np.maximum(cnt * srr * scc, 1e-300)
    ok = (cnt >= 3) & (np.abs(det) > 1e-9 * scale)
    # the fit is dz ~ a + b dr + c dc about sample i, so the plane predicts a at i
    a = np.linalg.solve(m[ok], rhs[ok][..., None])[:, 0, 0]
    out[ok] = -a
    return out
