"""The incremental gray-code decoder applies OpenCV's default thresholds (black 40, white 5,
``cv::structured_light::GrayCodePattern::Params``) exactly as the one-shot :func:`decode`."""

from __future__ import annotations

import numpy as np

from simlunar.scanner import gray_code as gc


def _stack_on_the_edges():
    W, H = 5, 3
    stack = gc.encode(W, H).astype(float)
    white, black = (a.astype(float) for a in gc.white_black(W, H))
    stack[2, 1, 1], stack[3, 1, 1] = 130.0, 125.0  # |pattern - inverse| = 5: reliable
    stack[2, 2, 2], stack[3, 2, 2] = 129.0, 125.0  # 4: unreliable
    black[0, 3] = white[0, 3] - 41.0  # contrast 41 > 40: lit
    black[0, 4] = white[0, 4] - 40.0  # contrast 40: shadow
    black[1, 0] = white[1, 0] - 9.0  # contrast 9: shadow (lit only above 40, not above 5)
    return (H, W), stack, white, black


def test_the_decoder_defaults_are_opencvs_as_decodes():
    shape, stack, white, black = _stack_on_the_edges()
    one_shot = gc.decode(stack, white, black, proj_shape=shape)
    dec = gc.GrayDecoder(shape, white.shape)
    for bit in range(dec.n_bits):
        dec.add_pair(bit, stack[2 * bit], stack[2 * bit + 1])
    dec.add_white_black(white, black)
    res = dec.result()
    np.testing.assert_array_equal(res.valid, one_shot.valid)
    np.testing.assert_array_equal(res.reliable, one_shot.reliable)
    assert res.reliable[1, 1, 1] and not res.reliable[1, 2, 2]
    assert res.lit[0, 3] and not res.lit[0, 4] and not res.lit[1, 0]
    assert (res.valid[1, 1], res.valid[2, 2], res.valid[0, 4]) == (True, False, False)
