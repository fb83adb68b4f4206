"""Run an experiment: expand sweeps into work units, compute missing ones, write the results.

A work unit is one point of the sweep's cartesian product (one scene rendered once, shared by
all strategies, densities and trials). Finished units are cached in ``<out>/units/`` under the
SHA-256 of their resolved configuration, the contents of the files they read (DEM, albedo,
preset YAML) and the simlunar version, so an interrupted run resumes where it stopped, a
finished one reruns instantly and a changed input is recomputed.

A run owns its folder (:class:`~simlunar.results.store.FolderLock`), and a folder belongs to
one configuration: a run whose config differs from the folder's ``config.yaml`` is refused.
Every sweep point is checked (:mod:`simlunar.pipeline.preflight`) before anything is written. ``results.csv`` is assembled in a fixed order (units in sweep
order; rows by strategy, reconstruction, density, trial and metric in config order) from the
cache, so the
same seed always gives a byte-identical file whatever the executor or completion order.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import simlunar
from simlunar.config.loading import apply_sweep_value, to_plain
from simlunar.config.schema import ExperimentCfg
from simlunar.config.yamlio import dump_yaml
from simlunar.errors import (
    ResultFolderError,
    RunInterrupted,
)
from simlunar.interrupts import interrupted
from simlunar.pipeline import preflight
from simlunar.pipeline.executors import Executor, LocalPoolExecutor
from simlunar.pipeline.inputs import check_size, input_hashes
from simlunar.pipeline.resume import compute_missing, kept_message, prune_steps
from simlunar.pipeline.rows import DEFAULT_RECONSTRUCTION, ROW_COLUMNS, collect_rows
from simlunar.pipeline.unit import CACHE_VERSION, compute_unit
from simlunar.plotting.landing_tables import landing_tables, paired_table
from simlunar.plotting.lidar_tables import lidar_tables
from simlunar.plotting.scanner_tables import scanner_tables
from simlunar.results.cache_keys import (
    reconstruction_versions,
    render_without_new_defaults,
    terrain_without_new_defaults,
    without_new_defaults,
)
from simlunar.results.figures import write_figures_pruned
from simlunar.results.folder import (
    _check_writable,
    _invalidate,
    _read_provenance,
    _remove_empty,
    _scans_present,
    array_folders,
    claim_folder,
    folder_complete,
    prune_scans,
    scan_folders,
)
from simlunar.results.md_tables import write_table_csvs
from simlunar.results.records import WorkUnit
from simlunar.results.store import (
    FolderLock,
    UnitCache,
    atomic_write_json,
    atomic_write_text,
    csv_text,
)
from simlunar.results.summaries import (
    _names,
    _notes,
    _sampling_tables,
    _write_provenance,
    tables_code,
)

__all__ = ["ROW_COLUMNS", "RunSummary", "collect_rows", "expand", "run_experiment", "unit_key"]

#: keys that do not change a unit's numbers (excluded from its cache key)
_NON_RESULT_KEYS = ("name", "description", "sweep", "catalogue")


def unit_key(config: dict[str, Any], inputs: dict[str, dict[str, str]] | None = None) -> str:
    """Cache key of a resolved unit config: what determines its numbers, and nothing else.

    It covers the config (less names and figure formats), the SHA-256 of every file the unit
    reads (``inputs``, :func:`simlunar.pipeline.inputs.input_hashes`; computed when not
    given) and the simlunar version.
    """
    if inputs is None:
        inputs = input_hashes(config)
    relevant = {k: v for k, v in config.items() if k not in _NON_RESULT_KEYS}
    relevant.pop("figures", None)
    terrain = relevant.get("terrain")
    if isinstance(terrain, dict) and not terrain.get("overrides"):
        # no overrides = the preset as shipped: keep the keys of caches made before the
        # overrides key existed
        relevant["terrain"] = {k: v for k, v in terrain.items() if k != "overrides"}
    terrain = relevant.get("terrain")
    if isinstance(terrain, dict) and not terrain.get("seed_index"):
        # realisation 0 is the terrain of runs before seed_index existed: same keys
        relevant["terrain"] = {k: v for k, v in terrain.items() if k != "seed_index"}
    if isinstance(relevant.get("terrain"), dict):
        relevant["terrain"] = terrain_without_new_defaults(relevant["terrain"])
    if isinstance(relevant.get("render"), dict):
        relevant["render"] = render_without_new_defaults(relevant["render"])
    study = relevant.get("study")
    if isinstance(study, dict):
        relevant["study"] = study = without_new_defaults(study)
    if isinstance(study, dict) and "terrain_seeds" in study:
        # how many realisations run does not change any one unit's numbers
        relevant["study"] = {k: v for k, v in study.items() if k != "terrain_seeds"}
    figures = config.get("figures") or {}
    # the panel arrays depend on these, the file formats do not
    relevant["_figures"] = {
        k: figures.get(k)
        for k in (
            "enabled",
            "panel_density",
            "sparse_mesh_density",
            "sparse_mesh_sigma_deg",
            "sparse_mesh_roughness_threshold",
        )
    }
    key = {
        "cache_version": CACHE_VERSION,
        "config": relevant,
        "inputs": {k: v["sha256"] for k, v in inputs.items()},
        "simlunar": simlunar.__version__,
    }
    versions = reconstruction_versions(study) if isinstance(study, dict) else {}
    if versions:  # only then: every other unit keeps its key
        key["reconstruction_versions"] = versions
    blob = json.dumps(key, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def expand(cfg: ExperimentCfg) -> list[WorkUnit]:
    """The work units of an experiment (cartesian product of its sweep axes, in order)."""
    base = {k: v for k, v in to_plain(cfg).items() if k != "sweep"}
    axes = list(cfg.sweep.items())
    n_units = math.prod(len(vals) for _, vals in axes) * int(
        getattr(cfg.study, "terrain_seeds", 1) or 1
    )
    sizes = " x ".join(str(len(vals)) for _, vals in axes) or "1"
    # before expanding: a sweep product of millions is refused, not built point by point
    check_size(
        "sweep",
        f"{sizes} sweep points x {getattr(cfg.study, 'terrain_seeds', 1) or 1} terrain seeds "
        "= units",
        n_units,
        "SIMLUNAR_MAX_UNITS",
    )
    units = []
    for combo in itertools.product(*[vals for _, vals in axes]):
        point = base
        # a kind resets its section, so kinds go first and the other axes refine them
        ordered = sorted(zip(axes, combo), key=lambda av: av[0][0].split(".")[-1] != "kind")
        for (path, _), value in ordered:
            point = apply_sweep_value(point, path, value)
        resolved = to_plain(ExperimentCfg.model_validate(point))
        resolved.pop("sweep", None)
        sweep = {p: v for (p, _), v in zip(axes, combo)}
        n_seeds = int(resolved.get("study", {}).get("terrain_seeds", 1) or 1)
        if n_seeds == 1:
            inputs = input_hashes(resolved)
            key = unit_key(resolved, inputs)
            units.append(WorkUnit(len(units), key, sweep, resolved, inputs=inputs))
            continue
        for seed_index in range(n_seeds):
            one = apply_sweep_value(resolved, "terrain.seed_index", seed_index)
            one = to_plain(ExperimentCfg.model_validate(one))
            one.pop("sweep", None)
            inputs = input_hashes(one)
            units.append(
                WorkUnit(
                    len(units),
                    unit_key(one, inputs),
                    sweep,
                    one,
                    inputs=inputs,
                    terrain_seed=seed_index,
                )
            )
    return units


@dataclass
class RunSummary:
    out_dir: Path
    units_total: int
    units_cached: int
    units_computed: int
    elapsed_s: float
    scores_markdown: str
    figures: list[Path] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def figures_dir(self) -> Path:
        return self.out_dir / "figures"


def run_experiment(
    cfg: ExperimentCfg,
    out_dir: str | Path,
    *,
    executor: Executor | None = None,
    compute: Callable[[dict], dict] = compute_unit,
    progress: bool = True,
    figures: bool = True,
) -> RunSummary:
    """Run (or resume) an experiment into ``out_dir``.

    Parameters
    ----------
    cfg : ExperimentCfg
        A validated experiment.
    out_dir : path
        Result folder (created). Finished units already cached there are not recomputed.
        The run holds the folder's lock; a folder of another configuration is refused.
    executor : Executor, optional
        Where units run; default: serial in this process.
    compute : callable
        ``payload -> record`` for one unit (default :func:`stages.compute_unit`); must be
        picklable by reference for process pools and Dask.
    progress : bool
        Show a progress bar with ETA on stderr.
    figures : bool
        Write ``figures/`` (when the experiment enables them).

    Raises
    ------
    simlunar.errors.ConfigError, simlunar.errors.ResultFolderError
        A user mistake (a file, the geometry, the folder), found before anything is written.
    simlunar.errors.InfrastructureError
        The executor's cluster failed; finished units are kept.
    simlunar.errors.RunInterrupted
        Ctrl-C; finished units are kept (a ``KeyboardInterrupt``).
    """
    t_start = time.perf_counter()
    out = Path(out_dir)
    # every user mistake first, before connecting, locking or writing anything
    preflight.check_out_dir(out)
    units = expand(cfg)
    checks = preflight.check_units(units)
    preflight.check_renderer()
    config_text = dump_yaml(to_plain(cfg))
    executor = executor or LocalPoolExecutor(1)
    run = _Run(cfg, out, units, checks, figures, t_start, executor, compute, progress)
    with _connected(executor):
        lock, created = _lock_folder(out)
        try:
            try:
                claim_folder(out, config_text)
            except ResultFolderError:
                lock.release()
                if created:
                    _remove_empty(out)
                raise
            return _run_locked(run)
        except RunInterrupted:
            raise
        except BaseException as exc:
            if not (isinstance(exc, KeyboardInterrupt) or interrupted()):
                raise
            # after the units, while the summary or the figures were written (whatever
            # the interrupted code raised: the Ctrl-C decides)
            done = len(UnitCache(out).keys() & {u.key for u in units})
            raise RunInterrupted(kept_message(out, done, len(units), "interrupted")) from None
        finally:
            lock.release()


@dataclass(frozen=True)
class _Run:
    """One run of :func:`run_experiment`: its experiment, folder, units and how it computes."""

    cfg: ExperimentCfg
    out: Path
    units: list[WorkUnit]
    checks: preflight.Preflight
    figures: bool
    t_start: float
    executor: Executor
    compute: Callable[[dict], dict]
    progress: bool


@contextmanager
def _connected(executor: Executor):
    """The executor opened (connect before writing anything: a bad address leaves no
    folder) and closed whatever happens."""
    executor_open = getattr(executor, "open", None)
    if executor_open is not None:
        executor_open()
    try:
        yield executor
    finally:
        close = getattr(executor, "close", None)
        if close is not None:
            close()


def _lock_folder(out: Path) -> tuple[FolderLock, bool]:
    """The folder created if needed and locked; whether this run created it."""
    created = not out.exists()
    try:
        out.mkdir(parents=True, exist_ok=True)
        lock = FolderLock(out).acquire()
    except OSError as exc:
        raise ResultFolderError(
            f"--out {out}: cannot create the folder ({exc.strerror or exc})"
        ) from None
    return lock, created


def _run_locked(run: _Run) -> RunSummary:
    out, units = run.out, run.units
    cache = UnitCache(out)
    keys = [u.key for u in units]
    scan_dirs = scan_folders(units)
    array_dirs = array_folders(units)
    records, todo = _cached_records(cache, out, units, scan_dirs, array_dirs)
    n_cached = len(units) - len(todo)
    stale = cache.keys() - set(keys)
    # nothing of a finished folder is removed before this run is known to be able to write
    _check_writable(out, scan_dirs, array_dirs)
    previous = _read_provenance(out)  # before anything is removed: its run time is kept
    prune_steps(out, {u.key for u in todo})  # steps only of the units still to compute
    if (
        not todo
        and not stale
        and folder_complete(out, keys)
        and previous.get("tables_code") == tables_code()
    ):
        # nothing changed: the tables stand; provenance adds this rerun's time
        return _rerun(run, previous, records)
    # units computed again only for an export they lack (--save-arrays / save_scans on a
    # finished folder): their numbers are cached and seeded, so the summary and the figures
    # still describe them and are kept (with --no-figures nothing would draw them again)
    exports_only = (
        bool(todo)
        and not stale
        and folder_complete(out, keys, ignore=("config.yaml",))
        and all(cache.load(u.key) is not None and cache.arrays_readable(u.key) for u in todo)
    )
    if (todo or stale or not folder_complete(out, keys)) and not exports_only:
        # the folder's summary and figures no longer describe its units: remove them before
        # any unit changes, so an interrupted run never leaves them beside other units
        _invalidate(out)
        cache.remove_except(set(keys))
    prune_scans(out, scan_dirs)  # the exports of units no longer produced go with them
    prune_scans(out, array_dirs, sub="arrays")

    compute_missing(run, cache, todo, records, n_cached)

    rows, columns = collect_rows(units, records)
    atomic_write_text(out / "results.csv", csv_text(rows, columns))
    md, tex = _tables(run.cfg, units, records, rows, out)
    atomic_write_text(out / "scores.md", md)
    atomic_write_text(out / "scores.tex", tex)
    write_table_csvs(out, md)

    elapsed = time.perf_counter() - run.t_start
    timings = {"run_s": round(elapsed, 3)}
    if not todo and "run_s" in (previous.get("timings") or {}):
        # every unit cached: the run that computed them keeps its time; this one is added
        timings = {"run_s": previous["timings"]["run_s"], "rerun_s": round(elapsed, 3)}
    _write_provenance(out, run.cfg, units, records, run.executor, n_cached, timings, run.checks)
    return _summary(run, n_cached, len(todo), md, records)


def _cached_records(cache: UnitCache, out: Path, units, scan_dirs, array_dirs=None):
    """The records of the units already finished, and the units (one per key) to compute."""
    records: dict[str, dict] = {}
    todo: list[WorkUnit] = []
    for u in units:
        rec = cache.load(u.key)
        # a cached unit whose scan export is missing (deleted, interrupted) is computed again:
        # the numbers are the same (seeded), the export comes back
        scans_ok = _scans_present(out, scan_dirs, u)
        scans_ok = scans_ok and _scans_present(out, array_dirs or {}, u, sub="arrays")
        if rec is not None and cache.arrays_readable(u.key) and scans_ok:
            records[u.key] = rec
        elif u.key not in {t.key for t in todo}:
            todo.append(u)
    return records, todo


def _tables(cfg: ExperimentCfg, units, records: dict, rows: list[dict], out: Path):
    """``scores.md`` and ``scores.tex`` of the study's kind."""
    if cfg.study.kind in ("scanner", "lidar"):
        # one set of tables per reconstruction (the one set of before for linear alone)
        groups: dict[str, list[dict]] = {}
        for r in rows:
            groups.setdefault(str(r.get("reconstruction", DEFAULT_RECONSTRUCTION)), []).append(r)
        parts = []
        for name, group in groups.items():
            title = cfg.name if len(groups) == 1 else f"{cfg.name} -- reconstruction {name}"
            parts.append(_sensor_tables(cfg, units, group, title))
        if cfg.study.kind == "lidar":  # the landing scores, every sensor and light in one table
            keys = [k for k in cfg.sweep if k not in ("seed", "terrain.seed_index")]
            parts.append(landing_tables(rows, keys=keys, title=cfg.name))
            light = "render.light.elevation_deg"
            paired = paired_table(rows, sensor_key="study.sensor",
                                  light_key=light if light in cfg.sweep else None,
                                  title=cfg.name) if "study.sensor" in cfg.sweep else ""  # fmt: skip
            parts.append((paired, ""))
        return "\n".join(md for md, _ in parts if md), "\n".join(tex for _, tex in parts if tex)
    return _sampling_tables(cfg, units, records, rows, out)


