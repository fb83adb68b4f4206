"""Compiled kernels behind :func:`simlunar.reconstruction.reconstruct`.

Kept in their own module so the Numba compilation (cached on disk) happens only when the
reconstruction is first used.
"""

from __future__ import annotations

import math

import numba
import numpy as np

# Tolerance (in cells) of the span test: a cell within _EPS of a triangle's edge counts as
# inside, so cells on an edge shared by two triangles (or on the hull) are always covered; they
# are written twice with values equal to rounding.
_EPS = 1e-9
# Height (in cells, over the longest edge) under which a triangle is clamped to its vertices'
# values (see rasterise_linear).
_THIN = 1e-3


@numba.njit(cache=True, nogil=True)
def scan_points(pts):  # pragma: no cover - compiled
    """One pass over (k, 2) float64 points: what :func:`reconstruct` needs to know.

    Returns ``(finite, lex_sorted, has_duplicates, integer, extent)``: all coordinates finite;
    rows non-decreasing and columns non-decreasing within a row; two consecutive points equal
    (only meaningful when sorted); every coordinate an integer; the larger of the row and
    column extents (max - min).
    """
    k = pts.shape[0]
    finite = True
    lex_sorted = True
    dup = False
    integer = True
    rmin = cmin = math.inf
    rmax = cmax = -math.inf
    for i in range(k):
        r, c = pts[i, 0], pts[i, 1]
        if not (math.isfinite(r) and math.isfinite(c)):
            finite = False
            continue
        if integer and (r != math.floor(r) or c != math.floor(c)):
            integer = False
        rmin, rmax = min(rmin, r), max(rmax, r)
        cmin, cmax = min(cmin, c), max(cmax, c)
        if i > 0:
            pr, pc = pts[i - 1, 0], pts[i - 1, 1]
            if r < pr or (r == pr and c < pc):
                lex_sorted = False
            elif r == pr and c == pc:
                dup = True
    extent = max(rmax - rmin, cmax - cmin) if k > 0 else 0.0
    return finite, lex_sorted, dup, integer, extent


@numba.njit(cache=True, nogil=True)
def _span(ra, ca, rb, cb, r):  # pragma: no cover - compiled
    """Column where the edge (ra, ca)-(rb, cb), ra <= rb, crosses row r (clamped to the edge).

    A horizontal edge (ra == rb) gives cb: the callers pass b as the endpoint that the
    triangle's long edge does not reach.
    """
    if rb == ra:
        return cb
    t = (r - ra) / (rb - ra)
    t = min(max(t, 0.0), 1.0)
    return ca + t * (cb - ca)


@numba.njit(cache=True, nogil=True)
def _by_row(r0, c0, r1, c1, r2, c2):  # pragma: no cover - compiled
    """The vertices ordered by row: a (top) <= b <= c (bottom)."""
    ra, ca, rb, cb, rc, cc = r0, c0, r1, c1, r2, c2
    if rb < ra:
        ra, ca, rb, cb = rb, cb, ra, ca
    if rc < rb:
        rb, cb, rc, cc = rc, cc, rb, cb
        if rb < ra:
            ra, ca, rb, cb = rb, cb, ra, ca
    return ra, ca, rb, cb, rc, cc


@numba.njit(cache=True, nogil=True)
def _row_run(ra, ca, rb, cb, rc, cc, r, nc):  # pragma: no cover - compiled
    """First and last column of row ``r`` that the triangle a, b, c (by row) covers.

    A row within _EPS above the top vertex (below the bottom one) is spanned as the
    triangle's first (last) row; a row beside an edge within _EPS of horizontal, as that
    edge's lower (upper) end's row, so the whole edge is covered (float points off a lattice
    row by rounding).
    """
    rr = min(max(float(r), ra), rc)
    if (rb - ra <= _EPS and rr <= rb) or (rc - rb <= _EPS and rr >= rb):
        rr = rb
    x1 = _span(ra, ca, rc, cc, rr)
    # the other edge: a-b above b, b-c from b down; a horizontal edge reaches b
    if rr < rb or rc == rb:
        x2 = _span(ra, ca, rb, cb, rr)
    else:
        x2 = _span(rb, cb, rc, cc, rr)
    lo, hi = min(x1, x2), max(x1, x2)
    return max(math.ceil(lo - _EPS), 0), min(math.floor(hi + _EPS), nc - 1)


@numba.njit(cache=True, nogil=True)
def _along(r, c, ra, ca, va, rb, cb, vb, rm, cm, vm):  # pragma: no cover - compiled
    """Value at (r, c) of a sliver: projected onto its longest edge a-b and interpolated
    piecewise linearly through a, the middle vertex m (projected too) and b."""
    dr, dc = rb - ra, cb - ca
    l2 = dr * dr + dc * dc
    if l2 == 0.0:
        return va
    t = min(max(((r - ra) * dr + (c - ca) * dc) / l2, 0.0), 1.0)
    tm = min(max(((rm - ra) * dr + (cm - ca) * dc) / l2, 0.0), 1.0)
    if t <= tm:
        return va + (vm - va) * (t / tm) if tm > 0.0 else vm
    return vm + (vb - vm) * ((t - tm) / (1.0 - tm)) if tm < 1.0 else vm


