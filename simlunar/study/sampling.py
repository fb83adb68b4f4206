"""The sampling study of the paper (section 4.1) on one depth grid and its guide image.

The study protocol (:mod:`simlunar.study.protocol`) with the ideal Dirac sampler
(:class:`~simlunar.sensors.ideal.IdealSampler`): for every strategy, density and trial, plan
k = round(density * N) pixels from the guide image, read the true depth there (optionally with
Gaussian range noise), reconstruct the full grid with every configured reconstruction
(Delaunay-linear interpolation by default; a guided one reads the :class:`Guide`) and score each
reconstruction against the true depth.
"""

from __future__ import annotations

import functools
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from simlunar.features import check_image
from simlunar.metrics import METRICS, check_densities
from simlunar.metrics.interior import interior_mask, sparsest_pitch
from simlunar.planner import PAPER_STRATEGIES, check_k
from simlunar.progress import stage
from simlunar.reconstruction import Guide
from simlunar.sensors.ideal import IdealOptions, IdealSampler
from simlunar.study.protocol import (
    DEFAULT_RECONSTRUCTION,
    Trials,
    outcome_rows,
    reconstruction_options,
    run_protocol,
)
from simlunar.study.sampling_planners import MeasuringPlanner, study_planners
from simlunar.study.sampling_result import SamplingStudyResult, study_result
from simlunar.study.sampling_scores import (
    SCORE_REGIONS,
    SamplingEvaluator,
    scored_metrics,
)
from simlunar.study.steps import LabelStep, ProtocolSteps, Steps

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
    setup = _setup(o, depth, image, guide, rng=rng, keep_trial=keep_trial)
    labels = _run_strategies(o, setup, workers=workers, steps=steps, keep_trial=keep_trial)
    measuring = [s for s, p in setup.trials.planners.items() if isinstance(p, MeasuringPlanner)]
    return study_result(o, labels, densities=setup.dens, ks=setup.ks, metrics=setup.metrics,
                        reconstructions=list(setup.recons), measuring=measuring)  # fmt: skip


@dataclass(frozen=True, eq=False)
class _Setup:
    """What a sampling study runs: the checked grids and :class:`Guide`, densities and their
    sample counts, reconstructions, the ideal sensor, the protocol's trials (planners and
    seeds), the evaluator and the scored metric names."""

    depth: np.ndarray
    guide: Guide
    dens: list
    ks: list
    recons: dict
    sensor: IdealSampler
    trials: Trials
    evaluate: SamplingEvaluator
    metrics: list


def _setup(o: SamplingStudyOptions, depth, image, guide, *, rng, keep_trial) -> _Setup:
    """Check the inputs; build the sensor, the planners (each importance map once), the
    evaluator (metric weights once) and the seeds of a study."""
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
    trials = Trials(planners, ks, int(o.trials), functools.partial(_seeds, base_seed))
    metrics = scored_metrics(o.metrics, o.score_region)
    return _Setup(depth, guide, dens, ks, recons, sensor, trials, evaluate, metrics)


def _run_strategies(o, setup: _Setup, *, workers: int, steps, keep_trial) -> list[LabelStep]:
    """Every strategy's step through the protocol wrapper (kept strategies loaded, the others
    run in parallel over ``workers``), counted as acquisitions."""
    names = {label: _step_name(label, keep_trial) for label in setup.trials.planners}
    store = ProtocolSteps(steps, names)
    run = functools.partial(
        run_protocol, setup.sensor, evaluate=setup.evaluate, outside=o.outside, workers=workers,
        reconstructions=setup.recons, guide=setup.guide, keep_trial=keep_trial,
    )  # fmt: skip
    rows = functools.partial(_rows, setup.dens, setup.metrics)
    per_label = len(setup.ks) * int(o.trials)
    total, done = len(names) * per_label, len(store.kept) * per_label
    with stage("sampling study", total=total, unit="acquisitions", done=done) as bar:
        return list(store.run(setup.trials, run, rows=rows, advance=bar.advance))


def _rows(dens, metrics, oc) -> list[dict]:
    """The tidy rows of one outcome: strategy, reconstruction, its guide frames, density, k,
    trial, metric, value."""
    middle = {"density": float(dens[oc.budget_index]), "k": oc.k}
    return outcome_rows(oc, {"strategy": oc.label}, middle, metrics=metrics, value=float)


def _step_name(label: str, keep_trial: int | None = None) -> str:
    # a step that kept a trial's grids (an export) is another step than one that did not
    return f"sampling strategy {label}" + ("" if keep_trial is None else f" grids {keep_trial}")


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


def _seeds(base: int, label: str, trial: int, density_index: int) -> tuple:
    """(planner, range noise) streams of one (label, trial, density): :func:`_seed` 0 and 1."""
    return (
        _seed(base, label, trial, density_index, 0),
        _seed(base, label, trial, density_index, 1),
    )
