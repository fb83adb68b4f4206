"""Per-bit errors of a bit-plane (gray-code) decode against ground-truth correspondences (NumPy
only).

A decoded bit is wrong where it differs from the bit (of the decode's code) of the true
projector column (row) of the
surface point a camera pixel sees; bits whose true value changes inside a pixel's neighbourhood are
left out (:func:`stable_bits`), as their decoded value is a coin toss, not an error of the light
transport. Bit order and stack layout: :mod:`simlunar.scanner.bitcodes`; the decode:
:class:`simlunar.scanner.gray_code.GrayDecode`.
"""

from __future__ import annotations

import numpy as np

from simlunar.scanner.bitcodes import GRAY, BitCode

__all__ = [
    "bit_error_rates",
    "bit_error_table",
    "bit_errors",
    "stable_bits",
]


def bit_errors(
    result, true_col: np.ndarray, true_row: np.ndarray, mask: np.ndarray | None = None
) -> np.ndarray:
    """Per-bit error maps against ground-truth correspondences.

    Parameters
    ----------
    result : GrayDecode (its ``code`` spells the true bits)
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
            result.code.planes(np.clip(true_col, 0, None), result.n_col_bits),
            result.code.planes(np.clip(true_row, 0, None), result.n_row_bits),
        ]
    )
    return (tb != result.bits) & mask[None]


def stable_bits(
    true_col: np.ndarray,
    true_row: np.ndarray,
    n_col_bits: int,
    n_row_bits: int,
    *,
    margin: int = 1,
    code: BitCode = GRAY,
) -> np.ndarray:
    """Pixels away from each bit's stripe edges in the camera image.

    A camera pixel integrates light over its area, so where the true bit changes inside the
    pixel its decoded value is a coin toss, not an error of the light transport. This is True
    where the true bit is the same over the ``(2 margin + 1)^2`` neighbourhood (and the
    neighbourhood has true correspondences). ``code``: the code whose bits are meant (gray).

    Returns
    -------
    (n_col_bits + n_row_bits, rows, cols) bool
    """
    from scipy import ndimage

    true_col = np.asarray(true_col)
    true_row = np.asarray(true_row)
    has = (true_col >= 0) & (true_row >= 0)
    size = 2 * int(margin) + 1
    all_has = ndimage.minimum_filter(has.astype(np.int8), size=size, mode="constant", cval=0) > 0
    out = np.empty((n_col_bits + n_row_bits, *true_col.shape), bool)
    k = 0
    for idx, n in ((true_col, n_col_bits), (true_row, n_row_bits)):
        g = code.words(np.clip(idx, 0, None))
        # a bit is constant over the window iff its OR and its AND over the window agree;
        # both are separable box filters (borders: the edge pixel repeated)
        changes = _box_bitwise(g, margin, np.bitwise_or) ^ _box_bitwise(g, margin, np.bitwise_and)
        for i in range(n):
            out[k] = (((changes >> (n - 1 - i)) & 1) == 0) & all_has
            k += 1
    return out


def _box_bitwise(a: np.ndarray, margin: int, op) -> np.ndarray:
    """Bitwise ``op`` over the (2 margin + 1)^2 window of each pixel, edge pixels repeated."""
    m = int(margin)
    out = a
    for axis in (0, 1):
        p = np.pad(out, [(m, m) if ax == axis else (0, 0) for ax in (0, 1)], mode="edge")
        n = out.shape[axis]

        def window(s, p=p, n=n, axis=axis):
            return p[s : s + n] if axis == 0 else p[:, s : s + n]

        acc = window(0).copy()
        for s in range(1, 2 * m + 1):
            op(acc, window(s), out=acc)
        out = acc
    return out


def bit_error_table(decode, truth: dict, mask=None, *, edge_margin: int = 1) -> dict[str, float]:
    """Per-bit error rates of a bit-plane decode (a ``GrayDecode``) against camera ground truth.

    ``truth`` has the true projector ``col``, ``row`` and ``lit`` per camera pixel
    (:func:`simlunar.render.capture.camera_truth`). ``mask`` (camera (rows, cols) bool)
    restricts the pixels; always only pixels lit by the projector in both the ground truth and
    the decode count, and for each bit only pixels ``edge_margin`` pixels away from that bit's
    true stripe edges (:func:`stable_bits`; 0 keeps every pixel).

    Returns
    -------
    dict ``ber_c<i>`` / ``ber_r<i>`` -> rate of column / row bit i (MSB first; NaN if no pixel)
    """
    dec = decode
    base = truth["lit"] & dec.lit & (truth["col"] >= 0)
    m = base if mask is None else base & np.asarray(mask, bool)
    err = bit_errors(dec, truth["col"], truth["row"], mask=m)
    per_bit = np.broadcast_to(m, err.shape)
    if edge_margin > 0:
        per_bit = per_bit & stable_bits(
            truth["col"],
            truth["row"],
            dec.n_col_bits,
            dec.n_row_bits,
            margin=edge_margin,
            code=dec.code,
        )
    rates = bit_error_rates(err, per_bit)
    names = [f"ber_c{i}" for i in range(dec.n_col_bits)] + [
        f"ber_r{i}" for i in range(dec.n_row_bits)
    ]
    return dict(zip(names, (float(r) for r in rates)))


def bit_error_rates(errors: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Fraction of masked pixels with an error, per bit: (n_bits,) float64 (NaN if none).

    ``mask`` is (rows, cols) for all bits or (n_bits, rows, cols) per bit.
    """
    mask = np.broadcast_to(np.asarray(mask, bool), errors.shape)
    n = mask.sum(axis=(1, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > 0, (errors & mask).sum(axis=(1, 2)) / np.maximum(n, 1), np.nan)
