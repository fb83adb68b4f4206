import numpy as np
import pytest
from PIL import Image

from simlunar.imaging.png import auto_exposure, to_srgb8, write_png_preview


def test_srgb_encoding_matches_the_iec_formula():
    # IEC 61966-2-1: V = 1.055 L^(1/2.4) - 0.055 for L > 0.0031308, 12.92 L below
    lin = np.array([[0.0, 0.002, 0.18, 0.5, 1.0]])
    want = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055)
    got = to_srgb8(lin, exposure=1.0)
    np.testing.assert_array_equal(got, np.round(want * 255).astype(np.uint8))
    assert got[0, 3] == 188  # mid grey 0.5 -> 0.7354 -> 188


def test_auto_exposure_puts_a_low_contrast_median_at_middle_grey(rng):
    # uniform on [0, 7): median 3.5, 99th percentile 6.93 -> 0.18 / 3.5 < 0.9 / 6.93
    img = rng.random((200, 100)) * 7.0
    k = auto_exposure(img)
    assert np.median(img * k) == pytest.approx(0.18)
    assert np.percentile(img * k, 99) < 0.9
    assert auto_exposure(np.zeros((3, 3))) == 1.0


def test_auto_exposure_keeps_the_highlights_of_a_high_contrast_image(rng):
    # lognormal, sigma 2: the 99th percentile is e^(2 x 2.326) ~ 105 x the median, so middle grey
    # at the median would clip it; the 99th percentile goes to 0.9 instead
    img = rng.lognormal(0.0, 2.0, size=(300, 300))
    k = auto_exposure(img)
    assert np.percentile(img * k, 99) == pytest.approx(0.9)
    assert np.median(img * k) < 0.18


def test_a_lunar_like_render_is_not_washed_out(rng):
    # the quickstart render's spread (99th / 1st percentile about 2.1): the old rule (99th
    # percentile to 0.9) put its median at 211 / 255; middle grey is 118 / 255
    img = rng.uniform(0.42, 0.9, size=(64, 64))
    px = to_srgb8(img)
    assert 110 <= np.median(px) <= 125


def test_png_written_atomically_with_shape_and_nan_as_black(tmp_path, rng):
    img = rng.random((6, 8, 3)).astype(np.float32)
    img[0, 0] = np.nan
    p = write_png_preview(tmp_path / "p.png", img)
    px = np.asarray(Image.open(p))
    assert px.shape == (6, 8, 3) and px.dtype == np.uint8
    assert np.all(px[0, 0] == 0)
    g = write_png_preview(tmp_path / "g.png", img[..., 0], exposure=1.0)
    assert np.asarray(Image.open(g)).shape == (6, 8)
    assert sorted(x.name for x in tmp_path.iterdir()) == ["g.png", "p.png"]


def test_bad_inputs():
    with pytest.raises(ValueError, match="exposure"):
        to_srgb8(np.ones((2, 2)), exposure=-1.0)
    with pytest.raises(ValueError, match="rows, cols"):
        to_srgb8(np.ones((2, 2, 2)))
