"""Shading calibration from the samples and the image alone: planted gain and azimuth,
heights against depths, the explained-variance share, and the in-hull pitfall."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.reconstruction.calibration import (
    CalibrationOptions,
    calibrate,
    valid_pixels,
)
from simlunar.reconstruction.integrate import central_gradient
from simlunar.reconstruction.synthetic import fbm_heights, jittered_samples, lit_terrain

SHAPE = (160, 224)


def _samples(h, density=1 / 64, rng=3):
    pts = jittered_samples(h.shape, density, rng=rng)
    return pts, h[pts[:, 0], pts[:, 1]]


def test_recovers_a_planted_linear_shading_model():
    # the image IS eq. 3.5 on a smooth surface: I = a + b . grad h, with b planted
    h, _, _ = fbm_heights(SHAPE, beta=4.5, slope_rms=0.2, rng=1)
    gr, gc = central_gradient(h)
    a0, b0 = 0.5, np.array([-0.15, 0.25])
    image = a0 + b0[0] * gr + b0[1] * gc
    assert 0.02 < image.min() and image.max() < 0.98  # nothing shadowed or saturated
    pts, v = _samples(h)
    cal = calibrate(image, pts, v)
    assert cal.b == pytest.approx(b0, rel=0.1)  # within 10 % of the planted gain
    assert cal.a == pytest.approx(a0, abs=0.01)
    assert cal.azimuth_deg == pytest.approx(np.degrees(np.arctan2(0.25, -0.15)), abs=3.0)
    assert cal.share > 0.9 and cal.heldout_share > 0.85
    np.testing.assert_allclose(np.hypot(*cal.direction), 1.0)


@pytest.mark.parametrize("azimuth", [40.0, 200.0])
def test_lambert_render_gives_gain_and_sun_azimuth_for_heights_and_depths(azimuth):
    # Lambert, constant albedo rho: I = rho (s_up - s_h . grad h) / |n|
    #                                  ~ rho s_up - rho s_h . grad h
    t = lit_terrain(SHAPE, elevation_deg=30.0, azimuth_deg=azimuth, beta=4.5, slope_rms=0.15,
                    rng=2)  # fmt: skip
    rho = float(t.albedo.mean())
    assert np.ptp(t.albedo) == 0
    pts, v = _samples(t.heights)
    cal_h = calibrate(t.image, pts, v)
    sun_h = t.light[:2] / np.hypot(*t.light[:2])
    # heights: the image brightens towards -s_h; |b| = rho |s_h|
    assert cal_h.direction @ -sun_h > np.cos(np.radians(3.0))
    assert cal_h.gain == pytest.approx(rho * np.hypot(*t.light[:2]), rel=0.15)
    # depths (values negated): the same fit with b's sign flipped
    cal_d = calibrate(t.image, pts, -v)
    np.testing.assert_allclose(cal_d.b, -cal_h.b, rtol=1e-9, atol=1e-12)
    assert cal_d.share == pytest.approx(cal_h.share)


def test_share_falls_with_albedo_and_is_zero_without_shading():
    t0 = lit_terrain(SHAPE, beta=4.0, albedo_contrast=0.0, rng=4)
    t1 = lit_terrain(SHAPE, beta=4.0, albedo_contrast=0.5, albedo_beta=3.0, rng=4)
    pts, v = _samples(t0.heights)
    s0 = calibrate(t0.image, pts, v).share
    s1 = calibrate(t1.image, pts, v).share
    assert s0 > 0.8 and s1 < s0 - 0.1
    const = calibrate(np.full(SHAPE, 0.4), pts, v)
    assert const.share == 0.0 and const.gain == 0.0 and np.isnan(const.azimuth_deg)
    # pure noise: held out, nothing is explained
    noise = 0.4 + 0.05 * np.random.default_rng(0).normal(size=SHAPE)
    assert calibrate(noise, pts, v).heldout_share < 0.05


def test_plane_samples_explain_nothing():
    r, c = np.mgrid[0 : SHAPE[0], 0 : SHAPE[1]]
    plane = 0.2 * r - 0.1 * c
    pts, v = _samples(plane)
    # the slopes of a plane do not vary (but where the blur's mirror bends them at the edges)
    cal = calibrate(0.5 + 0.01 * np.sin(r / 5.0), pts, v)
    assert cal.share < 0.05 and cal.heldout_share < 0.05


def test_fit_stays_inside_the_hull():
    # samples on the left half only: the nearest-filled right half must not enter the fit
    h, _, _ = fbm_heights(SHAPE, beta=4.5, slope_rms=0.2, rng=5)
    gr, gc = central_gradient(h)
    image = 0.5 + 0.2 * gr - 0.1 * gc
    pts, v = _samples(h)
    left = pts[:, 1] < SHAPE[1] // 2
    cal = calibrate(image, pts[left], v[left])
    assert cal.b == pytest.approx([0.2, -0.1], rel=0.1)
    assert cal.n_pixels < 0.5 * SHAPE[0] * SHAPE[1]


def test_valid_pixels_and_options():
    img = np.array([[0.0, 0.5], [1.0, 0.99]])
    np.testing.assert_array_equal(valid_pixels(img), [[False, True], [False, True]])
    with pytest.raises(ValueError, match="sigma_pitch"):
        CalibrationOptions(sigma_pitch=0)
    with pytest.raises(ValueError, match="shadow"):
        CalibrationOptions(shadow=1.0)
    with pytest.raises(ValueError, match="valid has shape"):
        calibrate(np.zeros((4, 4)), [[0, 0], [3, 3], [0, 3]], [0.0, 1.0, 2.0], linear=None,
                  valid=np.ones((5, 5), bool))  # fmt: skip


def test_a_fit_whose_held_out_share_cannot_be_formed_is_not_used():
    # the planted model of the first test, with all but a 40 x 40 corner of the image in shadow
    # (invalid) and sparse samples: too few blurred cells for the checkerboard check
    h, _, _ = fbm_heights(SHAPE, beta=4.5, slope_rms=0.2, rng=1)
    gr, gc = central_gradient(h)
    image = 0.5 - 0.15 * gr + 0.25 * gc
    valid = np.zeros(SHAPE, bool)
    valid[:40, :40] = True
    pts, v = _samples(h, density=1 / 256)
    cal = calibrate(image, pts, v, valid=valid)
    assert cal.gain > 0 and cal.share > 0.5  # the in-sample fit explains the few cells...
    assert np.isnan(cal.heldout_share)  # ...but cannot be checked
    assert cal.usable_share == 0.0
    # checked, the usable share is the held-out one, never above the in-sample one
    full = calibrate(image, pts, v)
    assert np.isfinite(full.heldout_share)
    assert full.usable_share == min(full.heldout_share, full.share)
