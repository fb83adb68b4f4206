"""Planners that fit the sensor: scan time, receiver pixels and the first frame's ranges.

The sampling study's planners choose *where* to sample from the image; a LIDAR also pays for
*how* it visits the samples. Three sensor-aware rules, on arrays (the study wires them to its
sensors, :mod:`simlunar.study.lidar`):

- :func:`fit_to_time` (tour-aware): density and visiting order chosen together. For a time
  budget, the largest sample count ``k`` whose plan, in the sensor's own visiting order
  (a steered beam's nearest-neighbour + 2-opt tour under its steering model, a micromirror's
  frames), fits the budget. With the budget of a reference plan (e.g. the grid's time at the
  same density) every comparison is at equal scan time. :func:`fit_to_budget` is the same
  search for an absolute budget from any count (time, laser energy or both): sensors side by
  side at equal time or equal energy.
- :func:`receiver_capped_plan` (receiver-aware micromirror): at most ``frames`` dots per
  receiver pixel, so the micromirror fires at most ``frames`` frames (dots sharing a receiver
  pixel need separate frames, :func:`simlunar.lidar.flash.micromirror_frames`). The
  ``k`` dots are shared among the receiver pixels in proportion to the importance map's mass in
  each, capped at ``frames`` (water-filling), and placed inside each receiver pixel by a
  weighted draw without replacement. :func:`receiver_capped_layout` keeps a planner's own
  layout instead (a Lloyd layout's spacing) and moves only the dots over the cap, each to the
  nearest free guide pixel of a receiver pixel with room.
- :func:`tile_range_scores` and :func:`choose_tiles` (flash revisits): the zoomed revisits go to
  the tiles whose first-frame ranges look least like a plane (the RMS residual of a plane fit to
  the measured points, unmeasured pixels counted as rough), mixed with the image plan's share
  of planned pixels per tile. Only the sensor's own measurement is read, never the truth.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.spatial import cKDTree

__all__ = [
    "choose_tiles",
    "fit_to_budget",
    "fit_to_time",
    "receiver_capped_layout",
    "receiver_capped_plan",
    "receiver_cells",
    "tile_range_scores",
]


def fit_to_time(
    place: Callable[[int], np.ndarray],
    scan_seconds: Callable[[np.ndarray], float],
    budget_s: float,
    *,
    k_max: int,
    k_min: int = 1,
) -> tuple[np.ndarray, float]:
    """The plan of the largest ``k`` in ``[k_min, k_max]`` whose scan fits ``budget_s``.

    Scan time grows with ``k`` (not strictly, plan to plan): a bisection on ``k`` keeps the
    largest fitting ``k`` it evaluated; the result never exceeds the budget unless even
    ``k_min`` does (then the ``k_min`` plan is returned).

    Parameters
    ----------
    place : callable k -> (k, 2) int rc
        The planner at ``k`` samples (deterministic for a given ``k``).
    scan_seconds : callable rc -> float
        The sensor's modelled time of scanning ``rc`` (its own visiting order) (s).
    budget_s : float
        Time budget (s), > 0.
    k_max, k_min : int
        Search range, ``1 <= k_min <= k_max``.

    Returns
    -------
    rc : (k, 2) int
    seconds : float
        Its modelled scan time (s).
    """
    k_min, k_max = _checked("budget_s", budget_s, k_min, k_max)
    at, cache = _memo(place, scan_seconds)
    if at(k_max)[1] <= budget_s:
        return at(k_max)
    if at(k_min)[1] > budget_s:
        return at(k_min)
    return _bisect(at, cache, budget_s, k_min, k_max)


def _checked(name: str, budget: float, k_min, k_max) -> tuple[int, int]:
    """``(k_min, k_max)`` as ints, after checking the budget (finite, > 0) and the range."""
    if not (np.isfinite(budget) and budget > 0):
        raise ValueError(f"{name} must be finite and > 0, got {budget}")
    k_min, k_max = int(k_min), int(k_max)
    if not 1 <= k_min <= k_max:
        raise ValueError(f"need 1 <= k_min <= k_max, got {k_min}, {k_max}")
    return k_min, k_max


def _memo(place, cost):
    """``at(k)``: the plan at ``k`` and its cost, each made once (``cache``: k -> both)."""
    cache: dict[int, tuple[np.ndarray, float]] = {}

    def at(k: int) -> tuple[np.ndarray, float]:
        if k not in cache:
            rc = place(k)
            cache[k] = (rc, float(cost(rc)))
        return cache[k]

    return at, cache


def _bisect(at, cache: dict, budget: float, lo: int, hi: int):
    """Bisection on ``k`` between ``lo`` (its plan fits) and ``hi`` (does not); the largest
    fitting ``k`` evaluated (``cache``: every plan ``at`` made)."""
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if at(mid)[1] <= budget:
            lo = mid
        else:
            hi = mid
    best = max((k for k, (_, c) in cache.items() if c <= budget))
    return at(best)


def fit_to_budget(
    place: Callable[[int], np.ndarray],
    cost: Callable[[np.ndarray], float],
    budget: float,
    *,
    k_start: int,
    k_max: int,
    k_min: int = 1,
) -> tuple[np.ndarray, float]:
    """The plan of the largest ``k`` in ``[k_min, k_max]`` whose ``cost`` fits ``budget``,
    searched from ``k_start``: doubling while the plan fits, halving while it does not, then
    :func:`fit_to_time`'s bisection between the last count that fits and the first that does
    not (so a far budget costs a few plans, never the ``k_max`` one unless the budget
    reaches it).

    Parameters
    ----------
    place : callable k -> (k, 2) int rc
        The planner at ``k`` samples (deterministic for a given ``k``).
    cost : callable rc -> float
        The plan's cost (e.g. its scan time in s, or its laser energy in J), growing with ``k``.
    budget : float
        The most cost, > 0.
    k_start, k_max, k_min : int
        First count tried (clipped to ``[k_min, k_max]``), the largest and the smallest.

    Returns
    -------
    rc : (k, 2) int
    cost : float
        Its cost (over ``budget`` only when even ``k_min`` samples are).
    """
    k_min, k_max = _checked("budget", budget, k_min, k_max)
    at, cache = _memo(place, cost)
    k = min(max(int(k_start), k_min), k_max)
    if at(k)[1] <= budget:
        lo, hi = k, None
        while lo < k_max:
            nxt = min(2 * lo, k_max)
            if at(nxt)[1] > budget:
                hi = nxt
                break
            lo = nxt
        if hi is None:
            return at(lo)
    else:
        hi, lo = k, None
        while hi > k_min:
            nxt = max(hi // 2, k_min)
            if at(nxt)[1] <= budget:
                lo = nxt
                break
            hi = nxt
        if lo is None:
            return at(k_min)
    return _bisect(at, cache, budget, lo, hi)


def receiver_cells(rc: np.ndarray, shape, receiver_shape) -> np.ndarray:
    """Receiver pixel (flat index, row-major) of guide pixels ``rc`` (k, 2) (row, col): a
    co-located receiver of ``receiver_shape`` (rows, cols) with the guide's field of view."""
    (h, w), (rh, rw) = shape, receiver_shape
    rc = np.asarray(rc).reshape(-1, 2)
    i = np.clip(((rc[:, 0] + 0.5) * rh / h).astype(np.int64), 0, rh - 1)
    j = np.clip(((rc[:, 1] + 0.5) * rw / w).astype(np.int64), 0, rw - 1)
    return i * rw + j


