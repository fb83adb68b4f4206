"""Bit-plane codes: the gray code's words by hand, the table inversion every code decodes by,
a code that is not a permutation refused, another code through the same stack and decoder."""

from __future__ import annotations

import numpy as np
import pytest

from simlunar.scanner import bitcodes as bc
from simlunar.scanner import gray_code as gc


def _skip_gray(values):
    """A permutation of every n-bit range other than gray or binary: ``x ^ (x >> 2)``."""
    v = np.asarray(values, np.int64)
    return v ^ (v >> 2)


def _squares(values):
    return np.asarray(values, np.int64) ** 2


def test_gray_words_by_hand_and_neighbours_differ_in_one_bit():
    assert bc.GRAY.words(np.arange(8)).tolist() == [0, 1, 3, 2, 6, 7, 5, 4]
    planes = bc.GRAY.planes(np.arange(8), 3)
    assert planes[:, 5].tolist() == [1, 1, 1]  # gray(5) = 7
    assert np.all((planes[:, 1:] != planes[:, :-1]).sum(axis=0) == 1)


@pytest.mark.parametrize("n", [1, 3, 10])
def test_index_inverts_the_planes_for_every_word(n):
    x = np.arange(1 << n)
    np.testing.assert_array_equal(bc.GRAY.index(bc.GRAY.planes(x, n)), x)
    np.testing.assert_array_equal(bc.gray_to_binary(bc.bit_planes(x, n)), x)
    table = bc.GRAY.table(n)
    assert not table.flags.writeable
    np.testing.assert_array_equal(np.sort(table), x)


def test_index_takes_bool_planes_and_a_single_pixel():
    planes = np.array([True, False, True])  # gray 101 = 6
    assert int(bc.GRAY.index(planes)) == 6


def test_a_code_that_is_not_a_permutation_is_refused():
    with pytest.raises(ValueError, match="the squares code is not a permutation of the 3-bit"):
        bc.BitCode("squares", _squares).table(3)


def test_another_code_goes_through_the_same_stack_and_decoder():
    code = bc.BitCode("skip-gray", _skip_gray)
    W, H = 12, 5
    stack = bc.encode(W, H, code).astype(float) / 255
    white, black = np.ones((H, W)), np.zeros((H, W))
    dec = gc.decode(stack, white, black, proj_shape=(H, W), black_threshold=0.5,
                    white_threshold=0.5, code=code)  # fmt: skip
    rr, cc = np.mgrid[0:H, 0:W]
    assert dec.valid.all() and dec.code is code
    np.testing.assert_array_equal(dec.col, cc)
    np.testing.assert_array_equal(dec.row, rr)
    # the same stack read as gray code names other columns: the code matters
    as_gray = gc.decode(stack, white, black, proj_shape=(H, W), black_threshold=0.5,
                        white_threshold=0.5)  # fmt: skip
    assert not np.array_equal(np.where(as_gray.valid, as_gray.col, -1), cc)
