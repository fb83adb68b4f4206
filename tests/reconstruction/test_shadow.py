"""The shadow mask read from the frames alone, and shadows leaving the calibration."""

from __future__ import annotations

import inspect

import numpy as np
import pytest
from scipy import ndimage

from simlunar.reconstruction import Guide
from simlunar.reconstruction.calibration import calibrate
from simlunar.reconstruction.integrate import central_gradient
from simlunar.reconstruction.photoclinometry import PhotoclinometryOptions, photoclinometry
from simlunar.reconstruction.shading import ShadingOptions, shading, shading_frames, shadow_masks
from simlunar.reconstruction.shadow import (
    ShadowOptions,
    _bilinear,
    _block_percentiles,
    local_lit_level,
    shadow_mask,
)
from simlunar.reconstruction.synthetic import (
    fbm_heights,
    jittered_samples,
    lambert,
    lit_terrain,
    sun,
)

SHAPE = (96, 128)


def _plane_frames(elevation_deg=5.0, band=slice(40, 52)):
    """A plane tilted 3 deg towards a 5 deg sun (Lambert, albedo 0.8) with a cast-shadow band
    of rows ``band``: the sun frame there is the interreflected light, 0.2 % of the lit level;
    the co-located frame (nadir light) lights it all."""
    slope = np.tan(np.radians(3.0))
    s = sun(elevation_deg, 0.0)  # towards +row; the plane falls along +row: it faces the sun
    hr = np.full(SHAPE, -slope)
    hc = np.zeros(SHAPE)
    lit = lambert(hr, hc, s, 0.8)
    image = lit.copy()
    image[band] = 0.002 * lit[band]
    flat = lambert(hr, hc, (0.0, 0.0, 1.0), 0.8)
    truth = np.zeros(SHAPE, bool)
    truth[band] = True
    return image, flat, truth


def test_a_cast_shadow_band_on_a_plane_is_masked_exactly():
    image, flat, band = _plane_frames()
    # hand value: the lit level is n . s = (sin 5 + tan 3 cos 5) / sqrt(1 + tan^2 3) x 0.8
    lit = 0.8 * (np.sin(np.radians(5)) + np.tan(np.radians(3)) * np.cos(np.radians(5)))
    lit /= np.sqrt(1 + np.tan(np.radians(3)) ** 2)
    assert image[0, 0] == pytest.approx(lit, rel=1e-12)
    np.testing.assert_allclose(local_lit_level(image)[:30], lit, rtol=1e-12)
    np.testing.assert_array_equal(shadow_mask(image), band)
    np.testing.assert_array_equal(shadow_mask(image, flat), band)
    grown = shadow_mask(image, options=ShadowOptions(margin=2))
    assert grown.sum() == band.sum() + 4 * SHAPE[1]  # two rows each side
    assert not shadow_mask(image, options=ShadowOptions(lit_fraction=0.0)).any()


def test_the_flash_frame_tells_shadow_from_dark_albedo():
    image, flat, band = _plane_frames()
    # a dark patch of albedo 1 % of the rest, in both frames: dark in the sun frame, but the
    # flash frame is dark there too, so sun / flash keeps its level: not a shadow
    dark = np.zeros(SHAPE, bool)
    dark[70:80, 20:60] = True
    image[dark] *= 0.01
    flat[dark] *= 0.01
    alone = shadow_mask(image)
    assert alone[dark].all()  # the sun frame alone cannot tell
    lit_by_flash = ShadowOptions(flat_guard=0.005)  # the flash frame lights the dark patch
    both = shadow_mask(image, flat, options=lit_by_flash)
    assert not both[dark].any()
    np.testing.assert_array_equal(both, band)
    # with the default guard (5 % of the flash frame's median) the patch is unlit by the
    # flash too, and the sun frame decides
    assert shadow_mask(image, flat)[dark].all()
    # where the flash frame is unlit too (under flat_guard of its median) the sun frame decides
    flat[band] = 0.0
    np.testing.assert_array_equal(shadow_mask(image, flat, options=lit_by_flash)[band], True)


def test_the_lit_level_is_local():
    # a large-scale change of the lit level (the left half 20x brighter): a shadow in the dim
    # half at 1 % of its lit level, 0.05 % of the image's, is found; the dim half is not shadow
    image = np.full(SHAPE, 0.05)
    image[:, :64] = 1.0
    image[10:20, 90:110] = 0.0005
    m = shadow_mask(image)
    assert m[10:20, 90:110].all()
    assert m.sum() == 200
    level = local_lit_level(image)
    np.testing.assert_allclose(level[:, :16], 1.0)
    np.testing.assert_allclose(level[:, -16:], 0.05)


