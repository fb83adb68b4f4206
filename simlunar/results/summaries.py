"""What a run writes beside its units: the score tables (scores.md/.tex/.csv), the
samples-saved tables as CSV (samples_saved.csv; reconstructions.csv: each reconstruction vs
linear on the same layouts), the notes of its checks and provenance.json (config, versions,
inputs, timings, the code that wrote the tables)."""

from __future__ import annotations

import functools
import hashlib
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import simlunar
from simlunar.plotting.tables import (
    Cell,
    headroom_tables,
    paired_saved_tables,
    reconstruction_saved_tables,
    samples_saved_tables,
    score_tables,
    seed_summary_numbers,
)
from simlunar.render.backend import versions
from simlunar.results import aggregate
from simlunar.results.folder import RESULT_FILES
from simlunar.results.records import WorkUnit
from simlunar.results.store import (
    atomic_write_json,
    atomic_write_text,
    csv_text,
    file_sha256,
)

__all__ = ["RECONSTRUCTIONS_CSV_COLUMNS", "SAVED_CSV_COLUMNS", "tables_code"]

#: columns of samples_saved.csv: per point (and reconstruction), reference, metric, strategy
#: and density, the factor (``extrapolated`` 1 beyond the reference's range); the
#: ``density`` "geo_mean" rows hold the summary over ``n`` densities
SAVED_CSV_COLUMNS = [
    "point", "reconstruction", "reference", "metric", "strategy", "density", "k", "factor",
    "extrapolated", "n",
]  # fmt: skip
#: columns of reconstructions.csv: samples linear needs for each reconstruction's error on the
#: same layout, per terrain seed and ("all") geometric mean over seeds with its 95 % t interval
RECONSTRUCTIONS_CSV_COLUMNS = [
    "point", "metric", "strategy", "reconstruction", "terrain_seed", "saved_vs_linear",
    "ci_low", "ci_high", "n",
]  # fmt: skip


