"""The sampling study of the paper (section 4.1) on one depth grid and its guide image.

The study protocol (:mod:`simlunar.study.protocol`) with the ideal Dirac sampler
(:class:`~simlunar.sensors.ideal.IdealSampler`): for every strategy, density and trial, plan
k = round(density * N) pixels from the guide image, read the true depth there (optionally with
Gaussian range noise), reconstruct the full grid by Delaunay-linear interpolation and score the
reconstruction against the true depth.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from simlunar.features import check_image, feature_map
from simlunar.metrics import METRICS, check_densities, depth_gradient_weights
from simlunar.metrics import samples_for_equal_error as _samples_for_equal_error
from simlunar.metrics import score as _score
from simlunar.metrics._fast import error_sums
from simlunar.planner import STRATEGIES, check_k, plan, strategy_weights
from simlunar.sensors.ideal import IdealOptions, IdealSampler
from simlunar.study.protocol import Trials, run_protocol
from simlunar.study.stats import bootstrap_scores, samples_saved

__all__ = [
    "PAPER_STRATEGIES",
    "SamplingStudyOptions",
    "SamplingStudyResult",
    "paper_densities",
    "run_sampling_study",
    "sample_count",
]

PAPER_STRATEGIES = ("grid", "random", "gradient", "entropy", "wavelet")


def paper_densities() -> list[float]:
    """The paper's 11 densities k / N: 1/2, 1/4, ..., 1/2048."""
    return [2.0**-i for i in range(1, 12)]


def sample_count(density: float, n: int) -> int:
    """k = round(density * N); a density that gives k < 3 on this grid is an error."""
    k = round(density * n)
    if k < 3:
        raise ValueError(
            f"density {density:g} gives k = {k} < 3 samples on a grid of N = {n} pixels"
        )
    return check_k(k, n)


@dataclass
class SamplingStudyResult:
    """Outcome of :func:`run_sampling_study`.

    Attributes
    ----------
    rows : list of dict
        Tidy table, one row per (strategy, density, trial, metric): keys strategy, density, k,
        trial, metric, value.
    scores : dict of str -> dict of str -> float
        metric -> strategy -> score (eq. 4.3) against ``reference``; empty if the reference
        strategy was not run.
    strategies, metrics : list of str
    densities : list of float
    ks : list of int
    reference : str
    """

    rows: list[dict]
    scores: dict[str, dict[str, float]]
    strategies: list[str]
    densities: list[float]
    ks: list[int]
    metrics: list[str]
    reference: str = "random"
    _errors: dict = field(default_factory=dict, repr=False)

    def errors(self, metric: str) -> dict[str, np.ndarray]:
        """strategy -> errors, float64 (densities, trials)."""
        if metric not in self._errors:
            raise ValueError(
                f"metric {metric!r} not in this study; have: {', '.join(self.metrics)}"
            )
        return self._errors[metric]

    def mean_errors(self) -> dict[str, dict[str, np.ndarray]]:
        """metric -> strategy -> mean error per density over trials, float64 (densities,).

        The summary for error-vs-density plots.
        """
        return {m: {s: e.mean(axis=1) for s, e in by.items()} for m, by in self._errors.items()}

    def samples_for_equal_error(self, metric: str = "mse") -> dict[str, np.ndarray]:
        """Relative samples each strategy needs for the reference's error (see metrics)."""
        return _samples_for_equal_error(self.errors(metric), self.ks, reference=self.reference)

    def score_intervals(self, metric: str = "mse", *, n_boot: int = 2000, rng=0):
        """Scores of ``metric`` with paired bootstrap 95 % intervals over the trials.

        One scene: the interval says how well the trials pin each score down on this terrain
        (see :func:`simlunar.study.stats.bootstrap_scores`).
        """
        errs = self.errors(metric)
        return bootstrap_scores(
            errs, self.densities, reference=self.reference, n_boot=n_boot, rng=rng
        )

    def samples_saved(self, metric: str = "mse", reference: str | None = None):
        """Samples ``reference`` (default: the study's) needs for each strategy's mean error,
        over the strategy's, per density (:func:`simlunar.study.stats.samples_saved`)."""
        means = {s: e.mean(axis=1) for s, e in self.errors(metric).items()}
        n = round(self.ks[0] / self.densities[0])
        return samples_saved(
            means, self.ks, reference=reference or self.reference, n_pixels=float(n)
        )


