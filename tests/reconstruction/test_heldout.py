"""The held-out check: the detail's weight is the one that predicts left-out samples, near 1
for the truth's own detail and 0 for a detail against the surface."""

from __future__ import annotations

import numpy as np

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
