"""Compiled greedy Poisson-disk acceptance for blue-noise weighted sampling."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def poisson_accept(order, radius, shape, k):  # pragma: no cover - compiled
    """Greedy dart throwing over candidates in priority order.

    Candidate ``order[i]`` (flat pixel index) is accepted when no accepted pixel lies closer
    than ``radius[order[i]]`` (pixels). Candidates are visited once; if fewer than ``k`` pass,
    the remaining slots take the best rejected candidates in order (so exactly ``k`` return).
    """
    nr, nc = shape[0], shape[1]
    occ = np.zeros(nr * nc, dtype=np.bool_)
    chosen = np.empty(k, dtype=np.int64)
    n = 0
    for i in range(order.size):
        if n == k:
            break
        p = order[i]
        r0 = p // nc
        c0 = p % nc
        rad = radius[p]
        ir = int(rad)
        rad2 = rad * rad
        ok = True
        for r in range(max(r0 - ir, 0), min(r0 + ir, nr - 1) + 1):
            dr2 = (r - r0) * (r - r0)
            for c in range(max(c0 - ir, 0), min(c0 + ir, nc - 1) + 1):
                if occ[r * nc + c] and dr2 + (c - c0) * (c - c0) < rad2:
                    ok = False
                    break
            if not ok:
                break
        if ok:
            occ[p] = True
            chosen[n] = p
            n += 1
    for i in range(order.size):
        if n == k:
            break
        p = order[i]
        if not occ[p]:
            occ[p] = True
            chosen[n] = p
            n += 1
    return chosen
