"""Feature maps: parity with numpy / scikit-image references and hand-computed cases."""

from __future__ import annotations

import numpy as np
import pytest
import pywt
from skimage.filters.rank import entropy as sk_entropy

from simlunar.features import (
    FEATURES,
    entropy,
    feature_map,
    gradient,
    to_gray,
    to_uint8,
    wavelet,
    wavelet_levels,
)


def test_gradient_equals_numpy_gradient(rng):
    img = rng.random((23, 31))
    gy, gx = np.gradient(img)
    np.testing.assert_array_equal(gradient(img), np.hypot(gx, gy))


def test_gradient_hand_computed():
    # Ramp 3 c: central differences 3 inside, one-sided 3 at the borders too.
    img = np.tile(3.0 * np.arange(5), (4, 1))
    np.testing.assert_allclose(gradient(img), 3.0)
    # MATLAB gradient of [1 2 4 8]: [1, 1.5, 3, 4]
    np.testing.assert_allclose(
        gradient(np.array([[1, 2, 4, 8], [1, 2, 4, 8.0]])), [[1, 1.5, 3, 4]] * 2
    )


def test_rgb_uses_matlab_rgb2gray_weights():
    img = np.zeros((3, 3, 3))
    img[..., 0], img[..., 1], img[..., 2] = 1.0, 0.5, 0.25
    # MATLAB rgb2gray: 0.2989 R + 0.5870 G + 0.1140 B
    np.testing.assert_allclose(
        to_gray(img), 0.298936021293775 + 0.5 * 0.587043074451121 + 0.25 * 0.114020904255103
    )


@pytest.mark.parametrize("scale", ["minmax", "unit"])
def test_entropy_equals_skimage_rank_entropy(rng, scale):
    img = rng.random((40, 57)) ** 2
    img[10:20, 5:30] = 0.5  # flat patch: entropy 0 inside
    ours = entropy(img, scale=scale)
    # Reference: skimage rank entropy (log2, square footprint) on the symmetric-padded 8-bit
    # image, then cropped, which is MATLAB entropyfilt's definition.
    u8 = to_uint8(img, scale=scale)
    ref = sk_entropy(np.pad(u8, 4, mode="symmetric"), np.ones((9, 9), dtype=bool))[4:-4, 4:-4]
    np.testing.assert_allclose(ours, ref, atol=1e-12)
    assert ours[15, 17] == 0.0


def test_entropy_hand_computed():
    # Checkerboard of two levels: every 9x9 window holds 41 of one and 40 of the other.
    img = (np.indices((12, 12)).sum(axis=0) % 2).astype(float)
    p = np.array([41, 40]) / 81
    expected = -(p * np.log2(p)).sum()
    np.testing.assert_allclose(entropy(img)[4:8, 4:8], expected, atol=1e-12)
    assert entropy(np.full((10, 10), 0.3)).max() == 0.0


def test_to_uint8_unit_matches_im2uint8():
    np.testing.assert_array_equal(
        to_uint8(np.array([[-0.1, 0.0, 0.5, 1.0, 2.0]]), scale="unit"), [[0, 0, 128, 255, 255]]
    )


@pytest.mark.parametrize("shape", [(64, 64), (37, 50)])
def test_wavelet_levels_sum_to_detail_energy(rng, shape):
    img = rng.random(shape)
    maps = wavelet_levels(img, levels=3, boundary="periodic")
    coeffs = pywt.wavedec2(img, "db2", mode="periodization", level=3)
    for j, m in enumerate(maps, start=1):
        details = coeffs[-j]
        np.testing.assert_allclose(m.sum(), sum((d**2).sum() for d in details), rtol=1e-12)
    np.testing.assert_allclose(
        wavelet(img, levels=3, boundary="periodic"), np.sum(maps, axis=0), rtol=1e-12
    )
    # symmetric boundary = the periodic maps of the mirrored image, cropped
    mirrored = np.pad(img, ((0, shape[0]), (0, shape[1])), mode="symmetric")
    for m_sym, m_per in zip(
        wavelet_levels(img, levels=3), wavelet_levels(mirrored, levels=3, boundary="periodic")
    ):
        np.testing.assert_allclose(m_sym, m_per[: shape[0], : shape[1]], rtol=1e-12)
    np.testing.assert_allclose(
        wavelet(img, levels=3), np.sum(wavelet_levels(img, levels=3), axis=0)
    )