@numba.njit(cache=True, nogil=True)
def _fill_sliver(pts, vals, i0, i1, i2, out, covered):  # pragma: no cover - compiled
    """Cells of a sliver that no other triangle covered, valued along its longest edge."""
    nr, nc = out.shape
    # the longest edge a-b and the middle vertex m
    ia, ib, im = i0, i1, i2
    best = (pts[i1, 0] - pts[i0, 0]) ** 2 + (pts[i1, 1] - pts[i0, 1]) ** 2
    d = (pts[i2, 0] - pts[i0, 0]) ** 2 + (pts[i2, 1] - pts[i0, 1]) ** 2
    if d > best:
        ia, ib, im, best = i0, i2, i1, d
    d = (pts[i2, 0] - pts[i1, 0]) ** 2 + (pts[i2, 1] - pts[i1, 1]) ** 2
    if d > best:
        ia, ib, im = i1, i2, i0
    ra, ca, rb, cb, rc, cc = _by_row(pts[i0, 0], pts[i0, 1], pts[i1, 0], pts[i1, 1],
                                     pts[i2, 0], pts[i2, 1])  # fmt: skip
    rlo = max(math.ceil(ra - _EPS), 0)
    rhi = min(math.floor(rc + _EPS), nr - 1)
    for r in range(rlo, rhi + 1):
        clo, chi = _row_run(ra, ca, rb, cb, rc, cc, r, nc)
        for c in range(clo, chi + 1):
            if not covered[r, c]:
                out[r, c] = _along(r, c, pts[ia, 0], pts[ia, 1], vals[ia], pts[ib, 0],
                                   pts[ib, 1], vals[ib], pts[im, 0], pts[im, 1], vals[im])  # fmt: skip
                covered[r, c] = True


@numba.njit(cache=True, nogil=True)
def rasterise_linear(pts, vals, tris, out, covered):  # pragma: no cover - compiled
    """Linear interpolation of ``vals`` over triangles ``tris`` onto every covered cell.

    ``pts`` (k, 2) float64 (row, col) index coordinates, ``vals`` (k,), ``tris`` (m, 3) int,
    ``out`` (rows, cols) float64 written in place, ``covered`` (rows, cols) bool set in place.

    Scan conversion: for each row a triangle spans, the two edges crossing that row bound a
    run of cells, each set from the triangle's plane ``v0 + gr (r - r0) + gc (c - c0)`` (one
    multiply-add per cell). A sample that sits exactly on a cell sets that cell to its own value.

    Slivers (less than _EPS high over their longest edge: nearly collinear float points, e.g.
    lattice points off by rounding) have planes too steep to read (values 1e14x outside the
    samples' range were seen): they go last and only fill cells no other triangle covered,
    with the value along their longest edge. A thin triangle (less than _THIN high) is
    clamped to its vertices' values, which bounds its plane at cells within _EPS outside its
    edges (a fat one's plane moves by less than 1e-6 of its values' range there; unclamped,
    its row loop stays vectorised).
    """
    nr, nc = out.shape
    slivers = np.zeros(tris.shape[0], np.bool_)
    for t in range(tris.shape[0]):
        i0, i1, i2 = tris[t, 0], tris[t, 1], tris[t, 2]
        r0, c0 = pts[i0, 0], pts[i0, 1]
        r1, c1 = pts[i1, 0], pts[i1, 1]
        r2, c2 = pts[i2, 0], pts[i2, 1]
        det = (r1 - r0) * (c2 - c0) - (r2 - r0) * (c1 - c0)
        e2 = max((r1 - r0) ** 2 + (c1 - c0) ** 2, (r2 - r0) ** 2 + (c2 - c0) ** 2,
                 (r2 - r1) ** 2 + (c2 - c1) ** 2)  # fmt: skip
        if det == 0.0 or det * det < _EPS * _EPS * e2:
            slivers[t] = True
            continue
        inv = 1.0 / det
        v0 = vals[i0]
        thin = det * det < _THIN * _THIN * e2
        vlo = min(v0, vals[i1], vals[i2])
        vhi = max(v0, vals[i1], vals[i2])
        d1, d2 = vals[i1] - v0, vals[i2] - v0
        gr = (d1 * (c2 - c0) - d2 * (c1 - c0)) * inv
        gc = (d2 * (r1 - r0) - d1 * (r2 - r0)) * inv
        ra, ca, rb, cb, rc, cc = _by_row(r0, c0, r1, c1, r2, c2)
        rlo = max(math.ceil(ra - _EPS), 0)
        rhi = min(math.floor(rc + _EPS), nr - 1)
        for r in range(rlo, rhi + 1):
            clo, chi = _row_run(ra, ca, rb, cb, rc, cc, r, nc)
            base = v0 + gr * (r - r0)
            if thin:
                for c in range(clo, chi + 1):
                    out[r, c] = min(max(base + gc * (c - c0), vlo), vhi)
                    covered[r, c] = True
            else:
                for c in range(clo, chi + 1):
                    out[r, c] = base + gc * (c - c0)
                    covered[r, c] = True
    for t in range(tris.shape[0]):
        if slivers[t]:
            _fill_sliver(pts, vals, tris[t, 0], tris[t, 1], tris[t, 2], out, covered)
    # a sample on a cell is that cell's value, not the plane's rounding of it
    for i in range(pts.shape[0]):
        r, c = pts[i, 0], pts[i, 1]
        if 0.0 <= r < nr and 0.0 <= c < nc and r == math.floor(r) and c == math.floor(c):
            ri, ci = int(r), int(c)
            if covered[ri, ci]:
                out[ri, ci] = vals[i]
