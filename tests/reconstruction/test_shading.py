"""The image-anchored reconstruction: far better than linear on a lit Lambert surface, exact on
planes, linear when the image holds no shading, albedo cancelled by the co-located frame."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from simlunar.reconstruction import Guide, ShadingOptions, run_reconstruction
from simlunar.reconstruction._anchor import linear_field
from simlunar.reconstruction.shading import fallback_gamma, fuse_slopes
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


def test_the_check_pools_folds_at_the_sparse_end():
    # 250 x 400 cells at 1/2048: 48 samples, one split leaves fewer than 20 in the hull. The
    # check used to return 0 there (the result was linear exactly); pooled over the five
    # splits it weighs the detail on every sample held out once
    shape = (250, 400)
    t = lit_terrain(shape, rng=3)
    pts = jittered_samples(shape, 1 / 2048, rng=5)
    v = t.heights[pts[:, 0], pts[:, 1]]
    lin = run_reconstruction("linear", pts, v, shape).heights
    res = run_reconstruction("shading", pts, v, shape, guide=Guide(t.image))
    assert res.info["heldout_samples"] > 20 and res.info["gamma"] > 0.5
    assert _mse(res.heights, t.heights) * 1.5 < _mse(lin, t.heights)


def test_the_check_remakes_the_detail_without_the_held_out_samples(monkeypatch):
    import importlib

    mod = importlib.import_module("simlunar.reconstruction.shading")

    t, pts, v = _case(rng=4)
    seen = []
    original = mod._shading_detail

    def spy(lin, guide, o, **kw):
        seen.append({tuple(p) for p in np.asarray(lin.points).tolist()})
        return original(lin, guide, o, **kw)

    monkeypatch.setattr(mod, "_shading_detail", spy)
    res = run_reconstruction("shading", pts, v, SHAPE, guide=Guide(t.image))
    everything = {tuple(p) for p in np.asarray(pts, float).tolist()}
    assert seen[0] == everything  # the reconstruction's own detail: all samples
    remade = seen[1:]
    assert remade and res.info["heldout_samples"] >= 20
    for kept in remade:  # each fold's detail: made without its held-out fifth
        assert kept < everything and len(everything) - len(kept) >= len(everything) // 5


def test_frame_noise_reads_white_noise_and_not_ramps():
    from simlunar.reconstruction.shading import denoised_flat, frame_noise

    r, c = np.mgrid[0:300, 0:400]
    ramp = 1.0 + 0.001 * r - 0.0005 * c  # median 1.05
    assert frame_noise(ramp) < 1e-9
    noisy = ramp + np.random.default_rng(0).normal(0, 0.021, ramp.shape)
    assert frame_noise(noisy) == pytest.approx(0.02, rel=0.05)  # 0.021 / 1.05
    assert denoised_flat(ramp, 0.05) is ramp  # clean: untouched
    # blurred towards the target (a 1.1 px Gaussian for 0.02 -> 0.005): the noise divided by
    # about 3 (the small-sigma kernel does a little less than the continuous 4), the ramp kept
    blurred = denoised_flat(noisy, 0.005)
    resid = (blurred - ramp)[10:-10, 10:-10]
    assert abs(resid.mean()) < 1e-3 and resid.std() < 0.021 / 2.5


def test_the_noise_response_is_ndimages_convolution_to_the_bit(rng):
    from simlunar.reconstruction.shading import _NOISE_MASK, _noise_response

    for shape, scale in (((3, 3), 1.0), ((5, 8), 1e-3), ((120, 170), 1e4)):
        f = scale * rng.gamma(2.0, 1.0, shape)
        want = ndimage.convolve(f, _NOISE_MASK, mode="mirror")[1:-1, 1:-1]
        np.testing.assert_array_equal(_noise_response(f, _NOISE_MASK), want)


@pytest.mark.parametrize("snr", [1.0, 3.0])
def test_a_noisy_flat_is_denoised_before_the_ratio(snr):
    # a co-located frame buried in noise (a daylight flash much weaker than the sun: its
    # flash-on minus flash-off), dark albedo patches near zero: read raw (flat_noise 1: no
    # denoising) the ratio is noise and the result is linear at best; denoised to the sun
    # frame's level, the ratio keeps the albedo's large scales and the slopes read again
    shape = (200, 320)
    t = lit_terrain(shape, albedo_contrast=0.95, rng=4)
    flat = t.flat + np.random.default_rng(0).normal(0, np.median(t.flat) / snr, shape)
    guide = Guide(t.image, flat=flat)
    for density in (1 / 16, 1 / 256):
        pts = jittered_samples(shape, density, rng=1)
        v = t.heights[pts[:, 0], pts[:, 1]]
        lin = _mse(run_reconstruction("linear", pts, v, shape).heights, t.heights)
        raw = run_reconstruction("shading", pts, v, shape, guide=guide, options={"flat_noise": 1.0})
        den = run_reconstruction("shading", pts, v, shape, guide=guide)
        # measured: raw 1.00-1.24x, denoised 1.76-3.1x linear's samples
        assert lin / _mse(den.heights, t.heights) > 1.5
        assert lin / _mse(den.heights, t.heights) > 1.3 * lin / _mse(raw.heights, t.heights)
