"""One-pass error sums for the sampling study (Numba, cached on disk)."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def error_sums(recon, truth, weights):  # pragma: no cover - compiled
    """Sums over the finite cells of ``recon`` (1-D, same length as ``truth``).

    Returns (count, sum e^2, sum |e|, sum_i w_j e^2 per weight row j, sum_i w_j per row j),
    with e = recon - truth and ``weights`` of shape (m, n).
    """
    m = weights.shape[0]
    count = 0
    sse = 0.0
    sae = 0.0
    wse = np.zeros(m)
    wsum = np.zeros(m)
    for i in range(recon.size):
        r = recon[i]
        if not np.isfinite(r):
            continue
        e = r - truth[i]
        e2 = e * e
        count += 1
        sse += e2
        sae += abs(e)
        for j in range(m):
            w = weights[j, i]
            wse[j] += w * e2
            wsum[j] += w
    return count, sse, sae, wse, wsum
