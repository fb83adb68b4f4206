"""The held-out check: the detail's weight is the one that predicts left-out samples, near 1
for the truth's own detail and 0 for a detail against the surface."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.reconstruction._anchor import linear_field
from simlunar.reconstruction.heldout import blend_detail, checked_blend
from simlunar.reconstruction.synthetic import jittered_samples, lit_terrain

SHAPE = (192, 256)


def _case(density=1 / 256, **kw):
    t = lit_terrain(SHAPE, **kw)
    pts = jittered_samples(SHAPE, density, rng=7)
    return t, pts, t.heights[pts[:, 0], pts[:, 1]]


def test_checked_blend_caps_gamma_by_the_held_out_samples():
    t, pts, v = _case(rng=1)
    lin = linear_field(pts, v, SHAPE)
    # without a check: the blend at the weight asked, info untouched
    info = {}
    out = checked_blend(lin, t.heights, 0.5, info)
    np.testing.assert_array_equal(out, blend_detail(lin, t.heights, 0.5))
    assert info == {}
    # the truth as detail predicts every held-out sample: the weight stays near 1
    info = {}
    checked_blend(lin, t.heights, 1.0, info, remade=t.heights)
    assert info["gamma"] == info["heldout_gamma"] > 0.9 and info["heldout_samples"] > 20
    # a detail against the surface is refused: the linear heights, gamma 0
    info = {}
    out = checked_blend(lin, -t.heights, 1.0, info, remade=-t.heights)
    assert info["gamma"] == info["heldout_gamma"] == 0.0
    np.testing.assert_array_equal(out, lin.heights)


def _departure_rms(lin, every=5):
    """The RMS of the first split's held-out samples' departure from the kept samples'
    interpolation, written out from the definition (row-major order, every 5th left out,
    those inside the kept samples' hull, interpolated bilinearly from the kept grid)."""
    from simlunar.reconstruction._anchor import at_points

    pts, vals = lin.points, lin.values
    order = np.lexsort((pts[:, 1], pts[:, 0]))
    test = np.zeros(len(pts), bool)
    test[order[::every]] = True
    keep = linear_field(pts[~test], vals[~test], lin.shape)
    inside = at_points(keep.hull.astype(float), pts[test]) > 0.5
    r = vals[test][inside] - at_points(keep.heights, pts[test][inside])
    return float(np.sqrt(np.mean(r**2)))


def test_the_detail_is_limited_to_clip_times_the_held_out_departures():
    # the truth's detail with one absurd spike between samples: the check's weight stays near
    # 1 (no held-out sample sits on the spike), so without a limit the spike goes through
    t, pts, v = _case(rng=1)
    lin = linear_field(pts, v, SHAPE)
    spike = t.heights.copy()
    free = np.ones(SHAPE, bool)
    free[pts[:, 0], pts[:, 1]] = False
    r0, c0 = 96, 128
    assert free[r0, c0] and lin.hull[r0, c0]
    spike[r0, c0] += 50.0
    info = {}
    loose = checked_blend(lin, spike, 1.0, info, remade=spike)
    g = info["gamma"]
    assert g > 0.9 and "detail_limit" not in info
    assert loose[r0, c0] - lin.heights[r0, c0] > 40.0
    info = {}
    out = checked_blend(lin, spike, 1.0, info, remade=spike, clip=3.0)
    limit = 3.0 * _departure_rms(lin)
    assert info["detail_limit"] == pytest.approx(limit, abs=1e-12)
    assert info["gamma"] == g
    d = (out - lin.heights)[lin.hull]
    assert np.abs(d).max() <= g * limit + 1e-12
    assert out[r0, c0] - lin.heights[r0, c0] == pytest.approx(g * limit, abs=1e-12)
    # cells whose detail is within the limit are those of the unlimited blend, to the bit
    within = np.abs(loose - lin.heights) < g * limit * 0.999
    np.testing.assert_array_equal(out[within], loose[within])
    # no check: no scale to limit by, the blend as asked
    info = {}
    np.testing.assert_array_equal(
        checked_blend(lin, spike, 0.5, info, clip=3.0), blend_detail(lin, spike, 0.5)
    )
    assert info == {}


def test_shading_and_photoclinometry_limit_their_detail_by_default():
    from simlunar.reconstruction.photoclinometry import PhotoclinometryOptions
    from simlunar.reconstruction.shading import ShadingOptions

    assert ShadingOptions().detail_clip == PhotoclinometryOptions().detail_clip == 3.0
    assert ShadingOptions(detail_clip=0).detail_clip == 0
    # through the reconstruction: the limit is recorded and holds
    from simlunar.reconstruction.base import Guide
    from simlunar.reconstruction.shading import shading

    t, pts, v = _case(rng=2)
    guide = Guide(t.image, light=t.light)
    res = shading(pts, v, SHAPE, guide=guide)
    lin = linear_field(pts, v, SHAPE)
    lim = res.info["detail_limit"]
    assert lim == pytest.approx(3.0 * _departure_rms(lin), rel=1e-12)
    assert np.abs(res.heights - lin.heights).max() <= res.info["gamma"] * lim + 1e-12
    off = shading(pts, v, SHAPE, guide=guide, options=ShadingOptions(detail_clip=0))
    assert "detail_limit" not in off.info
