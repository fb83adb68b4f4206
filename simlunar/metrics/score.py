"""The paper's strategy score (eq. 4.3) and samples-for-equal-error."""

from __future__ import annotations

import numpy as np

__all__ = ["check_densities", "samples_for_equal_error", "score"]


def check_densities(densities) -> np.ndarray:
    """Densities k/N as float64 (n,), each in (0, 1]."""
    d = np.asarray(densities, dtype=np.float64).reshape(-1)
    if d.size == 0:
        raise ValueError("densities is empty")
    if not np.all(np.isfinite(d)) or np.any(d <= 0) or np.any(d > 1):
        raise ValueError(f"densities must lie in (0, 1], got {d.tolist()}")
    return d


def _mean_errors(errors, n: int, name: str) -> np.ndarray:
    e = np.asarray(errors, dtype=np.float64)
    if e.ndim == 2:  # (densities, trials): average the trials first
        e = e.mean(axis=1)
    if e.shape != (n,):
        raise ValueError(
            f"errors of {name!r} must have shape ({n},) or ({n}, trials), got {e.shape}"
        )
    if not np.all(np.isfinite(e)) or np.any(e < 0):
        raise ValueError(f"errors of {name!r} must be finite and >= 0")
    return e


def score(errors_by_strategy: dict, densities, reference: str = "random") -> dict[str, float]:
    """Score of each strategy relative to a reference (paper eq. 4.3).

    score_s = sum_d w_d e_ref(d) / e_s(d) / sum_d w_d with w_d = 1 / d (inverse density, the
    same as 1 / k up to the constant N), so sparse densities weigh most, the reference scores
    exactly 1 and higher is better. Errors are averaged over trials before the ratio.

    Parameters
    ----------
    errors_by_strategy : dict of str -> array_like, shape (n,) or (n, trials)
        Error per density (and trial) for each strategy; must contain ``reference``.
    densities : array_like, shape (n,)
        Densities k / N in (0, 1].
    reference : str
        The strategy every other is compared with (default ``"random"``).

    Returns
    -------
    dict of str -> float
        0 / 0 counts as a ratio of 1 (both exact); a zero strategy error against a positive
        reference error gives ``inf``.
    """
    d = check_densities(densities)
    if reference not in errors_by_strategy:
        raise ValueError(f"reference {reference!r} missing; have: {', '.join(errors_by_strategy)}")
    w = 1.0 / d
    e_ref = _mean_errors(errors_by_strategy[reference], d.size, reference)
    out = {}
    for name, errs in errors_by_strategy.items():
        e = _mean_errors(errs, d.size, name)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where((e == 0) & (e_ref == 0), 1.0, e_ref / e)
        out[name] = float(np.sum(w * ratio) / np.sum(w))
    return out


def samples_for_equal_error(
    errors_by_strategy: dict, ks, reference: str = "random"
) -> dict[str, np.ndarray]:
    """Samples a strategy needs to match the reference's error, relative to the reference.

    For each reference sample count k_i with error e_ref(k_i), the strategy's error-vs-k curve
    is interpolated linearly in log-log to find k_s with e_s(k_s) = e_ref(k_i); the result is
    k_s / k_i (< 1: the strategy needs fewer samples). NaN where e_ref(k_i) lies outside the
    strategy's measured error range (no extrapolation).

    Parameters
    ----------
    errors_by_strategy : dict of str -> array_like, shape (n,) or (n, trials)
    ks : array_like, shape (n,)
        Sample counts (> 0), any order.
    reference : str

    Returns
    -------
    dict of str -> ndarray, shape (n,)
        Ratios in the order of ``ks``.
    """
    k = np.asarray(ks, dtype=np.float64).reshape(-1)
    if k.size < 2 or np.any(k <= 0) or np.unique(k).size != k.size:
        raise ValueError("ks must hold at least two distinct positive sample counts")
    if reference not in errors_by_strategy:
        raise ValueError(f"reference {reference!r} missing; have: {', '.join(errors_by_strategy)}")
    order = np.argsort(k)
    logk = np.log(k[order])
    e_ref = _mean_errors(errors_by_strategy[reference], k.size, reference)
    out = {}
    for name, errs in errors_by_strategy.items():
        e = _mean_errors(errs, k.size, name)[order]
        loge = np.log(np.maximum(e, np.finfo(float).tiny))
        target = np.log(np.maximum(e_ref, np.finfo(float).tiny))
        res = np.full(k.size, np.nan)
        # walk the piecewise-linear log-log curve: first segment that brackets the target
        for i, t in enumerate(target):
            for a in range(logk.size - 1):
                lo, hi = loge[a], loge[a + 1]
                if min(lo, hi) <= t <= max(lo, hi):
                    f = 0.0 if hi == lo else (t - lo) / (hi - lo)
                    res[i] = np.exp(logk[a] + f * (logk[a + 1] - logk[a])) / k[i]
                    break
        out[name] = res
    return out