def test_wavelet_parseval_on_power_of_two_image(rng):
    # db2 is orthogonal: with periodization on a 64 x 64 image, the image energy equals the
    # approximation energy plus the detail energy, i.e. plus the sum of the wavelet map.
    img = rng.random((64, 64))
    approx = pywt.wavedec2(img, "db2", mode="periodization", level=4)[0]
    total = wavelet(img, levels=4, boundary="periodic").sum() + (approx**2).sum()
    np.testing.assert_allclose(total, (img**2).sum(), rtol=1e-10)


def test_wavelet_localises_energy():
    img = np.zeros((64, 64))
    img[:, 40:] = 1.0  # vertical step at column 40
    # symmetric borders add no false edge: with 3 levels (blocks up to 8 px) all the energy
    # sits in the blocks touching the step; with all levels the coarse blocks spread it wider
    w3 = wavelet(img, levels=3)
    assert w3[:, 32:48].sum() > (1 - 1e-12) * w3.sum()
    w = wavelet(img)
    assert w[:, 36:44].mean() > 100 * w[:, :8].mean()
    assert w[:, 32:48].sum() > 0.8 * w.sum()
    assert np.all(w >= 0)


@pytest.mark.parametrize("name", sorted(FEATURES))
def test_all_maps_shape_and_sign(rng, name):
    img = rng.random((33, 45, 3))
    m = feature_map(name, img)
    assert m.shape == (33, 45) and m.dtype == np.float64
    assert np.all(m >= 0) and np.all(np.isfinite(m))


def test_unknown_feature_lists_valid_names():
    with pytest.raises(
        ValueError, match="unknown feature 'sobel'; valid: gradient, entropy, wavelet, saliency"
    ):
        feature_map("sobel", np.zeros((4, 4)))


@pytest.mark.parametrize(
    ("image", "match"),
    [
        (np.array([[0.0, np.nan], [1.0, 2.0]]), "NaN"),
        (np.zeros((4, 4, 2)), "shape"),
        (np.zeros(5), "shape"),
    ],
)
def test_bad_images(image, match):
    with pytest.raises(ValueError, match=match):
        feature_map("gradient", image)


def test_entropy_bad_size():
    with pytest.raises(ValueError, match="odd"):
        entropy(np.zeros((5, 5)), size=4)


def _h(counts):
    p = np.asarray(counts, float) / 81.0
    return float(-(p * np.log2(p)).sum())


def test_entropy_matlab_parity_hand_computed():
    # entropyfilt(I) on a 2 x 2 double image, true(9), symmetric padding: every 9 x 9 window
    # holds the pixel's own row and column 5 times and the other row / column 4 times, so the
    # four pixels have weights 25, 20, 20, 16 (of 81).
    img = np.array([[0.3, 1.7], [-0.2, 76.6 / 255]])
    # im2uint8: 0.3 * 255 = 76.5 rounds half away from zero to 77 (numpy.rint gives 76);
    # 1.7 clips to 255, -0.2 to 0; 76.6 rounds to 77. No min-max rescaling.
    np.testing.assert_array_equal(to_uint8(img, scale="unit"), [[77, 255], [0, 77]])
    got = entropy(img, scale="unit")
    expected = [
        [_h([25 + 16, 20, 20]), _h([25, 20 + 20, 16])],
        [_h([25, 20 + 20, 16]), _h([25 + 16, 20, 20])],
    ]
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    # without rescaling, close values share one bin: zero entropy (min-max would split them)
    flat = np.array([[0.100, 0.101], [0.102, 0.102]])
    np.testing.assert_array_equal(entropy(flat, scale="unit"), 0.0)
    assert entropy(flat, scale="minmax").min() > 1.0