def receiver_capped_plan(
    weights: np.ndarray | None,
    k: int,
    *,
    shape,
    receiver_shape,
    frames: int | None = None,
    rng=None,
) -> np.ndarray:
    """``k`` guide pixels with at most ``frames`` in any receiver pixel.

    Parameters
    ----------
    weights : (rows, cols) float >= 0 or None
        Importance map of the guide view (None: uniform).
    k : int
        Dots, ``1 <= k <= frames x receiver pixels`` and ``<=`` guide pixels.
    shape : (rows, cols)
        Guide view.
    receiver_shape : (rows, cols)
        Receiver (same field of view).
    frames : int or None
        Most dots per receiver pixel (the frames the micromirror may fire); None = the least
        that holds ``k``: ``ceil(k / receiver pixels)``.
    rng : seed or Generator

    Returns
    -------
    (k, 2) int64 (row, col), distinct pixels.
    """
    g = np.random.default_rng(rng)
    h, w = (int(x) for x in shape)
    rh, rw = (int(x) for x in receiver_shape)
    cells = rh * rw
    k = int(k)
    if frames is None:
        frames = -(-k // cells)
    frames = int(frames)
    r, c = np.mgrid[0:h, 0:w]
    pix = np.stack([r.ravel(), c.ravel()], -1)
    cell = receiver_cells(pix, (h, w), (rh, rw))
    size = np.bincount(cell, minlength=cells)
    cap = np.minimum(frames, size)
    if not 1 <= k <= int(cap.sum()):
        raise ValueError(
            f"k = {k} dots do not fit {frames} per receiver pixel of {rh} x {rw} "
            f"(at most {int(cap.sum())})"
        )
    wmap = np.ones(h * w) if weights is None else np.asarray(weights, float).reshape(-1)
    if wmap.size != h * w or not np.all(np.isfinite(wmap)) or wmap.min() < 0:
        raise ValueError(f"weights must be finite, >= 0 and of shape {shape}")
    wmap = wmap + 1e-12 * max(wmap.max(), 1e-300)  # every pixel drawable
    mass = np.bincount(cell, weights=wmap, minlength=cells)
    counts = _water_fill(mass, cap, k, g)
    out = []
    order = np.argsort(cell, kind="stable")
    start = np.concatenate([[0], np.cumsum(size)])
    for q in np.flatnonzero(counts):
        members = order[start[q] : start[q + 1]]
        p = wmap[members] / wmap[members].sum()
        out.append(members[g.choice(len(members), int(counts[q]), replace=False, p=p)])
    sel = np.concatenate(out)
    return pix[sel].astype(np.int64)


def receiver_capped_layout(rc, *, shape, receiver_shape, frames: int | None = None) -> np.ndarray:
    """A layout ``rc`` moved as little as needed to put at most ``frames`` dots in any
    receiver pixel.

    Dots in receiver pixels within the cap stay where they are. Of the dots in a receiver
    pixel over the cap, the ones nearest (Euclidean, guide pixels) to a free guide pixel of a
    receiver pixel with room move there, nearest first, until no receiver pixel is over: a
    Lloyd layout keeps its spacing except where it clustered (where
    :func:`receiver_capped_plan` would redraw every dot inside its receiver pixel).
    Deterministic.

    Parameters
    ----------
    rc : (k, 2) int
        The layout (row, col), distinct guide pixels.
    shape, receiver_shape : (rows, cols)
        Guide view; receiver (same field of view).
    frames : int or None
        Most dots per receiver pixel; None = the least that holds ``k``.

    Returns
    -------
    (k, 2) int64 (row, col): distinct pixels; row ``i`` is dot ``i`` of ``rc``, moved or not.
    """
    h, w = (int(x) for x in shape)
    rh, rw = (int(x) for x in receiver_shape)
    cells = rh * rw
    out = np.asarray(rc, dtype=np.int64).reshape(-1, 2).copy()
    k = len(out)
    if k and (out.min() < 0 or (out[:, 0] >= h).any() or (out[:, 1] >= w).any()):
        raise ValueError(f"rc must lie in the guide view {h} x {w}")
    flat = out[:, 0] * w + out[:, 1]
    if np.unique(flat).size != k:
        raise ValueError("rc must be distinct guide pixels")
    frames = -(-k // cells) if frames is None else int(frames)
    r, c = np.mgrid[0:h, 0:w]
    pix = np.stack([r.ravel(), c.ravel()], -1)
    pix_cell = receiver_cells(pix, (h, w), (rh, rw))
    cap = np.minimum(frames, np.bincount(pix_cell, minlength=cells))
    if k > int(cap.sum()):
        raise ValueError(
            f"k = {k} dots do not fit {frames} per receiver pixel of {rh} x {rw} "
            f"(at most {int(cap.sum())})"
        )
    dot_cell = receiver_cells(out, (h, w), (rh, rw))
    count = np.bincount(dot_cell, minlength=cells)
    used = np.zeros(h * w, bool)
    used[flat] = True
    while (count > cap).any():
        movers = np.flatnonzero(count[dot_cell] > cap[dot_cell])
        free = np.flatnonzero(~used & (count[pix_cell] < cap[pix_cell]))
        dist, nearest = cKDTree(pix[free]).query(out[movers])
        for i in np.argsort(dist, kind="stable"):
            d, target = movers[i], free[nearest[i]]
            src, dst = dot_cell[d], pix_cell[target]
            if count[src] <= cap[src] or used[target] or count[dst] >= cap[dst]:
                continue  # settled already, or its target was taken: the next pass
            used[out[d, 0] * w + out[d, 1]] = False
            used[target] = True
            count[src] -= 1
            count[dst] += 1
            out[d], dot_cell[d] = pix[target], dst
    return out


def _water_fill(mass: np.ndarray, cap: np.ndarray, k: int, g) -> np.ndarray:
    """Integer counts (sum ``k``, ``<= cap``) proportional to ``mass`` where not capped: the
    level ``lam`` with ``sum(min(cap, lam mass)) = k`` by bisection, remainders drawn in
    proportion to their fractions."""
    lo, hi = 0.0, float(k) / max(mass[mass > 0].min(), 1e-300) + 1.0
    for _ in range(200):
        lam = 0.5 * (lo + hi)
        if np.minimum(cap, lam * mass).sum() < k:
            lo = lam
        else:
            hi = lam
    share = np.minimum(cap, hi * mass)
    counts = np.floor(share).astype(np.int64)
    left = k - int(counts.sum())
    if left > 0:
        frac = np.where(counts < cap, share - counts, 0.0)
        room = np.flatnonzero(frac > 0)
        if room.size < left:  # rounding left fewer fractional cells than dots: any with room
            room = np.flatnonzero(counts < cap)
            frac = np.ones(mass.size)
        pick = g.choice(room, left, replace=False, p=frac[room] / frac[room].sum())
        counts[pick] += 1
    return counts


def tile_range_scores(points: np.ndarray, valid: np.ndarray, zoom: int) -> np.ndarray:
    """Roughness of each tile of a zoom x zoom grid over a flash frame, from its own points.

    Parameters
    ----------
    points : (rows, cols, 3) float
        The first frame's world points (m; NaN where invalid), receiver pixel grid.
    valid : (rows, cols) bool
    zoom : int >= 1

    Returns
    -------
    (zoom, zoom) float64
        RMS residual (m) of a least-squares plane ``z = a x + b y + c`` through each tile's
        valid points; a tile with fewer than 3 valid points gets the largest score of the frame
        (unmeasured ground may hide anything); the share of invalid pixels in a tile adds
        that fraction of the largest score.
    """
    p = np.asarray(points, float)
    ok = np.asarray(valid, bool)
    rows, cols = ok.shape
    zoom = int(zoom)
    out = np.full((zoom, zoom), np.nan)
    miss = np.zeros((zoom, zoom))
    for ti in range(zoom):
        for tj in range(zoom):
            sl = (slice(ti * rows // zoom, (ti + 1) * rows // zoom),
                  slice(tj * cols // zoom, (tj + 1) * cols // zoom))  # fmt: skip
            m = ok[sl]
            miss[ti, tj] = 1.0 - m.mean() if m.size else 1.0
            q = p[sl][m]
            if len(q) >= 3:
                a = np.c_[q[:, 0], q[:, 1], np.ones(len(q))]
                coef, *_ = np.linalg.lstsq(a, q[:, 2], rcond=None)
                out[ti, tj] = np.sqrt(np.mean((q[:, 2] - a @ coef) ** 2))
    top = np.nanmax(out) if np.isfinite(out).any() else 1.0
    out = np.where(np.isfinite(out), out, top)
    return out + miss * top


def choose_tiles(
    plan_counts: np.ndarray | None,
    range_scores: np.ndarray | None,
    count: int,
    *,
    range_weight: float = 0.5,
) -> np.ndarray:
    """The ``count`` tiles of highest ``(1 - w) plan share + w range share``.

    Parameters
    ----------
    plan_counts : (zoom, zoom) float or None
        Planned pixels per tile (the image's choice); None: ranges only.
    range_scores : (zoom, zoom) float or None
        :func:`tile_range_scores`; None: the plan only.
    count : int
    range_weight : float in [0, 1]
        ``w``, the share of the ranges (used when both are given).

    Returns
    -------
    (count, 2) int (tile row, tile col), best first (ties: row-major).
    """
    if plan_counts is None and range_scores is None:
        raise ValueError("choose_tiles needs plan_counts, range_scores or both")
    if not 0.0 <= range_weight <= 1.0:
        raise ValueError(f"range_weight must be in [0, 1], got {range_weight}")

    def share(a):
        a = np.asarray(a, float)
        s = a.sum()
        return a / s if s > 0 else np.full(a.shape, 1.0 / a.size)

    if plan_counts is None:
        score = share(range_scores)
    elif range_scores is None:
        score = share(plan_counts)
    else:
        score = (1 - range_weight) * share(plan_counts) + range_weight * share(range_scores)
    zoom = score.shape[1]
    best = np.argsort(-score.ravel(), kind="stable")[: int(count)]
    return np.stack([best // zoom, best % zoom], axis=-1)
