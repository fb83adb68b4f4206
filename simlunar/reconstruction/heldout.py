"""The held-out check of an image's detail and the blend it caps.

A reconstruction that adds detail to the samples' linear interpolation (``shading``,
``photoclinometry``, ``learned``) weighs it by how well it predicts samples it did not see
(:func:`heldout_gamma`): every fifth sample is left out, the detail is re-anchored on the rest,
and the least-squares weight of that detail against the left-out samples' departure from the
kept samples' interpolation is the largest weight allowed. :func:`blend_detail` adds the
re-anchored detail at that weight inside the samples' hull (the linear reconstruction's nearest
fill outside); :func:`checked_blend` does both and records the check in ``info``.
"""

from __future__ import annotations

import numpy as np

from simlunar.reconstruction._anchor import (
    LinearField,
    at_points,
    linear_field,
    reanchored_detail,
)

__all__ = ["blend_detail", "checked_blend", "heldout_fit", "heldout_gamma"]


def blend_detail(
    lin: LinearField, field: np.ndarray, gamma: float, *, limit: float | None = None
) -> np.ndarray:
    """``z_lin + gamma * hull * (z_a - z_lin)``: ``field`` re-anchored on the samples, weighted
    by ``gamma`` inside their hull (the linear reconstruction's nearest fill outside); with
    ``limit``, the re-anchored detail is clipped to ``[-limit, limit]`` first."""
    d = reanchored_detail(field, lin)
    if limit is not None:
        d = np.clip(d, -limit, limit)
    return np.where(lin.hull, lin.heights + gamma * d, lin.heights)


def checked_blend(
    lin: LinearField,
    detail,
    gamma: float,
    info: dict,
    *,
    remade=None,
    pool_folds=False,
    clip: float = 0.0,
) -> np.ndarray:
    """:func:`blend_detail` at ``gamma``, first capped by the held-out check of ``remade``
    (:func:`heldout_gamma`'s ``field``: the detail, or a function of the kept samples that
    makes it again; None: no check), which records ``heldout_gamma``, ``heldout_samples`` and
    the capped ``gamma`` in ``info``; the linear heights where the weight is 0.

    ``clip`` > 0 (with a check): the re-anchored detail is limited to ``clip`` times the RMS of
    the held-out samples' departure from the kept samples' interpolation (``info``:
    ``detail_limit``), the scale of linear's own error at this density. The check weighs the
    detail at a few hundred held-out samples; where the frames mislead in a few cells (a
    shadow's edge under a 5 deg sun with a flash frame: 1 % of the cells carried 60 % of
    the error at 1/16) it never sees them, and one weight for the whole field let them
    through.
    """
    limit = None
    if remade is not None:
        g_cv, n_test, r2, rms = _heldout_fit(remade, lin, pool_folds=pool_folds)
        info["heldout_gamma"], info["heldout_samples"] = g_cv, n_test
        info["heldout_r2"] = r2
        gamma = min(gamma, g_cv)
        info["gamma"] = gamma
        if clip > 0 and np.isfinite(rms):
            limit = clip * rms
            info["detail_limit"] = limit
    if gamma == 0.0:
        return lin.heights
    return blend_detail(lin, detail, gamma, limit=limit)


