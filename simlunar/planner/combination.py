"""Fit the coefficients of a linear combination of feature maps (paper section 4.1).

"Optimal linear coefficients were found using fminsearch": MATLAB's ``fminsearch`` is the
Nelder-Mead simplex method, here ``scipy.optimize.minimize(method="Nelder-Mead")``. What the
paper combined is not stated; this fits weights a_i of the normalised maps
w = sum_i |a_i| m_i / mean(m_i) of ``uniform`` (a constant map: a share of uniform sampling),
``gradient``, ``entropy``, ``wavelet`` and ``saliency``, maximising the mean eq. 4.3 score
against uniform random sampling over training scenes. Score the result on held-out scenes
with :func:`score_combination`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from simlunar.features import check_image, feature_map
from simlunar.metrics import check_densities, depth_gradient_weights
from simlunar.metrics import metric as error_metric
from simlunar.metrics import score as eq43
from simlunar.planner.strategies import COMBINABLE, check_k, combination_map, combine_maps, plan
from simlunar.reconstruction import reconstruct
from simlunar.registry import Options, option

__all__ = [
    "DEFAULT_FEATURES",
    "DEFAULT_PROTOCOL",
    "DEFAULT_SEARCH",
    "CombinationFit",
    "NelderMeadOptions",
    "ScoreProtocol",
    "fit_combination",
    "score_combination",
]

#: the maps :func:`fit_combination` weights by default
DEFAULT_FEATURES = COMBINABLE


@dataclass(frozen=True)
class ScoreProtocol(Options):
    """How coefficients are scored: the eq. 4.3 protocol of the fit and of the held-out score.

    The trials' seeds are fixed across objective evaluations (common random numbers), so the
    objective is deterministic and Nelder-Mead can compare points. With ``placement="lloyd"``
    the combined map is placed by the deterministic halftone + weighted Lloyd layout
    (:mod:`simlunar.planner.placement`, border covered), whose plan changes smoothly with the
    coefficients; the reference of the eq. 4.3 score stays uniform random sampling either way,
    and the weight on ``uniform`` is the share of the uniform Lloyd layout, so "all on uniform"
    is the image-free reference layout.
    """

    densities: Sequence[float] = option(
        (1 / 16, 1 / 64, 1 / 256, 1 / 1024), doc="densities k / N in (0, 1] of the protocol"
    )
    trials: int = option(2, doc="trials per density (common random numbers)")
    metric: str = option(
        "mse",
        doc="error metric the score uses (mse, rmse, mae, grad; sal uses the image's saliency map)",
    )
    placement: str = option(
        "random",
        doc="how the combined map places its samples: the paper's weighted random draw, or "
        "the halftone + weighted Lloyd layout",
        choices=("random", "lloyd"),
    )


@dataclass(frozen=True)
class NelderMeadOptions:
    """The search of :func:`fit_combination`.

    The initial simplex is set in log-ratio space: each vertex multiplies one coefficient by
    e^step (scipy's default 5 % steps are too small for the nearly piecewise-constant
    objective of a sampled plan); coefficients that are 0 in ``x0`` start at 1e-6 of the
    largest. Each restart runs from the best point so far with a fresh simplex.
    """

    maxiter: int = option(60, doc="Nelder-Mead iterations (per run)")
    x0: Sequence[float] | None = option(None, doc="starting coefficients (None: all ones)")
    step: float = option(1.0, doc="initial simplex size in log-ratio space")
    restarts: int = option(2, doc="Nelder-Mead runs after the first")


#: the protocol and the search :func:`fit_combination` uses unless told otherwise
DEFAULT_PROTOCOL = ScoreProtocol()
DEFAULT_SEARCH = NelderMeadOptions()


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


def _prepare(scenes, maps, features, dens, protocol, base, feature_opts):

    trials, metric = protocol.trials, protocol.metric
    placed = {"placement": protocol.placement}
    if maps is not None and len(maps) != len(scenes):
        raise ValueError(f"maps: one dict per scene, got {len(maps)} for {len(scenes)} scenes")
    prepared = []
    for si, (depth, image) in enumerate(scenes):
        depth = np.asarray(depth, dtype=np.float64)
        image = check_image(image)
        if depth.shape != image.shape[:2] or not np.all(np.isfinite(depth)):
            raise ValueError(f"scene {si}: depth must be finite and match the image grid")
        given = {} if maps is None else dict(maps[si])
        m = {}
        for f in features:
            if f in given:
                m[f] = np.asarray(given[f], dtype=np.float64)
                if m[f].shape != depth.shape:
                    raise ValueError(f"scene {si}: map {f!r} shape {m[f].shape} != {depth.shape}")
            else:
                m[f] = combination_map(f, image, **(feature_opts or {}).get(f, {}))
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
            opts = placed if strategy == "combination" else {}
            for di, k in enumerate(ks):
                for t in range(trials):
                    p = plan(
                        strategy, k, weights=weights, shape=depth.shape, rng=seeds[di][t], **opts
                    )
                    rec = reconstruct(p.rc, depth[p.rows, p.cols], depth.shape)
                    e[di, t] = error_metric(metric, rec, depth, weights=mw)
            return e

        prepared.append((m, errors, errors("random", None)))
    return prepared


def _check(features, densities, scenes):

    features = list(features)
    bad = [f for f in features if f not in COMBINABLE]
    if bad or not features:
        raise ValueError(f"unknown feature(s) {bad}; valid: {', '.join(COMBINABLE)}")
    dens = check_densities(densities)
    if not scenes:
        raise ValueError("fit_combination needs at least one training scene")
    return features, dens


def _mean_score(prepared, coefs, dens):

    total = 0.0
    for m, errors, e_random in prepared:
        w = combine_maps(m, coefs)
        e = errors("combination", w)
        total += eq43({"random": e_random, "combination": e}, dens)["combination"]
    return total / len(prepared)


def _start_point(x0, n: int) -> np.ndarray:
    start = np.ones(n) if x0 is None else np.asarray(x0, dtype=np.float64)
    if start.shape != (n,):
        raise ValueError(f"x0 must have {n} entries, got {start.shape}")
    start = np.abs(start)
    if not start.sum() > 0:
        raise ValueError("x0 must have a non-zero entry")
    return start


def _log_ratio_space(start: np.ndarray):
    """The search space of the coefficients: ``(coefs_of, z0)``.

    Search in log-ratios z_i = log(a_i / a_ref) against the largest start coefficient: the
    score does not depend on the scale of a, so this drops the flat direction, keeps every
    weight positive, and makes a simplex step a factor (e^step) rather than an increment.
    ``coefs_of(z)`` maps a point to coefficients summing to 1; ``z0`` is the start's point.
    """
    ref = int(np.argmax(start))
    free = [i for i in range(len(start)) if i != ref]
    floor = 1e-6 * start[ref]

    def coefs_of(z):
        logs = np.zeros(len(start))
        logs[free] = z
        a = np.exp(logs - logs.max())
        return a / a.sum()

    return coefs_of, np.log(np.maximum(start[free], floor) / start[ref])


def _nelder_mead(objective, z, search: NelderMeadOptions):
    """Best point of ``search.restarts + 1`` Nelder-Mead runs: ``(z, f(z), f(start))``."""
    fz = objective(z)
    initial = fz
    # scipy.optimize is imported where a fit runs: it adds 0.2 s to every import of the planner
    from scipy.optimize import minimize

    for _ in range(search.restarts + 1 if z.size else 0):
        # restarting from the best vertex with a fresh simplex (as is usual with fminsearch)
        # escapes a simplex that collapsed on a plateau of the sampled objective
        simplex = np.vstack([z, z + search.step * np.eye(z.size)])
        res = minimize(
            objective,
            z,
            method="Nelder-Mead",
            options={"maxiter": search.maxiter, "initial_simplex": simplex},
        )
        if res.fun < fz:
            z, fz = res.x, float(res.fun)
    return z, fz, initial


def fit_combination(
    scenes: Sequence[tuple[np.ndarray, np.ndarray]],
    *,
    features: Sequence[str] = DEFAULT_FEATURES,
    protocol: ScoreProtocol = DEFAULT_PROTOCOL,
    rng,
    search: NelderMeadOptions = DEFAULT_SEARCH,
    maps: Sequence[dict[str, np.ndarray]] | None = None,
    feature_opts: dict[str, dict] | None = None,
) -> CombinationFit:
    """Fit combination coefficients by Nelder-Mead on training scenes.

    Parameters
    ----------
    scenes : sequence of (depth, image)
        Training scenes: depth (rows, cols) and guide image (rows, cols) or (rows, cols, 3).
    features : sequence of str
        Maps to combine (names of :data:`simlunar.planner.strategies.COMBINABLE`: ``uniform``
        and the feature maps).
    protocol : ScoreProtocol
        Densities, trials and metric of the training score.
    rng : None, int, SeedSequence or Generator
    search : NelderMeadOptions
        Iterations, start, initial simplex and restarts of the search.
    maps : sequence of dict, optional
        Per scene, precomputed maps by name (used instead of computing them from the image).
    feature_opts : dict of str -> dict, optional
        Options of each computed map (e.g. ``{"entropy": {"scale": "unit"}}``).

    Returns
    -------
    CombinationFit
        The best vertex Nelder-Mead found (never worse than the start, which is a vertex).
    """
    features, dens = _check(features, protocol.densities, scenes)
    base = int(np.random.default_rng(rng).integers(0, 2**63))
    prepared = _prepare(scenes, maps, features, dens, protocol, base, feature_opts)
    coefs_of, z0 = _log_ratio_space(_start_point(search.x0, len(features)))
    nfev = 0

    def objective(z):
        nonlocal nfev
        nfev += 1
        return -_mean_score(prepared, dict(zip(features, coefs_of(z))), dens)

    z, fz, f_start = _nelder_mead(objective, z0, search)
    a = coefs_of(z)
    return CombinationFit(
        coefficients={f: float(v) for f, v in zip(features, a)},
        score=float(-fz),
        initial_score=float(-f_start),
        nfev=nfev,
    )


def score_combination(
    scenes: Sequence[tuple[np.ndarray, np.ndarray]],
    coefficients: dict[str, float],
    *,
    protocol: ScoreProtocol = DEFAULT_PROTOCOL,
    rng,
    maps: Sequence[dict[str, np.ndarray]] | None = None,
    feature_opts: dict[str, dict] | None = None,
) -> float:
    """Mean eq. 4.3 score of fixed coefficients over (held-out) scenes, as in the fit."""
    features, dens = _check(list(coefficients), protocol.densities, scenes)
    base = int(np.random.default_rng(rng).integers(0, 2**63))
    prepared = _prepare(scenes, maps, features, dens, protocol, base, feature_opts)
    return _mean_score(prepared, dict(coefficients), dens)
