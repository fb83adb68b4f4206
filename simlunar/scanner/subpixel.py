"""Sub-pixel stripe-edge refinement of a bit-plane (gray-code) decode
(:class:`simlunar.scanner.gray_code.GrayDecode`): the projector column (row) of a camera pixel
from where the stripe edges between its neighbours fall, instead of the projector pixel
centre."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["refine_subpixel", "refine_subpixel_from_diff"]


@njit(cache=True, nogil=True, error_model="numpy")
def _refine_lines(
    index, valid, lit, diff, words, n_bits, max_gap, out
):  # pragma: no cover - compiled
    """Sub-pixel projector index along each line (row) of 2-D views; writes ``out``.

    Stripe edges: an edge follows valid pixel x when the next valid pixel x' on its line is at
    most ``max_gap + 1`` pixels on, every pixel between them is lit (they only failed the
    reliability test, as a pixel straddling a stripe edge does) and the two indices differ by
    exactly one: the code words ``words`` of consecutive indices differ in one bit (the gray
    code; else the most significant bit that differs is used), whose pattern-minus-inverse
    signal changes sign across the edge. The first zero crossing of that signal from x to x', linear
    between pixel centres, is the edge's camera position; its projector coordinate is the
    boundary ``max(i, i')``. Edges are keyed by their left pixel x.

    A valid pixel then takes the projector index interpolated linearly between the nearest
    edge keyed left of it and the nearest keyed at or right of it, if those two edges bound
    the one projector stripe of its decoded index; else NaN.
    """
    lines, n = index.shape
    ok = np.zeros(n, np.bool_)
    pos = np.empty(n, np.float64)
    uu = np.empty(n, np.float64)
    left = np.empty(n, np.int64)
    for r in range(lines):
        for x in range(n):
            ok[x] = False
            out[r, x] = np.nan
        for x in range(n):
            if not valid[r, x]:
                continue
            x2 = -1
            g = 1
            while g <= max_gap + 1 and x + g < n:
                if valid[r, x + g]:
                    x2 = x + g
                    break
                if not lit[r, x + g]:
                    break
                g += 1
            if x2 < 0:
                continue
            a = index[r, x]
            b = index[r, x2]
            if abs(a - b) != 1:
                continue
            lo = min(a, b)
            flip = words[lo] ^ words[lo + 1]
            p = 0
            while flip > 1:
                flip >>= 1
                p += 1
            k = min(max(n_bits - 1 - p, 0), n_bits - 1)
            s_start = np.float64(diff[k, r, x])
            for j in range(g):
                s0 = np.float64(diff[k, r, x + j])
                s1 = np.float64(diff[k, r, x + j + 1])
                if s0 * s_start > 0 and s1 * s_start <= 0 and s0 != s1:
                    t = min(max(s0 / (s0 - s1), 0.0), 1.0)
                    ok[x] = True
                    pos[x] = x + j + 0.5 + t
                    uu[x] = lo + 1.0
                    break
        # nearest edge keyed strictly left of each pixel, then at or right of it
        last = -1
        for x in range(n):
            left[x] = last
            if ok[x]:
                last = x
        nxt = n
        for x in range(n - 1, -1, -1):
            if ok[x]:
                nxt = x
            if not valid[r, x] or left[x] < 0 or nxt >= n:
                continue
            li = left[x]
            lu, ru = uu[li], uu[nxt]
            if abs(ru - lu) != 1 or min(lu, ru) != index[r, x]:
                continue
            lp, rp = pos[li], pos[nxt]
            v = lu + (ru - lu) * (x + 0.5 - lp) / (rp - lp)
            if v != v:
                continue
            lo_v = np.float64(index[r, x])
            out[r, x] = min(max(v, lo_v), lo_v + 1 - 1e-9)


def _refine_along_rows(index, valid, lit, diff, code, n_bits, max_gap) -> np.ndarray:
    """Sub-pixel projector index per camera pixel along rows of (possibly transposed) views."""
    out = np.empty(index.shape, np.float64)
    _refine_lines(
        np.asarray(index, np.int64),
        np.asarray(valid, np.bool_),
        np.asarray(lit, np.bool_),
        diff,
        code.table(n_bits),
        int(n_bits),
        int(max_gap),
        out,
    )
    return out


def refine_subpixel(result, images: np.ndarray, *, max_gap: int = 2):
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
    images = np.asarray(images)
    nb = result.n_col_bits + result.n_row_bits
    if images.ndim != 3 or images.shape[0] != 2 * nb or images.shape[1:] != result.shape:
        raise ValueError(
            f"images must be the decoded ({2 * nb}, {result.shape[0]}, {result.shape[1]}) "
            f"gray-code stack, got shape {images.shape}"
        )
    diff = np.subtract(images[0::2], images[1::2], dtype=np.float64)
    return refine_subpixel_from_diff(result, diff, max_gap=max_gap)


def refine_subpixel_from_diff(result, diff: np.ndarray, *, max_gap: int = 2):
    """:func:`refine_subpixel` from each bit's ``pattern - inverse`` signal.

    Parameters
    ----------
    result : GrayDecode
    diff : (n_col_bits + n_row_bits, rows, cols) float32 or float64
        Pattern minus inverse per gray bit (e.g. :attr:`GrayDecoder.diff`).
    max_gap : int
        As in :func:`refine_subpixel`.

    Returns
    -------
    GrayDecode with ``subpixel`` set
    """
    nb = result.n_col_bits + result.n_row_bits
    diff = np.asarray(diff)
    if diff.dtype not in (np.float32, np.float64):
        diff = diff.astype(np.float64)
    if diff.shape != (nb, *result.shape):
        raise ValueError(
            f"diff must be ({nb}, {result.shape[0]}, {result.shape[1]}), got {diff.shape}"
        )
    if int(max_gap) < 0:
        raise ValueError(f"max_gap must be >= 0 pixels, got {max_gap}")
    ncb = result.n_col_bits
    sub = np.empty((*result.shape, 2), np.float64)
    sub[..., 0] = _refine_along_rows(
        result.col, result.valid, result.lit, diff[:ncb], result.code, ncb, int(max_gap)
    )
    # rows are refined along camera columns: transposed views, no copies
    sub[..., 1] = _refine_along_rows(
        result.row.T,
        result.valid.T,
        result.lit.T,
        diff[ncb:].transpose(0, 2, 1),
        result.code,
        result.n_row_bits,
        int(max_gap),
    ).T
    import dataclasses

    return dataclasses.replace(result, subpixel=sub)
