"""Compiled kernels of deterministic placement: error diffusion, Voronoi assignment, centroids."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def diffuse(target, thresh, cap):  # pragma: no cover - compiled
    """Serpentine Floyd-Steinberg error diffusion of ``target`` to integer counts.

    Parameters
    ----------
    target : ndarray of float64, shape (rows, cols)
        Expected samples per cell (or per block of cells), >= 0.
    thresh : ndarray of float64, shape (rows, cols)
        Per-cell rounding threshold (about 0.5, jittered): a cell gets floor(v) + 1 samples
        when the fractional part of its value v reaches the threshold.
    cap : ndarray of int64, shape (rows, cols)
        Most samples a cell can take.

    Returns
    -------
    count : ndarray of int64, shape (rows, cols)
    value : ndarray of float64, shape (rows, cols)
        Target plus diffused error at each cell when it was visited (the fix-up's priority).

    Notes
    -----
    Weights 7/16 ahead, 3/16 behind-below, 5/16 below, 1/16 ahead-below, mirrored on odd rows;
    at the image border the weights that would leave the image are renormalised over those
    that stay, so no mass is lost and the count stays close to the target's sum.
    """
    nr, nc = target.shape
    acc = target.copy()
    value = np.empty((nr, nc))
    count = np.zeros((nr, nc), dtype=np.int64)
    for r in range(nr):
        step = 1 if r % 2 == 0 else -1
        start = 0 if step == 1 else nc - 1
        for i in range(nc):
            c = start + step * i
            v = acc[r, c]
            value[r, c] = v
            n = int(np.floor(v)) if v > 0 else 0
            if v - n >= thresh[r, c]:
                n += 1
            n = min(max(n, 0), cap[r, c])
            count[r, c] = n
            e = v - n
            cn = c + step
            cb = c - step
            ahead = 0 <= cn < nc
            behind = 0 <= cb < nc
            below = r + 1 < nr
            total = (7.0 if ahead else 0.0) + (
                (5.0 + (3.0 if behind else 0.0) + (1.0 if ahead else 0.0)) if below else 0.0
            )
            if total == 0.0:
                continue
            e /= total
            if ahead:
                acc[r, cn] += 7.0 * e
            if below:
                acc[r + 1, c] += 5.0 * e
                if behind:
                    acc[r + 1, cb] += 3.0 * e
                if ahead:
                    acc[r + 1, cn] += 1.0 * e
    return count, value


@numba.njit(cache=True, nogil=True)
def pick_in_blocks(keys, count, b):  # pragma: no cover - compiled
    """The ``count`` cells of smallest key in each b x b block (flat indices, block order).

    Parameters
    ----------
    keys : ndarray of float64, shape (rows, cols)
        Priority of each cell (smallest first; inf = never unless needed).
    count : ndarray of int64, shape (ceil(rows / b), ceil(cols / b))
        Samples per block (at most the block's cells).
    b : int
        Block side (pixels).
    """
    nr, nc = keys.shape
    out = np.empty(count.sum(), dtype=np.int64)
    buf_k = np.empty(b * b)
    buf_i = np.empty(b * b, dtype=np.int64)
    j = 0
    for br in range(count.shape[0]):
        for bc in range(count.shape[1]):
            n = count[br, bc]
            if n == 0:
                continue
            m = 0
            for r in range(br * b, min(br * b + b, nr)):
                for c in range(bc * b, min(bc * b + b, nc)):
                    buf_k[m] = keys[r, c]
                    buf_i[m] = r * nc + c
                    m += 1
            order = np.argsort(buf_k[:m])
            for q in range(n):
                out[j] = buf_i[order[q]]
                j += 1
    return out


@numba.njit(cache=True, nogil=True)
def assign(sr, sc, rad, order, nr, nc, best, owner):  # pragma: no cover - compiled
    """Nearest site of each cell among the sites whose disc of radius ``rad`` covers it.

    Serial on purpose: measured on the shared 2-core machine, a 2-thread version (row bands
    in parallel) ran 1.4-2x slower in wall time under load (barrier waits), and the study
    already runs planners in parallel processes.

    Parameters
    ----------
    sr, sc : ndarray of float64, shape (k,)
        Site positions (row, col) in index coordinates.
    rad : ndarray of float64, shape (k,)
        Search radius of each site (pixels).
    order : ndarray of int64, shape (k,)
        Visiting order of the sites (sorted by row, so successive discs share cache lines;
        ties go to the site first in this order).
    nr, nc : int
        Grid shape.
    best : ndarray of float32, shape (rows * cols,)
        Work array (overwritten): squared distance to the owner.
    owner : ndarray of int32, shape (rows * cols,)
        Output: index of the nearest covering site, -1 where no disc covers the cell.
    """
    best[:] = np.inf
    owner[:] = -1
    for j in range(order.size):
        s = order[j]
        r0 = sr[s]
        c0 = sc[s]
        rr = rad[s]
        r_lo = max(int(np.ceil(r0 - rr)), 0)
        r_hi = min(int(np.floor(r0 + rr)), nr - 1)
        for r in range(r_lo, r_hi + 1):
            dr2 = (r - r0) * (r - r0)
            half = np.sqrt(max(rr * rr - dr2, 0.0))
            c_lo = max(int(np.ceil(c0 - half)), 0)
            c_hi = min(int(np.floor(c0 + half)), nc - 1)
            base = r * nc
            for c in range(c_lo, c_hi + 1):
                d = np.float32(dr2 + (c - c0) * (c - c0))
                if d < best[base + c]:
                    best[base + c] = d
                    owner[base + c] = s


@numba.njit(cache=True, nogil=True)
def centroids(owner, best, weight, nc, k):  # pragma: no cover - compiled
    """Weighted centroid of each site's cells, and the squared distance to its farthest cell.

    Returns
    -------
    mass, mr, mc : ndarray of float64, shape (k,)
        Total weight and the weighted sums of row and column of each site's cells.
    far2 : ndarray of float64, shape (k,)
        Largest squared distance from the site to one of its cells (``best``).
    """
    mass = np.zeros(k)
    mr = np.zeros(k)
    mc = np.zeros(k)
    far2 = np.zeros(k)
    nr = owner.size // nc
    for r in range(nr):
        for c in range(nc):
            i = r * nc + c
            s = owner[i]
            if s < 0:
                continue
            if best[i] > far2[s]:
                far2[s] = best[i]
            w = weight[i]
            mass[s] += w
            mr[s] += w * r
            mc[s] += w * c
    return mass, mr, mc, far2


@numba.njit(cache=True, nogil=True)
def distinct_pixels(rows, cols, nr, nc):  # pragma: no cover - compiled
    """Flat pixel of each site, in order, moving a site whose pixel is taken to the nearest free one.

    Parameters
    ----------
    rows, cols : ndarray of int64, shape (k,)
        Rounded site positions, in priority order (earlier sites keep their pixel).

    Returns
    -------
    ndarray of int64, shape (k,)
        Distinct flat indices.
    """
    occ = np.zeros(nr * nc, dtype=np.bool_)
    out = np.empty(rows.size, dtype=np.int64)
    for i in range(rows.size):
        r0 = rows[i]
        c0 = cols[i]
        if not occ[r0 * nc + c0]:
            occ[r0 * nc + c0] = True
            out[i] = r0 * nc + c0
            continue
        # rings of growing Chebyshev radius; keep the Euclidean-nearest free cell of a ring
        # and stop once no farther ring can hold a nearer one
        best = -1
        best_d = np.inf
        ring = 1
        while best < 0 or ring * ring < best_d:
            for r in range(max(r0 - ring, 0), min(r0 + ring, nr - 1) + 1):
                edge = r == r0 - ring or r == r0 + ring
                stride = 1 if edge else 2 * ring
                for c in range(c0 - ring, c0 + ring + 1, stride):
                    if c < 0 or c >= nc or occ[r * nc + c]:
                        continue
                    d = (r - r0) * (r - r0) + (c - c0) * (c - c0)
                    if d < best_d:
                        best_d = d
                        best = r * nc + c
            ring += 1
            if ring > nr + nc:
                break
        occ[best] = True
        out[i] = best
    return out
