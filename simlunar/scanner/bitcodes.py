"""Bit-plane codes and their pattern stacks (NumPy only).

A *bit-plane code* numbers the projector's columns (rows) with ``n``-bit code words, one
projected pattern per bit, most significant first: :class:`BitCode` is a code's word function,
a permutation of ``0 .. 2**n - 1`` for every ``n``; decoding reads a camera pixel's word from
its bit planes and inverts the permutation (:meth:`BitCode.index`, by table). The
binary-reflected gray code (:data:`GRAY`, ``x ^ (x >> 1)``: neighbours differ in one bit) is
the paper's and OpenCV's; another code is one more :class:`BitCode`. The decoder that reads
the planes, its options and its scan: :mod:`simlunar.scanner.gray_code`.

The stack layout follows OpenCV contrib ``structured_light.GrayCodePattern`` (its
documentation and source): ``ceil(log2 W)`` column bits, then ``ceil(log2 H)`` row bits, MSB
first; (pattern, inverse) pairs, columns first; a pattern pixel is lit (255) where the code bit
of its column (row) is 1; white and black frames are separate.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

__all__ = [
    "GRAY",
    "BitCode",
    "bit_planes",
    "encode",
    "frame_names",
    "gray",
    "gray_to_binary",
    "interleave",
    "inverses_by_linearity",
    "num_bits",
    "positive_patterns",
    "white_black",
]


def num_bits(n: int) -> int:
    """Bits OpenCV uses for ``n`` columns or rows: ``ceil(log2 n)``.

    Parameters
    ----------
    n : int
        Number of projector columns (or rows), >= 2.
    """
    n = int(n)
    if n < 2:
        raise ValueError(f"a gray-code pattern needs at least 2 columns and rows, got {n}")
    return int(np.ceil(np.log2(n)))


def gray(values) -> np.ndarray:
    """Binary-reflected gray code ``x ^ (x >> 1)`` of non-negative integers."""
    v = np.asarray(values, dtype=np.int64)
    return v ^ (v >> 1)


@dataclass(frozen=True)
class BitCode:
    """A bit-plane code: ``words(index) -> code word``, a permutation of ``0 .. 2**n - 1``
    for every bit count ``n`` (a module-level function, so options holding the code pickle).

    Attributes
    ----------
    name : str
        How exports and messages name the code.
    words : callable
        (...) int64 indices -> (...) int64 code words.
    """

    name: str
    words: Callable[[np.ndarray], np.ndarray]

    def planes(self, values, n: int) -> np.ndarray:
        """The code words of ``values`` as (n, ...) uint8 bit planes, most significant first."""
        w = self.words(np.asarray(values, np.int64))
        out = np.empty((n, *w.shape), np.uint8)
        for i in range(n):
            np.bitwise_and(w >> (n - 1 - i), 1, out=out[i], casting="unsafe")
        return out

    def table(self, n: int) -> np.ndarray:
        """(2**n,) int64 code word of every ``n``-bit index (read-only)."""
        return _tables(self, int(n))[0]

    def index(self, planes) -> np.ndarray:
        """The indices whose code words the (n, ...) 0/1 ``planes`` (MSB first) spell: (...)
        int64, plane by plane (no (n, ...) int64 temporary)."""
        planes = np.asarray(planes)
        word = np.zeros(planes.shape[1:], np.int64)
        for p in planes:
            word <<= 1
            word |= p
        return _tables(self, len(planes))[1][word]


@lru_cache(maxsize=64)
def _tables(code: BitCode, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(words of 0 .. 2**n - 1, their inverse permutation); ValueError if not a permutation."""
    idx = np.arange(1 << n, dtype=np.int64)
    words = np.asarray(code.words(idx), np.int64)
    if not np.array_equal(np.sort(words), idx):
        raise ValueError(f"the {code.name} code is not a permutation of the {n}-bit words")
    inverse = np.empty_like(idx)
    inverse[words] = idx
    words.setflags(write=False)
    inverse.setflags(write=False)
    return words, inverse


#: the binary-reflected gray code (OpenCV's ``GrayCodePattern``, the paper's)
GRAY = BitCode("gray", gray)


