"""Delaunay-linear reconstruction: parity with scipy, exact planes, hull policy, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import LinearNDInterpolator

from simlunar.reconstruction import reconstruct, triangulate
from simlunar.reconstruction.delaunay import loo_residuals


def _grid_cells(shape):
    rr, cc = np.mgrid[0 : shape[0], 0 : shape[1]]
    return np.column_stack((rr.ravel(), cc.ravel())).astype(float)


@pytest.mark.parametrize("k", [5, 60, 2000])
def test_matches_linear_nd_interpolator_inside_hull(rng, k):
    # Random non-integer points: the Delaunay triangulation is unique (no co-circular sets),
    # so scipy (Qhull) and Triangle must build the same triangles and agree to rounding.
    shape = (48, 71)
    pts = rng.uniform([-2.0, -3.0], [shape[0] + 1.0, shape[1] + 2.0], size=(k, 2))
    vals = rng.normal(size=k) * 10.0
    ours = reconstruct(pts, vals, shape, outside="nan")
    ref = LinearNDInterpolator(pts, vals)(_grid_cells(shape)).reshape(shape)
    inside = np.isfinite(ref)
    assert inside.sum() > 100
    np.testing.assert_allclose(ours[inside], ref[inside], rtol=0, atol=1e-9)
    # Outside the hull both leave NaN (up to cells within rounding of the hull boundary).
    assert np.mean(np.isnan(ours) == ~inside) > 0.995


def test_plane_is_reproduced_exactly(rng):
    # Linear interpolation of samples of a plane is the plane itself inside the hull.
    shape = (30, 40)
    pts = np.vstack([[0, 0], [0, 39], [29, 0], [29, 39], rng.uniform(0, [29, 39], (50, 2))])
    vals = 2.5 * pts[:, 0] - 0.75 * pts[:, 1] + 3.0
    rec = reconstruct(pts, vals, shape)
    rr, cc = np.mgrid[0:30, 0:40]
    np.testing.assert_allclose(rec, 2.5 * rr - 0.75 * cc + 3.0, atol=1e-9)


def test_hand_computed_triangle():
    # One triangle (0,0), (0,4), (4,0) with values 0, 4, 8: f(r, c) = 2 r + c inside.
    pts = np.array([[0.0, 0.0], [0.0, 4.0], [4.0, 0.0]])
    vals = np.array([0.0, 4.0, 8.0])
    rec = reconstruct(pts, vals, (5, 5), outside="nan")
    assert rec[1, 1] == pytest.approx(3.0)
    assert rec[2, 2] == pytest.approx(6.0)  # on the hypotenuse
    assert rec[0, 4] == pytest.approx(4.0)
    assert np.isnan(rec[3, 3]) and np.isnan(rec[4, 4])
    nearest = reconstruct(pts, vals, (5, 5))
    # (4, 4): distances to (0,4) and (4,0) are 4 each; (4, 3) is nearer to (4, 0) -> 8.
    assert nearest[4, 3] == 8.0
    assert nearest[3, 4] == 4.0


def test_integer_plan_passes_directly():
    pts = np.array([[0, 0], [0, 9], [9, 0], [9, 9], [4, 5]])
    vals = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    rec = reconstruct(pts, vals, (10, 10))
    for (r, c), v in zip(pts, vals):
        assert rec[r, c] == v


def test_duplicates_are_averaged():
    pts = np.array([[0.0, 0.0], [0.0, 4.0], [4.0, 0.0], [4.0, 0.0], [4.0, 4.0]])
    vals = np.array([0.0, 0.0, 2.0, 4.0, 0.0])
    rec = reconstruct(pts, vals, (5, 5))
    assert rec[4, 0] == pytest.approx(3.0)
    assert np.all(np.isfinite(rec))


def test_collinear_samples_fall_back_to_policy():
    pts = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]])
    vals = np.array([0.0, 1.0, 2.0, 3.0])
    assert triangulate(pts).shape == (0, 3)
    rec = reconstruct(pts, vals, (4, 4))
    np.testing.assert_array_equal(np.diag(rec), vals)
    # (0, 3) is sqrt(5) from both (1, 1) and (2, 2) and 3 from the ends: a tie of the two
    assert rec[0, 3] in (1.0, 2.0)
    assert np.isnan(reconstruct(pts, vals, (4, 4), outside="nan")).all()


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"points_rc": np.zeros((3, 3)), "values": np.zeros(3)}, "shape \\(k, 2\\)"),
        ({"points_rc": np.zeros((3, 2)), "values": np.zeros(4)}, "values must have shape"),
        ({"points_rc": np.zeros((0, 2)), "values": np.zeros(0)}, "empty"),
        ({"points_rc": np.array([[0, np.nan]] * 3), "values": np.zeros(3)}, "points_rc contains"),
        ({"points_rc": np.eye(3)[:, :2], "values": [0, np.nan, 1]}, "values contains NaN"),
        ({"points_rc": np.eye(3)[:, :2], "values": np.zeros(3), "shape": (0, 3)}, "positive"),
        ({"points_rc": np.eye(3)[:, :2], "values": np.zeros(3), "outside": "zero"}, "outside"),
    ],
)
def test_bad_input(kwargs, match):
    kwargs = {"shape": (4, 4), **kwargs}
    with pytest.raises(ValueError, match=match):
        reconstruct(**kwargs)


def _incircle_exact(a, b, c, d):
    """Sign of the incircle determinant of d against ccw (a, b, c), in exact integers."""
    adx, ady = a[..., 0] - d[..., 0], a[..., 1] - d[..., 1]
    bdx, bdy = b[..., 0] - d[..., 0], b[..., 1] - d[..., 1]
    cdx, cdy = c[..., 0] - d[..., 0], c[..., 1] - d[..., 1]
    alift, blift, clift = adx * adx + ady * ady, bdx * bdx + bdy * bdy, cdx * cdx + cdy * cdy
    return (
        alift * (bdx * cdy - cdx * bdy)
        + blift * (cdx * ady - adx * cdy)
        + clift * (adx * bdy - bdx * ady)
    )


@pytest.mark.parametrize("density", [0.5, 0.05])
def test_lattice_triangulation_is_delaunay(density):
    # Integer points take Triangle's fast switches (no adaptive exact arithmetic): check the
    # result independently, in int64 arithmetic. Every edge must be locally Delaunay (the
    # opposite vertex never strictly inside the circumcircle), which makes the whole
    # triangulation Delaunay, and the triangles must tile the convex hull exactly.
    from scipy.spatial import ConvexHull

    gen = np.random.default_rng(7)
    rows, cols = 60, 90
    flat = np.sort(gen.choice(rows * cols, int(density * rows * cols), replace=False))
    pts = np.column_stack((flat // cols, flat % cols))
    tris = triangulate(pts.astype(float)).astype(np.int64)
    p = pts.astype(np.int64)
    a, b, c = p[tris[:, 0]], p[tris[:, 1]], p[tris[:, 2]]
    orient = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    assert np.all(orient != 0)
    # make every triangle counter-clockwise in (row, col) so the incircle sign is meaningful
    flip = orient < 0
    tris[flip] = tris[flip][:, [0, 2, 1]]
    a, b, c = p[tris[:, 0]], p[tris[:, 1]], p[tris[:, 2]]
    area2 = np.abs(orient).sum()
    hull = ConvexHull(pts.astype(float))
    assert area2 == pytest.approx(2.0 * hull.volume, abs=1e-9)
    # opposite vertex across each shared edge
    edges = {}
    for t, tri in enumerate(tris):
        for j in range(3):
            e = tuple(sorted((tri[j], tri[(j + 1) % 3])))
            edges.setdefault(e, []).append((t, tri[(j + 2) % 3]))
    pairs = [(v[0][0], v[1][1]) for v in edges.values() if len(v) == 2]
    pairs += [(v[1][0], v[0][1]) for v in edges.values() if len(v) == 2]
    assert all(len(v) <= 2 for v in edges.values())
    t_idx, opp = np.array(pairs).T
    s = _incircle_exact(p[tris[t_idx, 0]], p[tris[t_idx, 1]], p[tris[t_idx, 2]], p[opp])
    assert np.all(s <= 0), "an opposite vertex lies strictly inside a circumcircle"


def _reference_raster(pts, vals, tris, shape):
    """Barycentric test of every cell against every triangle (slow, obviously right)."""
    rr, cc = np.mgrid[0 : shape[0], 0 : shape[1]]
    out = np.full(shape, np.nan)
    for i0, i1, i2 in tris:
        (r0, c0), (r1, c1), (r2, c2) = pts[i0], pts[i1], pts[i2]
        det = (r1 - r0) * (c2 - c0) - (r2 - r0) * (c1 - c0)
        b1 = ((rr - r0) * (c2 - c0) - (r2 - r0) * (cc - c0)) / det
        b2 = ((r1 - r0) * (cc - c0) - (rr - r0) * (c1 - c0)) / det
        b0 = 1.0 - b1 - b2
        inside = (b0 >= -1e-12) & (b1 >= -1e-12) & (b2 >= -1e-12)
        out[inside] = (b0 * vals[i0] + b1 * vals[i1] + b2 * vals[i2])[inside]
    return out


@pytest.mark.parametrize("integer", [True, False])
def test_scanline_raster_matches_barycentric_reference(integer):
    # The scan-converting rasteriser against a per-cell barycentric test on the same triangles,
    # with lattice points (horizontal and vertical edges, cells on shared edges) and with
    # non-integer points (edges between cells).
    gen = np.random.default_rng(3)
    shape = (23, 31)
    if integer:
        flat = np.sort(gen.choice(shape[0] * shape[1], 60, replace=False))
        pts = np.column_stack((flat // shape[1], flat % shape[1])).astype(float)
    else:
        pts = gen.uniform([-1.5, -1.5], [shape[0] + 0.5, shape[1] + 0.5], size=(60, 2))
    vals = gen.normal(size=len(pts))
    ours = reconstruct(pts, vals, shape, outside="nan")
    ref = _reference_raster(pts, vals, triangulate(pts), shape)
    np.testing.assert_array_equal(np.isnan(ours), np.isnan(ref))
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-12)


def _near_lattice(seed, *, sheared):
    """Lattice points (rows 3 apart, columns 4 apart; odd rows shifted 1.5 when ``sheared``,
    which leaves no co-circular four inside) and the same points off by 1e-13, as projected
    sensor points land: collinear runs on the hull become sliver triangles."""
    gen = np.random.default_rng(seed)
    r, c = np.mgrid[0:60:3, 0:80:4].astype(float)
    if sheared:
        c[1::2] += 1.5
    exact = np.column_stack((r.ravel(), c.ravel()))
    return exact, exact + gen.normal(scale=1e-13, size=exact.shape), gen.normal(size=len(exact))


@pytest.mark.parametrize("seed", range(6))
def test_near_lattice_float_points_stay_inside_the_samples_range(seed):
    # a linear interpolant never leaves its samples' range; sliver triangles of points off a
    # lattice by rounding read steep planes at cells just outside them (up to 5.6e14 times the
    # samples' largest value before the rasteriser skipped slivers and clamped to the vertices)
    _, pts, vals = _near_lattice(seed, sheared=False)
    out = reconstruct(pts, vals, (60, 80), outside="nan")
    inside = out[np.isfinite(out)]
    assert inside.size > 0.9 * out.size
    # (fat triangles are not clamped: within 1e-9 cells outside them their planes move by
    # less than 1e-6 of the values' range)
    tol = 1e-6 * np.ptp(vals)
    assert inside.min() >= vals.min() - tol and inside.max() <= vals.max() + tol


@pytest.mark.parametrize("seed", range(3))
def test_near_lattice_float_points_agree_with_the_exact_lattice(seed):
    # no co-circular sets: both triangulations are the same up to slivers, so wherever both
    # cover a cell they agree to rounding
    exact, pts, vals = _near_lattice(seed, sheared=True)
    ours = reconstruct(pts, vals, (60, 80), outside="nan")
    ref = reconstruct(exact, vals, (60, 80), outside="nan")
    # every cell the exact lattice covers is covered (slivers fill what their neighbours
    # leave), with the exact lattice's value to rounding
    assert not (np.isfinite(ref) & ~np.isfinite(ours)).any()
    both = np.isfinite(ours) & np.isfinite(ref)
    np.testing.assert_allclose(ours[both], ref[both], rtol=0, atol=1e-11)


def test_a_sliver_inside_the_hull_leaves_no_hole():
    # three points of a nearly horizontal sliver (rows 3 -+ 1e-12) inside a rectangle: a
    # cell it holds is 1e-12 from its neighbours' edges in rows but 0.4 cells in columns, so
    # skipping slivers left (3, 2) uncovered (NaN, or a nearest-sample step)
    pts = np.array([[0, -3], [0, 9], [6, -3], [6, 9], [2, 0], [3 - 1.2e-12, 0.5],
                    [3 - 4e-13, 0.5], [3 + 1e-12, 4], [4, 0.5]])  # fmt: skip
    vals = np.array([0, 0, 0, 0, 1, 2, 2, 3, 1.0])
    out = reconstruct(pts, vals, (7, 10), outside="nan")
    assert np.isfinite(out).all()  # the hull holds the whole grid
    assert out[3, 2] == pytest.approx(2.0 + (2.0 - 0.5) / 3.5, abs=1e-9)  # along 2 -> 3
    assert out.min() >= vals.min() - 1e-9 and out.max() <= vals.max() + 1e-9


def test_unsorted_duplicate_points_are_averaged():
    """Three samples at (2, 2), not next to each other in the input, become one of their mean
    (1 + 3 + 8) / 3 = 4; the corners are 0, so the centre cell reads 4 and the midpoint
    (1, 1) of the corner-centre edge reads 2 (linear)."""
    pts = np.array([[2.0, 2.0], [0, 0], [0, 4], [2, 2], [4, 0], [4, 4], [2, 2]])
    vals = np.array([1.0, 0, 0, 3, 0, 0, 8])
    out = reconstruct(pts, vals, (5, 5))
    assert out[2, 2] == pytest.approx(4.0, abs=1e-12)
    assert out[1, 1] == pytest.approx(2.0, abs=1e-12)
    assert out[0, 0] == 0.0 and out[4, 4] == 0.0


def test_a_sliver_fills_its_cells_along_its_longest_edge_by_hand():
    """a = (0, 0) value 0, b = (4, 4) value 8, m = (2, 2 + 1e-10) value 2: a triangle of
    height ~1e-10 (a sliver: |det| < 1e-9 x its longest edge) whose plane cannot be read.
    Its cells take the value along a-b interpolated through m projected onto it (t_m = 1/2):
    (1, 1) at t = 1/4 -> 0 + (2 - 0) (1/4) / (1/2) = 1, (3, 3) at t = 3/4 -> 2 + (8 - 2)
    (1/4) / (1/2) = 5; the cells off the sliver stay NaN (outside the hull)."""
    pts = np.array([[0.0, 0.0], [4.0, 4.0], [2.0, 2.0 + 1e-10]])
    out = reconstruct(pts, np.array([0.0, 8.0, 2.0]), (5, 5), outside="nan")
    np.testing.assert_allclose(np.diag(out), [0.0, 1.0, 2.0, 5.0, 8.0], atol=1e-6)
    off = ~np.eye(5, dtype=bool)
    assert np.isnan(out[off]).all()
    # the same sliver listed in another vertex order: the same cells and values
    again = reconstruct(pts[[2, 0, 1]], np.array([2.0, 0.0, 8.0]), (5, 5), outside="nan")
    np.testing.assert_allclose(again, out, atol=1e-6)


@pytest.mark.parametrize("order", [(0, 1, 2), (2, 0, 1), (1, 2, 0), (2, 1, 0)])
@pytest.mark.parametrize("offset", [(3.0, 5.0), (6.0, 1.0)])
def test_a_sliver_away_from_the_origin_in_any_vertex_order(order, offset):
    """The sliver of the test above moved off the origin and listed in every rotation and a
    reflection of its vertices: the same cells and values (1 and 5 between the samples)."""
    dr, dc = offset
    pts = np.array([[0.0, 0.0], [4.0, 4.0], [2.0, 2.0 + 1e-10]]) + np.array([dr, dc])
    vals = np.array([0.0, 8.0, 2.0])
    idx = list(order)
    out = reconstruct(pts[idx], vals[idx], (12, 12), outside="nan")
    r0, c0 = int(dr), int(dc)
    diag = [out[r0 + i, c0 + i] for i in range(5)]
    np.testing.assert_allclose(diag, [0.0, 1.0, 2.0, 5.0, 8.0], atol=1e-6)
    assert np.isfinite(out).sum() == 5


def test_fewer_than_three_points_have_no_triangle():
    for k in (1, 2):
        tris = triangulate(np.arange(2 * k, dtype=float).reshape(k, 2))
        assert tris.shape == (0, 3) and tris.dtype == np.int32


#: slivers a-m-b by hand: a and b 4 cells apart along a row, a column or a diagonal, m at
#: their midpoint moved by h along ``shift``; (reconstruct sorts the points, so which edge
#: Triangle lists first depends on the geometry: these put the long edge first, last and
#: between the other two)
SLIVERS = {
    "diagonal, m right": ((0, 0), (4, 4), (0, 1)),
    "diagonal, m left": ((0, 0), (4, 4), (0, -1)),
    "anti-diagonal, m left": ((0, 4), (4, 0), (0, -1)),
    "row, m up": ((2, 0), (2, 4), (-1, 0)),
    "row, m down": ((2, 0), (2, 4), (1, 0)),
    "column, m left": ((0, 2), (4, 2), (0, -1)),
}


@pytest.mark.parametrize("offset", [(0, 0), (20, 30)])
@pytest.mark.parametrize("geometry", list(SLIVERS))
def test_the_sliver_threshold_is_a_height_of_1e_9_cells_over_the_longest_edge(geometry, offset):
    """a value 0, b value 8, m (their midpoint moved by h) value 2. The height over the long
    edge a-b is h (row, column) or h / sqrt(2) (diagonals). h = 1e-4 and 1.8e-9 (at least
    1.27e-9 high) are thin triangles read by their plane (clamped to the vertices' values):
    along a-b it is linear, 0, 2, 4, 6, 8 at a + i (b - a) / 4; h = 0.9e-9 and 0.5e-9
    (under 1e-9 high) are slivers, valued along a-b through m (t_m = 1/2): 0, 1, 2, 5, 8. The same away
    from the origin (coordinates much larger than the edges)."""
    a, b, shift = (np.array(v, dtype=float) for v in SLIVERS[geometry])
    a, b = a + offset, b + offset
    cells = [tuple(int(x) for x in a + i * (b - a) / 4) for i in range(5)]
    shape = (offset[0] + 5, offset[1] + 5)
    plane, along = [0.0, 2.0, 4.0, 6.0, 8.0], [0.0, 1.0, 2.0, 5.0, 8.0]
    for h, want in ((1e-4, plane), (1.8e-9, plane), (0.9e-9, along), (0.5e-9, along)):
        pts = np.array([a, b, (a + b) / 2 + h * shift])
        out = reconstruct(pts, np.array([0.0, 8.0, 2.0]), shape, outside="nan")
        np.testing.assert_allclose([out[c] for c in cells], want, atol=1e-6, err_msg=f"h={h}")
        assert np.isfinite(out).sum() == 5


def _loo_reference(pts, z):
    """Per sample: the least-squares plane through its Delaunay neighbours (scipy's Qhull
    triangulation, numpy's lstsq) evaluated at the sample; 0 with fewer than three
    neighbours or a rank-deficient fit."""
    from scipy.spatial import Delaunay

    ptr, nbr = Delaunay(pts).vertex_neighbor_vertices
    out = np.zeros(len(pts))
    for i in range(len(pts)):
        j = nbr[ptr[i] : ptr[i + 1]]
        a = np.column_stack((np.ones(j.size), pts[j] - pts[i]))
        if j.size >= 3 and np.linalg.matrix_rank(a) == 3:
            coef = np.linalg.lstsq(a, z[j] - z[i], rcond=None)[0]
            out[i] = -coef[0]
    return out


def test_loo_residuals_by_hand():
    """Triangle A (0, 0), B (0, 4), C (4, 0) with D (1, 1) inside; z = r + 2 c on A, B, C
    (0, 8, 4) and 8 at D. D's three neighbours span the plane r + 2 c = 3 at D: residual 5.
    A's neighbours B, C, D span z = 10 - 1.5 r - 0.5 c: residual 0 - 10 = -10. Every sample
    has exactly three neighbours, so each residual is its value minus the plane through the
    other three samples."""
    pts = np.array([[0.0, 0.0], [0.0, 4.0], [4.0, 0.0], [1.0, 1.0]])
    z = np.array([0.0, 8.0, 4.0, 8.0])
    res = loo_residuals(pts, z)
    assert res[3] == pytest.approx(5.0, abs=1e-9)
    assert res[0] == pytest.approx(-10.0, abs=1e-9)

    def through(i):  # the plane through the other three samples, at sample i
        o = [j for j in range(4) if j != i]
        coef = np.linalg.solve(np.column_stack((np.ones(3), pts[o])), z[o])
        return z[i] - coef @ [1.0, *pts[i]]

    np.testing.assert_allclose(res, [through(i) for i in range(4)], atol=1e-9)


def test_loo_residuals_of_collinear_neighbours_are_zero():
    """Square corners (0, 0), (0, 2), (2, 0), (2, 2) at 0 and the centre (1, 1) at 1: the
    centre's four neighbours fit the plane 0, residual 1; each corner's three neighbours
    (two corners and the centre) lie on one line, so its fit is degenerate: 0."""
    pts = np.array([[0.0, 0.0], [0.0, 2.0], [2.0, 0.0], [2.0, 2.0], [1.0, 1.0]])
    res = loo_residuals(pts, np.array([0.0, 0.0, 0.0, 0.0, 1.0]))
    np.testing.assert_allclose(res, [0.0, 0.0, 0.0, 0.0, 1.0], atol=1e-12)


def test_loo_residuals_match_a_least_squares_reference(rng):
    pts = rng.uniform(0.0, 50.0, size=(80, 2))
    z = np.sin(pts[:, 0] / 7.0) + 0.1 * pts[:, 1] + rng.normal(scale=0.2, size=80)
    np.testing.assert_allclose(loo_residuals(pts, z), _loo_reference(pts, z), atol=1e-9)
    # fewer than three points span no triangle: every residual is 0
    np.testing.assert_array_equal(loo_residuals(pts[:2], z[:2]), [0.0, 0.0])
