"""Pool a sampling experiment's units over terrain seeds: score intervals and samples saved.

Units that differ only in their terrain realisation (``study.terrain_seeds``, or a sweep over
``terrain.seed_index``) form one *point* per reconstruction (``study.reconstructions``; one
point per sweep point for ``linear`` alone); every point gets its eq. 4.3 scores with bootstrap
intervals (:func:`simlunar.study.stats.bootstrap_scores`), the test of its best strategy
against the runner-up, and the samples saved at equal error against random and the grid.
Each reconstruction is also compared with ``linear`` on the same layouts
(:func:`reconstruction_saved_entries`): the samples linear needs for its error, paired by seed.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from simlunar.plotting.style import point_title
from simlunar.results.records import WorkUnit, unit_label
from simlunar.study.reconstruction_spec import parse_reconstructions
from simlunar.study.sampling_scores import INTERIOR_SUFFIX, scored_metrics
from simlunar.study.stats import (
    SamplesSaved,
    ScoreIntervals,
    Separation,
    best_separation,
    bootstrap_scores,
    samples_saved,
)

__all__ = [
    "HEADROOM_REFERENCE",
    "N_BOOT",
    "SAVED_REFERENCES",
    "SCORES_CSV_COLUMNS",
    "SEED_AXES",
    "SEED_AXIS",
    "Point",
    "density_panels",
    "error_arrays",
    "group_points",
    "headroom_entries",
    "paired_saved_entries",
    "scores_csv_rows",
    "summarise",
    "sweep_value",
]

SEED_AXIS = "terrain.seed_index"
#: the reconstruction of rows that name none (written before reconstructions were configurable)
#: and the baseline of the reconstruction-vs-linear tables
BASELINE_RECONSTRUCTION = "linear"
#: bootstrap replicates per point and metric
N_BOOT = 2000
#: references of the samples-saved tables and figure (lloyd_uniform: the image-free layout
#: of the same placement as the image-directed Lloyd layouts, the fair reference)
SAVED_REFERENCES = ("random", "grid", "lloyd_uniform")
#: the reference of the headroom: samples saved vs it, over the oracle's
HEADROOM_REFERENCE = "lloyd_uniform"


@dataclass
class Point:
    """One sweep point pooled over its terrain seeds."""

    label: str
    sweep: dict[str, Any]
    unit_indices: list[int]
    seeds: list[int]
    strategies: list[str]
    metrics: list[str]
    densities: list[float] = field(default_factory=list)
    ks: list[int] = field(default_factory=list)
    n_pixels: int = 0
    intervals: dict[str, ScoreIntervals] = field(default_factory=dict)
    separation: dict[str, Separation | None] = field(default_factory=dict)
    saved_metric: str | None = None
    saved: dict[str, SamplesSaved] = field(default_factory=dict)
    mean_errors: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    #: samples saved on the interior-only metric (``<metric>_interior``), by reference
    saved_interior: dict[str, SamplesSaved] = field(default_factory=dict)
    #: oracle label -> strategy -> per terrain seed: log(saved vs lloyd_uniform) / log(the
    #: oracle's saved vs lloyd_uniform) (paired on the seed; nan where undefined)
    headroom: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    #: strategy -> per terrain seed: geometric-mean samples saved vs lloyd_uniform
    saved_per_seed: dict[str, np.ndarray] = field(default_factory=dict)
    #: the reconstruction whose rows this point holds
    reconstruction: str = BASELINE_RECONSTRUCTION
    #: the sweep point's key (the same for every reconstruction of it)
    sweep_key: str = ""


def _label(sweep: dict, config: dict) -> str:

    return unit_label(WorkUnit(0, "", sweep, config))


def reconstruction_names(study: dict) -> list[str]:
    """The names of a study section's ``reconstructions`` (items a name or ``{name: opts}``),
    ``[linear]`` when it has none."""
    items = study.get("reconstructions") or [BASELINE_RECONSTRUCTION]
    return [spec.label for spec in parse_reconstructions(items)]


def group_points(records: list[dict], *, per_reconstruction: bool = True) -> list[Point]:
    """Units (records in results order: ``sweep``, ``config``) grouped into points.

    Two units belong to one point when their sweep values agree on every axis but
    ``terrain.seed_index`` (and, with ``per_reconstruction``, the point is one per configured
    reconstruction); points keep the order of their first unit, the reconstructions their
    configured order. With several reconstructions the label names the reconstruction.
    """
    points: dict[tuple, Point] = {}
    for i, rec in enumerate(records):
        sweep = {k: v for k, v in (rec.get("sweep") or {}).items() if k != SEED_AXIS}
        key = json.dumps(sweep, sort_keys=True, default=str)
        cfg = rec.get("config") or {}
        study = cfg.get("study") or {}
        names = reconstruction_names(study) if per_reconstruction else [BASELINE_RECONSTRUCTION]
        for name in names:
            if (key, name) not in points:
                label = _label(sweep, cfg)
                if len(names) > 1:  # without a sweep, the name alone (the title has the rest)
                    label = f"{label}, reconstruction={name}" if sweep else f"reconstruction={name}"
                points[(key, name)] = Point(
                    label=label,
                    sweep=sweep,
                    unit_indices=[],
                    seeds=[],
                    strategies=list(study.get("strategies") or []),
                    metrics=scored_metrics(
                        study.get("metrics") or [], study.get("score_region") or "full"
                    ),
                    reconstruction=name,
                    sweep_key=key,
                )
            p = points[(key, name)]
            p.unit_indices.append(i)
            p.seeds.append(int((cfg.get("terrain") or {}).get("seed_index", 0) or 0))
            shape = (rec.get("meta") or {}).get("shape")
            if shape:
                p.n_pixels = int(np.prod(shape[:2]))
    return list(points.values())


def first_reconstruction_rows(res: dict) -> list[dict]:
    """The rows of a result folder (``res``: ``config``, ``rows``) of its first configured
    reconstruction (``linear`` by default; rows that name none are linear's): what a figure of
    one reconstruction draws."""
    first = reconstruction_names(res["config"].get("study") or {})[0]
    return [r for r in res["rows"] if row_reconstruction(r) == first]


def row_reconstruction(row: dict) -> str:
    """The reconstruction of a results row (``linear`` for rows that name none)."""
    return str(row.get("reconstruction") or BASELINE_RECONSTRUCTION)


def error_arrays(rows: list[dict], point: Point, metric: str):
    """``(densities, ks, {strategy: errors (seeds, densities, trials)})`` of one point (its
    reconstruction's rows).

    Densities descending (the results order). Rows may hold strings (read from CSV).
    """
    units = {str(i): j for j, i in enumerate(point.unit_indices)}
    cells: dict[str, dict[tuple[int, float, int], float]] = {s: {} for s in point.strategies}
    ks: dict[float, int] = {}
    trials: set[int] = set()
    for r in rows:
        j = units.get(str(r.get("unit")))
        if j is None or r.get("metric") != metric or r.get("strategy") not in cells:
            continue
        if row_reconstruction(r) != point.reconstruction:
            continue
        d = float(r["density"])
        t = int(float(r["trial"]))
        cells[r["strategy"]][(j, d, t)] = float(r["value"])
        ks[d] = int(float(r["k"]))
        trials.add(t)
    dens = sorted(ks, reverse=True)
    n_t = len(trials)
    out = {}
    for s, c in cells.items():
        e = np.full((len(point.unit_indices), len(dens), n_t), np.nan)
        for (j, d, t), v in c.items():
            e[j, dens.index(d), t] = v
        if np.isnan(e).any():
            raise ValueError(f"results of {point.label!r}: missing errors of {s!r} ({metric})")
        out[s] = e
    return dens, [ks[d] for d in dens], out


def summarise(
    records: list[dict], rows: list[dict], *, seed: int, n_boot: int = N_BOOT
) -> list[Point]:
    """Every point of a sampling experiment with intervals and samples saved.

    Parameters
    ----------
    records : list of dict
        Unit records in results order (``sweep``, ``config``, ``meta``).
    rows : list of dict
        The tidy results (``unit`` = position in ``records``).
    seed : int
        The experiment seed; point i's bootstrap uses ``SeedSequence([seed, i])``.
    n_boot : int
        Bootstrap replicates.
    """
    points = group_points(records)
    for i, p in enumerate(points):
        for m in p.metrics:
            dens, ks, errs = error_arrays(rows, p, m)
            if not p.densities:
                p.densities, p.ks = dens, ks
            p.mean_errors[m] = {s: e.mean(axis=(0, 2)) for s, e in errs.items()}
            if "random" not in p.strategies:
                continue  # eq. 4.3 scores are relative to random; samples saved vs grid are not
            rng = np.random.default_rng(np.random.SeedSequence([seed, i, p.metrics.index(m)]))
            res = bootstrap_scores(errs, dens, n_boot=n_boot, rng=rng)
            p.intervals[m] = res
            p.separation[m] = best_separation(res)
        if len(p.ks) >= 2 and p.metrics:
            _saved(p, rows)
    return points


def _saved(p: Point, rows: list[dict]) -> None:
    """Samples saved vs each reference (first metric, and its interior twin) and the headroom."""
    m = p.metrics[0]
    p.saved_metric = m
    n_pix = p.n_pixels or np.inf
    inner = m + INTERIOR_SUFFIX if not m.endswith(INTERIOR_SUFFIX) else None
    for ref in SAVED_REFERENCES:
        if ref in p.strategies:
            p.saved[ref] = samples_saved(p.mean_errors[m], p.ks, reference=ref, n_pixels=n_pix)
            if inner in p.mean_errors:
                p.saved_interior[ref] = samples_saved(
                    p.mean_errors[inner], p.ks, reference=ref, n_pixels=n_pix
                )
    if HEADROOM_REFERENCE in p.strategies:
        _headroom(p, rows, m, n_pix)


def _headroom(p: Point, rows: list[dict], metric: str, n_pix: float) -> None:
    """Per seed: samples saved vs the uniform layout, and the share of each oracle's saving a
    strategy captures, log(saved) / log(oracle saved) (paired by terrain seed)."""
    _, _, errs = error_arrays(rows, p, metric)
    per_seed = {s: np.full(len(p.seeds), np.nan) for s in p.strategies}
    for j in range(len(p.seeds)):
        means = {s: e[j].mean(axis=1) for s, e in errs.items()}
        sv = samples_saved(means, p.ks, reference=HEADROOM_REFERENCE, n_pixels=n_pix)
        for s in p.strategies:
            per_seed[s][j] = sv.summary[s]
    p.saved_per_seed = per_seed
    for o in (s for s in p.strategies if s.startswith("oracle")):
        with np.errstate(divide="ignore", invalid="ignore"):
            log_o = np.log(per_seed[o])
            p.headroom[o] = {
                s: np.where(log_o > 0, np.log(per_seed[s]) / log_o, np.nan)
                for s in p.strategies
                if s != o and s != HEADROOM_REFERENCE
            }


def headroom_entries(points: list[Point]) -> list[dict]:
    """The headroom each strategy captures, one entry per (sweep point, oracle), as
    :func:`simlunar.plotting.tables.headroom_tables` and
    :func:`simlunar.plotting.headroom.headroom_plot` take them."""
    return [
        {"label": p.label if len(points) > 1 else "", "oracle": o, "metric": p.saved_metric,
         "strategies": [s for s in p.strategies if s in by], "captured": by,
         "saved": p.saved_per_seed, "seeds": p.seeds}
        for p in points
        for o, by in p.headroom.items()
    ]  # fmt: skip


def paired_saved_entries(points: list[Point]) -> list[dict]:
    """Samples saved vs uniform Lloyd paired by terrain seed, for the points that have the
    uniform layout and at least two seeds but no oracle (with one, the headroom table holds
    the same numbers), as :func:`simlunar.plotting.tables.paired_saved_tables` takes them."""
    return [
        {"label": p.label if len(points) > 1 else "", "metric": p.saved_metric,
         "strategies": [s for s in p.strategies if s != HEADROOM_REFERENCE],
         "saved": p.saved_per_seed, "seeds": p.seeds}
        for p in points
        if p.saved_per_seed and not p.headroom and len(p.seeds) >= 2
    ]  # fmt: skip


def scores_csv_rows(points: list[Point], records: list[dict]) -> list[dict]:
    """Per-seed scores (from each unit) and pooled scores with intervals, one row each."""
    out = []
    for p in points:
        r = p.reconstruction
        for m in p.metrics:
            for j, seed in zip(p.unit_indices, p.seeds):
                sc = _unit_scores(records[j], r).get(m, {})
                for s in p.strategies:
                    if s in sc:
                        out.append(
                            {"point": p.label, "terrain_seed": seed, "metric": m, "strategy": s,
                             "reconstruction": r, "score": sc[s], "ci_low": "", "ci_high": ""}
                        )  # fmt: skip
            res = p.intervals.get(m)
            if res is None:
                continue
            for s in p.strategies:
                sc, lo, hi = res.interval(s)
                out.append(
                    {"point": p.label, "terrain_seed": "all", "metric": m, "strategy": s,
                     "reconstruction": r, "score": sc, "ci_low": lo, "ci_high": hi}
                )  # fmt: skip
    return out


def _unit_scores(record: dict, reconstruction: str) -> dict:
    """A unit's eq. 4.3 scores of one reconstruction: the record's ``scores`` are the first
    reconstruction's, the others' are in ``meta["reconstruction_scores"]``."""
    others = (record.get("meta") or {}).get("reconstruction_scores") or {}
    if reconstruction in others:
        return others[reconstruction]
    first = reconstruction_names((record.get("config") or {}).get("study") or {})[0]
    return (record.get("scores") or {}) if reconstruction == first else {}


SCORES_CSV_COLUMNS = [
    "point", "terrain_seed", "metric", "strategy", "reconstruction", "score", "ci_low", "ci_high",
]  # fmt: skip


def reconstruction_saved_entries(points: list[Point], rows: list[dict]) -> list[dict]:
    """Per sweep point with a reconstruction besides ``linear``: the samples ``linear`` needs
    for each reconstruction's error on the same layout (strategy), paired by terrain seed.

    Per (strategy, seed), :func:`simlunar.study.stats.samples_saved` of the reconstruction's
    mean error (over trials) against linear's on the same plans, summarised as the geometric
    mean over the densities where the two error curves overlap; > 1: the reconstruction
    needs fewer samples. The tables summarise the seeds as a geometric mean with a 95 %
    Student t interval in log space.

    Returns
    -------
    list of dict
        ``label`` (the sweep point's, empty for a single one), ``sweep`` (its sweep values,
        terrain seed aside), ``metric``, ``strategies``,
        ``reconstructions`` (the compared ones, configured order), ``saved``
        (reconstruction -> strategy -> float64 (seeds,)), ``seeds`` and, when the point has
        the uniform Lloyd layout (:data:`HEADROOM_REFERENCE`), ``joint``: every (layout,
        reconstruction) pair against uniform Lloyd reconstructed by linear, the image-free
        baseline (reconstruction, ``linear`` first -> strategy -> float64 (seeds,)), so the
        best layout + reconstruction reads against the paper's reconstruction on the best
        image-free layout; empty without uniform Lloyd.
    """
    by_key: dict[str, dict[str, Point]] = {}
    for p in points:
        by_key.setdefault(p.sweep_key, {})[p.reconstruction] = p
    n_sweep = len(by_key)
    out = []
    for group in by_key.values():
        base = group.get(BASELINE_RECONSTRUCTION)
        others = [p for r, p in group.items() if r != BASELINE_RECONSTRUCTION]
        if base is None or not others or len(base.ks) < 2 or not base.metrics:
            continue
        m = base.metrics[0]
        _, ks, e_base = error_arrays(rows, base, m)
        n_pix = base.n_pixels or np.inf
        saved: dict[str, dict[str, np.ndarray]] = {}
        errors = {BASELINE_RECONSTRUCTION: e_base}
        for p in others:
            _, _, e_other = error_arrays(rows, p, m)
            errors[p.reconstruction] = e_other
            saved[p.reconstruction] = {
                s: np.array([
                    samples_saved(
                        {BASELINE_RECONSTRUCTION: e_base[s][j].mean(axis=1),
                         p.reconstruction: e_other[s][j].mean(axis=1)},
                        ks, reference=BASELINE_RECONSTRUCTION, n_pixels=n_pix,
                    ).summary[p.reconstruction]
                    for j in range(len(base.seeds))
                ])
                for s in base.strategies
            }  # fmt: skip
        joint = {}
        if HEADROOM_REFERENCE in base.strategies:
            ref = e_base[HEADROOM_REFERENCE]
            joint = {
                r: {s: np.array([
                        samples_saved({"_ref": ref[j].mean(axis=1), "_it": e[s][j].mean(axis=1)},
                                      ks, reference="_ref", n_pixels=n_pix).summary["_it"]
                        for j in range(len(base.seeds))])
                    for s in base.strategies}
                for r, e in errors.items()
            }  # fmt: skip
        label = _label(base.sweep, {}) if n_sweep > 1 else ""
        out.append(
            {"label": label, "sweep": base.sweep, "metric": m, "strategies": list(base.strategies),
             "reconstructions": list(saved), "saved": saved, "seeds": list(base.seeds),
             "joint": joint}
        )  # fmt: skip
    return out


#: sweep axes that repeat a scene rather than change it (their units are pooled as seeds)
SEED_AXES = ("seed", SEED_AXIS)


def sweep_value(rec: dict, path: str):
    """A unit's value on sweep axis ``path`` as a plot position or label: numbers as they
    are, a model (dict) by its ``kind``, null as ``"preset default"``."""
    v = rec["sweep"][path]
    if isinstance(v, dict):
        return v.get("kind", json.dumps(v, sort_keys=True))
    return "preset default" if v is None else v


def density_panels(units: list[dict]) -> list[tuple[str, list[dict]]]:
    """The panels of ``error_vs_density``: ``[(title, unit records)]`` in results order.

    One panel per sweep point (:func:`simlunar.results.aggregate.group_points`): the units of
    a point that differ only by terrain seed share a panel, whose curves pool their rows (mean
    and spread over terrain seeds and trials), so a repeated experiment draws as many panels
    as it has sweep points, not seeds times points.
    """
    return [
        (point_title(p.sweep), [units[i] for i in p.unit_indices])
        for p in group_points(units, per_reconstruction=False)
    ]
