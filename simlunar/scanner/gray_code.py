"""Binary-reflected gray-code patterns and their decoder (NumPy only).

The stack layout, bit order and decision rules follow OpenCV contrib
``structured_light.GrayCodePattern`` (../shared/REFERENCES.md, "Structured light"), so stacks made
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
    shifts = np.arange(n - 1, -1, -1, dtype=np.int64).reshape((n,) + (1,) * g.ndim)
    return ((g[None] >> shifts) & 1).astype(np.uint8)


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
        (:func:`refine_subpixel`), each inside its decoded pixel; NaN where a pixel could not be
        refined (its pixel centre is used). None: not refined.
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

    @property
    def shape(self) -> tuple[int, int]:
        return self.valid.shape  # type: ignore[return-value]

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
    images = np.asarray(images, dtype=np.float64)
    white = np.asarray(white, dtype=np.float64)
    black = np.asarray(black, dtype=np.float64)
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
    pat, inv = images[0::2], images[1::2]
    bits = (pat > inv).astype(np.uint8)
    reliable = np.abs(pat - inv) >= white_threshold
    lit = (white - black) > black_threshold
    col = gray_to_binary(bits[:ncb])
    row = gray_to_binary(bits[ncb:])
    valid = lit & (col < W) & (row < H)
    if require_reliable:
        valid &= np.all(reliable, axis=0)
    col = np.where(valid, col, -1)
    row = np.where(valid, row, -1)
    return GrayDecode(
        col=col,
        row=row,
        valid=valid,
        lit=lit,
        bits=bits,
        reliable=reliable,
        n_col_bits=ncb,
        n_row_bits=nrb,
        proj_shape=(H, W),
    )


def bit_errors(
    result: GrayDecode, true_col: np.ndarray, true_row: np.ndarray, mask: np.ndarray | None = None
) -> np.ndarray:
    """Per-bit error maps against ground-truth correspondences.

    Parameters
    ----------
    result : GrayDecode
    true_col, true_row : (rows, cols) int
        True projector column and row of the surface point each camera pixel sees (-1 where the
        point is not lit by the projector).
    mask : (rows, cols) bool, optional
        Pixels to score; default: lit in the decode and with a true correspondence.

    Returns
    -------
    (n_col_bits + n_row_bits, rows, cols) bool
        True where the decoded gray bit differs from the true one (False outside ``mask``).
    """
    true_col = np.asarray(true_col)
    true_row = np.asarray(true_row)
    if true_col.shape != result.shape or true_row.shape != result.shape:
        raise ValueError(
            f"true correspondences {true_col.shape} must match the decode {result.shape}"
        )
    if mask is None:
        mask = result.lit & (true_col >= 0) & (true_row >= 0)
    tb = np.concatenate(
        [
            bit_planes(np.clip(true_col, 0, None), result.n_col_bits),
            bit_planes(np.clip(true_row, 0, None), result.n_row_bits),
        ]
    )
    return (tb != result.bits) & mask[None]


def stable_bits(
    true_col: np.ndarray, true_row: np.ndarray, n_col_bits: int, n_row_bits: int, *, margin: int = 1
) -> np.ndarray:
    """Pixels away from each bit's stripe edges in the camera image.

    A camera pixel integrates light over its area, so where the true bit changes inside the
    pixel its decoded value is a coin toss, not an error of the light transport. This is True
    where the true bit is the same over the ``(2 margin + 1)^2`` neighbourhood (and the
    neighbourhood has true correspondences).

    Returns
    -------
    (n_col_bits + n_row_bits, rows, cols) bool
    """
    from scipy import ndimage

    true_col = np.asarray(true_col)
    has = (true_col >= 0) & (np.asarray(true_row) >= 0)
    tb = np.concatenate(
        [
            bit_planes(np.clip(true_col, 0, None), n_col_bits),
            bit_planes(np.clip(true_row, 0, None), n_row_bits),
        ]
    ).astype(np.int8)
    size = 2 * int(margin) + 1
    out = np.empty(tb.shape, bool)
    all_has = ndimage.minimum_filter(has.astype(np.int8), size=size, mode="constant", cval=0) > 0
    for i, b in enumerate(tb):
        lo = ndimage.minimum_filter(b, size=size, mode="nearest")
        hi = ndimage.maximum_filter(b, size=size, mode="nearest")
        out[i] = (lo == hi) & all_has
    return out


def bit_error_rates(errors: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Fraction of masked pixels with an error, per bit: (n_bits,) float64 (NaN if none).

    ``mask`` is (rows, cols) for all bits or (n_bits, rows, cols) per bit.
    """
    mask = np.broadcast_to(np.asarray(mask, bool), errors.shape)
    n = mask.sum(axis=(1, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > 0, (errors & mask).sum(axis=(1, 2)) / np.maximum(n, 1), np.nan)


def _edges_along_rows(
    index: np.ndarray,
    valid: np.ndarray,
    lit: np.ndarray,
    diff: np.ndarray,
    n_bits: int,
    max_gap: int,
):
    """Stripe edges between horizontally consecutive valid camera pixels (refine_subpixel helper).

    ``index`` (rows, cols) decoded projector index, ``diff`` (n_bits, rows, cols) the
    pattern-minus-inverse signal of each gray bit. An edge follows valid pixel x when the next
    valid pixel x' in its row is at most ``max_gap + 1`` pixels on, every pixel between them is
    lit (they only failed the reliability test, as a pixel straddling a stripe edge does) and
    the two indices differ by exactly one: consecutive gray codes differ in one bit, whose
    signal changes sign across the edge. The first zero crossing of that signal from x to x',
    linear between pixel centres, is the edge's camera position.

    Returns
    -------
    ok : (rows, cols) bool, keyed by the left pixel x
    pos : (rows, cols) float64 camera coordinate of the edge (pixel centres at x + 0.5)
    u : (rows, cols) float64 projector coordinate of the edge (the boundary ``max(i, i')``)
    """
    rows, cols = index.shape
    r, c = np.indices((rows, cols))
    ok = np.zeros((rows, cols), bool)
    pos = np.full((rows, cols), np.nan)
    u = np.full((rows, cols), np.nan)
    between = np.ones((rows, cols), bool)  # every pixel from x + 1 to x + g - 1 is lit, invalid
    for g in range(1, max_gap + 2):
        if g >= cols:
            break
        a, b = index[:, :-g], index[:, g:]
        pair = valid[:, :-g] & valid[:, g:] & between[:, :-g] & ~ok[:, :-g]
        step = pair & (np.abs(a - b) == 1)
        lo = np.minimum(a, b)
        flip = gray(np.where(step, lo, 0)) ^ gray(np.where(step, lo + 1, 1))
        # bit position (MSB first) of the one gray bit that changes between lo and lo + 1
        k = np.clip(n_bits - 1 - np.log2(np.maximum(flip, 1)).astype(np.int64), 0, n_bits - 1)
        rr, cc = r[:, :-g], c[:, :-g]
        s_start = diff[k, rr, cc]
        found = np.zeros(step.shape, bool)
        where = np.full(step.shape, np.nan)
        for j in range(g):
            s0, s1 = diff[k, rr, cc + j], diff[k, rr, cc + j + 1]
            cross = step & ~found & (s0 * s_start > 0) & (s1 * s_start <= 0) & (s0 != s1)
            with np.errstate(divide="ignore", invalid="ignore"):
                t = np.clip(s0 / (s0 - s1), 0.0, 1.0)
            where = np.where(cross, cc + j + 0.5 + t, where)
            found |= cross
        ok[:, :-g] |= found
        pos[:, :-g] = np.where(found, where, pos[:, :-g])
        u[:, :-g] = np.where(found, lo + 1.0, u[:, :-g])
        # the next gap size needs pixel x + g to be lit and invalid, and x' = x + g + 1 valid
        between[:, :-g] &= lit[:, g:] & ~valid[:, g:]
    return ok, pos, u


def _refine_along_rows(index, valid, lit, diff, n_bits, max_gap) -> np.ndarray:
    """Sub-pixel projector index per camera pixel from the edges left and right of it."""
    ok, pos, u = _edges_along_rows(index, valid, lit, diff, n_bits, max_gap)
    rows, cols = index.shape
    e = np.arange(cols)
    # edges keyed by their left pixel: those keyed < x lie left of valid pixel x's centre,
    # those keyed >= x right of it
    left = np.maximum.accumulate(np.where(ok, e, -1), axis=1)
    right = np.minimum.accumulate(np.where(ok, e, cols)[:, ::-1], axis=1)[:, ::-1]
    li = np.full((rows, cols), -1)
    li[:, 1:] = left[:, :-1]
    ri = right
    has = (li >= 0) & (ri < cols) & valid
    r = np.indices((rows, cols))[0]
    lp = np.where(has, pos[r, np.clip(li, 0, cols - 1)], np.nan)
    rp = np.where(has, pos[r, np.clip(ri, 0, cols - 1)], np.nan)
    lu = np.where(has, u[r, np.clip(li, 0, cols - 1)], np.nan)
    ru = np.where(has, u[r, np.clip(ri, 0, cols - 1)], np.nan)
    # the pixel must lie in the one projector stripe bounded by the two edges
    has &= (np.abs(ru - lu) == 1) & (np.minimum(lu, ru) == index)
    xc = np.arange(cols) + 0.5
    with np.errstate(divide="ignore", invalid="ignore"):
        out = lu + (ru - lu) * (xc[None] - lp) / (rp - lp)
    out = np.clip(out, index, index + 1 - 1e-9)
    return np.where(has, out, np.nan)


def refine_subpixel(result: GrayDecode, images: np.ndarray, *, max_gap: int = 2) -> GrayDecode:
    """Sub-pixel stripe-edge refinement of a gray-code decode.

    Along each camera row, the boundary between projector columns ``c`` and ``c + 1`` is
    located at the zero crossing of ``pattern - inverse`` of the one gray bit that changes
    there (linear interpolation between the two pixel centres); a camera pixel between two
    such edges gets the projector column interpolated linearly in its camera position. Rows
    are refined the same way along camera columns with the row bits. This removes most of the
    +-0.5 projector pixel quantisation of the integer decode on smooth surfaces; it assumes the
    camera resolves each projector stripe by at least about one pixel.

    Parameters
    ----------
    result : GrayDecode from :func:`decode`
    images : (2 * n_bits, rows, cols) the same captured stack
    max_gap : int
        Most lit but unreliable pixels allowed between the two valid pixels on either side of
        an edge (a camera pixel straddling a stripe edge sees both stripes, so its
        pattern - inverse is near zero and it fails the reliability test; the edge is then
        found in the signal across it).

    Returns
    -------
    GrayDecode
        ``result`` with ``subpixel`` set: (rows, cols, 2) projector (u, v) inside each decoded
        pixel, NaN where no edge pair brackets the pixel (the pixel centre is used there).
    """
    images = np.asarray(images, dtype=np.float64)
    nb = result.n_col_bits + result.n_row_bits
    if images.ndim != 3 or images.shape[0] != 2 * nb or images.shape[1:] != result.shape:
        raise ValueError(
            f"images must be the decoded ({2 * nb}, {result.shape[0]}, {result.shape[1]}) "
            f"gray-code stack, got shape {images.shape}"
        )
    diff = images[0::2] - images[1::2]
    ncb = result.n_col_bits
    if int(max_gap) < 0:
        raise ValueError(f"max_gap must be >= 0 pixels, got {max_gap}")
    u = _refine_along_rows(result.col, result.valid, result.lit, diff[:ncb], ncb, int(max_gap))
    v = _refine_along_rows(
        result.row.T,
        result.valid.T,
        result.lit.T,
        diff[ncb:].transpose(0, 2, 1),
        result.n_row_bits,
        int(max_gap),
    ).T
    import dataclasses

    return dataclasses.replace(result, subpixel=np.stack([u, v], axis=-1))
