"""Binary-reflected gray-code patterns and their decoder (NumPy only).

The stack layout, bit order and decision rules follow OpenCV contrib
``structured_light.GrayCodePattern`` (its documentation and source), so stacks made
here decode with OpenCV and the other way round:

* ``ceil(log2 W)`` column bits, then ``ceil(log2 H)`` row bits, most significant bit first;
* images are (pattern, inverse) pairs, columns first; white and black frames are separate;
* a pattern pixel is lit (255) where the gray-code bit of its column (row) is 1;
* a camera pixel is valid if ``white - black > black_threshold``; a bit is 1 if
  ``pattern > inverse`` and unreliable if ``|pattern - inverse| < white_threshold``;
* gray to binary by cumulative XOR; a decoded index outside the pattern is invalid.

Thresholds are in the units of the images passed in (OpenCV's defaults 40 and 5 are for 8-bit
images; for float images in [0, 1] use about 40/255 and 5/255).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "GrayDecode",
    "GrayDecoder",
    "bit_planes",
    "decode",
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


def gray_to_binary(bits: np.ndarray) -> np.ndarray:
    """Integers from gray-code bit planes by cumulative XOR.

    Parameters
    ----------
    bits : (n_bits, ...) array of 0/1
        Gray-code bits, most significant first.

    Returns
    -------
    (...) int64 array
    """
    bits = np.asarray(bits).astype(np.int64)
    binary = np.bitwise_xor.accumulate(bits, axis=0)
    n = bits.shape[0]
    weights = (1 << np.arange(n - 1, -1, -1, dtype=np.int64)).reshape((n,) + (1,) * (bits.ndim - 1))
    return np.sum(binary * weights, axis=0)


def bit_planes(values, n: int) -> np.ndarray:
    """Gray-code bits of ``values`` as (n, ...) uint8 planes, most significant first."""
    g = gray(values)
    out = np.empty((n, *g.shape), np.uint8)
    for i in range(n):
        np.bitwise_and(g >> (n - 1 - i), 1, out=out[i], casting="unsafe")
    return out


def encode(width: int, height: int) -> np.ndarray:
    """Gray-code pattern stack in OpenCV ``GrayCodePattern.generate`` order.

    Parameters
    ----------
    width, height : int
        Projector resolution in pixels (any size >= 2, powers of two not required).

    Returns
    -------
    (2 * (num_bits(width) + num_bits(height)), height, width) uint8
        Values 0 or 255: column (pattern, inverse) pairs MSB first, then row pairs.
    """
    ncb, nrb = num_bits(width), num_bits(height)
    col_bits = bit_planes(np.arange(width), ncb)  # (ncb, W)
    row_bits = bit_planes(np.arange(height), nrb)  # (nrb, H)
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


def positive_patterns(width: int, height: int) -> np.ndarray:
    """Only the non-inverted patterns, (num_bits(width) + num_bits(height), height, width) uint8.

    A scan that obtains inverses by linearity of light transport renders these plus white and
    black: ``bits + 2`` renders instead of ``2 * bits + 2``.
    """
    return encode(width, height)[0::2]


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
    """(pattern, inverse) pairs as one (2n, rows, cols) stack in OpenCV order."""
    patterns = np.asarray(patterns)
    out = np.empty(
        (2 * patterns.shape[0], *patterns.shape[1:]), dtype=np.result_type(patterns, inverses)
    )
    out[0::2] = patterns
    out[1::2] = inverses
    return out


@dataclass(frozen=True, eq=False)
class GrayDecode:
    """Dense result of decoding a gray-code stack seen by a camera.

    All arrays are over camera pixels (rows, cols).

    Attributes
    ----------
    col, row : int64
        Decoded projector column and row; -1 where ``valid`` is False.
    valid : bool
        Lit (``white - black > black_threshold``), every bit reliable and the decoded index
        inside the projector.
    lit : bool
        ``white - black > black_threshold`` (False in projector shadow / outside the projection).
    bits : (n_col_bits + n_row_bits, rows, cols) uint8
        Decoded gray-code bits (MSB first, columns then rows).
    reliable : (n_col_bits + n_row_bits, rows, cols) bool
        ``|pattern - inverse| >= white_threshold`` per bit.
    n_col_bits, n_row_bits : int
    proj_shape : (int, int)
        Projector (height, width).
    subpixel : (rows, cols, 2) float64 or None
        Sub-pixel projector coordinates (u, v) from stripe-edge refinement
        (:func:`simlunar.scanner.subpixel.refine_subpixel`), each inside its decoded pixel; NaN where a pixel could not be
        refined (its pixel centre is used). None: not refined.
    contrast : (rows, cols) float32 or None
        ``white - black`` per camera pixel (frame units): how brightly the projector lights
        what the pixel sees (the ``low_contrast`` rescan planner ranks by it).
    """

    col: np.ndarray
    row: np.ndarray
    valid: np.ndarray
    lit: np.ndarray
    bits: np.ndarray
    reliable: np.ndarray
    n_col_bits: int
    n_row_bits: int
    proj_shape: tuple[int, int]
    subpixel: np.ndarray | None = None
    contrast: np.ndarray | None = None

    @property
    def shape(self) -> tuple[int, int]:
        return self.valid.shape  # type: ignore[return-value]

    def decoded_index(self) -> tuple[np.ndarray, np.ndarray]:
        """``(col, row)`` int64 that every camera pixel's bits name, valid or not (``col``
        and ``row`` hold -1 where the pixel is invalid)."""
        ncb = self.n_col_bits
        return _gray_planes_to_index(self.bits[:ncb]), _gray_planes_to_index(self.bits[ncb:])

    def proj_uv(self) -> np.ndarray:
        """(rows, cols, 2) projector coordinates (u, v); NaN where invalid.

        Pixel centres ``(col + 0.5, row + 0.5)``, or the refined coordinates where
        ``subpixel`` has them.
        """
        uv = np.stack([self.col + 0.5, self.row + 0.5], axis=-1).astype(float)
        if self.subpixel is not None:
            uv = np.where(np.isfinite(self.subpixel), self.subpixel, uv)
        uv[~self.valid] = np.nan
        return uv


class GrayDecoder:
    """Streaming gray-code decoder: frames are added as they are captured.

    Holds per camera pixel only the decoded bits, their reliability and (for sub-pixel
    refinement) the pattern-minus-inverse signal of each bit, never the frame stack, so a
    scan's memory does not grow with its number of frames. :func:`decode` is this class fed
    with a whole stack; both give identical results.

    Parameters
    ----------
    proj_shape : (H, W)
        Projector pattern shape (height, width).
    cam_shape : (rows, cols)
        Camera frame shape.
    black_threshold, white_threshold : float
        OpenCV's thresholds, in the units of the frames (see :func:`decode`).
    keep_diff : bool
        Keep each bit's ``pattern - inverse`` signal (float32 for float32 frames, else
        float64) for :func:`simlunar.scanner.subpixel.refine_subpixel_from_diff`.
    """

    def __init__(
        self,
        proj_shape: tuple[int, int],
        cam_shape: tuple[int, int],
        *,
        black_threshold: float = 40.0,
        white_threshold: float = 5.0,
        keep_diff: bool = False,
    ) -> None:
        self.proj_shape = (int(proj_shape[0]), int(proj_shape[1]))
        self.cam_shape = (int(cam_shape[0]), int(cam_shape[1]))
        H, W = self.proj_shape
        self.n_col_bits, self.n_row_bits = num_bits(W), num_bits(H)
        self.n_bits = self.n_col_bits + self.n_row_bits
        self.black_threshold = float(black_threshold)
        self.white_threshold = float(white_threshold)
        self.bits = np.zeros((self.n_bits, *self.cam_shape), np.uint8)
        self.reliable = np.zeros((self.n_bits, *self.cam_shape), bool)
        self.keep_diff = bool(keep_diff)
        self.diff: np.ndarray | None = None
        self._seen = np.zeros(self.n_bits, bool)
        self.lit: np.ndarray | None = None
        self.contrast: np.ndarray | None = None

    def _frame(self, name: str, a) -> np.ndarray:
        a = np.asarray(a)
        if a.shape != self.cam_shape:
            raise ValueError(f"{name} frame {a.shape} must match the camera shape {self.cam_shape}")
        return a

    def add_pair(self, bit: int, pattern, inverse) -> None:
        """Add the captured (pattern, inverse) frames of gray bit ``bit``.

        ``bit`` counts column bits MSB first, then row bits MSB first (the pair index of the
        :func:`encode` stack).
        """
        bit = int(bit)
        if not 0 <= bit < self.n_bits:
            raise ValueError(f"bit must be in 0..{self.n_bits - 1}, got {bit}")
        p = self._frame("pattern", pattern)
        i = self._frame("inverse", inverse)
        # the decision is made in float64 whatever the frames' type
        d = np.subtract(p, i, dtype=np.float64)
        np.greater(d, 0.0, out=self.bits[bit], casting="unsafe")
        np.greater_equal(np.abs(d), self.white_threshold, out=self.reliable[bit])
        if self.keep_diff:
            if self.diff is None:
                dt = np.float64 if np.result_type(p, i) == np.float64 else np.float32
                self.diff = np.zeros((self.n_bits, *self.cam_shape), dt)
            self.diff[bit] = d
        self._seen[bit] = True

    def add_white_black(self, white, black) -> None:
        """Add the captured all-white and all-black frames."""
        w = self._frame("white", white)
        b = self._frame("black", black)
        contrast = np.subtract(w, b, dtype=np.float64)
        self.lit = contrast > self.black_threshold
        self.contrast = contrast.astype(np.float32)

    def result(self, *, require_reliable: bool = True) -> GrayDecode:
        """The decode of the frames added so far (every pair and white/black are needed)."""
        missing = np.flatnonzero(~self._seen)
        if missing.size or self.lit is None:
            what = [f"bit {int(k)}" for k in missing] + (
                ["white/black"] if self.lit is None else []
            )
            raise ValueError(f"gray-code decode is missing frames: {', '.join(what)}")
        H, W = self.proj_shape
        ncb = self.n_col_bits
        col = _gray_planes_to_index(self.bits[:ncb])
        row = _gray_planes_to_index(self.bits[ncb:])
        valid = self.lit & (col < W) & (row < H)
        if require_reliable:
            valid &= np.all(self.reliable, axis=0)
        col[~valid] = -1
        row[~valid] = -1
        return GrayDecode(
            col=col,
            row=row,
            valid=valid,
            lit=self.lit,
            bits=self.bits,
            reliable=self.reliable,
            n_col_bits=ncb,
            n_row_bits=self.n_row_bits,
            proj_shape=(H, W),
            contrast=self.contrast,
        )


def _gray_planes_to_index(planes: np.ndarray) -> np.ndarray:
    """:func:`gray_to_binary` plane by plane (no (n_bits, ...) int64 temporary)."""
    binary = np.zeros(planes.shape[1:], np.uint8)
    out = np.zeros(planes.shape[1:], np.int64)
    for g in planes:
        binary ^= g
        out <<= 1
        out |= binary
    return out


def decode(
    images: np.ndarray,
    white: np.ndarray,
    black: np.ndarray,
    *,
    proj_shape: tuple[int, int],
    black_threshold: float = 40.0,
    white_threshold: float = 5.0,
    require_reliable: bool = True,
) -> GrayDecode:
    """Decode a gray-code image stack into per-pixel projector correspondences.

    Parameters
    ----------
    images : (2 * (num_bits(W) + num_bits(H)), rows, cols) array
        Captured (pattern, inverse) pairs in :func:`encode` order.
    white, black : (rows, cols) array
        Captured all-white and all-black frames.
    proj_shape : (H, W)
        Projector pattern shape (height, width).
    black_threshold, white_threshold : float
        OpenCV's thresholds, in the units of the images.
    require_reliable : bool
        If True (OpenCV's behaviour) a pixel with any unreliable bit is invalid.

    Returns
    -------
    GrayDecode
    """
    H, W = (int(proj_shape[0]), int(proj_shape[1]))
    ncb, nrb = num_bits(W), num_bits(H)
    images = np.asarray(images)
    white = np.asarray(white)
    black = np.asarray(black)
    n_expected = 2 * (ncb + nrb)
    if images.ndim != 3 or images.shape[0] != n_expected:
        raise ValueError(
            f"images must be a ({n_expected}, rows, cols) gray-code stack for a {W}x{H} projector "
            f"({ncb} column + {nrb} row bits, pattern and inverse each), got shape {images.shape}"
        )
    if white.shape != images.shape[1:] or black.shape != images.shape[1:]:
        raise ValueError(
            f"white {white.shape} and black {black.shape} frames must match the "
            f"camera shape {images.shape[1:]}"
        )
    dec = GrayDecoder(
        (H, W),
        images.shape[1:],
        black_threshold=black_threshold,
        white_threshold=white_threshold,
    )
    for k in range(ncb + nrb):
        dec.add_pair(k, images[2 * k], images[2 * k + 1])
    dec.add_white_black(white, black)
    return dec.result(require_reliable=require_reliable)
