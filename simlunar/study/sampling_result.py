"""What a sampling study returns: its tidy rows and the tables behind its scores.

:class:`SamplingStudyResult` is made by :func:`study_result` from the study's labels (one
:class:`~simlunar.study.steps.LabelStep` per strategy, run or loaded): each outcome's scores,
diagnostics and rounds go into per-(density, trial) tables, from which the paper's scores
(eq. 4.3), samples saved and intervals are read.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from simlunar.metrics import samples_for_equal_error as _samples_for_equal_error
from simlunar.metrics import score as _score
from simlunar.study.protocol import DEFAULT_RECONSTRUCTION
from simlunar.study.stats import bootstrap_scores, samples_saved

__all__ = ["SamplingStudyResult", "study_result"]


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


def study_result(o, labels: Sequence, *, densities, ks, metrics, reconstructions,
                 measuring: Sequence[str] = ()) -> SamplingStudyResult:  # fmt: skip
    """The result of a sampling study with options ``o`` from its labels' steps.

    Parameters
    ----------
    o : SamplingStudyOptions
    labels : sequence of LabelStep
        One per strategy, in the study's order: its rows and its (light) outcomes.
    densities, ks : the study's densities and their sample counts
    metrics : the scored metric names (:func:`~simlunar.study.sampling_scores.scored_metrics`)
    reconstructions : the reconstruction labels, in order
    measuring : the labels of multi-round planners (their rounds are reported)
    """
    strategies = [step.label for step in labels]
    shape = (len(ks), int(o.trials))
    errors = {r: {m: {s: np.empty(shape) for s in strategies} for m in metrics}
              for r in reconstructions}  # fmt: skip
    rounds = {s: np.ones(shape, np.int64) for s in strategies}
    info: dict = {r: {s: {} for s in strategies} for r in reconstructions}
    grids: dict = {}
    for step in labels:
        for oc in step.outcomes:
            cell = (oc.budget_index, oc.trial)
            for r, scores in oc.recon_scores.items():
                for m, v in scores.items():
                    errors[r][m][oc.label][cell] = v
                _record_info(info[r][oc.label], oc.recon_info[r], shape, cell)
            rounds[oc.label][cell] = oc.rounds
            for r, grid in (oc.grids or {}).items():
                grids[(oc.label, oc.budget_index, r)] = grid
    first = errors[reconstructions[0]]
    scores = {}
    if o.reference in strategies:
        scores = {m: _score(first[m], densities, reference=o.reference) for m in metrics}
    order = {r: i for i, r in enumerate(reconstructions)}
    # a strategy's rows reconstruction by reconstruction, each in task order
    rows = [
        row
        for step in labels
        for row in sorted(step.rows, key=lambda row: order[row["reconstruction"]])
    ]
    return SamplingStudyResult(
        rows=rows,
        scores=scores,
        strategies=strategies,
        densities=[float(d) for d in densities],
        ks=list(ks),
        metrics=list(metrics),
        reference=o.reference,
        _errors=errors,
        rounds={s: r for s, r in rounds.items() if s in measuring},
        reconstructions=list(reconstructions),
        info={r: by for r, by in info.items() if any(by.values())},
        grids=grids,
    )


def _record_info(acc: dict, info: dict, shape, cell) -> None:
    """The numeric diagnostics of one reconstruction into ``acc`` (key -> (densities, trials))."""
    for key, v in info.items():
        if key in ("guide_frames", "exposures"):
            continue
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.number)):
            continue
        acc.setdefault(key, np.full(shape, np.nan))[cell] = float(v)
