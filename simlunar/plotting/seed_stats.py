"""Per-seed summaries of the tables and figures: the mean with its 95 % Student t interval,
in log space for ratios (split from :mod:`simlunar.plotting.tables`, which re-exports
:func:`t_interval` and :func:`seed_summary_numbers`)."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["seed_summary_numbers", "t_interval"]


def t_interval(values) -> tuple[float, float, float]:
    """Mean and two-sided 95 % Student t interval of independent values (at least two).

    ``mean +- t(0.975, n - 1) * s / sqrt(n)`` with the sample standard deviation ``s``: the
    interval for a handful of terrain seeds, where a bootstrap's percentiles would be too
    narrow. (The t quantile from ``scipy.special.stdtrit``: ``scipy.stats`` costs 0.45 s to
    import and a table never needs the rest of it.)
    """
    from scipy.special import stdtrit

    v = np.asarray(values, dtype=float)
    if v.size < 2:
        raise ValueError(f"a t interval needs at least two values, got {v.size}")
    m = float(v.mean())
    h = float(stdtrit(v.size - 1, 0.975) * v.std(ddof=1) / math.sqrt(v.size))
    return m, m - h, m + h


def _seed_summary(v: np.ndarray, *, log: bool, digits: int = 2) -> tuple[str, str]:
    """``(mean [95 % t interval], min–max)`` of per-seed values, finite ones only.

    ``log``: values are ratios (> 0); mean and interval in log space (a geometric mean and a
    multiplicative interval). One seed: the value alone and no range. Seeds left out (no
    finite value: no density inside the reference's range, or an oracle that saves nothing)
    are counted in the range cell ("(2 of 3 seeds)").
    """
    n = v.size
    v = v[np.isfinite(v)]
    if log:
        v = v[v > 0]
    of = f" ({v.size} of {n} seeds)" if v.size < n else ""
    if v.size == 0:
        return "–", of.strip()
    if v.size == 1:
        return f"{v[0]:.{digits}f}", of.strip()
    m, lo, hi = t_interval(np.log(v) if log else v)
    if log:
        m, lo, hi = np.exp(m), np.exp(lo), np.exp(hi)
    return (f"{m:.{digits}f} [{lo:.{digits}f}, {hi:.{digits}f}]",
            f"{v.min():.{digits}f}–{v.max():.{digits}f}{of}")  # fmt: skip


def seed_summary_numbers(values, *, log: bool) -> tuple[float, float, float, int]:
    """``(mean, low, high, n)`` of the finite per-seed values (positive ones with ``log``):
    the geometric mean with its 95 % t interval in log space (``log``) or the mean with its
    t interval; with one value, the value and NaN bounds; with none, NaNs and 0."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if log:
        v = v[v > 0]
    if v.size == 0:
        return math.nan, math.nan, math.nan, 0
    if v.size == 1:
        return float(v[0]), math.nan, math.nan, 1
    m, lo, hi = t_interval(np.log(v) if log else v)
    if log:
        m, lo, hi = math.exp(m), math.exp(lo), math.exp(hi)
    return m, lo, hi, int(v.size)