def _sensor_tables(cfg: ExperimentCfg, units, rows: list[dict], title: str):
    """The scanner or LIDAR tables of rows of one reconstruction."""
    if cfg.study.kind == "scanner":
        return scanner_tables(rows, metrics=_names(units, "metrics"), title=title)
    # one table block per sweep point; terrain seeds pooled (their interval in the figures)
    # (several axes: a block per point of the others, a seed axis's units pooled too)
    axes = [k for k in cfg.sweep if k not in ("seed", "terrain.seed_index")]
    by = next(iter(cfg.sweep)) if len(cfg.sweep) == 1 else (axes or None)
    return lidar_tables(rows, metrics=_names(units, "metrics"), title=title, by=by)


def _rerun(run: _Run, previous: dict, records: dict) -> RunSummary:
    """A rerun with nothing to compute: the tables stand, provenance records the rerun's
    time beside the original run's, the figures are redrawn only if their inputs changed."""
    md = (run.out / "scores.md").read_text()
    write_table_csvs(run.out, md)  # a folder written before tables/ existed gets them
    prov = dict(previous)
    timings = dict(prov.get("timings") or {})
    timings["rerun_s"] = round(time.perf_counter() - run.t_start, 3)
    prov["timings"] = timings
    n = len(run.units)
    prov["units"] = {"total": n, "cached": n, "computed": 0}
    atomic_write_json(run.out / "provenance.json", prov)
    return _summary(run, n, 0, md, records)


def _summary(run: _Run, n_cached: int, n_computed: int, md: str, records: dict) -> RunSummary:
    """The figures written (when asked for and enabled) and the run's summary."""
    written: list[Path] = []
    if run.figures and run.cfg.figures.enabled:
        written = write_figures_pruned(run.out)
    return RunSummary(
        run.out,
        len(run.units),
        n_cached,
        n_computed,
        time.perf_counter() - run.t_start,
        md,
        written,
        _notes(run.checks, run.units, records),
    )
