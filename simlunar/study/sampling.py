"""The sampling study of the paper (section 4.1) on one depth grid and its guide image.

For every strategy, density and trial: plan k = round(density * N) pixels from the guide image,
read the true depth there (optionally with Gaussian range noise), reconstruct the full grid by
Delaunay-linear interpolation and score the reconstruction against the true depth.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import signal
import zlib
from collections.abc import Callable, Sequence
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field

import numpy as np

from simlunar.errors import InfrastructureError
from simlunar.features import check_image, feature_map
from simlunar.metrics import METRIC_NAMES, METRICS, check_densities, depth_gradient_weights
from simlunar.metrics import samples_for_equal_error as _samples_for_equal_error
from simlunar.metrics import score as _score
from simlunar.metrics._fast import error_sums
from simlunar.planner import STRATEGIES, check_k, plan, strategy_weights
from simlunar.reconstruction import OUTSIDE_POLICIES, reconstruct

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
        from simlunar.study.stats import bootstrap_scores

        errs = self.errors(metric)
        return bootstrap_scores(
            errs, self.densities, reference=self.reference, n_boot=n_boot, rng=rng
        )

    def samples_saved(self, metric: str = "mse", reference: str | None = None):
        """Samples ``reference`` (default: the study's) needs for each strategy's mean error,
        over the strategy's, per density (:func:`simlunar.study.stats.samples_saved`)."""
        from simlunar.study.stats import samples_saved

        means = {s: e.mean(axis=1) for s, e in self.errors(metric).items()}
        n = round(self.ks[0] / self.densities[0])
        return samples_saved(
            means, self.ks, reference=reference or self.reference, n_pixels=float(n)
        )

    def _table(self):
        # display labels from the one style registry, as in figure legends and the result
        # folders' scores.md (a strategy_options variant such as wavelet_bn gets its label)
        from simlunar.plotting.style import label

        cols = [s for s in self.strategies]
        header = [label(s) for s in cols]
        body = []
        for m in self.metrics:
            if m in self.scores:
                body.append((METRIC_NAMES.get(m, m), [self.scores[m][s] for s in cols]))
        return header, body

    def score_table_markdown(self, digits: int = 2) -> str:
        """Scores as a Markdown table: rows = metrics, columns = strategies (paper Tables 1-2)."""
        header, body = self._table()
        lines = ["| Metric | " + " | ".join(header) + " |", "|---|" + "---:|" * len(header)]
        for label, vals in body:
            lines.append(f"| {label} | " + " | ".join(f"{v:.{digits}f}" for v in vals) + " |")
        return "\n".join(lines) + "\n"

    def score_table_latex(self, digits: int = 2) -> str:
        """Scores as a LaTeX tabular (booktabs), same layout as :meth:`score_table_markdown`."""
        from simlunar.plotting.tables import tex_escape

        header, body = self._table()
        header = [tex_escape(h) for h in header]
        lines = [
            "\\begin{tabular}{l" + "r" * len(header) + "}",
            "\\toprule",
            "Metric & " + " & ".join(header) + " \\\\",
            "\\midrule",
        ]
        for label, vals in body:
            lines.append(f"{label} & " + " & ".join(f"{v:.{digits}f}" for v in vals) + " \\\\")
        lines += ["\\bottomrule", "\\end{tabular}"]
        return "\n".join(lines) + "\n"


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


def run_sampling_study(
    depth,
    image,
    *,
    strategies: Sequence[str] = PAPER_STRATEGIES,
    densities: Sequence[float] | None = None,
    trials: int = 20,
    metrics: Sequence[str] = ("mse", "grad", "sal"),
    rng,
    range_noise_std: float = 0.0,
    strategy_options: dict[str, dict] | None = None,
    outside: str = "nearest",
    reference: str = "random",
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
        SAL weights from the Itti-Koch saliency map of ``image`` (the guide image).
    rng : None, int, SeedSequence or Generator
        Seed of the study; split per (strategy label, trial, density) with ``SeedSequence``.
    range_noise_std : float
        Standard deviation of additive Gaussian noise on each range sample (units of depth).
    strategy_options : dict of str -> dict, optional
        Per label planner options (see ``simlunar.planner``), plus ``"strategy"``.
    outside : {"nearest", "nan"}
        Reconstruction policy outside the samples' convex hull (same for every strategy).
    reference : str
        Strategy label the scores compare against (default ``"random"``).
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
    depth = _check_grid(depth, "depth")
    image = check_image(image)
    if image.shape[:2] != depth.shape:
        raise ValueError(f"image {image.shape[:2]} and depth {depth.shape} must have the same grid")
    dens = check_densities(paper_densities() if densities is None else densities)
    if isinstance(trials, bool) or not isinstance(trials, (int, np.integer)) or trials < 1:
        raise ValueError(f"trials must be an integer >= 1, got {trials!r}")
    metrics = list(metrics)
    for m in metrics:
        if m not in METRICS:
            raise ValueError(f"unknown metric {m!r}; valid: {', '.join(METRICS)}")
    if outside not in OUTSIDE_POLICIES:
        raise ValueError(
            f"unknown outside policy {outside!r}; valid: {', '.join(OUTSIDE_POLICIES)}"
        )
    if not np.isfinite(range_noise_std) or range_noise_std < 0:
        raise ValueError(f"range_noise_std must be >= 0, got {range_noise_std}")
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    strategies = list(strategies)
    if not strategies or len(set(strategies)) != len(strategies):
        raise ValueError(
            f"strategies must be a non-empty list of distinct labels, got {strategies}"
        )
    strategy_options = dict(strategy_options or {})
    unknown_opts = sorted(set(strategy_options) - set(strategies))
    if unknown_opts:
        raise ValueError(f"strategy_options for strategies not in the study: {unknown_opts}")

    shape = depth.shape
    n = depth.size
    ks = [sample_count(d, n) for d in dens]

    # Resolve labels and compute each distinct importance map once.
    specs = {}
    maps_cache: dict[tuple, np.ndarray | None] = {}
    for label in strategies:
        opts = dict(strategy_options.get(label, {}))
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
        specs[label] = (base, maps_cache[key], plan_opts)
        # validate options once, before any long loop
        plan(base, 3, weights=maps_cache[key], shape=shape, rng=0, **plan_opts)

    metric_w = {}
    if "grad" in metrics:
        metric_w["grad"] = depth_gradient_weights(depth).ravel()
    if "sal" in metrics:
        sal_key = ("saliency", repr(None), repr(None))
        sal = maps_cache.get(sal_key)
        metric_w["sal"] = (sal if sal is not None else feature_map("saliency", image)).ravel()
    for m, w in metric_w.items():
        if float(w.sum()) <= 0:
            raise ValueError(f"metric {m!r} weights are zero everywhere on this scene")

    weight_names = list(metric_w)
    weight_rows = (
        np.stack([metric_w[m] for m in weight_names]) if weight_names else np.zeros((0, n))
    )
    base_seed = int(np.random.default_rng(rng).integers(0, 2**63))
    state = {
        "truth": depth.ravel(),
        "shape": shape,
        "ks": ks,
        "specs": specs,
        "metrics": metrics,
        "weight_names": weight_names,
        "weight_rows": weight_rows,
        "noise": float(range_noise_std),
        "outside": outside,
        "base_seed": base_seed,
    }
    tasks = [(label, trial) for label in strategies for trial in range(trials)]
    errors = {m: {s: np.empty((len(ks), trials)) for s in strategies} for m in metrics}
    total = len(tasks) * len(ks)
    done = 0
    for (label, trial), per_density in zip(tasks, _map_tasks(state, tasks, workers)):
        for di, vals in enumerate(per_density):
            for m, v in vals.items():
                errors[m][label][di, trial] = v
        done += len(ks)
        if progress is not None:
            progress(done, total)
    rows = [
        {"strategy": label, "density": float(dens[di]), "k": k, "trial": trial,
         "metric": m, "value": float(errors[m][label][di, trial])}
        for label in strategies
        for trial in range(trials)
        for di, k in enumerate(ks)
        for m in metrics
    ]  # fmt: skip

    scores = {}
    if reference in strategies:
        scores = {m: _score(errors[m], dens, reference=reference) for m in metrics}
    return SamplingStudyResult(
        rows=rows,
        scores=scores,
        strategies=strategies,
        densities=[float(d) for d in dens],
        ks=ks,
        metrics=metrics,
        reference=reference,
        _errors=errors,
    )


_STATE: dict = {}


def _init_worker(state):
    # Ctrl-C reaches the whole process group: the parent stops the pool, so a worker must not
    # print its own KeyboardInterrupt traceback
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _STATE.clear()
    _STATE.update(state)


def _task(task):
    return _trial_errors(_STATE, *task)


def _map_tasks(state, tasks, workers):
    """Per (label, trial) results, in task order; a fork pool when workers > 1."""
    if workers == 1 or len(tasks) == 1:
        return (_trial_errors(state, *t) for t in tasks)
    methods = multiprocessing.get_all_start_methods()
    # fork shares the arrays with the workers without pickling them
    ctx = multiprocessing.get_context("fork" if "fork" in methods else None)
    # Load the compiled kernels the tasks call before forking: the children then never enter
    # Numba's dispatcher lock, which another thread of this process (a concurrent unit of
    # LocalPoolExecutor) may hold at the moment of the fork.
    _warm_kernels(state)
    # concurrent.futures notices a dead worker (multiprocessing.Pool waits for it forever)
    pool = cf.ProcessPoolExecutor(
        min(workers, len(tasks)), mp_context=ctx, initializer=_init_worker, initargs=(state,)
    )
    try:
        out = list(pool.map(_task, tasks))
    except BrokenProcessPool:
        _stop(pool)
        raise InfrastructureError(
            "a sampling-study worker process died (killed by the system, e.g. out of memory, "
            "or by an operator)"
        ) from None
    except BaseException:
        _stop(pool)  # Ctrl-C: the workers ignore SIGINT, so end them instead of waiting
        raise
    pool.shutdown(wait=True)
    return out


def _stop(pool: cf.ProcessPoolExecutor) -> None:
    """End a pool's workers now (their tasks are abandoned) and release it."""
    # the executor has no public way to end running workers; _processes is {pid: Process}
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        try:
            proc.terminate()
        except (OSError, ValueError):
            pass  # already gone
    pool.shutdown(wait=False, cancel_futures=True)


def _warm_kernels(state) -> None:
    """Call every compiled kernel of a task once, on tiny inputs of the same types."""
    pts = np.array([[0, 0], [0, 2], [2, 0], [2, 2]])
    recon = reconstruct(pts, np.arange(4.0), (3, 3), outside=state["outside"]).ravel()
    rows = state["weight_rows"]
    error_sums(recon, recon, np.ones((rows.shape[0], recon.size), dtype=rows.dtype))


def _trial_errors(state, label, trial) -> list[dict[str, float]]:
    """Errors of one strategy label and trial at every density (list over densities)."""
    base, weights, plan_opts = state["specs"][label]
    truth, shape = state["truth"], state["shape"]
    out = []
    for di, k in enumerate(state["ks"]):
        p = plan(
            base, k, weights=weights, shape=shape,
            rng=_seed(state["base_seed"], label, trial, di, 0), **plan_opts,
        )  # fmt: skip
        values = truth[p.flat]
        if state["noise"] > 0:
            noise_rng = np.random.default_rng(_seed(state["base_seed"], label, trial, di, 1))
            values = values + noise_rng.normal(0.0, state["noise"], size=k)
        recon = reconstruct(p.rc, values, shape, outside=state["outside"]).ravel()
        out.append(
            _evaluate(recon, truth, state["metrics"], state["weight_names"], state["weight_rows"])
        )
    return out


def _evaluate(recon, truth, metrics, weight_names, weight_rows) -> dict[str, float]:
    """All metrics of one reconstruction in one pass (same definitions as ``metric``)."""
    count, sse, sae, wse, wsum = error_sums(recon, truth, weight_rows)
    if count == 0:
        raise ValueError("reconstruction has no finite cell to evaluate")
    out = {}
    for m in metrics:
        if m == "mse":
            out[m] = sse / count
        elif m == "rmse":
            out[m] = float(np.sqrt(sse / count))
        elif m == "mae":
            out[m] = sae / count
        else:
            j = weight_names.index(m)
            if wsum[j] <= 0:
                raise ValueError(f"metric {m!r} weights sum to zero over the evaluated cells")
            out[m] = float(wse[j] / wsum[j])
    return out
