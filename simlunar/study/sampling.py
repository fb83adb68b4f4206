"""The sampling study of the paper (section 4.1) on one depth grid and its guide image.

The study protocol (:mod:`simlunar.study.protocol`) with the ideal Dirac sampler
(:class:`~simlunar.sensors.ideal.IdealSampler`): for every strategy, density and trial, plan
k = round(density * N) pixels from the guide image, read the true depth there (optionally with
Gaussian range noise), reconstruct the full grid with every configured reconstruction
(Delaunay-linear interpolation by default; a guided one reads the :class:`Guide`) and score each
reconstruction against the true depth.
"""

from __future__ import annotations

import dataclasses
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from simlunar.features import check_image
from simlunar.metrics import METRICS, check_densities
from simlunar.metrics import samples_for_equal_error as _samples_for_equal_error
from simlunar.metrics import score as _score
from simlunar.metrics._fast import error_sums
from simlunar.metrics.interior import interior_mask, sparsest_pitch
from simlunar.planner import PAPER_STRATEGIES, check_k
from simlunar.progress import stage
from simlunar.reconstruction import Guide
from simlunar.sensors.ideal import IdealOptions, IdealSampler
from simlunar.study.protocol import (
    DEFAULT_RECONSTRUCTION,
    Trials,
    light_outcome,
    reconstruction_options,
    run_protocol,
)
from simlunar.study.sampling_planners import MeasuringPlanner, study_planners
from simlunar.study.sampling_scores import (
    SCORE_REGIONS,
    SamplingEvaluator,
    scored_metrics,
)
from simlunar.study.stats import bootstrap_scores, samples_saved
from simlunar.study.steps import Steps

