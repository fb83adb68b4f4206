"""Itti-Koch saliency: the normalisation operator and the map's behaviour."""

from __future__ import annotations

import numpy as np

from simlunar.features import saliency
from simlunar.features.saliency import normalise


def test_normalise_promotes_single_peak():
    one = np.zeros((20, 20))
    one[10, 10] = 1.0
    many = np.zeros((20, 20))
    many[2::4, 2::4] = 1.0
    many[10, 10] = 1.0
    # one peak: no other maxima -> weight (1 - 0)^2 = 1
    np.testing.assert_allclose(normalise(one), one)
    # 25 equal peaks: mean of the other maxima is 1 -> map suppressed to 0
    assert normalise(many).max() == 0.0


def test_normalise_hand_computed():
    m = np.zeros((9, 9))
    m[1, 1], m[7, 7], m[1, 7] = 4.0, 2.0, 1.0
    # scaled to [0, 1]: peaks 1, 0.5, 0.25 -> mbar = 0.375 -> factor 0.625^2
    np.testing.assert_allclose(normalise(m)[1, 1], 0.625**2)


def test_constant_image_has_zero_saliency():
    assert saliency(np.full((64, 64), 0.4)).max() == 0.0


def test_salient_blob_wins(rng):
    img = 0.5 + 0.02 * rng.standard_normal((128, 160))
    img[60:72, 100:112] = 1.0
    s = saliency(img)
    blob = s[60:72, 100:112].mean()
    assert blob > 5 * s.mean()
    r, c = np.unravel_index(np.argmax(s), s.shape)
    assert abs(r - 66) < 12 and abs(c - 106) < 12


def test_colour_channel_sees_isoluminant_patch():
    # red patch on green background with the same intensity (r + g + b) / 3
    img = np.zeros((128, 128, 3))
    img[..., 1] = 0.6
    img[50:70, 50:70] = [0.6, 0.0, 0.0]
    s_rgb = saliency(img)
    assert s_rgb[55:65, 55:65].mean() > 3 * s_rgb.mean()