def _git_commit() -> dict[str, Any]:
    root = Path(__file__).resolve().parents[2]
    try:
        head = subprocess.run(
            ["git", "-C", str(root), "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        ).stdout.strip()
        dirty = (
            subprocess.run(
                ["git", "-C", str(root), "status", "--porcelain", "--", "simlunar"],
                capture_output=True,
                text=True,
                timeout=10,
            ).stdout.strip()
            != ""
        )
        return {"commit": head, "dirty": dirty}
    except (OSError, subprocess.SubprocessError):
        return {"commit": None, "dirty": None}


#: modules that write the tables: a change of any of them rewrites the tables of a rerun
_TABLE_MODULES = (
    "simlunar.pipeline.runner",
    "simlunar.pipeline.rows",  # the rows of results.csv, their order and columns
    "simlunar.plotting.lidar_tables",  # the LIDAR study's tables
    "simlunar.results.summaries",
    "simlunar.plotting.tables",
    "simlunar.plotting.scanner_tables",
    "simlunar.results.aggregate",
    "simlunar.study.stats",
)


@functools.cache
def tables_code() -> str:
    """SHA-256 of the code that writes a folder's tables (recorded in ``provenance.json``).

    Hashed once per process, when this module is imported (with the modules that write the
    tables): the code the process runs. Hashed at write time instead, a table module edited
    during a long run labelled the tables its old code wrote with the new code's hash, and
    the next rerun kept them. (``simlunar.plotting.lidar`` is imported only when a LIDAR
    study writes its tables, so an edit of it during such a run is the one case left: its
    tables then carry the start's hash and are rewritten by the next rerun.)
    """
    root = Path(simlunar.__file__).parent  # module paths without importing them
    h = hashlib.sha256()
    for mod in _TABLE_MODULES:
        path = root.joinpath(*mod.split(".")[1:]).with_suffix(".py")
        h.update(file_sha256(path).encode() if path.is_file() else mod.encode())
    return h.hexdigest()


tables_code()


def _notes(checks, units, records) -> list[str]:
    """Lines for the user about what the run did to its inputs (NaN holes filled)."""
    notes = []
    for h in checks.holes():
        notes.append(
            f"note: {h['file']}: {100 * h['nan_fraction']:.2f}% of the DEM heights are NaN "
            "(holes); ground-truth pixels without a hit take the depth of the nearest valid "
            "pixel (see provenance.json)"
        )
    return notes


def _sampling_tables(cfg, units, records, rows, out: Path) -> tuple[str, str]:
    """Score tables (pooled over terrain seeds, with intervals), samples-saved tables and
    ``scores.csv`` (per-seed and pooled scores) of a sampling experiment."""

    recs = [{**records[u.key], "sweep": u.sweep, "config": u.config} for u in units]
    points = aggregate.summarise(recs, rows, seed=cfg.seed)
    labelled = []
    for p in points:
        scores = {}
        for m in p.metrics:
            res, sep = p.intervals.get(m), p.separation.get(m)
            if res is None:
                continue
            scores[m] = {
                s: Cell(
                    *res.interval(s), bold=sep is not None and sep.significant and s == sep.best
                )
                for s in res.strategies
            }
        labelled.append((p.label, scores))
    strategies = _names(units, "strategies")
    # the scored names: with study.score_region, <metric>_interior rows too
    metrics = list(dict.fromkeys(m for p in points for m in p.metrics))
    seeds = sorted({len(p.seeds) for p in points})
    trials = sorted({int(float(r["trial"])) for r in rows}, reverse=True)[:1]
    n_trials = "/".join(str(t + 1) for t in trials)
    n_seeds = "/".join(map(str, seeds))
    if any(scores for _, scores in labelled):
        note = (
            f"Scores pool {n_seeds} terrain seed(s) x {n_trials} trials; [95 % interval]: "
            "paired bootstrap over terrain seeds (one seed: over trials), percentile, "
            "small-sample widened. Bold: the best score of a row where the paired bootstrap "
            "95 % interval of its difference to the runner-up excludes 0."
        )
        md, tex = score_tables(
            labelled, strategies=strategies, metrics=metrics, title=cfg.name, note=note
        )
    else:
        # no table of dashes: say why there is none
        no_csv = "" if aggregate.scores_csv_rows(points, recs) else " and no scores.csv"
        note = (
            f"No score table{no_csv}: the scores (eq. 4.3) are errors relative to "
            f"the random strategy, which study.strategies ({', '.join(strategies)}) does not "
            f"include; add random to get them. The errors are in results.csv."
        )
        md, tex = note + "\n", "% " + note + "\n"
    saved_entries = _saved_entries(points)
    recon_entries = aggregate.reconstruction_saved_entries(points, rows)
    md2, tex2 = samples_saved_tables(saved_entries, title=cfg.name)
    _write_csv(out / "samples_saved.csv", _saved_csv_rows(saved_entries), SAVED_CSV_COLUMNS)
    _write_csv(
        out / "reconstructions.csv", _recon_csv_rows(recon_entries), RECONSTRUCTIONS_CSV_COLUMNS
    )
    # per-seed tables: the headroom (with an oracle) or the paired savings (without one)
    for md3, tex3 in (
        headroom_tables(aggregate.headroom_entries(points), title=cfg.name),
        paired_saved_tables(aggregate.paired_saved_entries(points), title=cfg.name),
        reconstruction_saved_tables(recon_entries, title=cfg.name),
    ):
        if md3:
            md2, tex2 = md2 + "\n" + md3, tex2 + "\n" + tex3
    if md2:
        md, tex = md + "\n" + md2, tex + "\n" + tex2
    elif not any(p.saved for p in points):
        why = (
            "one density (a curve needs two)"
            if all(len(p.ks) < 2 for p in points)
            else "neither random nor grid among study.strategies"
        )
        line = f"No samples-saved table: it compares against random or grid, and there is {why}."
        md, tex = f"{md}\n{line}\n", f"{tex}\n% {line}\n"
    score_rows = aggregate.scores_csv_rows(points, recs)
    if score_rows:
        atomic_write_text(out / "scores.csv", csv_text(score_rows, aggregate.SCORES_CSV_COLUMNS))
    else:
        (out / "scores.csv").unlink(missing_ok=True)  # scores.md says why there is none
    return md, tex


def _names(units: list[WorkUnit], key: str) -> list[str]:
    out: list[str] = []
    for u in units:
        for n in u.config.get("study", {}).get(key) or []:
            if n not in out:
                out.append(n)
    return out


def _write_provenance(out: Path, cfg, units, records, executor, n_cached, timings, checks) -> None:

    variants = sorted(
        {
            str(r.get("meta", {}).get("variant"))
            for r in records.values()
            if r.get("meta", {}).get("variant")
        }
    )
    prov = {
        "experiment": cfg.name,
        "seed": cfg.seed,
        "versions": versions(),
        "variant": variants[0] if len(variants) == 1 else variants,
        "git": _git_commit(),
        "python": sys.version.split()[0],
        "executor": executor.describe(),
        "units": {"total": len(units), "cached": n_cached, "computed": len(units) - n_cached},
        "timings": {
            **timings,
            "units": {u.key: records[u.key].get("timings", {}) for u in units},
        },
        "unit_keys": [u.key for u in units],
        "simlunar": simlunar.__version__,
        "tables_code": tables_code(),
        "inputs": _inputs(units),
        "terrain_holes": checks.holes(),
        "filled_pixels": {
            u.key: records[u.key].get("meta", {}).get("invalid_pixels_filled") for u in units
        },
        # the folder's files this provenance belongs to (checked by `simlunar figures`)
        "files": {
            name: file_sha256(out / name)
            for name in ("config.yaml", *RESULT_FILES[1:])
            if (out / name).is_file()
        },
    }
    atomic_write_json(out / "provenance.json", prov)


def _inputs(units: list[WorkUnit]) -> list[dict[str, str]]:
    """Distinct input files of the units: key path, path and SHA-256."""
    seen: dict[tuple, dict[str, str]] = {}
    for u in units:
        for key, v in u.inputs.items():
            seen.setdefault((key, v["path"], v["sha256"]), {"key": key, **v})
    return list(seen.values())


def _write_csv(path: Path, rows: list[dict], columns: list[str]) -> None:
    """``rows`` as CSV, or no file where there are none (scores.md says what is missing)."""
    if rows:
        atomic_write_text(path, csv_text(rows, columns))
    else:
        path.unlink(missing_ok=True)


def _saved_csv_rows(entries: list[dict]) -> list[dict]:
    """The samples-saved tables (vs random, grid, uniform Lloyd; per reconstruction) as rows."""
    out = []
    for e in entries:
        base = {"point": e["label"], "reconstruction": e.get("reconstruction", "linear"),
                "reference": e["reference"], "metric": e["metric"]}  # fmt: skip
        for s in e["strategies"]:
            if s == e["reference"] or s not in e["factor"]:
                continue
            for d, k, v, f in zip(e["densities"], e["ks"], e["factor"][s], e["flag"][s]):
                out.append({**base, "strategy": s, "density": d, "k": k, "factor": v,
                            "extrapolated": int(bool(f)), "n": ""})  # fmt: skip
            out.append({**base, "strategy": s, "density": "geo_mean", "k": "",
                        "factor": e["summary"][s], "extrapolated": "",
                        "n": e["n_summary"][s]})  # fmt: skip
    return out


def _recon_csv_rows(entries: list[dict]) -> list[dict]:
    """The reconstruction-vs-linear tables as rows: per seed, then over seeds."""
    out = []
    for e in entries:
        for r in e["reconstructions"]:
            for s in e["strategies"]:
                v = e["saved"][r][s]
                base = {"point": e["label"], "metric": e["metric"], "strategy": s,
                        "reconstruction": r}  # fmt: skip
                for seed, x in zip(e["seeds"], v):
                    out.append({**base, "terrain_seed": seed, "saved_vs_linear": x,
                                "ci_low": "", "ci_high": "", "n": ""})  # fmt: skip
                m, lo, hi, n = (
                    "" if isinstance(x, float) and math.isnan(x) else x
                    for x in seed_summary_numbers(v, log=True)
                )
                out.append({**base, "terrain_seed": "all", "saved_vs_linear": m,
                            "ci_low": lo, "ci_high": hi, "n": n})  # fmt: skip
    return out


def _saved_entries(points) -> list[dict]:
    """Samples-saved table entries: per point, per reference, the first metric and (with
    ``score_region: both``) its interior-only twin."""
    return [
        {"label": p.label if len(points) > 1 else "", "reference": ref, "metric": metric,
         "strategies": p.strategies, "ks": p.ks, "densities": p.densities,
         "factor": sv.factor, "flag": sv.flag, "summary": sv.summary, "n_summary": sv.n_summary,
         "reconstruction": p.reconstruction}
        for p in points
        for metric, saved in ((p.saved_metric, p.saved), (f"{p.saved_metric}_interior",
                                                          p.saved_interior))
        for ref, sv in saved.items()
    ]  # fmt: skip
