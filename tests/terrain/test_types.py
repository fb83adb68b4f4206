"""Terrain: the grid's geometry (cell centres, extent, points) by hand, and its input checks."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.terrain.types import Terrain


def _terrain(**kw):
    heights = np.array([[1.0, 2.0, 3.0], [4.0, np.nan, 6.0]])
    args = {"heights": heights, "albedo": np.full((2, 3), 0.12), "spacing": 0.5}
    return Terrain(**{**args, **kw})


def test_cell_centres_extent_and_points_by_hand():
    t = _terrain(origin=(10, 20))
    x, y = t.cell_centers()
    np.testing.assert_allclose(x, [10.25, 10.75, 11.25])  # x0 + (c + 0.5) * spacing
    np.testing.assert_allclose(y, [19.75, 19.25])  # y0 - (r + 0.5) * spacing
    assert t.extent == (10.0, 11.5, 19.0, 20.0)
    pts = t.points()
    assert pts.shape == (2, 3, 3)
    np.testing.assert_allclose(pts[1, 2], [11.25, 19.25, 6.0])
    np.testing.assert_array_equal(t.nodata, [[False, False, False], [False, True, False]])
    assert t.shape == (2, 3)


def test_types_copies_and_read_only():
    heights = np.ones((2, 2), np.float32)
    t = Terrain(heights, np.ones((2, 2)), 1, origin=(1, 2))
    assert t.heights.dtype == np.float64 and t.albedo.dtype == np.float32
    assert isinstance(t.spacing, float) and t.origin == (1.0, 2.0)
    heights[0, 0] = 5  # the caller's array is not the terrain's
    assert t.heights[0, 0] == 1
    with pytest.raises(ValueError, match="read-only"):
        t.heights[0, 0] = 2
    assert t.crs is None


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        (
            {"heights": np.zeros(3), "albedo": np.zeros(3)},
            r"heights must be 2-D \(rows, cols\), got shape \(3,\)",
        ),
        (
            {"albedo": np.zeros((3, 2))},
            r"albedo shape \(3, 2\) does not match heights shape \(2, 3\)",
        ),
        ({"spacing": 0}, "spacing must be a positive number of metres, got 0"),
        ({"spacing": float("nan")}, "spacing must be a positive number of metres, got nan"),
        ({"heights": np.full((2, 3), np.inf)}, r"heights contain inf \(use NaN for nodata\)"),
        ({"crs": 4326}, "crs must be a WKT string or None, got int"),
    ],
)
def test_bad_terrains_are_refused(kw, message):
    with pytest.raises(ValueError, match=f"^{message}$"):
        _terrain(**kw)
