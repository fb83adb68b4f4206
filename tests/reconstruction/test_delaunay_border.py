"""The Delaunay reconstruction's border treatment: long hull triangles (slivers of border
samples a fraction of a pixel off their lattice rows) peeled and filled from the nearest sample."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.reconstruction import LinearOptions, run_reconstruction
from simlunar.reconstruction.delaunay import reconstruct, triangulate, trim_hull


def _moved_lattice():
    """Samples every 8 px of a 65 x 65 grid; the top row's inner samples 0.4 px down (a moving
    platform's border samples off their rest rows), its corners on row 0."""
    r, c = np.mgrid[0:65:8, 0:65:8]
    pts = np.column_stack([r.ravel(), c.ravel()]).astype(float)
    top = (pts[:, 0] == 0) & (pts[:, 1] > 0) & (pts[:, 1] < 64)
    pts[top, 0] = 0.4
    return pts


def _longest(pts, tris):
    e = [np.hypot(*(pts[tris[:, i]] - pts[tris[:, (i + 1) % 3]]).T) for i in range(3)]
    return np.max(e, axis=0)


def test_the_hull_sliver_is_peeled_and_its_strip_filled_from_the_nearest_sample():
    pts = _moved_lattice()
    z = np.sin(pts[:, 1] / 5.0) + 0.01 * pts[:, 0]
    tris = triangulate(pts)
    # the raw hull spans the whole top row: a fan of slivers up to 64 px long (8 lattice
    # edges); peeled at 3 x the median edge (8 px), they go and nothing else does
    assert _longest(pts, tris).max() == pytest.approx(64.0)
    kept = trim_hull(pts, tris, 3.0)
    assert (_longest(pts, kept) <= 24).all()
    assert len(kept) == (_longest(pts, tris) <= 24).sum() < len(tris)
    old = reconstruct(pts, z, (65, 65))
    new = reconstruct(pts, z, (65, 65), hull_edge_ratio=3.0)
    # cell (0, 24) lay on the sliver's edge from (0, 0) to (0, 64): the old value is the
    # interpolation between those two samples, the new one the sample at (0.4, 24)
    i24 = np.flatnonzero((pts[:, 0] == 0.4) & (pts[:, 1] == 24))[0]
    i0, i64 = (np.flatnonzero((pts[:, 0] == 0) & (pts[:, 1] == c))[0] for c in (0, 64))
    assert old[0, 24] == pytest.approx(z[i0] + 24 / 64 * (z[i64] - z[i0]))
    assert new[0, 24] == pytest.approx(z[i24])
    # below the strip nothing changed
    assert np.array_equal(old[1:], new[1:])
    # the option through the registry; 0 keeps the hull (the default, byte for byte)
    via = run_reconstruction("linear", pts, z, (65, 65), options=LinearOptions(hull_edge_ratio=3))
    assert np.array_equal(via.heights, new)
    assert np.array_equal(reconstruct(pts, z, (65, 65), hull_edge_ratio=0.0), old)


def test_peeling_repeats_on_the_new_hull_and_keeps_the_interior():
    # two nested slivers along the top (rows 0, 0.3 at the ends, 0.6 inside): both peeled,
    # the lattice's inner triangles (edges 8 and 8 sqrt 2) all kept
    pts = _moved_lattice()
    inner = (pts[:, 0] == 0.4) & (pts[:, 1] > 8) & (pts[:, 1] < 56)
    pts[inner, 0] = 0.8
    tris = triangulate(pts)
    kept = trim_hull(pts, tris, 3.0)
    assert (_longest(pts, tris) > 24).sum() >= 2
    assert (_longest(pts, kept) <= 24).all()
    assert (_longest(pts, tris) <= 24).sum() == len(kept)
    with pytest.raises(ValueError, match="hull_edge_ratio must be >= 0"):
        LinearOptions(hull_edge_ratio=-1.0)
