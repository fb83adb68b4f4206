"""The reconstruction contract: the Guide's checks and normalisations (channels averaged, light
directions made unit, other suns checked by index), Reconstructed, and ``linear`` called
directly: exact on a plane inside the samples' hull, nearest or NaN outside it."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.reconstruction.base import Guide, LinearOptions, Reconstructed, linear


def test_a_colour_guide_is_averaged_over_its_channels():
    rgb = np.zeros((2, 3, 3))
    rgb[..., 0], rgb[..., 1], rgb[..., 2] = 0.3, 0.6, 0.9
    g = Guide(rgb)
    np.testing.assert_allclose(g.image, np.full((2, 3), 0.6))
    assert g.light is None and g.flat is None and g.others == ()
    assert g.spacing == 1.0 and g.frames == ("sun",)


def test_other_suns_are_checked_and_normalised():
    img = np.ones((3, 3))
    g = Guide(
        img, others=[(img * 2, [3, 0, 4])], frames=["sun", "flat", 7], spacing=np.float32(0.5)
    )
    ((other_img, other_light),) = g.others
    np.testing.assert_allclose(other_light, [0.6, 0.0, 0.8])
    assert not other_img.flags.writeable and not other_light.flags.writeable
    assert g.frames == ("sun", "flat", "7") and type(g.spacing) is float
    with pytest.raises(
        ValueError, match=r"^guide others\[1\] image has shape \(2, 3\), the image \(3, 3\)$"
    ):
        Guide(img, others=[(img, None), (np.ones((2, 3)), None)])
    with pytest.raises(ValueError, match=r"^others\[0\] light must be a non-zero 3-vector"):
        Guide(img, others=[(img, [1, 0])])


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"image": np.ones(4)}, r"^guide image must have shape \(rows, cols\), got \(4,\)$"),
        ({"image": np.ones((2, 2)), "flat": np.full((2, 2), np.inf)},
         "^guide flat contains NaN or infinite values$"),
        ({"image": np.ones((2, 2)), "light": [0, np.nan, 1]},
         r"^light must be a non-zero 3-vector \(d_row, d_col, up\)"),
        ({"image": np.ones((2, 2)), "spacing": float("nan")},
         "^guide spacing must be a finite number > 0, got nan$"),
    ],
)  # fmt: skip
def test_bad_guides(kw, message):
    with pytest.raises(ValueError, match=message):
        Guide(**kw)


def test_linear_is_exact_on_a_plane_inside_the_hull():
    # z = 2 r - c + 1 sampled at the four corners of a 5 x 6 grid: every cell is in the hull
    pts = np.array([[0, 0], [0, 5], [4, 0], [4, 5]])
    vals = 2.0 * pts[:, 0] - pts[:, 1] + 1
    out = linear(pts, vals, (5, 6))
    assert isinstance(out, Reconstructed) and out.info == {}
    r, c = np.mgrid[0:5, 0:6]
    np.testing.assert_allclose(out.heights, 2.0 * r - c + 1, atol=1e-12)


def test_linear_outside_the_hull_nearest_or_nan():
    pts = np.array([[1, 1], [1, 3], [3, 1]])  # the triangle's hull leaves (4, 4) outside
    vals = np.array([1.0, 2.0, 3.0])
    near = linear(pts, vals, (5, 5)).heights
    assert near[4, 0] == 3.0 and near[0, 4] == 2.0 and near[0, 0] == 1.0  # the nearest sample
    nan = linear(pts, vals, (5, 5), options=LinearOptions(outside="nan")).heights
    assert np.isnan(nan[4, 4]) and np.isnan(nan[0, 0])
    assert nan[1, 1] == 1.0 and nan[2, 2] == pytest.approx(2.5)  # midpoint of (1, 3)-(3, 1)
    assert LinearOptions().outside == "nearest"
