"""Per-bit gray-code errors: flipped bits located, stripe edges left out, the filter definition."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner import gray_code as gc
from simlunar.scanner import gray_errors as ge


def test_bit_errors_locate_flipped_bits():
    W, H = 20, 10
    stack = gc.encode(W, H)
    w, b = gc.white_black(W, H)
    stack[[0, 1]] = stack[[1, 0]]  # swap MSB pattern and inverse: flips bit 0 everywhere
    stack[6, 3, 4], stack[7, 3, 4] = stack[7, 3, 4], stack[6, 3, 4]  # flip bit 3 at (3, 4)
    res = gc.decode(stack, w, b, proj_shape=(H, W))
    rows, cols = np.mgrid[0:H, 0:W]
    err = ge.bit_errors(res, cols, rows)
    assert err.shape == (5 + 4, H, W)
    assert err[0].all()
    assert np.argwhere(err[3]).tolist() == [[3, 4]]
    assert not err[[1, 2, 4, 5, 6, 7, 8]].any()
    rates = ge.bit_error_rates(err, np.ones((H, W), bool))
    np.testing.assert_allclose(rates[:4], [1.0, 0, 0, 1 / (W * H)])


def test_stable_bits_exclude_stripe_edges():
    W, H = 8, 4
    rows, cols = np.mgrid[0:H, 0:W]
    st = ge.stable_bits(cols, rows, 3, 2, margin=1)
    # MSB of columns changes between columns 3 and 4, so the 3x3 window excludes columns 3
    # and 4; columns 0 and 7 touch the border (no correspondence outside)
    np.testing.assert_array_equal(st[0, 1], [False, True, True, False, False, True, True, False])
    # image borders: the window is padded with 'no correspondence', so borders are excluded
    assert not st[:, 0].any() and not st[:, :, 0].any()
    errs = np.zeros((5, H, W), bool)
    errs[0, 1, 1] = True
    rates = ge.bit_error_rates(errs, st)
    assert rates[0] == pytest.approx(1 / st[0].sum())


def test_stable_bits_equals_min_max_filter_definition():
    from scipy import ndimage

    rng = np.random.default_rng(2)
    col = np.cumsum(rng.random((30, 45)) * 0.8, axis=1).astype(int)
    row = np.cumsum(rng.random((30, 45)) * 0.6, axis=0).astype(int)
    col[rng.random(col.shape) < 0.05] = -1
    for margin in (0, 1, 2):
        size = 2 * margin + 1
        tb = np.concatenate(
            [gc.bit_planes(np.clip(col, 0, None), 6), gc.bit_planes(np.clip(row, 0, None), 5)]
        )
        has = ndimage.minimum_filter(
            ((col >= 0) & (row >= 0)).astype(np.int8), size=size, mode="constant"
        )
        want = np.stack(
            [
                (
                    ndimage.minimum_filter(b, size=size, mode="nearest")
                    == ndimage.maximum_filter(b, size=size, mode="nearest")
                )
                & (has > 0)
                for b in tb
            ]
        )
        np.testing.assert_array_equal(ge.stable_bits(col, row, 6, 5, margin=margin), want)
