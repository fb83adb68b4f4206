"""The bit-plane code's table by hand, the gray-code frames' light levels (off 0, on 1: the
projector's full range), and the stack helpers taking frames as lists."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from simlunar.scanner import bitcodes as bc
from simlunar.scanner.gray_code import GrayCodeOptions, GrayCoding


def test_the_gray_table_is_the_binary_reflected_code_and_read_only():
    # g(i) = i xor (i >> 1): 000 001 011 010 110 111 101 100
    table = bc.GRAY.table(3)
    np.testing.assert_array_equal(table, [0, 1, 3, 2, 6, 7, 5, 4])
    with pytest.raises(ValueError, match="read-only"):
        table[0] = 1  # the table is cached and shared by every caller


def test_gray_code_frames_switch_the_projector_fully_off_and_on():
    """An 8 x 4 projector: 3 column bits, 2 row bits, each a (pattern, inverse) pair, then
    white and black. The most significant column bit is off on columns 0-3 and on at 4-7
    (g(4..7) = 6, 7, 5, 4 all have the top bit set), its inverse the opposite; every level
    is exactly 0 or 1 (a pattern at 255/256 would be a dimmer projector than the white frame)."""
    frames = GrayCoding().patterns((4, 8))
    assert frames.shape == (2 * (3 + 2) + 2, 4, 8)
    assert set(np.unique(frames).tolist()) == {0.0, 1.0}
    np.testing.assert_array_equal(frames[0], np.tile([0, 0, 0, 0, 1, 1, 1, 1], (4, 1)))
    np.testing.assert_array_equal(frames[1], 1 - frames[0])
    np.testing.assert_array_equal(frames[-2], 1.0)  # white
    np.testing.assert_array_equal(frames[-1], 0.0)  # black


def test_inverses_by_linearity_take_a_list_of_frames():
    """inverse = white + black - pattern, pixel by pixel: 0.9 + 0.1 - 0.3 = 0.7."""
    white, black = np.full((2, 3), 0.9), np.full((2, 3), 0.1)
    inv = bc.inverses_by_linearity([np.full((2, 3), 0.3), np.full((2, 3), 0.8)], white, black)
    np.testing.assert_allclose(inv, [np.full((2, 3), 0.7), np.full((2, 3), 0.2)])


def test_interleave_takes_the_patterns_as_a_list_of_frames():
    """Captured patterns as a list (one frame each) and their inverses computed by linearity
    (white 1, black 0: 1 - p) as one stack, in OpenCV's pattern, inverse order."""
    p = [np.full((1, 2), 0.25), np.full((1, 2), 0.5)]
    out = bc.interleave(p, bc.inverses_by_linearity(p, np.ones((1, 2)), np.zeros((1, 2))))
    np.testing.assert_array_equal(out[:, 0, 0], [0.25, 0.75, 0.5, 0.5])


def test_the_exported_opencv_thresholds_are_the_frame_thresholds_at_255_full_scale():
    """OpenCV's decoder takes 8-bit thresholds: a frame-unit threshold t is round(255 t) there
    (full scale 1.0 is 255, halves rounded to even): 0.7 -> 178.5 -> 178, 0.1 -> 25.5 -> 26."""
    meta = GrayCoding(GrayCodeOptions(black_threshold=0.7, white_threshold=0.1)).export_meta(
        SimpleNamespace(n_col_bits=3, n_row_bits=2)
    )
    assert meta["opencv_black_threshold_8bit"] == 178
    assert meta["opencv_white_threshold_8bit"] == 26
    assert (meta["n_col_bits"], meta["n_row_bits"]) == (3, 2)


def test_interleave_takes_the_inverses_as_a_list_too_and_refuses_a_shape_mismatch():
    """Inverses captured frame by frame (a list) interleave like an array (they raised a
    TypeError from numpy's result_type); inverses of another shape are refused by name."""
    p = [np.full((1, 2), 0.25), np.full((1, 2), 0.5)]
    out = bc.interleave(p, [np.full((1, 2), 0.75), np.full((1, 2), 0.5)])
    np.testing.assert_array_equal(out[:, 0, 1], [0.25, 0.75, 0.5, 0.5])
    with pytest.raises(ValueError, match="differ in shape"):
        bc.interleave(p, [np.full((1, 2), 0.75)])
