"""The image-anchored reconstruction: far better than linear on a lit Lambert surface, exact on
planes, linear when the image holds no shading, albedo cancelled by the co-located frame."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from simlunar.reconstruction import Guide, ShadingOptions, run_reconstruction
from simlunar.reconstruction._anchor import linear_field
from simlunar.reconstruction.shading import blend_detail, checked_blend, fallback_gamma, fuse_slopes
from simlunar.reconstruction.synthetic import jittered_samples, lit_terrain

SHAPE = (192, 256)


def _mse(a, b):
    return float(np.mean((a - b) ** 2))


def _case(density=1 / 256, **kw):
    t = lit_terrain(SHAPE, **kw)
    pts = jittered_samples(SHAPE, density, rng=7)
    return t, pts, t.heights[pts[:, 0], pts[:, 1]]


@pytest.mark.parametrize("seed", [1, 2])
def test_lambert_surface_far_better_than_linear(seed):
    # fBm (beta 3.2), constant albedo, 30 deg sun, one sample per 256 cells
    t, pts, v = _case(elevation_deg=30.0, azimuth_deg=40.0, rng=seed)
    lin = run_reconstruction("linear", pts, v, SHAPE).heights
    res = run_reconstruction("shading", pts, v, SHAPE, guide=Guide(t.image, light=t.light))
    assert _mse(res.heights, t.heights) * 3.0 < _mse(lin, t.heights)  # at least 3x lower MSE
    # the samples are kept exactly
    np.testing.assert_allclose(res.heights[pts[:, 0], pts[:, 1]], v, atol=1e-9)
    assert res.info["gamma"] == 1.0 and res.info["frames"] == "sun"
    assert res.info["shading_share"] > 0.6
    assert res.info["light_axis_error_deg"] < 5.0


def test_depths_are_reconstructed_as_negated_heights():
    t, pts, v = _case(elevation_deg=30.0, rng=3)
    g = Guide(t.image)
    h = run_reconstruction("shading", pts, v, SHAPE, guide=g)
    d = run_reconstruction("shading", pts, -v, SHAPE, guide=g)
    np.testing.assert_allclose(d.heights, -h.heights, atol=1e-9 * np.abs(v).max())
    assert abs((d.info["azimuth_deg"] - h.info["azimuth_deg"]) % 360 - 180) < 1e-6


def test_a_lit_plane_is_reproduced_exactly():
    r, c = np.mgrid[0 : SHAPE[0], 0 : SHAPE[1]]
    plane = 3.0 + 0.2 * r - 0.35 * c
    pts = jittered_samples(SHAPE, 1 / 256, rng=1)
    v = plane[pts[:, 0], pts[:, 1]]
    # Lambert under a 30 deg sun: a plane is uniformly lit
    s = np.array([0.6, 0.5, 0.5])
    img = np.full(SHAPE, 0.5 * (s[2] - 0.2 * s[0] + 0.35 * s[1]) / np.sqrt(1 + 0.2**2 + 0.35**2))
    out = run_reconstruction("shading", pts, v, SHAPE, guide=Guide(img)).heights
    np.testing.assert_allclose(out, plane, rtol=0, atol=1e-9 * np.abs(plane).max())
    # the integration and re-anchoring themselves: the plane's slopes give the plane
    lin = linear_field(pts, v, SHAPE)
    fused = fuse_slopes(lin, np.full(SHAPE, 0.2), np.full(SHAPE, -0.35), 1.0,
                        along=(0.6, 0.5), across_weight=0.05)  # fmt: skip
    np.testing.assert_allclose(fused, plane, rtol=0, atol=1e-9 * np.abs(plane).max())


@pytest.mark.parametrize("kind", ["constant", "noise"])
def test_an_image_without_shading_gives_linear(kind):
    _, pts, v = _case(rng=4)
    img = np.full(SHAPE, 0.4)
    if kind == "noise":  # no shading, only albedo-like noise at 10 % of the mean
        img = img * (1 + 0.1 * np.random.default_rng(0).normal(size=SHAPE))
    lin = run_reconstruction("linear", pts, v, SHAPE).heights
    res = run_reconstruction("shading", pts, v, SHAPE, guide=Guide(img))
    assert np.abs(res.heights - lin).max() <= 0.01 * np.ptp(lin)
    assert res.info["gamma"] == 0.0


def test_albedo_ratio_cancels_a_planted_albedo():
    kw = dict(elevation_deg=50.0, azimuth_deg=-60.0, rng=5)
    plain, pts, v = _case(**kw)
    spotted, _, _ = _case(albedo_contrast=0.6, albedo_beta=2.0, **kw)
    assert np.ptp(spotted.albedo) > 0.5 * spotted.albedo.mean()
    ref = run_reconstruction("shading", pts, v, SHAPE, guide=Guide(plain.image))
    ratio = run_reconstruction(
        "shading", pts, v, SHAPE, guide=Guide(spotted.image, flat=spotted.flat)
    )
    raw = run_reconstruction("shading", pts, v, SHAPE, guide=Guide(spotted.image))
    e_ref, e_ratio, e_raw = (_mse(x.heights, plain.heights) for x in (ref, ratio, raw))
    assert ratio.info["frames"] == "sun+camera"
    assert e_ratio < 1.1 * e_ref  # the ratio sees the constant-albedo render's shading
    assert e_ratio * 2.0 < e_raw  # and is far better than the spotted image alone
    assert ratio.info["shading_share"] > raw.info["shading_share"]


def test_photometric_stereo_with_a_second_sun():
    kw = dict(elevation_deg=35.0, azimuth_deg=0.0, rng=6)
    t1, pts, v = _case(**kw)
    t2, _, _ = _case(**{**kw, "azimuth_deg": 90.0})
    one = run_reconstruction("shading", pts, v, SHAPE, guide=Guide(t1.image))
    two = run_reconstruction(
        "shading", pts, v, SHAPE, guide=Guide(t1.image, others=((t2.image, t2.light),))
    )
    assert two.info["frames"].startswith("sun+sun2")  # (+ their ratio "sun/sun2")
    assert _mse(two.heights, t1.heights) < _mse(one.heights, t1.heights)
    # a second frame from nearly the same azimuth: the raw frames add no direction, their
    # ratio (noise-free here) does; in any case no worse than one frame
    t3, _, _ = _case(**{**kw, "azimuth_deg": 3.0})
    near = run_reconstruction(
        "shading", pts, v, SHAPE, guide=Guide(t1.image, others=((t3.image, t3.light),))
    )
    assert _mse(near.heights, t1.heights) <= 1.05 * _mse(one.heights, t1.heights)


def test_fallback_rule():
    o = ShadingOptions(share_lo=0.1, share_hi=0.5, gamma_max=0.8)
    assert fallback_gamma(0.05, o) == 0.0
    assert fallback_gamma(0.3, o) == pytest.approx(0.4)
    assert fallback_gamma(0.9, o) == 0.8
    assert fallback_gamma(float("nan"), o) == 0.0
    with pytest.raises(ValueError, match="share_hi must be > share_lo"):
        ShadingOptions(share_lo=0.5, share_hi=0.4)


def test_needs_the_guide_and_its_grid():
    with pytest.raises(ValueError, match="needs the guide"):
        run_reconstruction("shading", [[0, 0], [1, 1], [0, 1]], [0.0, 1.0, 2.0], (4, 4))
    with pytest.raises(ValueError, match="guide image has shape"):
        run_reconstruction("shading", [[0, 0], [1, 1], [0, 1]], [0.0, 1.0, 2.0], (4, 4),
                           guide=Guide(np.zeros((5, 4))))  # fmt: skip


def test_two_suns_cancel_albedo_without_a_flat():
    # spotted albedo, no co-located frame: the ratio of the two sun frames is albedo-free
    kw = dict(elevation_deg=45.0, rng=5, albedo_contrast=0.6, albedo_beta=2.0)
    t1, pts, v = _case(azimuth_deg=0.0, **kw)
    t2, _, _ = _case(azimuth_deg=90.0, **kw)
    one = run_reconstruction("shading", pts, v, SHAPE, guide=Guide(t1.image))
    two = run_reconstruction(
        "shading", pts, v, SHAPE, guide=Guide(t1.image, others=((t2.image, t2.light),))
    )
    assert "sun/sun2" in two.info["frames"]
    assert _mse(two.heights, t1.heights) * 2.0 < _mse(one.heights, t1.heights)
    # with the flat as well: photometric stereo on albedo-free ratios, far better still
    both = run_reconstruction(
        "shading", pts, v, SHAPE,
        guide=Guide(t1.image, flat=t1.flat, others=((t2.image, t2.light),)),
    )  # fmt: skip
    assert both.info["frames"] == "sun+sun2+camera"
    assert _mse(both.heights, t1.heights) * 3.0 < _mse(two.heights, t1.heights)


def test_float_sample_positions():
    # projected sensor points are not on cells: the re-anchoring interpolates bilinearly
    t, pts, _ = _case(elevation_deg=30.0, rng=8)
    fpts = np.clip(pts + np.random.default_rng(0).uniform(-0.4, 0.4, pts.shape), 0, None)
    fpts = np.minimum(fpts, np.array(SHAPE) - 1.0)
    v = ndimage.map_coordinates(t.heights, fpts.T, order=1)
    lin = run_reconstruction("linear", fpts, v, SHAPE).heights
    res = run_reconstruction("shading", fpts, v, SHAPE, guide=Guide(t.image))
    assert np.isfinite(res.heights).all()
    assert _mse(res.heights, t.heights) * 2.0 < _mse(lin, t.heights)


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
