"""Visiting order of a steered beam's points: raster reference, nearest neighbour + 2-opt.

The cost of an edge is the mechanical move time (:func:`simlunar.lidar.steering.move_time`),
which grows monotonically with the Chebyshev (L-infinity) distance between pointings (both
axes move at once, alike); so a k-d tree in that metric finds the nearest points in time.
Tours are open paths from a fixed start. The nearest-neighbour tour and the planner's own
order are both improved by 2-opt over k-nearest-neighbour candidate lists (compiled with
numba) and the shorter is kept (above 5000 points only the nearest-neighbour tour is
improved, and kept if shorter than the planner's order), so the result is never longer
than the planner's order.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numba
import numpy as np
from scipy.spatial import cKDTree

from simlunar.lidar.steering import SteeringOptions, move_time, raster_sweep, scan_timing
from simlunar.registry import Options, option

__all__ = [
    "METHODS",
    "OrderOptions",
    "exact_order",
    "nearest_neighbour_order",
    "order_scan",
    "raster_order",
    "two_opt",
]

METHODS = ("nn2opt", "raster", "given")


@dataclass(frozen=True)
class OrderOptions(Options):
    """How the points of a steered scan are ordered."""

    method: str = option(
        "nn2opt",
        doc="nearest neighbour + 2-opt; serpentine raster lines; the planner's order",
        choices=METHODS,
    )
    neighbours: int = option(8, doc="candidate neighbours per point for 2-opt", ge=1)
    max_passes: int = option(50, doc="largest number of 2-opt passes over the tour", ge=0)
    line_pitch_rad: float | None = option(
        None,
        doc="raster line spacing in elevation; None = sqrt(area / n) of the points' box",
        unit="rad",
        gt=0,
    )


def raster_order(angles: np.ndarray, line_pitch_rad: float | None = None) -> np.ndarray:
    """Serpentine raster: lines of elevation from the top, alternate lines reversed in azimuth.

    Parameters
    ----------
    angles : (n, 2) float
        (azimuth, elevation) in rad.
    line_pitch_rad : float or None
        Line height (rad); None = sqrt(area / n) of the points' bounding box.

    Returns
    -------
    (n,) int64 permutation.
    """
    p = np.asarray(angles, float)
    if len(p) == 0:
        return np.zeros(0, np.int64)
    span = np.ptp(p, axis=0)
    if line_pitch_rad is None:
        area = max(span[0], 1e-12) * max(span[1], 1e-12)
        line_pitch_rad = np.sqrt(area / len(p)) if span[1] > 0 else 1.0
    line = np.floor((p[:, 1].max() - p[:, 1]) / line_pitch_rad).astype(np.int64)
    az = np.where(line % 2 == 0, p[:, 0], -p[:, 0])
    return np.lexsort((az, line)).astype(np.int64)


def nearest_neighbour_order(angles: np.ndarray, start: int = 0) -> np.ndarray:
    """Greedy tour from point ``start`` to the nearest unvisited point (Chebyshev metric).

    Compiled (numba): the unvisited points sit in a uniform grid of about two points per cell,
    searched in rings of cells around the current point; the grid is rebuilt on the points
    left whenever half of its points are visited, so queries stay local (O(n log n) overall
    on spread-out plans).

    Parameters
    ----------
    angles : (n, 2) float
        Pointings (rad).
    start : int
        First point.

    Returns
    -------
    (n,) int64 permutation starting with ``start``.
    """
    p = np.ascontiguousarray(angles, dtype=float)
    if len(p) == 0:
        return np.zeros(0, np.int64)
    return _nn_grid(p, int(start))


@numba.njit(cache=True, nogil=True)
def _scan_cell(p, cur, items, cstart, clen, c, best, bi):
    for t in range(cstart[c], cstart[c] + clen[c]):
        q = items[t]
        d = max(abs(p[q, 0] - p[cur, 0]), abs(p[q, 1] - p[cur, 1]))
        if d < best:
            best, bi = d, t
    return best, bi


@numba.njit(cache=True, nogil=True)
def _nn_grid(p, start):
    n = p.shape[0]
    order = np.empty(n, np.int64)
    visited = np.zeros(n, np.bool_)
    order[0], visited[start], k, cur = start, True, 1, start
    while k < n:
        ids = np.flatnonzero(~visited)
        m = ids.size
        g = max(1, int(np.sqrt(m / 2.0)))
        lo0, lo1 = p[ids, 0].min(), p[ids, 1].min()
        cs = max(p[ids, 0].max() - lo0, p[ids, 1].max() - lo1) / g + 1e-12
        cell = np.empty(m, np.int64)
        for t in range(m):
            i = min(int((p[ids[t], 0] - lo0) / cs), g - 1)
            j = min(int((p[ids[t], 1] - lo1) / cs), g - 1)
            cell[t] = i * g + j
        srt = np.argsort(cell, kind="mergesort")
        items, clen = ids[srt], np.zeros(g * g, np.int64)
        for t in range(m):
            clen[cell[t]] += 1
        cstart = np.zeros(g * g, np.int64)
        for c in range(1, g * g):
            cstart[c] = cstart[c - 1] + clen[c - 1]
        target = n if m < 64 else k + m // 2
        while k < min(target, n):
            ci = min(max(int((p[cur, 0] - lo0) / cs), 0), g - 1)
            cj = min(max(int((p[cur, 1] - lo1) / cs), 0), g - 1)
            best, bi, r = np.inf, -1, 0
            while r <= g:
                for i in range(max(ci - r, 0), min(ci + r, g - 1) + 1):
                    for j in range(max(cj - r, 0), min(cj + r, g - 1) + 1):
                        if max(abs(i - ci), abs(j - cj)) == r:
                            best, bi = _scan_cell(p, cur, items, cstart, clen, i * g + j, best, bi)
                if bi >= 0 and r * cs >= best:
                    break
                r += 1
            q = items[bi]
            c = (min(int((p[q, 0] - lo0) / cs), g - 1)) * g + min(int((p[q, 1] - lo1) / cs), g - 1)
            last = cstart[c] + clen[c] - 1
            items[bi], items[last] = items[last], items[bi]
            clen[c] -= 1
            visited[q] = True
            order[k], cur, k = q, q, k + 1
    return order


@numba.njit(cache=True, nogil=True)
def _cost(p, i, j, v, a, settle):
    d = max(abs(p[i, 0] - p[j, 0]), abs(p[i, 1] - p[j, 1]))
    if d == 0.0:
        return 0.0
    if d <= v * v / a:
        return 2.0 * np.sqrt(d / a) + settle
    return d / v + v / a + settle


@numba.njit(cache=True, nogil=True)
def _two_opt(p, tour, nbrs, v, a, settle, max_passes):
    n = tour.size
    pos = np.empty(n, np.int64)
    for i in range(n):
        pos[tour[i]] = i
    for _ in range(max_passes):
        improved = False
        for q0 in range(n - 1):
            ta, tb = tour[q0], tour[q0 + 1]
            dab = _cost(p, ta, tb, v, a, settle)
            for kk in range(nbrs.shape[1]):
                c = nbrs[ta, kk]
                if c == ta or c == tb:
                    continue
                dac = _cost(p, ta, c, v, a, settle)
                if dac >= dab:
                    break
                lo, hi = min(q0, pos[c]), max(q0, pos[c])
                removed = _cost(p, tour[lo], tour[lo + 1], v, a, settle)
                added = _cost(p, tour[lo], tour[hi], v, a, settle)
                if hi < n - 1:
                    removed += _cost(p, tour[hi], tour[hi + 1], v, a, settle)
                    added += _cost(p, tour[lo + 1], tour[hi + 1], v, a, settle)
                if added < removed - 1e-12:
                    i, j = lo + 1, hi
                    while i < j:
                        tour[i], tour[j] = tour[j], tour[i]
                        pos[tour[i]], pos[tour[j]] = i, j
                        i += 1
                        j -= 1
                    improved = True
                    break
        if not improved:
            break
    return tour


def two_opt(
    angles: np.ndarray, order: np.ndarray, *, steering: SteeringOptions, options: OrderOptions
) -> np.ndarray:
    """Improve an open tour by 2-opt moves (the first point stays first).

    Parameters
    ----------
    angles : (n, 2) float
        Pointings (rad).
    order : (n,) int
        Starting tour (a permutation).
    steering : SteeringOptions
        Move-time model (the edge cost).
    options : OrderOptions
        ``neighbours`` and ``max_passes``.

    Returns
    -------
    (n,) int64 tour, never longer in time than ``order``.
    """
    p = np.ascontiguousarray(angles, dtype=float)
    tour = np.array(order, dtype=np.int64, copy=True)
    n = len(p)
    if n < 4:
        return tour
    k = min(int(options.neighbours) + 1, n)
    _, nbrs = cKDTree(p).query(p, k=k, p=np.inf)
    return _two_opt(
        p,
        tour,
        np.ascontiguousarray(nbrs, dtype=np.int64),
        float(steering.max_rate_rad_s),
        float(steering.move_accel_rad_s2),
        float(steering.settle_s),
        int(options.max_passes),
    )


def order_scan(
    angles: np.ndarray, *, steering: SteeringOptions, options: OrderOptions = OrderOptions()
) -> np.ndarray:
    """Visiting order of a plan's pointings; the planner's first point stays first.

    Parameters
    ----------
    angles : (n, 2) float
        Pointings (azimuth, elevation) in the planner's order (rad).
    steering : SteeringOptions
    options : OrderOptions

    Returns
    -------
    (n,) int64 permutation of ``range(n)``.
    """
    p = np.asarray(angles, float)
    n = len(p)
    given = np.arange(n, dtype=np.int64)
    if steering.model == "continuous_raster":
        return raster_sweep(p, options=steering).order  # the raster fires in its own order
    if options.method == "given" or n < 3:
        return given
    if options.method == "raster":
        return raster_order(p, options.line_pitch_rad)
    best, best_t = given, scan_timing(p, given, options=steering).total_s
    # 2-opt from a random-looking planner order is slow (long reversals): small plans only
    seeds = [nearest_neighbour_order(p, 0)] + ([given] if n <= 5000 else [])
    for seed in seeds:
        tour = two_opt(p, seed, steering=steering, options=options)
        t = scan_timing(p, tour, options=steering).total_s
        if t < best_t:
            best, best_t = tour, t
    return best


def exact_order(angles: np.ndarray, *, steering: SteeringOptions) -> np.ndarray:
    """Shortest open tour from point 0 by brute force (n <= 10: (n - 1)! tours)."""
    p = np.asarray(angles, float)
    n = len(p)
    if n > 10:
        raise ValueError(f"exact_order enumerates (n - 1)! tours; n = {n} > 10")
    if n < 3:
        return np.arange(n, dtype=np.int64)
    rest = np.array(list(itertools.permutations(range(1, n))), dtype=np.int64)
    tours = np.concatenate([np.zeros((len(rest), 1), np.int64), rest], axis=1)
    legs = move_time(p[tours[:, :-1]], p[tours[:, 1:]], steering)
    return tours[int(np.argmin(legs.sum(axis=1)))]
