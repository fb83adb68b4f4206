"""Compiled kernels for the feature maps (Numba, cached on disk)."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def sliding_entropy(padded, size, nlog_n):  # pragma: no cover - compiled
    """Shannon entropy (bits) of every ``size`` x ``size`` window of a uint8 image.

    ``padded`` is the image padded by ``size // 2`` on each side; ``nlog_n[n] = n log2 n``.
    The 256-bin histogram slides along each row (remove the leaving column, add the entering
    one) while the sum S = sum_b n_b log2 n_b is updated from the table, so the entropy
    H = log2(A) - S / A (A = size^2) costs O(size) per pixel instead of O(size^2 + 256).
    """
    half = size // 2
    nr = padded.shape[0] - 2 * half
    nc = padded.shape[1] - 2 * half
    area = size * size
    log_area = np.log2(area)
    out = np.empty((nr, nc), dtype=np.float64)
    hist = np.zeros(256, dtype=np.int64)
    for r in range(nr):
        hist[:] = 0
        s = 0.0
        for i in range(r, r + size):
            for j in range(size):
                b = padded[i, j]
                n = hist[b]
                s += nlog_n[n + 1] - nlog_n[n]
                hist[b] = n + 1
        out[r, 0] = log_area - s / area
        for c in range(1, nc):
            jo = c - 1
            ji = c + size - 1
            for i in range(r, r + size):
                b = padded[i, jo]
                n = hist[b]
                s += nlog_n[n - 1] - nlog_n[n]
                hist[b] = n - 1
                b = padded[i, ji]
                n = hist[b]
                s += nlog_n[n + 1] - nlog_n[n]
                hist[b] = n + 1
            out[r, c] = log_area - s / area
    return out
