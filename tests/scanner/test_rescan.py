"""The rescan planners that rank a coded scan's own pixels (``low_contrast``)."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner import gray_code as gc
from simlunar.scanner.gray_code import GrayScan
from simlunar.scanner.rescan import SCAN_PLANNERS, low_contrast_pixels


def test_the_scan_planners_are_named():
    assert SCAN_PLANNERS == ("low_contrast",)


def _decode_of(contrast: np.ndarray, proj_shape=(2, 4)):
    """A gray-code decode of a camera that sees the projector pixel for pixel (camera shape =
    projector shape), each pixel lit with ``contrast`` (white - black), black 0.1."""
    H, W = proj_shape
    pats = gc.encode(W, H).astype(float)  # (pattern, inverse) pairs
    black = np.full((H, W), 0.1)
    frames = black + pats * contrast
    return gc.decode(frames, black + contrast, black, proj_shape=(H, W),
                     black_threshold=0.01, white_threshold=0.001)  # fmt: skip


def test_decode_keeps_the_contrast():
    c = np.array([[0.5, 0.2, 0.9, 0.05], [0.3, 0.7, 0.6, 0.4]])
    dec = _decode_of(c)
    assert dec.contrast.dtype == np.float32
    np.testing.assert_allclose(dec.contrast, c, rtol=1e-6)
    assert np.all(dec.col == np.arange(4)) and np.all(dec.row.T == np.arange(2))


def test_low_contrast_planner_picks_the_least_lit_projector_pixels():
    c = np.array([[0.5, 0.2, 0.9, 0.05], [0.3, 0.7, 0.6, 0.004]])
    dec = _decode_of(c)  # (1, 3) is below black_threshold 0.01: unlit, ranked last
    assert dec.col[1, 3] == -1 and [a[1, 3] for a in dec.decoded_index()] == [3, 1]
    g = GrayScan(decode=dec, cloud=None, depth=np.zeros(dec.proj_shape), renders=0, frames={})
    rc = low_contrast_pixels(g, 3, rng=0)
    assert rc.tolist() == [[0, 3], [0, 1], [1, 0]]  # contrasts 0.05, 0.2, 0.3
    everything = low_contrast_pixels(g, 8, rng=0)
    assert everything[-1].tolist() == [1, 3]
    with pytest.raises(ValueError, match=r"k must be in 1\.\.8"):
        low_contrast_pixels(g, 9, rng=0)


def test_low_contrast_planner_takes_the_dimmest_camera_pixel_of_a_projector_pixel():
    # two camera pixels decode to each projector column: the projector pixel's rank is the
    # lower contrast of the two (a wrongly decoded dim pixel corrupts the depth there)
    H, W = 2, 4
    pats = gc.encode(W, H).astype(float)
    cam = np.repeat(pats, 2, axis=2)  # camera (2, 8): pixels 2j, 2j+1 see column j
    c = np.array([[0.9, 0.8, 0.15, 0.9, 0.5, 0.6, 0.3, 0.35], [0.95] * 8])
    dec = gc.decode(cam * c, c, np.zeros_like(c), proj_shape=(H, W),
                    black_threshold=0.01, white_threshold=0.001)  # fmt: skip
    g = GrayScan(decode=dec, cloud=None, depth=np.zeros((H, W)), renders=0, frames={})
    # row 0 by the lower contrast of its two camera pixels: 0.15, 0.3, 0.5, 0.8
    assert low_contrast_pixels(g, 4, rng=0).tolist() == [[0, 1], [0, 3], [0, 2], [0, 0]]