def test_mask_input_errors():
    with pytest.raises(ValueError, match="2-D"):
        shadow_mask(np.zeros(5))
    with pytest.raises(ValueError, match="flat has shape"):
        shadow_mask(np.ones((4, 4)), np.ones((4, 5)))
    with pytest.raises(ValueError, match="2-D"):
        local_lit_level(np.zeros((0, 3)))
    with pytest.raises(ValueError):
        ShadowOptions(lit_fraction=1.0)
    # a black frame has no lit level: nothing is called shadow
    assert not shadow_mask(np.zeros((8, 8))).any()


def test_the_mask_reads_the_frames_only():
    # by signature: frames and options, no truth
    assert list(inspect.signature(shadow_mask).parameters) == ["sun", "flat", "options"]
    assert list(inspect.signature(shadow_masks).parameters) == ["guide", "options", "flat"]
    # by behaviour: a 30 deg sun on gentle terrain casts no shadow (the truth's shadow map is
    # empty), but the image is given a dark band; the reconstructions mask the image's band,
    # so a mask made from the truth (empty) would fail here
    t = lit_terrain(SHAPE, elevation_deg=30.0, slope_rms=0.1, rng=4)
    _, hr, hc = fbm_heights(SHAPE, slope_rms=0.1, rng=np.random.default_rng(4))
    assert (lambert(hr, hc, t.light) > 0).all()  # no attached shadow in the truth
    image = t.image.copy()
    image[:, 30:38] *= 0.005
    pts = jittered_samples(SHAPE, 1 / 32, rng=1)
    values = t.heights[pts[:, 0], pts[:, 1]]
    guide = Guide(image, light=t.light)
    res = shading(pts, values, SHAPE, guide=guide)
    assert res.info["shadow_share"] == pytest.approx(8 / SHAPE[1])
    ((_, _, valid),) = shading_frames(guide, ShadingOptions(), linear=None)
    assert not valid[:, 30:38].any() and valid[:, :30].all()
    # an altered truth (other heights between the samples) changes nothing the mask sees
    altered = t.heights + 5.0 * (np.arange(SHAPE[1]) % 7 == 3)[None, :]
    altered[pts[:, 0], pts[:, 1]] = values
    res2 = shading(pts, altered[pts[:, 0], pts[:, 1]], SHAPE, guide=guide)
    np.testing.assert_array_equal(res2.heights, res.heights)


def _planted(shadow_rows=None):
    """The image IS eq. 3.5 on a smooth surface (I = a + b . grad h), optionally with a band of
    rows in cast shadow (the image 0.1 % of its level there)."""
    h, _, _ = fbm_heights((160, 224), beta=4.5, slope_rms=0.2, rng=1)
    gr, gc = central_gradient(h)
    image = 0.5 - 0.15 * gr + 0.25 * gc
    if shadow_rows is not None:
        image[shadow_rows] *= 0.001
    pts = jittered_samples(h.shape, 1 / 64, rng=3)
    return image, h, pts, h[pts[:, 0], pts[:, 1]]


def test_the_calibration_gain_is_unchanged_by_a_masked_shadow_band():
    image0, h, pts, v = _planted()
    clean = calibrate(image0, pts, v, valid=np.ones(h.shape, bool))
    band = slice(40, 100)  # 60 of 160 rows: 37 % of the image, as under a polar sun
    image, *_ = _planted(band)
    mask = shadow_mask(image)
    assert mask[band].all() and mask.mean() == pytest.approx(60 / 160)
    masked = calibrate(image, pts, v, valid=~mask)
    # the lit rows alone give the planted model: gain and direction as without the band
    # (the planted azimuth atan2(0.25, -0.15) = 121 deg; the band's edges, blurred with the
    # fit's sigma of 4 cells, move the masked fit by under 3 deg)
    planted = np.degrees(np.arctan2(0.25, -0.15))
    assert masked.gain == pytest.approx(clean.gain, rel=0.03)
    assert masked.a == pytest.approx(clean.a, abs=0.01)
    assert masked.azimuth_deg == pytest.approx(planted, abs=3.0)
    assert masked.share > 0.9
    # without the mask the band's zeros enter the fit as slopes away from the light: the gain
    # is 3x too large, the azimuth 50 deg off and shading explains little
    unmasked = calibrate(image, pts, v, valid=np.ones(h.shape, bool))
    assert unmasked.gain > 2.0 * clean.gain
    assert abs(unmasked.azimuth_deg - planted) > 20.0
    assert unmasked.share < 0.3