def _check_grid(a, name: str) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    if a.ndim != 2:
        raise ValueError(f"{name} must have shape (rows, cols), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return a


def _seed(base: int, label: str, trial: int, density_index: int, stream: int):
    """Independent stream per (strategy label, trial, density, purpose).

    Keyed by a hash of the label, not its position, so adding, removing or reordering a strategy
    never changes another strategy's samples.
    """
    key = (zlib.crc32(label.encode()), trial, density_index, stream)
    return np.random.SeedSequence(base, spawn_key=key)


@dataclass(frozen=True)
class SamplingStudyOptions:
    """What a sampling study runs.

    Attributes
    ----------
    strategies : sequence of str
        Strategy labels. A label is a strategy name of ``simlunar.planner.STRATEGIES`` or any
        label whose ``strategy_options`` entry names one under the key ``"strategy"`` (e.g.
        ``{"wavelet-bn": {"strategy": "wavelet", "blue_noise": True}}``).
    densities : sequence of float, optional
        k / N values in (0, 1]; default :func:`paper_densities`.
    trials : int
        Trials per strategy and density (the paper: 20). The grid shift, the draws and the
        noise are fresh per trial.
    metrics : sequence of str
        Names of ``simlunar.metrics.METRICS``. GRAD weights come from the true depth gradient,
        SAL weights from the Itti-Koch saliency map of the guide image.
    range_noise_std : float
        Standard deviation of additive Gaussian noise on each range sample (units of depth):
        the ideal sampler's option (:class:`~simlunar.sensors.ideal.IdealOptions`).
    strategy_options : mapping str -> mapping, optional
        Per label planner options (see ``simlunar.planner``), plus ``"strategy"``.
    outside : {"nearest", "nan"}
        Reconstruction policy outside the samples' convex hull (same for every strategy).
    reference : str
        Strategy label the scores compare against (default ``"random"``).
    """

    strategies: Sequence[str] = PAPER_STRATEGIES
    densities: Sequence[float] | None = None
    trials: int = 20
    metrics: Sequence[str] = ("mse", "grad", "sal")
    range_noise_std: float = 0.0
    strategy_options: Mapping[str, Mapping] = field(default_factory=dict)
    outside: str = "nearest"
    reference: str = "random"

    def __post_init__(self):
        trials = self.trials
        if isinstance(trials, bool) or not isinstance(trials, (int, np.integer)) or trials < 1:
            raise ValueError(f"trials must be an integer >= 1, got {trials!r}")
        for m in self.metrics:
            if m not in METRICS:
                raise ValueError(f"unknown metric {m!r}; valid: {', '.join(METRICS)}")
        strategies = list(self.strategies)
        if not strategies or len(set(strategies)) != len(strategies):
            raise ValueError(
                f"strategies must be a non-empty list of distinct labels, got {strategies}"
            )
        unknown = sorted(set(self.strategy_options or {}) - set(strategies))
        if unknown:
            raise ValueError(f"strategy_options for strategies not in the study: {unknown}")


def run_sampling_study(
    depth,
    image,
    options: SamplingStudyOptions | None = None,
    *,
    rng,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
) -> SamplingStudyResult:
    """Run the paper's sampling protocol on one scene.

    Parameters
    ----------
    depth : ndarray, shape (rows, cols)
        Ground-truth depth (or height), e.g. m; finite.
    image : ndarray, shape (rows, cols) or (rows, cols, 3)
        Guide image in the same view (pixel (r, c) sees depth cell (r, c)); finite.
    options : SamplingStudyOptions, optional
        Strategies, densities, trials, metrics, range noise, reconstruction policy.
    rng : None, int, SeedSequence or Generator
        Seed of the study; split per (strategy label, trial, density) with ``SeedSequence``.
    workers : int
        Processes (fork) that run (strategy, trial) tasks in parallel; results do not depend on
        it (every task has its own seed).
    progress : callable(done, total), optional
        Called with the number of reconstructions done after each (strategy, trial) task.

    Returns
    -------
    SamplingStudyResult

    Notes
    -----
    Feature maps (and metric weights) are computed once per study and reused across densities
    and trials. Scores average each strategy's errors over trials before eq. 4.3.
    """
    o = options or SamplingStudyOptions()
    depth = _check_grid(depth, "depth")
    image = check_image(image)
    if image.shape[:2] != depth.shape:
        raise ValueError(f"image {image.shape[:2]} and depth {depth.shape} must have the same grid")
    dens = check_densities(paper_densities() if o.densities is None else o.densities)
    sensor = IdealSampler(depth, IdealOptions(range_noise_std=float(o.range_noise_std)))
    ks = [sample_count(d, depth.size) for d in dens]
    planners, maps_cache = _planners(o, image, depth.shape)
    evaluate = _Evaluator(depth, image, list(o.metrics), maps_cache)
    base_seed = int(np.random.default_rng(rng).integers(0, 2**63))
    trials = Trials(planners, ks, int(o.trials), lambda lb, t, di: _seeds(base_seed, lb, t, di))
    if workers > 1:
        error_sums(np.zeros(1), np.zeros(1), np.ones((evaluate.rows.shape[0], 1)))  # compile
    strategies = list(o.strategies)
    errors = {m: {s: np.empty((len(ks), o.trials)) for s in strategies} for m in o.metrics}
    total, done = len(strategies) * o.trials * len(ks), 0
    for outcomes in run_protocol(sensor, trials, evaluate, outside=o.outside, workers=workers):
        for oc in outcomes:
            for m, v in oc.scores.items():
                errors[m][oc.label][oc.budget_index, oc.trial] = v
        done += len(ks)
        if progress is not None:
            progress(done, total)
    return _result(o, strategies, dens, ks, errors)


def _planners(o: SamplingStudyOptions, image, shape) -> tuple[dict, dict]:
    """Label -> protocol planner; each distinct importance map computed once."""
    planners, maps_cache = {}, {}
    for label in o.strategies:
        opts = dict(o.strategy_options.get(label, {}))
        base = opts.pop("strategy", label)
        if base not in STRATEGIES:
            raise ValueError(f"unknown strategy {base!r}; valid: {', '.join(STRATEGIES)}")
        key = (base, repr(opts.get("feature_opts")), repr(opts.get("coefficients")))
        if key not in maps_cache:
            maps_cache[key] = strategy_weights(
                base,
                image,
                feature_opts=opts.get("feature_opts"),
                coefficients=opts.get("coefficients"),
            )
        plan_opts = {k: v for k, v in opts.items() if k not in ("feature_opts", "coefficients")}
        # validate options once, before any long loop
        plan(base, 3, weights=maps_cache[key], shape=shape, rng=0, **plan_opts)
        planners[label] = _Planner(base, maps_cache[key], shape, plan_opts)
    return planners, maps_cache


@dataclass(frozen=True, eq=False)
class _Planner:
    """A strategy of :func:`simlunar.planner.plan` with its map: ``(k, rng) -> (k, 2) rc``."""

    base: str
    weights: np.ndarray | None
    shape: tuple
    opts: dict

    def __call__(self, k: int, rng) -> np.ndarray:
        return plan(self.base, k, weights=self.weights, shape=self.shape, rng=rng, **self.opts).rc


class _Evaluator:
    """All metrics of one reconstruction in one pass (same definitions as ``metric``); metric
    weights computed once per study."""

    def __init__(self, depth, image, metrics: list[str], maps_cache: dict):
        n = depth.size
        metric_w = {}
        if "grad" in metrics:
            metric_w["grad"] = depth_gradient_weights(depth).ravel()
        if "sal" in metrics:
            sal = maps_cache.get(("saliency", repr(None), repr(None)))
            metric_w["sal"] = (sal if sal is not None else feature_map("saliency", image)).ravel()
        for m, w in metric_w.items():
            if float(w.sum()) <= 0:
                raise ValueError(f"metric {m!r} weights are zero everywhere on this scene")
        self.truth = depth.ravel()
        self.metrics = metrics
        self.names = list(metric_w)
        self.rows = np.stack([metric_w[m] for m in self.names]) if self.names else np.zeros((0, n))

    def __call__(self, recon: np.ndarray, acquisition) -> dict[str, float]:
        count, sse, sae, wse, wsum = error_sums(recon.ravel(), self.truth, self.rows)
        if count == 0:
            raise ValueError("reconstruction has no finite cell to evaluate")
        out = {}
        for m in self.metrics:
            if m == "mse":
                out[m] = sse / count
            elif m == "rmse":
                out[m] = float(np.sqrt(sse / count))
            elif m == "mae":
                out[m] = sae / count
            else:
                j = self.names.index(m)
                if wsum[j] <= 0:
                    raise ValueError(f"metric {m!r} weights sum to zero over the evaluated cells")
                out[m] = float(wse[j] / wsum[j])
        return out


def _seeds(base: int, label: str, trial: int, density_index: int) -> tuple:
    """(planner, range noise) streams of one (label, trial, density): :func:`_seed` 0 and 1."""
    return (
        _seed(base, label, trial, density_index, 0),
        _seed(base, label, trial, density_index, 1),
    )


def _result(o, strategies, dens, ks, errors) -> SamplingStudyResult:
    rows = [
        {"strategy": label, "density": float(dens[di]), "k": k, "trial": trial,
         "metric": m, "value": float(errors[m][label][di, trial])}
        for label in strategies
        for trial in range(o.trials)
        for di, k in enumerate(ks)
        for m in o.metrics
    ]  # fmt: skip
    scores = {}
    if o.reference in strategies:
        scores = {m: _score(errors[m], dens, reference=o.reference) for m in o.metrics}
    return SamplingStudyResult(
        rows=rows,
        scores=scores,
        strategies=strategies,
        densities=[float(d) for d in dens],
        ks=ks,
        metrics=list(o.metrics),
        reference=o.reference,
        _errors=errors,
    )