def heldout_gamma(
    field, lin: LinearField, *, every: int = 5, pool_folds: bool = False
) -> tuple[float, int]:
    """The weight of ``field``'s detail that best predicts held-out samples, in [0, 1].

    Every ``every``-th sample (in row-major order: spread over the grid, no randomness) is
    left out; the rest are interpolated linearly (``z_tr``) and ``field`` is re-anchored on
    them (``d = field - interp(field at the kept samples)``). At the left-out samples inside the
    kept samples' hull, the least-squares ``g`` of ``v - z_tr ~ g d`` says how much of the
    image's detail is real at this density: about 1 where shading carries the shape between
    samples, 0 where the detail is albedo (a high sun on a bright-and-dark surface), where it
    would make the reconstruction worse than linear. The kept samples are 4/5 of all, so the
    check runs at a 12 % wider pitch: a conservative estimate.

    Parameters
    ----------
    field : ndarray, shape (rows, cols), or callable
        The detail field, or ``field(keep) -> ndarray (rows, cols)`` that makes it from the
        kept samples only (``keep``: their :class:`LinearField`). A field made from the
        samples themselves (the learned residual, whose features read the distance to the
        nearest sample and the samples' own residuals) must be remade without the samples it
        is checked on, or the check would see them.
    lin : LinearField
        The linear reconstruction of all the samples.
    every : int
        Every ``every``-th sample is held out.
    pool_folds : bool
        When the one split leaves fewer than 20 samples inside the hull (a sparse layout: on
        250 x 400 cells, 1/1024 and sparser), pool all ``every`` splits (each sample held out
        once, ``every`` fields made) into one least-squares weight instead of returning 0.
        Off: one split (every reconstruction that checks pools: ``shading``, ``photoclinometry``,
        ``learned``).

    Returns
    -------
    g : float in [0, 1]
        0 when fewer than 20 samples are left out inside the hull, or ``d`` vanishes there.
    n : int
        The left-out samples used.
    """
    g, n, _ = heldout_fit(field, lin, every=every, pool_folds=pool_folds)
    return g, n


def heldout_fit(
    field, lin: LinearField, *, every: int = 5, pool_folds: bool = False
) -> tuple[float, int, float]:
    """:func:`heldout_gamma`'s ``(g, n)`` and the share of the held-out samples' departure
    from the kept samples' interpolation that ``g`` times the detail explains,
    ``r2 = 1 - |v - z_tr - g d|^2 / |v - z_tr|^2`` (0 when ``g`` is 0)."""
    return _heldout_fit(field, lin, every=every, pool_folds=pool_folds)[:3]


def _heldout_fit(field, lin: LinearField, *, every: int = 5, pool_folds: bool = False):
    """:func:`heldout_fit`'s ``(g, n, r2)`` and the RMS of the held-out departures
    ``v - z_tr`` (NaN when fewer than 20 samples are held out)."""
    pts = lin.points
    if len(pts) < 5 * every:
        return 0.0, 0, 0.0, float("nan")
    order = np.lexsort((pts[:, 1], pts[:, 0]))
    parts = [_heldout_split(lin, order, 0, every)]
    if len(parts[0][1]) < 20 and pool_folds:
        parts += [_heldout_split(lin, order, f, every) for f in range(1, every)]
    n = sum(len(tp) for _, tp, _ in parts)
    if n < 20:
        return 0.0, n, 0.0, float("nan")
    num = den = ss = 0.0
    for keep, tp, tv in parts:
        if not len(tp):
            continue
        resid = tv - at_points(keep.heights, tp)
        f = field(keep) if callable(field) else field
        d = at_points(reanchored_detail(f, keep), tp)
        num += float(d @ resid)
        den += float(d @ d)
        ss += float(resid @ resid)
    rms = float(np.sqrt(ss / n))
    if not den > 0:
        return 0.0, n, 0.0, rms
    g = float(np.clip(num / den, 0.0, 1.0))
    r2 = (2.0 * g * num - g * g * den) / ss if ss > 0 else 0.0
    return g, n, float(r2), rms


def _heldout_split(lin: LinearField, order, start: int, every: int):
    """``(keep, points, values)``: the kept samples' :class:`LinearField` and the left-out
    samples (``order[start::every]``) inside its hull."""
    pts, vals = lin.points, lin.values
    test = np.zeros(len(pts), bool)
    test[order[start::every]] = True
    keep = linear_field(pts[~test], vals[~test], lin.shape)
    tp = pts[test]
    inside = at_points(keep.hull.astype(np.float64), tp) > 0.5
    return keep, tp[inside], vals[test][inside]