@pytest.mark.parametrize("method", ["shading", "photoclinometry"])
def test_shadowed_pixels_leave_the_slope_field(method):
    # a 20 deg sun, constant albedo, a band of 20 rows in cast shadow: masked, the band's
    # slopes are linear's and the rest is read from the image (most of the image's gain
    # kept); unmasked, the band's zeros wreck the calibration and the result is linear
    t = lit_terrain(SHAPE, elevation_deg=20.0, slope_rms=0.08, beta=4.0, rng=6)
    pts = jittered_samples(SHAPE, 1 / 48, rng=2)
    values = t.heights[pts[:, 0], pts[:, 1]]
    image = t.image.copy()
    image[50:70, :] *= 0.003
    run, opts = (
        (shading, ShadingOptions)
        if method == "shading"
        else (photoclinometry, PhotoclinometryOptions)
    )

    def err(img, **kw):
        o = opts(heldout_check=False, shadow=0.0, **kw)  # only the frames' mask masks
        z = run(pts, values, SHAPE, guide=Guide(img, light=t.light), options=o).heights
        return float(np.mean((z - t.heights) ** 2))

    lin = float(np.mean((run(pts, values, SHAPE, guide=Guide(np.ones(SHAPE)), options=opts())
                         .heights - t.heights) ** 2))  # fmt: skip
    clean = err(t.image)
    masked = err(image)
    unmasked = err(image, shadow_lit=0.0)
    assert clean < 0.4 * lin  # the image helps here
    assert clean < masked < 0.7 * lin
    assert unmasked > 1.5 * masked


def test_a_shadow_wider_than_the_lit_window_is_masked_whole():
    # 60 rows of shadow: blocks (16 cells, pooled 3 x 3) wholly inside it take the nearest
    # lit block's level, so the shadow's middle is found too
    image = np.full((160, 64), 0.3)
    image[40:100] = 0.0003
    m = shadow_mask(image)
    assert m[40:100].all() and not m[:40].any() and not m[100:].any()
    np.testing.assert_allclose(local_lit_level(image), 0.3)


@pytest.mark.parametrize("block", [2, 5, 16])
@pytest.mark.parametrize("percentile", [90.0, 50.0, 12.5, 100.0])
def test_block_percentiles_are_numpys_to_the_bit(rng, block, percentile):
    """The compiled per-block percentile equals np.percentile on each full block and
    np.nanpercentile on blocks holding NaN or cut by the grid's edge, bit for bit (ties and a
    block with no finite pixel included)."""
    f = np.round(rng.gamma(2.0, 1.0, (37, 43)), 1)  # rounded: many ties
    f[rng.random(f.shape) < 0.2] = np.nan
    f[:block, :block] = np.nan  # one block with nothing finite
    nr, nc = -(-37 // block), -(-43 // block)
    got = _block_percentiles(f, block, nr, nc, float(np.true_divide(percentile, 100)))
    for i in range(nr):
        for j in range(nc):
            vals = f[i * block : (i + 1) * block, j * block : (j + 1) * block]
            if np.isnan(vals).all():
                assert np.isnan(got[i, j])
                continue
            want = np.nanpercentile(vals, percentile)
            finite = vals[np.isfinite(vals)]
            assert got[i, j] == want == np.percentile(finite, percentile), (i, j)


def test_block_level_interpolation_is_map_coordinates_to_the_bit(rng):
    level = rng.gamma(2.0, 1.0, (7, 11))
    rows, cols, b = 100, 170, 16
    rc = np.clip((np.arange(rows) + 0.5) / b - 0.5, 0, 6)
    cc = np.clip((np.arange(cols) + 0.5) / b - 0.5, 0, 10)
    rr, cg = np.meshgrid(rc, cc, indexing="ij")
    want = ndimage.map_coordinates(level, [rr, cg], order=1, mode="nearest")
    np.testing.assert_array_equal(_bilinear(level, rc, cc), want)
    one = rng.gamma(2.0, 1.0, (1, 1))  # a frame smaller than a block: one level everywhere
    z = np.zeros(5)
    np.testing.assert_array_equal(_bilinear(one, z, z), np.full((5, 5), one[0, 0]))


@pytest.mark.parametrize("unlit", [False, True])
def test_the_sun_frames_own_rule_decides_only_where_the_flash_does_not_light(rng, unlit):
    """With a flash frame the mask is the ratio's rule where it lights and the sun frame's rule
    elsewhere (computed only when some pixel is unlit)."""
    image = rng.gamma(3.0, 1.0, (64, 80))
    image[rng.random(image.shape) < 0.05] *= 0.001  # shadows
    flat = 1.0 + rng.gamma(3.0, 1.0, image.shape)
    if unlit:
        flat[10:30, 20:50] = 1e-6
    o = ShadowOptions()
    med = float(np.median(flat))
    lit = flat > o.flat_guard * med
    assert lit.all() != unlit
    ratio = np.where(lit, image / np.where(lit, flat, 1.0), np.nan)
    lvl = local_lit_level(image, o)
    own = (lvl > 0) & (image <= o.lit_fraction * lvl)
    lvl = local_lit_level(ratio, o)
    with np.errstate(invalid="ignore"):
        by_ratio = (lvl > 0) & (ratio <= o.lit_fraction * lvl) & lit
    assert by_ratio.any() and own.any()
    np.testing.assert_array_equal(shadow_mask(image, flat, options=o), np.where(lit, by_ratio, own))