__all__ = [
    "PAPER_STRATEGIES",
    "SamplingStudyOptions",
    "SamplingStudyResult",
    "paper_densities",
    "run_sampling_study",
    "sample_count",
]


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
        Tidy table, one row per (strategy, reconstruction, density, trial, metric): keys
        strategy, reconstruction, density, k, trial, metric, value and, for a reconstruction
        that read guide frames, guide_frames ("+"-joined names) and exposures (their count).
    scores : dict of str -> dict of str -> float
        metric -> strategy -> score (eq. 4.3) against ``reference``, of the first
        reconstruction (``linear`` by default); empty if the reference strategy was not run.
    strategies, metrics : list of str
        ``metrics``: the scored names (``mse``, ``mse_interior``, ...; see ``score_region``).
    densities : list of float
    ks : list of int
    reference : str
    rounds : dict of str -> ndarray of int64, shape (densities, trials)
        Sensor rounds of each measuring (multi-round) label; a one-shot label takes 1.
    reconstructions : list of str
        The reconstructions run on every acquisition, in order.
    info : dict reconstruction -> strategy -> key -> ndarray float64 (densities, trials)
        The numeric diagnostics each reconstruction reported (e.g. ``shading_share``).
    grids : dict (strategy, density index, reconstruction) -> ndarray float32 (rows, cols)
        The reconstructed grids of trial ``keep_trial`` (:func:`run_sampling_study`); empty
        unless asked for.
    """

    rows: list[dict]
    scores: dict[str, dict[str, float]]
    strategies: list[str]
    densities: list[float]
    ks: list[int]
    metrics: list[str]
    reference: str = "random"
    _errors: dict = field(default_factory=dict, repr=False)
    rounds: dict = field(default_factory=dict)
    reconstructions: list = field(default_factory=lambda: [DEFAULT_RECONSTRUCTION])
    info: dict = field(default_factory=dict)
    grids: dict = field(default_factory=dict, repr=False)

    def errors(
        self, metric: str, reconstruction: str = DEFAULT_RECONSTRUCTION
    ) -> dict[str, np.ndarray]:
        """strategy -> errors of ``reconstruction``, float64 (densities, trials)."""
        if metric not in self.metrics:
            raise ValueError(
                f"metric {metric!r} not in this study; have: {', '.join(self.metrics)}"
            )
        if reconstruction not in self.reconstructions:
            raise ValueError(
                f"reconstruction {reconstruction!r} not in this study; have: "
                f"{', '.join(self.reconstructions)}"
            )
        return self._errors[reconstruction][metric]

    def mean_errors(
        self, reconstruction: str = DEFAULT_RECONSTRUCTION
    ) -> dict[str, dict[str, np.ndarray]]:
        """metric -> strategy -> mean error per density over trials, float64 (densities,).

        The summary for error-vs-density plots.
        """
        return {
            m: {s: e.mean(axis=1) for s, e in self.errors(m, reconstruction).items()}
            for m in self.metrics
        }

    def samples_for_equal_error(
        self, metric: str = "mse", reconstruction: str = DEFAULT_RECONSTRUCTION
    ) -> dict[str, np.ndarray]:
        """Relative samples each strategy needs for the reference's error (see metrics)."""
        return _samples_for_equal_error(
            self.errors(metric, reconstruction), self.ks, reference=self.reference
        )

    def score_intervals(
        self,
        metric: str = "mse",
        *,
        n_boot: int = 2000,
        rng=0,
        reconstruction: str = DEFAULT_RECONSTRUCTION,
    ):
        """Scores of ``metric`` with paired bootstrap 95 % intervals over the trials.

        One scene: the interval says how well the trials pin each score down on this terrain
        (see :func:`simlunar.study.stats.bootstrap_scores`).
        """
        errs = self.errors(metric, reconstruction)
        return bootstrap_scores(
            errs, self.densities, reference=self.reference, n_boot=n_boot, rng=rng
        )

    def samples_saved(
        self,
        metric: str = "mse",
        reference: str | None = None,
        reconstruction: str = DEFAULT_RECONSTRUCTION,
    ):
        """Samples ``reference`` (default: the study's) needs for each strategy's mean error,
        over the strategy's, per density (:func:`simlunar.study.stats.samples_saved`), both
        reconstructed with ``reconstruction``."""
        means = {s: e.mean(axis=1) for s, e in self.errors(metric, reconstruction).items()}
        n = round(self.ks[0] / self.densities[0])
        return samples_saved(
            means, self.ks, reference=reference or self.reference, n_pixels=float(n)
        )

    def reconstruction_saved(
        self, reconstruction: str, metric: str = "mse", baseline: str = DEFAULT_RECONSTRUCTION
    ):
        """Samples ``baseline`` (default ``linear``) needs for ``reconstruction``'s mean error,
        over ``reconstruction``'s, per strategy (the same layouts: paired) and density.

        Returns
        -------
        dict strategy -> SamplesSaved of the two reconstructions (labels ``baseline`` and
        ``reconstruction``; :func:`simlunar.study.stats.samples_saved`).
        """
        n = round(self.ks[0] / self.densities[0])
        base = self.errors(metric, baseline)
        other = self.errors(metric, reconstruction)
        return {
            s: samples_saved(
                {baseline: base[s].mean(axis=1), reconstruction: other[s].mean(axis=1)},
                self.ks,
                reference=baseline,
                n_pixels=float(n),
            )
            for s in self.strategies
        }


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
        Per label planner options (see ``simlunar.planner``), plus ``"strategy"``. Labels of
        :data:`simlunar.planner.ORACLES` are the ONLY ones given the true depth (``truth=``);
        an ``oracle_greedy`` label may add ``"reconstruction"``: a label of
        ``reconstructions`` whose true error it feeds back (default ``linear``: the oracle
        of the paper's reconstruction; e.g. ``shading``: the bound for the fused model);
        ``sequential`` (:data:`simlunar.planner.MEASURING`) takes ``{"sequential":
        SequentialOptions, "prior": map name or None, "feature_opts": ...}`` and reads the scene
        through the sensor's ``acquire`` only, round by round. The ``learned`` map is computed
        per density (``feature_opts={"model": path}``; the density is the study's).
    score_region : {"full", "interior", "both"}
        Score the full image, the interior (cells farther than the sparsest density's pitch
        from the border; metric names ``<metric>_interior``) or both.
    outside : {"nearest", "nan"}
        Policy of ``linear`` outside the samples' convex hull (same for every strategy).
    reference : str
        Strategy label the scores compare against (default ``"random"``).
    reconstructions : mapping name -> options (object, mapping or None), or names
        Reconstructions of :data:`simlunar.reconstruction.RECONSTRUCTIONS` run on every
        acquisition (default: ``linear`` alone, the paper's); each gets its own rows.
    """

    strategies: Sequence[str] = PAPER_STRATEGIES
    densities: Sequence[float] | None = None
    trials: int = 20
    metrics: Sequence[str] = ("mse", "grad", "sal")
    range_noise_std: float = 0.0
    strategy_options: Mapping[str, Mapping] = field(default_factory=dict)
    outside: str = "nearest"
    reference: str = "random"
    score_region: str = "full"
    reconstructions: Mapping | Sequence = (DEFAULT_RECONSTRUCTION,)

    def __post_init__(self):
        # names, stray option keys and bounds checked now, before any long loop
        reconstruction_options(self.reconstructions, outside=self.outside)
        if self.score_region not in SCORE_REGIONS:
            raise ValueError(
                f"unknown score_region {self.score_region!r}; valid: {', '.join(SCORE_REGIONS)}"
            )
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
    guide: Guide | None = None,
    steps: Steps | None = None,
    keep_trial: int | None = None,
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
    guide : Guide, optional
        What the camera saw, for the guided reconstructions (its frames, light directions,
        co-located frame, spacing); default ``Guide(image)`` (one frame, light unknown, unit
        spacing). Its grid must be the depth's. The reconstructions get the sensor's samples
        as measured: depth (camera distance) falls where height rises.
    steps : Steps, optional
        Where each strategy's finished trials are kept (:mod:`simlunar.study.steps`): a
        strategy found there is not computed again; the result is the same bit for bit.
    keep_trial : int, optional
        Keep the reconstructed grids of this trial (:attr:`SamplingStudyResult.grids`, for an
        export); no score changes.

    Returns
    -------
    SamplingStudyResult

    Notes
    -----
    Feature maps (and metric weights) are computed once per study and reused across densities
    and trials. Scores average each strategy's errors over trials before eq. 4.3.
    """
    o = options or SamplingStudyOptions()
    depth, image, guide, dens, recons = _check_inputs(o, depth, image, guide)
    if keep_trial is not None and not 0 <= keep_trial < o.trials:
        raise ValueError(f"keep_trial must be in [0, {o.trials}), got {keep_trial}")
    sensor = IdealSampler(depth, IdealOptions(range_noise_std=float(o.range_noise_std)))
    ks = [sample_count(d, depth.size) for d in dens]
    planners, maps_cache = study_planners(o, image, depth, ks, guide=guide)
    inner = None
    if o.score_region != "full":
        inner = interior_mask(depth.shape, sparsest_pitch(depth.shape, dens))
    evaluate = SamplingEvaluator(depth, image, list(o.metrics), maps_cache, inner, o.score_region)
    base_seed = int(np.random.default_rng(rng).integers(0, 2**63))
    trials = Trials(planners, ks, int(o.trials), lambda lb, t, di: _seeds(base_seed, lb, t, di))
    if workers > 1:
        error_sums(np.zeros(1), np.zeros(1), np.ones((evaluate.rows.shape[0], 1)))  # compile
    strategies = list(o.strategies)
    names = scored_metrics(o.metrics, o.score_region)
    shape = (len(ks), o.trials)
    errors = {r: {m: {s: np.empty(shape) for s in strategies} for m in names} for r in recons}
    rounds = {s: np.ones(shape, np.int64) for s in strategies}
    info: dict = {r: {s: {} for s in strategies} for r in recons}
    frames: dict = {}
    grids: dict = {}

    def record(oc) -> None:
        _record_outcome(oc, errors, info, frames, rounds, shape)
        for r, grid in (oc.grids or {}).items():
            grids[(oc.label, oc.budget_index, r)] = grid

    kept = _kept_strategies(steps, strategies, keep_trial)
    for outcomes in kept.values():
        for oc in outcomes:
            record(oc)
    todo = {s: planners[s] for s in strategies if s not in kept}
    total, done = len(strategies) * o.trials * len(ks), len(kept) * o.trials * len(ks)
    with stage("sampling study", total=total, unit="acquisitions", done=done) as bar:
        finished: dict = {s: [] for s in todo}
        tasks = iter(())
        if todo:  # only the strategies no previous run finished
            tasks = run_protocol(
                sensor, dataclasses.replace(trials, planners=todo), evaluate,
                outside=o.outside, workers=workers, reconstructions=recons, guide=guide,
                keep_trial=keep_trial,
            )  # fmt: skip
        for outcomes in tasks:
            for oc in outcomes:
                record(oc)
            label = outcomes[0].label
            finished[label].append([light_outcome(oc) for oc in outcomes])
            if steps is not None and len(finished[label]) == o.trials:
                # every trial of this strategy done: kept, so a rerun starts after it
                steps.save(_step_name(label, keep_trial), finished.pop(label))
            done += len(ks)
            bar.update(done)
    res = _result(o, strategies, dens, ks, errors, names, list(recons), frames)
    res.rounds = {s: r for s, r in rounds.items() if isinstance(planners[s], MeasuringPlanner)}
    res.info = {r: by for r, by in info.items() if any(by.values())}
    res.grids = grids
    return res


def _step_name(label: str, keep_trial: int | None = None) -> str:
    # a step that kept a trial's grids (an export) is another step than one that did not
    return f"sampling strategy {label}" + ("" if keep_trial is None else f" grids {keep_trial}")


def _kept_strategies(steps: Steps | None, strategies, keep_trial: int | None = None) -> dict:
    """label -> its outcomes (light: no samples), of the strategies a previous run of this
    study finished (:mod:`simlunar.study.steps`)."""
    if steps is None:
        return {}
    kept = {}
    for label in strategies:
        trials = steps.load(_step_name(label, keep_trial))
        if trials is not None:
            kept[label] = [oc for outcomes in trials for oc in outcomes]
    return kept


def _check_inputs(o: SamplingStudyOptions, depth, image, guide: Guide | None):
    """The checked depth grid, guide image, :class:`Guide` (default ``Guide(image)``; all of
    one grid), densities and reconstructions of a study."""
    depth = _check_grid(depth, "depth")
    image = check_image(image)
    if image.shape[:2] != depth.shape:
        raise ValueError(f"image {image.shape[:2]} and depth {depth.shape} must have the same grid")
    dens = check_densities(paper_densities() if o.densities is None else o.densities)
    recons = reconstruction_options(o.reconstructions, outside=o.outside)
    if guide is None:
        guide = Guide(image)
    if guide.shape != depth.shape:
        raise ValueError(f"guide {guide.shape} and depth {depth.shape} must have the same grid")
    return depth, image, guide, dens, recons


def _record_outcome(oc, errors: dict, info: dict, frames: dict, rounds: dict, shape) -> None:
    """One acquisition's scores, diagnostics, guide frames and rounds into the study's tables
    (cell = (density index, trial))."""
    cell = (oc.budget_index, oc.trial)
    for r, scores in oc.recon_scores.items():
        for m, v in scores.items():
            errors[r][m][oc.label][cell] = v
        _record_info(info[r][oc.label], oc.recon_info[r], shape, cell)
        frames[(r, oc.label, *cell)] = oc.recon_info[r]
    rounds[oc.label][cell] = oc.rounds


def _record_info(acc: dict, info: dict, shape, cell) -> None:
    """The numeric diagnostics of one reconstruction into ``acc`` (key -> (densities, trials))."""
    for key, v in info.items():
        if key in ("guide_frames", "exposures"):
            continue
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.number)):
            continue
        acc.setdefault(key, np.full(shape, np.nan))[cell] = float(v)


def _seeds(base: int, label: str, trial: int, density_index: int) -> tuple:
    """(planner, range noise) streams of one (label, trial, density): :func:`_seed` 0 and 1."""
    return (
        _seed(base, label, trial, density_index, 0),
        _seed(base, label, trial, density_index, 1),
    )


def _cost(info: dict) -> dict:
    """The guide-frame columns of a row: none for a reconstruction that read no frame."""
    if not info.get("guide_frames"):
        return {}
    return {"guide_frames": "+".join(info["guide_frames"]), "exposures": int(info["exposures"])}


def _result(o, strategies, dens, ks, errors, names, recons, frames) -> SamplingStudyResult:
    rows = [
        {"strategy": label, "reconstruction": r, **_cost(frames[(r, label, di, trial)]),
         "density": float(dens[di]), "k": k, "trial": trial,
         "metric": m, "value": float(errors[r][m][label][di, trial])}
        for label in strategies
        for r in recons
        for trial in range(o.trials)
        for di, k in enumerate(ks)
        for m in names
    ]  # fmt: skip
    first = errors[recons[0]]
    scores = {}
    if o.reference in strategies:
        scores = {m: _score(first[m], dens, reference=o.reference) for m in names}
    return SamplingStudyResult(
        rows=rows,
        scores=scores,
        strategies=strategies,
        densities=[float(d) for d in dens],
        ks=ks,
        metrics=names,
        reference=o.reference,
        _errors=errors,
        reconstructions=list(recons),
    )
