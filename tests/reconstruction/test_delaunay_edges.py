"""Delaunay-linear at its edges, by hand: one-column and one-row grids, fewer than three
samples, and the degeneracy rule of the leave-one-out residuals at any coordinate scale."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.reconstruction.delaunay import loo_residuals, reconstruct


@pytest.mark.parametrize("transpose", [False, True], ids=["one column", "one row"])
def test_a_grid_one_cell_wide_is_a_grid(transpose):
    # samples at cells 0 and 3 of a 4-cell line are collinear: no triangle, so every cell
    # takes its nearest sample (cells 0, 1 -> 1.0; 2, 3 -> 4.0), or NaN with outside="nan"
    pts = np.array([[0.0, 0.0], [3.0, 0.0]])
    shape = (4, 1)
    if transpose:
        pts, shape = pts[:, ::-1].copy(), (1, 4)
    got = reconstruct(pts, [1.0, 4.0], shape)
    np.testing.assert_array_equal(got.ravel(), [1.0, 1.0, 4.0, 4.0])
    assert np.isnan(reconstruct(pts, [1.0, 4.0], shape, outside="nan")).all()


def test_one_or_two_samples_span_no_triangle():
    one = reconstruct([[1.0, 1.0]], [2.5], (3, 3))
    np.testing.assert_array_equal(one, np.full((3, 3), 2.5))
    two = reconstruct([[0.0, 0.0], [2.0, 2.0]], [0.0, 6.0], (3, 3), outside="nan")
    assert np.isnan(two).all()
    near = reconstruct([[0.0, 0.0], [2.0, 2.0]], [0.0, 6.0], (3, 3))
    # nearest of the two corners; the anti-diagonal cells are equidistant (either value)
    assert near[0, 0] == near[0, 1] == near[1, 0] == 0.0
    assert near[2, 2] == near[2, 1] == near[1, 2] == 6.0


@pytest.mark.parametrize("scale", [1.0, 1e3, 1e-3])
def test_nearly_collinear_neighbours_are_degenerate_at_any_scale(scale):
    # the square's corners at 0 and its centre, moved 1e-6 off the corners' diagonal, at 1:
    # each corner's three neighbours (two corners and the centre) lie within 1e-6 of a line,
    # so the plane through them is ill-defined and its residual is 0 by rule; the centre's
    # four neighbours fit the plane 0 (residual 1). Scaling every coordinate by the same
    # factor keeps the triangulation, the planes and so the decision (the rule compares the
    # fit's determinant with the product of the neighbours' spreads, both ~ scale^4)
    pts = np.array([[0.0, 0.0], [0.0, 2.0], [2.0, 0.0], [2.0, 2.0], [1.0, 1.0 + 1e-6]])
    res = loo_residuals(scale * pts, np.array([0.0, 0.0, 0.0, 0.0, 1.0]))
    np.testing.assert_allclose(res, [0.0, 0.0, 0.0, 0.0, 1.0], atol=1e-9)