def gray_to_binary(bits: np.ndarray) -> np.ndarray:
    """Integers from gray-code bit planes (n_bits, ...) of 0/1, most significant first."""
    return GRAY.index(bits)


def bit_planes(values, n: int, code: BitCode = GRAY) -> np.ndarray:
    """Code bits (gray by default) of ``values`` as (n, ...) uint8 planes, MSB first."""
    return code.planes(values, n)


def encode(width: int, height: int, code: BitCode = GRAY) -> np.ndarray:
    """Bit-plane pattern stack in OpenCV ``GrayCodePattern.generate`` order.

    Parameters
    ----------
    width, height : int
        Projector resolution in pixels (any size >= 2, powers of two not required).
    code : BitCode
        The code (the gray code by default: OpenCV's stack).

    Returns
    -------
    (2 * (num_bits(width) + num_bits(height)), height, width) uint8
        Values 0 or 255: column (pattern, inverse) pairs MSB first, then row pairs.
    """
    ncb, nrb = num_bits(width), num_bits(height)
    col_bits = code.planes(np.arange(width), ncb)  # (ncb, W)
    row_bits = code.planes(np.arange(height), nrb)  # (nrb, H)
    out = np.empty((2 * (ncb + nrb), height, width), dtype=np.uint8)
    out[0 : 2 * ncb : 2] = (col_bits * 255)[:, None, :]
    out[2 * ncb :: 2] = (row_bits * 255)[:, :, None]
    out[1::2] = 255 - out[0::2]
    return out


def frame_names(n_col_bits: int, n_row_bits: int) -> list[str]:
    """Names of the frames in OpenCV ``GrayCodePattern`` order (white, black last).

    ``col3_inv`` is the inverse pattern of column bit 3 (bit 0 is the most significant).
    """
    names = []
    for axis, n in (("col", n_col_bits), ("row", n_row_bits)):
        for i in range(n):
            names += [f"{axis}{i}", f"{axis}{i}_inv"]
    return [*names, "white", "black"]


def white_black(width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """All-white and all-black uint8 frames of shape (height, width)."""
    return (np.full((height, width), 255, np.uint8), np.zeros((height, width), np.uint8))


def positive_patterns(width: int, height: int, code: BitCode = GRAY) -> np.ndarray:
    """Only the non-inverted patterns, (num_bits(width) + num_bits(height), height, width) uint8.

    A scan that obtains inverses by linearity of light transport renders these plus white and
    black: ``bits + 2`` renders instead of ``2 * bits + 2``.
    """
    return encode(width, height, code)[0::2]


def inverses_by_linearity(patterns: np.ndarray, white: np.ndarray, black: np.ndarray) -> np.ndarray:
    """Noise-free images of the inverse patterns from pattern, white and black images.

    Light transport is linear in the projector's emission, and a pattern plus its inverse is the
    white frame, so ``I(inverse) = I(white) - I(pattern) + I(black)``; the black frame carries any
    light that is not the projector's (sun, ambient) and would otherwise be counted twice.

    Parameters
    ----------
    patterns : (n, rows, cols) float
    white, black : (rows, cols) float

    Returns
    -------
    (n, rows, cols) float
    """
    patterns = np.asarray(patterns)
    if (
        patterns.ndim != 3
        or patterns.shape[1:] != np.shape(white)
        or np.shape(white) != np.shape(black)
    ):
        raise ValueError(
            f"patterns must be (n, rows, cols) matching white/black (rows, cols); got "
            f"{patterns.shape}, {np.shape(white)}, {np.shape(black)}"
        )
    return np.asarray(white)[None] + np.asarray(black)[None] - patterns


def interleave(patterns: np.ndarray, inverses: np.ndarray) -> np.ndarray:
    """(pattern, inverse) pairs as one (2n, rows, cols) stack in OpenCV order (arrays or
    nested lists of the same shape)."""
    patterns, inverses = np.asarray(patterns), np.asarray(inverses)
    if patterns.shape != inverses.shape:
        raise ValueError(
            f"interleave: patterns {patterns.shape} and inverses {inverses.shape} differ in shape"
        )
    out = np.empty(
        (2 * patterns.shape[0], *patterns.shape[1:]), dtype=np.result_type(patterns, inverses)
    )
    out[0::2] = patterns
    out[1::2] = inverses
    return out
