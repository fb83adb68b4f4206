"""Compiled kernels of the epipolar dot scheduler (Numba, cached on disk).

See :func:`simlunar.scanner.scheduling.dot_schedule` for the geometry. Every dot has a band
coordinate ``w`` (angle of its camera epipolar line about the epipole, or its offset when the
lines are parallel), an interval ``[s0, s1]`` along that line (distance from the epipole) and its
camera segment and projector position. Two dots whose segments come within ``sep`` always have
``|w_i - w_j| < reach`` and interval gap ``< sep``; the kernels use these as cheap necessary
conditions and decide every conflict with the exact segment-segment distance.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def _point_seg_d2(px, py, ax, ay, bx, by):  # pragma: no cover - compiled
    abx = bx - ax
    aby = by - ay
    apx = px - ax
    apy = py - ay
    L2 = abx * abx + aby * aby
    t = 0.0
    if L2 > 0.0:
        t = (apx * abx + apy * aby) / L2
        if t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
    dx = apx - t * abx
    dy = apy - t * aby
    return dx * dx + dy * dy


@numba.njit(cache=True, nogil=True)
def _orient(ax, ay, bx, by, cx, cy):  # pragma: no cover - compiled
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@numba.njit(cache=True, nogil=True)
def seg_seg_d2(seg, i, j):  # pragma: no cover - compiled
    """Squared distance between segments ``seg[i]`` and ``seg[j]`` ((n, 2, 2) array)."""
    ax, ay = seg[i, 0, 0], seg[i, 0, 1]
    bx, by = seg[i, 1, 0], seg[i, 1, 1]
    cx, cy = seg[j, 0, 0], seg[j, 0, 1]
    dx, dy = seg[j, 1, 0], seg[j, 1, 1]
    o1 = _orient(ax, ay, bx, by, cx, cy)
    o2 = _orient(ax, ay, bx, by, dx, dy)
    o3 = _orient(cx, cy, dx, dy, ax, ay)
    o4 = _orient(cx, cy, dx, dy, bx, by)
    if o1 * o2 < 0.0 and o3 * o4 < 0.0:
        return 0.0  # proper crossing
    d = _point_seg_d2(ax, ay, cx, cy, dx, dy)
    d = min(d, _point_seg_d2(bx, by, cx, cy, dx, dy))
    d = min(d, _point_seg_d2(cx, cy, ax, ay, bx, by))
    d = min(d, _point_seg_d2(dx, dy, ax, ay, bx, by))
    return d


@numba.njit(cache=True, nogil=True)
def greedy_colour(
    order,
    band,
    band_start,
    band_s0,
    band_idx,
    s0,
    s1,
    seg,
    sep,
    reach_bands,
    cyclic,
    max_len,
    puv,
    pcell_start,
    pcell_idx,
    pcell_of,
    pnx,
    pny,
    psp,
):  # pragma: no cover - compiled
    """First-fit colouring in ``order`` against the exact conflicts with coloured dots.

    Candidates for a camera conflict of dot i are the dots of bands ``band[i] +- reach_bands``
    (cyclic when ``cyclic``) whose interval starts within ``[s0_i - max_len - sep, s1_i + sep]``
    (``band_s0`` is sorted within each band, ``band_idx`` the dot indices in that order);
    candidates for a projector conflict share or neighbour its projector grid cell.
    """
    n = order.shape[0]
    nb = band_start.shape[0] - 1
    colour = np.full(n, -1, np.int64)
    # position of each dot in band order, and per band the end of the coloured prefix (every
    # coloured dot of band b lies before band_start[b] + done[b]; later ones need no look)
    pos = np.empty(n, np.int64)
    for m in range(n):
        pos[band_idx[m]] = m
    done = np.zeros(nb, np.int64)
    stamp = np.full(n + 1, -1, np.int64)
    sep2 = sep * sep
    psp2 = psp * psp
    for k in range(n):
        i = order[k]
        b = band[i]
        lo_s = s0[i] - max_len - sep
        hi_s = s1[i] + sep
        span = 2 * reach_bands + 1
        if cyclic and span > nb:
            span = nb
        for db in range(span):
            bb = b - reach_bands + db
            if cyclic:
                bb = bb % nb
            elif bb < 0 or bb >= nb:
                continue
            a = band_start[bb]
            e = a + done[bb]
            if e == a:
                continue
            lo = a + np.searchsorted(band_s0[a:e], lo_s)
            for m in range(lo, e):
                if band_s0[m] > hi_s:
                    break
                j = band_idx[m]
                cj = colour[j]
                if cj < 0 or stamp[cj] == k:
                    continue
                if s1[j] + sep <= s0[i]:
                    continue
                if seg_seg_d2(seg, i, j) < sep2:
                    stamp[cj] = k
        cx = pcell_of[i] % pnx
        cy = pcell_of[i] // pnx
        for yy in range(max(cy - 1, 0), min(cy + 2, pny)):
            for xx in range(max(cx - 1, 0), min(cx + 2, pnx)):
                c = yy * pnx + xx
                for m in range(pcell_start[c], pcell_start[c + 1]):
                    j = pcell_idx[m]
                    cj = colour[j]
                    if cj < 0 or stamp[cj] == k:
                        continue
                    ddx = puv[i, 0] - puv[j, 0]
                    ddy = puv[i, 1] - puv[j, 1]
                    if ddx * ddx + ddy * ddy < psp2:
                        stamp[cj] = k
        c = 0
        while stamp[c] == k:
            c += 1
        colour[i] = c
        if pos[i] - band_start[b] + 1 > done[b]:
            done[b] = pos[i] - band_start[b] + 1
    return colour


@numba.njit(cache=True, nogil=True)
def max_overlap_windows(bins, idx, s0, s1, q):  # pragma: no cover - compiled
    """Deepest common point of the intervals of the dots in ``q`` consecutive bins.

    ``bins`` (sorted bin numbers) and ``idx`` (the dots in that order); a window starts at each
    distinct bin number b and holds the bins b .. b + q - 1. Returns (best depth, first bin of
    the best window, the common point).
    """
    n = bins.shape[0]
    best = 0
    best_bin = 0
    best_s = 0.0
    a = 0
    while a < n:
        b = bins[a]
        e = a + np.searchsorted(bins[a:], b + q)
        m = e - a
        if m > best:
            ev = np.empty(2 * m)
            kind = np.empty(2 * m, np.int64)
            for t in range(m):
                j = idx[a + t]
                ev[2 * t] = s0[j]
                kind[2 * t] = 0
                ev[2 * t + 1] = s1[j]
                kind[2 * t + 1] = 1
            # by position, starts before ends at equal positions (closed intervals)
            key = np.argsort(ev + 0.0 * kind, kind="mergesort")
            depth = 0
            p = 0
            while p < 2 * m:
                r = p
                while r + 1 < 2 * m and ev[key[r + 1]] == ev[key[p]]:
                    r += 1
                for t in range(p, r + 1):
                    if kind[key[t]] == 0:
                        depth += 1
                if depth > best:
                    best = depth
                    best_bin = b
                    best_s = ev[key[p]]
                for t in range(p, r + 1):
                    if kind[key[t]] == 1:
                        depth -= 1
                p = r + 1
        # next distinct bin
        while a < n and bins[a] == b:
            a += 1
    return best, best_bin, best_s
