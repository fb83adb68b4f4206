"""Write a result folder's ``figures/`` from its ``results.csv`` and cached unit arrays.

Used by ``simlunar run`` at the end of a run and by ``simlunar figures RESULTS_DIR`` (which
redraws without recomputing anything).
"""

from __future__ import annotations

import json
from pathlib import Path

import yaml

from simlunar.pipeline.store import UnitCache, atomic_write_bytes, read_csv

MAX_UNIT_PANELS = 6


def load_results(out_dir: str | Path) -> dict:
    """Everything a figure needs from a result folder.

    Returns
    -------
    dict
        ``config`` (dict), ``rows`` (list of dict, strings as in the CSV), ``units`` (list of
        unit records in results order: sweep, scores, config, key) and ``dir`` (Path).

    Raises
    ------
    FileNotFoundError
        ``out_dir`` is not a finished result folder.
    """
    out = Path(out_dir)
    for name in ("config.yaml", "results.csv", "provenance.json"):
        if not (out / name).is_file():
            raise FileNotFoundError(
                f"{out}: not a result folder (missing {name}); "
                "run `simlunar run EXPERIMENT.yaml` first"
            )
    config = yaml.safe_load((out / "config.yaml").read_text())
    prov = json.loads((out / "provenance.json").read_text())
    cache = UnitCache(out)
    units = []
    for key in prov["unit_keys"]:
        rec = cache.load(key)
        if rec is None:
            raise FileNotFoundError(f"{out}: unit {key} is missing from units/")
        units.append(rec)
    return {
        "config": config,
        "rows": read_csv(out / "results.csv"),
        "units": units,
        "dir": out,
        "provenance": prov,
    }


def load_unit_arrays(out_dir: str | Path, index: int = 0) -> dict:
    """The arrays of unit ``index`` of a result folder (image, depth, wavelet_energy, ...)."""
    res = load_results(out_dir)
    rec = res["units"][index]
    return UnitCache(res["dir"]).load_arrays(rec["key"])


def _label(rec: dict) -> str:
    from simlunar.pipeline.runner import WorkUnit, unit_label

    return unit_label(
        WorkUnit(rec.get("index", 0), rec["key"], rec.get("sweep", {}), rec.get("config", {}))
    )


def write_figures(out_dir: str | Path) -> list[Path]:
    """Draw every figure the results support; returns the written paths (PNG and PDF)."""
    from simlunar.plotting import figures as F

    res = load_results(out_dir)
    out = res["dir"]
    cfg = res["config"]
    formats = (cfg.get("figures") or {}).get("formats") or ["png", "pdf"]
    fig_dir = out / "figures"
    written: list[Path] = []

    def emit(fig, stem):
        for suffix, data in F.save(fig, stem, formats):
            path = fig_dir / f"{stem}.{suffix}"
            atomic_write_bytes(path, data)
            written.append(path)
        F.close(fig)

    study = cfg.get("study", {})
    if study.get("kind", "sampling") != "sampling":
        _scanner_figures(res, emit)
        return written
    strategies = list(study.get("strategies") or [])
    metrics = list(study.get("metrics") or [])
    units = res["units"]
    shown = units[:MAX_UNIT_PANELS]

    for m in metrics:
        fig, axes = F.panel_row(len(shown), width=F.COLUMN_W * min(len(shown), 3))
        for ax, rec in zip(axes, shown):
            F.error_vs_density(
                res["rows"],
                metric=m,
                strategies=strategies,
                ax=ax,
                where={"unit": rec.get("index", 0)},
                title=_label(rec) if len(units) > 1 else None,
            )
        emit(fig, f"error_vs_density_{m}")

    cache = UnitCache(out)
    shown_arrays = [cache.load_arrays(rec["key"]) for rec in shown]  # each .npz read once
    for rec, arr in zip(shown, shown_arrays):
        if not {"image", "wavelet_energy", "plan_rows", "reconstruction", "depth"} <= set(arr):
            continue
        density = (rec.get("config", {}).get("figures") or {}).get("panel_density")
        label = f"(k/N = 1/{round(1 / density)})" if density else ""
        fig, _ = F.image_panels(
            arr["image"],
            arr["wavelet_energy"],
            arr["plan_rows"],
            arr["plan_cols"],
            arr["reconstruction"],
            arr["depth"],
            density_label=label,
        )
        emit(fig, f"panels_unit{rec.get('index', 0)}")

    for rec, arr in zip(shown, shown_arrays):
        if "sparse_mesh_render" not in arr or "radiance" not in arr:
            continue
        dens = (rec.get("config", {}).get("figures") or {}).get("sparse_mesh_density")
        n = round(dens * arr["radiance"].size) if dens else None
        fig, _ = F.sparse_mesh_panels(
            arr["sparse_mesh_render"],
            arr["radiance"],
            arr.get("wavelet_energy"),
            rough=arr.get("sparse_mesh_render_rough"),
            n_samples=n,
        )
        emit(fig, f"sparse_mesh_unit{rec.get('index', 0)}")

    _samples_saved_figures(res, emit)

    sweep = cfg.get("sweep") or {}
    if len(sweep) == 1 and len(units) > 1:
        (path,) = sweep
        points = []
        for rec in units:
            v = rec["sweep"][path]
            if isinstance(v, dict):
                v = v.get("kind", json.dumps(v, sort_keys=True))
            points.append((v, rec.get("scores", {})))
        axis = path.rsplit(".", 1)[-1]
        for m in metrics:
            fig, _ = F.score_vs_sweep(points, metric=m, strategies=strategies, axis_label=path)
            emit(fig, f"score_vs_{axis}_{m}")
    return written


def _scanner_figures(res: dict, emit) -> None:
    import numpy as np

    from simlunar.plotting import figures as F
    from simlunar.plotting.tables import scanner_summary

    rows = res["rows"]
    metrics = list(res["config"]["study"].get("metrics") or [])
    summary = scanner_summary(rows, metrics=metrics)
    fig, axes = F.panel_row(len(metrics))
    for ax, m in zip(axes, metrics):
        F.scanner_bars(summary, metric=m, ax=ax)
    emit(fig, "scanner_errors")
    ber = sorted(
        {r["metric"] for r in rows if r["metric"].startswith("ber_")},
        key=lambda n: (n[4], int(n[5:])),
    )
    if ber:
        vals = {n: np.mean([float(r["value"]) for r in rows if r["metric"] == n]) for n in ber}
        fig, ax = F.bit_error_rates(vals)
        emit(fig, "gray_code_bit_errors")


def _samples_saved_figures(res: dict, emit) -> None:
    """``samples_saved``: per sweep point (pooled over terrain seeds), one panel per reference
    (random, grid), the first metric; ``samples_saved_point<i>`` when there are several."""
    from simlunar.pipeline import aggregate
    from simlunar.plotting import figures as F

    points = aggregate.summarise(res["units"], res["rows"], seed=0, n_boot=10)
    points = [p for p in points if p.saved][:MAX_UNIT_PANELS]
    for i, p in enumerate(points):
        fig, axes = F.panel_row(len(p.saved))
        for ax, (ref, sv) in zip(axes, p.saved.items()):
            F.samples_saved_plot(
                p.densities,
                sv.factor,
                sv.flag,
                reference=ref,
                metric=p.saved_metric,
                strategies=p.strategies,
                ax=ax,
                title=f"{p.label}: vs {ref}" if len(points) > 1 else None,
            )
        emit(fig, "samples_saved" if len(points) == 1 else f"samples_saved_point{i}")
