"""Fit the coefficients of a linear combination of feature maps (paper section 4.1).

"Optimal linear coefficients were found using fminsearch": MATLAB's ``fminsearch`` is the
Nelder-Mead simplex method, here ``scipy.optimize.minimize(method="Nelder-Mead")``. What the
paper combined is not stated; this fits weights a_i of the normalised feature maps,
w = sum_i |a_i| m_i / mean(m_i), maximising the mean eq. 4.3 score against uniform random
sampling over training scenes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from simlunar.features import FEATURES, check_image, feature_map
from simlunar.planner.strategies import check_k, combine_maps, plan


@dataclass(frozen=True)
class CombinationFit:
    """Result of :func:`fit_combination`.

    Attributes
    ----------
    coefficients : dict of str -> float
        Non-negative weights summing to 1 (pass as ``coefficients=`` to the ``combination``
        strategy).
    score : float
        Mean training score (eq. 4.3 against random) at the optimum.
    initial_score : float
        The same at the starting point (equal weights unless ``x0`` is given).
    nfev : int
        Objective evaluations.
    """

    coefficients: dict[str, float]
    score: float
    initial_score: float
    nfev: int


def fit_combination(
    scenes: Sequence[tuple[np.ndarray, np.ndarray]],
    *,
    features: Sequence[str] = ("gradient", "entropy", "wavelet"),
    densities: Sequence[float] = (1 / 16, 1 / 64, 1 / 256, 1 / 1024),
    trials: int = 2,
    metric: str = "mse",
    rng,
    maxiter: int = 60,
    x0: Sequence[float] | None = None,
) -> CombinationFit:
    """Fit combination coefficients by Nelder-Mead on training scenes.

    Parameters
    ----------
    scenes : sequence of (depth, image)
        Training scenes: depth (rows, cols) and guide image (rows, cols) or (rows, cols, 3).
    features : sequence of str
        Feature maps to combine (names of ``simlunar.features.FEATURES``).
    densities : sequence of float
        Densities k / N in (0, 1] of the training protocol.
    trials : int
        Trials per density; the seeds are fixed across objective evaluations (common random
        numbers), so the objective is deterministic and Nelder-Mead can compare points.
    metric : str
        Error metric the score uses (``mse``, ``rmse``, ``mae``, ``grad``; ``sal`` uses the
        image's saliency map).
    rng : None, int, SeedSequence or Generator
    maxiter : int
        Nelder-Mead iterations.
    x0 : sequence of float, optional
        Starting coefficients (default all ones).

    Returns
    -------
    CombinationFit
    """
    from simlunar.metrics import check_densities, depth_gradient_weights
    from simlunar.metrics import metric as error_metric
    from simlunar.metrics import score as eq43
    from simlunar.reconstruction import reconstruct

    features = list(features)
    bad = [f for f in features if f not in FEATURES]
    if bad or not features:
        raise ValueError(f"unknown feature(s) {bad}; valid: {', '.join(FEATURES)}")
    dens = check_densities(densities)
    if not scenes:
        raise ValueError("fit_combination needs at least one training scene")
    base = int(np.random.default_rng(rng).integers(0, 2**63))

    prepared = []
    for si, (depth, image) in enumerate(scenes):
        depth = np.asarray(depth, dtype=np.float64)
        image = check_image(image)
        if depth.shape != image.shape[:2] or not np.all(np.isfinite(depth)):
            raise ValueError(f"scene {si}: depth must be finite and match the image grid")
        maps = {f: feature_map(f, image) for f in features}
        mw = None
        if metric == "grad":
            mw = depth_gradient_weights(depth)
        elif metric == "sal":
            mw = feature_map("saliency", image)
        ks = [check_k(max(3, round(d * depth.size)), depth.size) for d in dens]
        seeds = [
            [np.random.SeedSequence(base, spawn_key=(si, di, t)) for t in range(trials)]
            for di in range(len(ks))
        ]

        def errors(strategy, weights, depth=depth, ks=ks, seeds=seeds, mw=mw):
            e = np.empty((len(ks), trials))
            for di, k in enumerate(ks):
                for t in range(trials):
                    p = plan(strategy, k, weights=weights, shape=depth.shape, rng=seeds[di][t])
                    rec = reconstruct(p.rc, depth[p.rows, p.cols], depth.shape)
                    e[di, t] = error_metric(metric, rec, depth, weights=mw)
            return e

        prepared.append((maps, errors, errors("random", None)))

    nfev = 0

    def mean_score(x):
        nonlocal nfev
        nfev += 1
        coefs = dict(zip(features, np.abs(x)))
        if sum(coefs.values()) <= 0:
            return 0.0
        total = 0.0
        for maps, errors, e_random in prepared:
            w = combine_maps(maps, coefs)
            e = errors("combination", w)
            total += eq43({"random": e_random, "combination": e}, dens)["combination"]
        return total / len(prepared)

    start = np.ones(len(features)) if x0 is None else np.asarray(x0, dtype=np.float64)
    if start.shape != (len(features),):
        raise ValueError(f"x0 must have {len(features)} entries, got {start.shape}")
    initial = mean_score(start)
    res = minimize(
        lambda x: -mean_score(x), start, method="Nelder-Mead", options={"maxiter": maxiter}
    )
    best_x, best = (res.x, -float(res.fun)) if -res.fun >= initial else (start, initial)
    a = np.abs(best_x)
    a = a / a.sum()
    return CombinationFit(
        coefficients={f: float(v) for f, v in zip(features, a)},
        score=float(best),
        initial_score=float(initial),
        nfev=nfev,
    )
