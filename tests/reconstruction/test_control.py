"""The image-free control: smoothed and re-anchored linear reconstruction."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from simlunar.reconstruction import RECONSTRUCTIONS, SmoothedOptions, run_reconstruction
from simlunar.reconstruction.control import plane_preserving_smooth
from simlunar.reconstruction.synthetic import jittered_samples, lit_terrain

SHAPE = (96, 128)


def test_equals_linear_on_a_plane():
    r, c = np.mgrid[0 : SHAPE[0], 0 : SHAPE[1]]
    plane = -2.0 + 0.3 * r + 0.11 * c
    pts = jittered_samples(SHAPE, 1 / 64, rng=0)
    v = plane[pts[:, 0], pts[:, 1]]
    out = run_reconstruction("smoothed", pts, v, SHAPE)
    lin = run_reconstruction("linear", pts, v, SHAPE).heights
    np.testing.assert_allclose(out.heights, lin, rtol=0, atol=1e-9 * np.abs(plane).max())
    np.testing.assert_allclose(out.heights, plane, rtol=0, atol=1e-9 * np.abs(plane).max())
    assert out.info["sigma"] == pytest.approx(0.5 * 8.0, rel=0.05)


def test_keeps_the_samples_and_smooths_between_them():
    t = lit_terrain(SHAPE, rng=1)
    pts = jittered_samples(SHAPE, 1 / 64, rng=2)
    v = t.heights[pts[:, 0], pts[:, 1]]
    lin = run_reconstruction("linear", pts, v, SHAPE).heights
    out = run_reconstruction("smoothed", pts, v, SHAPE).heights
    np.testing.assert_allclose(out[pts[:, 0], pts[:, 1]], v, atol=1e-9)
    assert np.abs(out - lin).max() > 1e-3 * np.ptp(lin)  # it does change the field
    # no image, no gain to speak of: within 25 % of linear's error either way
    e_lin, e_out = (np.mean((x - t.heights) ** 2) for x in (lin, out))
    assert 0.8 < e_out / e_lin < 1.25
    zero = run_reconstruction("smoothed", pts, v, SHAPE, options={"gamma": 0.0}).heights
    np.testing.assert_array_equal(zero, lin)
    assert not RECONSTRUCTIONS["smoothed"].meta["guided"]


def test_plane_preserving_smooth(rng):
    r, c = np.mgrid[0:40, 0:50]
    plane = 1.5 * r - 0.25 * c
    np.testing.assert_allclose(plane_preserving_smooth(plane, 3.0), plane, atol=1e-10)
    a = rng.normal(size=(40, 50))
    ref = ndimage.gaussian_filter(a, 2.0, truncate=3.0)
    np.testing.assert_allclose(plane_preserving_smooth(a, 2.0)[8:-8, 8:-8], ref[8:-8, 8:-8],
                               atol=1e-12)  # fmt: skip
    with pytest.raises(ValueError, match="sigma"):
        plane_preserving_smooth(a, -1.0)
    with pytest.raises(ValueError, match="sigma_pitch"):
        SmoothedOptions(sigma_pitch=0)
