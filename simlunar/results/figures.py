"""Write a result folder's ``figures/`` from its ``results.csv`` and cached unit arrays.

Used by ``simlunar run`` at the end of a run and by ``simlunar figures RESULTS_DIR`` (which
redraws without recomputing anything).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

from simlunar.errors import ResultFolderError
from simlunar.results.aggregate import SEED_AXIS
from simlunar.results.store import UnitCache, atomic_write_bytes, file_sha256, read_csv

MAX_UNIT_PANELS = 6
#: sweep axes that repeat an experiment over realisations (pooled, not plotted against): the
#: experiment seed and the terrain realisation
SEED_AXES = ("seed", SEED_AXIS)


def load_results(out_dir: str | Path) -> dict:
    """Everything a figure needs from a result folder.

    Returns
    -------
    dict
        ``config`` (dict), ``rows`` (list of dict, strings as in the CSV), ``units`` (list of
        unit records in results order: sweep, scores, config, key) and ``dir`` (Path).

    Raises
    ------
    ResultFolderError
        ``out_dir`` is not a finished result folder, or its files disagree with each other
        (``provenance.json`` records the SHA-256 of ``config.yaml``, ``results.csv`` and the
        tables it was written with) or cannot be read; the message names the file.
    """
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ResultFolderError(f"{out}: is a file, not a result folder")
    for name in ("config.yaml", "results.csv", "provenance.json"):
        if not (out / name).is_file():
            hint = (
                "an unfinished run: rerun it with the same config to finish"
                if (out / "config.yaml").is_file()
                else "run `simlunar run EXPERIMENT.yaml` first"
            )
            raise ResultFolderError(f"{out}: not a result folder (missing {name}); {hint}")
    from simlunar.results.folder import read_folder_config

    config = read_folder_config(out / "config.yaml")
    prov = _read_provenance(out / "provenance.json")
    for name, digest in (prov.get("files") or {}).items():
        path = out / name
        if not path.is_file() or file_sha256(path) != digest:
            raise ResultFolderError(
                f"{path}: does not belong to this folder's results (changed or missing since "
                "provenance.json was written); rerun the experiment into this folder to repair"
            )
    rows = _read_rows(out / "results.csv")
    cache = UnitCache(out)
    units = []
    for key in prov["unit_keys"]:
        rec = cache.load(key)
        if rec is None:
            raise ResultFolderError(
                f"{cache.json_path(key)}: unit missing or unreadable; rerun the experiment "
                "into this folder to recompute it"
            )
        units.append(rec)
    return {
        "config": config,
        "rows": rows,
        "units": units,
        "dir": out,
        "provenance": prov,
    }


def _read_provenance(path: Path) -> dict:
    try:
        prov = json.loads(path.read_text())
    except (ValueError, OSError) as exc:
        raise ResultFolderError(f"{path}: not valid JSON ({exc})") from None
    keys = prov.get("unit_keys") if isinstance(prov, dict) else None
    if not isinstance(keys, list) or not keys or not all(isinstance(k, str) for k in keys):
        raise ResultFolderError(f"{path}: no 'unit_keys' list; not a simlunar provenance file")
    return prov


def _read_rows(path: Path) -> list[dict[str, str]]:
    try:
        rows = read_csv(path)
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ResultFolderError(f"{path}: unreadable ({exc})") from None
    if not rows:
        raise ResultFolderError(f"{path}: no result rows")
    missing = [c for c in ("unit", "metric", "value") if c not in rows[0]]
    if missing:
        raise ResultFolderError(f"{path}: no {missing[0]!r} column; not a simlunar results table")
    for i, r in enumerate(rows, start=2):
        try:
            float(r["value"])
            int(r["unit"])
        except (TypeError, ValueError):
            raise ResultFolderError(
                f"{path}: line {i}: unit {r['unit']!r}, value {r['value']!r} are not numbers"
            ) from None
    return rows


def load_unit_arrays(out_dir: str | Path, index: int = 0) -> dict:
    """The arrays of unit ``index`` of a result folder (image, depth, wavelet_energy, ...)."""
    res = load_results(out_dir)
    rec = res["units"][index]
    return UnitCache(res["dir"]).load_arrays(rec["key"])


def _label(rec: dict) -> str:
    from simlunar.results.records import WorkUnit, unit_label

    config = rec.get("config", {}) or {}
    repeats = int((config.get("study") or {}).get("terrain_seeds", 1) or 1)
    seed = int((config.get("terrain") or {}).get("seed_index", 0) or 0) if repeats > 1 else None
    return unit_label(
        WorkUnit(rec.get("index", 0), rec["key"], rec.get("sweep", {}), config, terrain_seed=seed)
    )


def _density_panels(units: list[dict]) -> list[tuple[str, list[dict]]]:
    """The panels of ``error_vs_density``: ``[(title, unit records)]`` in results order.

    One panel per sweep point (:func:`simlunar.results.aggregate.group_points`): the units of
    a point that differ only by terrain seed share a panel, whose curves pool their rows (mean
    and spread over terrain seeds and trials), so a repeated experiment draws as many panels
    as it has sweep points, not seeds times points.
    """
    from simlunar.results.aggregate import group_points

    return [(p.label, [units[i] for i in p.unit_indices]) for p in group_points(units)]


def write_figures(out_dir: str | Path) -> list[Path]:
    """Draw every figure the results support; returns the written paths (PNG and PDF)."""
    from simlunar.plotting import figures as F
    from simlunar.plotting.style import axis_name
    from simlunar.results import captions as captions_text

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
    captions: dict[str, str] = {}
    if study.get("kind", "sampling") != "sampling":
        (_lidar_figures if study.get("kind") == "lidar" else _scanner_figures)(res, emit, captions)
        write_captions(fig_dir, captions, written)
        return written
    strategies = list(study.get("strategies") or [])
    metrics = list(study.get("metrics") or [])
    units = res["units"]
    shown = units[:MAX_UNIT_PANELS]
    cache = UnitCache(out)
    # each .npz read once, before any figure is written; a corrupt one is an error naming it,
    # not a silently missing panel
    shown_arrays = [cache.load_arrays(rec["key"], strict=True) for rec in shown]

    groups = _density_panels(units)[:MAX_UNIT_PANELS]
    pooled = any(len(members) > 1 for _, members in groups)
    for m in metrics:
        fig, axes = F.panel_grid(len(groups))
        for ax, (title, members) in zip(axes, groups):
            F.error_vs_density(
                res["rows"],
                metric=m,
                strategies=strategies,
                ax=ax,
                where={"unit": [rec.get("index", 0) for rec in members]},
                title=title if len(units) > 1 else None,
                band_label=F.BAND_LABEL_SEEDS if pooled else F.BAND_LABEL,
            )
        if len(axes) > 1:
            F.shared_legend(fig, axes)
        emit(fig, f"error_vs_density_{m}")
        captions[f"error_vs_density_{m}"] = captions_text.error_vs_density(
            m, study, len(groups), seeds=max(len(members) for _, members in groups)
        )

    for rec, arr in zip(shown, shown_arrays):
        if not {"image", "wavelet_energy", "plan_rows", "reconstruction", "depth"} <= set(arr):
            continue
        density = (rec.get("config", {}).get("figures") or {}).get("panel_density")
        label = f"k/N = 1/{round(1 / density)}" if density else ""
        fig, _ = F.image_panels(
            arr["image"],
            arr["wavelet_energy"],
            arr["plan_rows"],
            arr["plan_cols"],
            arr["reconstruction"],
            arr["depth"],
            density_label=label,
            planner="wavelet",
            point=_label(rec) if len(units) > 1 else "",
        )
        emit(fig, f"panels_unit{rec.get('index', 0)}")
        captions[f"panels_unit{rec.get('index', 0)}"] = captions_text.panels(label, _label(rec))

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
            point=_label(rec) if len(units) > 1 else "",
        )
        emit(fig, f"sparse_mesh_unit{rec.get('index', 0)}")
        captions[f"sparse_mesh_unit{rec.get('index', 0)}"] = captions_text.sparse_mesh(
            n, "sparse_mesh_render_rough" in arr
        )

    _samples_saved_figures(res, emit, captions)

    sweep = cfg.get("sweep") or {}
    if len(sweep) == 1 and len(units) > 1:
        (path,) = sweep
        points = [(_sweep_value(rec, path), rec.get("scores", {})) for rec in units]
        axis = path.rsplit(".", 1)[-1]
        for m in metrics:
            fig, _ = F.score_vs_sweep(
                points, metric=m, strategies=strategies, axis_label=axis_name(path)
            )
            emit(fig, f"score_vs_{axis}_{m}")
            captions[f"score_vs_{axis}_{m}"] = captions_text.score_vs_sweep(m, path, study)
    write_captions(fig_dir, captions, written)
    return written


def write_captions(fig_dir: Path, captions: dict[str, str], written: list[Path]) -> None:
    """Write ``figures/captions.md``: one section per figure (stem), its caption beside it."""
    if not captions:
        return
    lines = ["# Figure captions", ""]
    for stem, text in captions.items():
        lines += [f"## {stem}", "", text, ""]
    path = fig_dir / "captions.md"
    atomic_write_bytes(path, "\n".join(lines).encode())
    written.append(path)


def _scanner_pooled(rows: list[dict], metrics: list[str]) -> list[dict]:
    """Mean, s.d. and count of each metric per (mode, planner) over all units and trials."""
    import numpy as np

    groups: dict[tuple, dict[str, list[float]]] = {}
    for r in rows:
        key = (r["mode"], r.get("planner") or "")
        groups.setdefault(key, {}).setdefault(r["metric"], []).append(float(r["value"]))
    out = []
    for (mode, planner), vals in groups.items():
        e = {"mode": mode, "planner": planner}
        for m in metrics:
            v = np.asarray(vals.get(m, []), float)
            v = v[np.isfinite(v)]
            e[m] = float(v.mean()) if v.size else None
            e[f"{m}_sd"] = float(v.std(ddof=1)) if v.size > 1 else None
            e["n"] = int(v.size)
        out.append(e)
    return out


def _sweep_value(rec: dict, path: str):
    """A unit's value on sweep axis ``path`` as a plot position or label: numbers as they
    are, a model (dict) by its ``kind``, null as ``"preset default"``."""
    v = rec["sweep"][path]
    if isinstance(v, dict):
        return v.get("kind", json.dumps(v, sort_keys=True))
    return "preset default" if v is None else v


def _ambient_axis(rows: list[dict], units: list[dict], path: str):
    """``(factor, label)`` of a sun-to-projector axis when every unit of a one-axis sweep is a
    daylight scan whose ``ambient_ratio`` is proportional to the swept value (the sun's
    irradiance), else None."""
    ratio = {str(r.get("unit")): float(r["value"]) for r in rows if r["metric"] == "ambient_ratio"}
    k = []
    for rec in units:
        x, v = rec["sweep"].get(path), ratio.get(str(rec.get("index", 0)))
        if v is None or not isinstance(x, (int, float)) or isinstance(x, bool) or x <= 0:
            return None
        k.append(v / x)
    if not k or max(k) - min(k) > 1e-3 * max(k) or not max(k) > 0:
        return None
    return float(sum(k) / len(k)), "sun / projector white, as the camera sees it"


def _scanner_figures(res: dict, emit, captions: dict) -> None:
    import numpy as np

    from simlunar.plotting import figures as F
    from simlunar.plotting.style import axis_name
    from simlunar.results import captions as captions_text

    rows = res["rows"]
    cfg = res["config"]
    metrics = list(cfg["study"].get("metrics") or [])
    sweep = cfg.get("sweep") or {}
    units = res["units"]
    n_units = len({str(r.get("unit", "0")) for r in rows})
    if len(sweep) == 1 and next(iter(sweep)) not in SEED_AXES and len(units) > 1:
        # an ablation: the errors against the swept value (pooling across it would mix
        # errors of different conditions into one bar)
        (path,) = sweep
        shown = [*metrics, "valid_fraction"]
        by_unit: dict[str, list[dict]] = {}
        for r in rows:
            by_unit.setdefault(str(r.get("unit")), []).append(r)
        points = [
            (
                _sweep_value(rec, path),
                _scanner_pooled(by_unit.get(str(rec.get("index", 0)), []), shown),
            )
            for rec in units
        ]
        fig, axes = F.panel_grid(len(shown), height=2.8)
        secondary = _ambient_axis(rows, units, path)
        for ax, m in zip(axes, shown):
            F.scanner_vs_sweep(
                points, metric=m, axis_label=axis_name(path), ax=ax, secondary=secondary
            )
        F.shared_legend(fig, axes, prune_labels=False)
        axis = path.rsplit(".", 1)[-1]
        emit(fig, f"scanner_vs_{axis}")
        captions[f"scanner_vs_{axis}"] = captions_text.scanner_vs_sweep(
            metrics, path, int(cfg["study"].get("trials", 1))
        )
    else:
        summary = _scanner_pooled(rows, metrics)
        fig, axes = F.panel_row(len(metrics))
        for ax, m in zip(axes, metrics):
            F.scanner_bars(summary, metric=m, ax=ax)
        emit(fig, "scanner_errors")
        captions["scanner_errors"] = captions_text.scanner_errors(metrics, n_units)
    ber = sorted(
        {r["metric"] for r in rows if r["metric"].startswith("ber_")},
        key=lambda n: (n[4], int(n[5:])),
    )
    if ber:
        vals = {n: np.mean([float(r["value"]) for r in rows if r["metric"] == n]) for n in ber}
        captions["gray_code_bit_errors"] = captions_text.bit_errors(
            n_units, all(v == 0 for v in vals.values())
        )
        fig, ax = F.bit_error_rates(vals)
        emit(fig, "gray_code_bit_errors")


def write_figures_pruned(out_dir: str | Path) -> list[Path]:
    """:func:`write_figures`, then remove the figures of ``figures/`` it did not write."""
    from simlunar.results.folder import prune_figures

    written = write_figures(out_dir)
    prune_figures(Path(out_dir), keep=written)
    return written


def _samples_saved_figures(res: dict, emit, captions: dict[str, str]) -> None:
    """``samples_saved``: per sweep point (pooled over terrain seeds), one panel per reference
    (random, grid), the first metric; ``samples_saved_point<i>`` when there are several."""
    from simlunar.plotting import figures as F
    from simlunar.results import aggregate
    from simlunar.results import captions as captions_text

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
        stem = "samples_saved" if len(points) == 1 else f"samples_saved_point{i}"
        emit(fig, stem)
        captions[stem] = captions_text.samples_saved(p.saved_metric, list(p.saved), p.label)


def _lidar_figures(res: dict, emit, captions: dict) -> None:
    """Error against scan time and against samples per planner; one panel per sweep point
    (units of one point, i.e. its terrain seeds, pooled into the interval)."""
    from simlunar.plotting import figures as F
    from simlunar.plotting.lidar import error_vs_time
    from simlunar.results import captions as captions_text

    study = res["config"].get("study", {})
    sweep = list(res["config"].get("sweep") or {})
    # a swept sensor option changes each acquisition's cost: its points are one curve
    by = sweep[0] if len(sweep) == 1 and sweep[0].startswith("study.options.") else None
    groups = [("", res["units"])] if by else _density_panels(res["units"])[:MAX_UNIT_PANELS]
    seeds = max(len(members) for _, members in groups)
    if by:
        seeds = max(1, int(study.get("terrain_seeds", 1) or 1))
    for m in study.get("metrics") or []:
        for x, name in (("seconds", "time"), ("samples", "samples")):
            fig, axes = F.panel_grid(len(groups))
            for ax, (title, members) in zip(axes, groups):
                error_vs_time(
                    res["rows"],
                    metric=m,
                    x=x,
                    planners=study.get("planners"),
                    where={"unit": [rec.get("index", 0) for rec in members]},
                    by=by,
                    title=title if len(groups) > 1 else "",
                    ax=ax,
                )
            emit(fig, f"lidar_error_vs_{name}_{m}")
            captions[f"lidar_error_vs_{name}_{m}"] = captions_text.lidar_error(
                m, study, x, len(groups), seeds=seeds, by=by
            )
