"""Re-anchoring a detail field to the samples; the linear field and its hull."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.reconstruction import reconstruct
from simlunar.reconstruction._anchor import at_points, linear_field, reanchored_detail, sample_pitch


def test_linear_field_is_the_registry_linear_with_its_hull(rng):
    pts = rng.integers(5, 35, size=(30, 2))
    vals = rng.normal(size=30)
    lin = linear_field(pts, vals, (40, 40))
    np.testing.assert_array_equal(lin.heights, reconstruct(pts, vals, (40, 40)))
    np.testing.assert_array_equal(
        lin.hull, np.isfinite(reconstruct(pts, vals, (40, 40), outside="nan"))
    )
    assert 0 < lin.hull.mean() < 1
    assert lin.pitch == sample_pitch(30, (40, 40)) == np.sqrt(1600 / 30)


def test_reanchored_detail_vanishes_at_samples_and_for_planes(rng):
    pts = np.vstack([rng.integers(0, 40, size=(50, 2)), [[0, 0], [0, 39], [39, 0], [39, 39]]])
    lin = linear_field(pts, rng.normal(size=len(pts)), (40, 40))
    field = rng.normal(size=(40, 40))
    d = reanchored_detail(field, lin)
    np.testing.assert_allclose(at_points(d, lin.points), 0.0, atol=1e-12)
    r, c = np.mgrid[0:40, 0:40]
    np.testing.assert_allclose(reanchored_detail(2.0 - 0.5 * r + 0.25 * c, lin), 0.0, atol=1e-12)


def test_at_points_lookup_and_bilinear():
    f = np.arange(12.0).reshape(3, 4)
    np.testing.assert_array_equal(at_points(f, np.array([[1.0, 2.0], [2.0, 3.0]])), [6.0, 11.0])
    np.testing.assert_allclose(at_points(f, np.array([[0.5, 0.5], [1.0, 2.5]])), [2.5, 6.5])


def test_the_linear_fields_interpolation_reuses_its_triangles_to_the_bit(rng):
    """The field's mesh (triangulated once, its nearest fill cached) interpolates any values at
    its samples exactly as a fresh reconstruction does: unsorted points with a duplicate,
    inside and outside the hull, and again with other values after the cache is filled."""
    pts = rng.integers(5, 35, size=(40, 2)).astype(float)
    pts[7] = pts[3]  # a duplicate position: its values are averaged
    vals = rng.normal(size=40)
    lin = linear_field(pts, vals, (40, 40))
    assert lin.mesh._order is not None and lin.mesh._merge is not None
    np.testing.assert_array_equal(lin.heights, reconstruct(pts, vals, (40, 40)))
    for _ in range(3):
        other = rng.normal(size=40)
        np.testing.assert_array_equal(lin.interpolate(other), reconstruct(pts, other, (40, 40)))
        np.testing.assert_array_equal(
            lin.mesh.interpolate(other, outside="nan"),
            reconstruct(pts, other, (40, 40), outside="nan"),
        )
    with pytest.raises(ValueError, match="NaN or infinite"):
        lin.interpolate(np.full(40, np.nan))
    with pytest.raises(ValueError, match="shape"):
        lin.interpolate(np.zeros(39))
