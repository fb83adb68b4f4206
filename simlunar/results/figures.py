"""Write a result folder's ``figures/`` from its ``results.csv`` and cached unit arrays.

Used by ``simlunar run`` at the end of a run and by ``simlunar figures RESULTS_DIR`` (which
redraws without recomputing anything).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

from simlunar.errors import ResultFolderError
from simlunar.results import aggregate
from simlunar.results import captions as captions_text
from simlunar.results.aggregate import SEED_AXIS, group_points
from simlunar.results.folder import prune_figures, read_folder_config
from simlunar.results.store import UnitCache, atomic_write_bytes, file_sha256, read_csv

MAX_UNIT_PANELS = 6
#: sweep axes that repeat an experiment over realisations (pooled, not plotted against): the
#: experiment seed and the terrain realisation


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
    """Title of one unit: its sweep point (:func:`simlunar.plotting.style.point_title`) and,
    when the experiment repeats terrains, its terrain seed."""
    from simlunar.plotting.style import point_title

    config = rec.get("config", {}) or {}
    sweep = {k: v for k, v in (rec.get("sweep") or {}).items() if k != SEED_AXIS}
    text = point_title(sweep)
    repeats = int((config.get("study") or {}).get("terrain_seeds", 1) or 1)
    if repeats > 1 or SEED_AXIS in (rec.get("sweep") or {}):
        seed = int((config.get("terrain") or {}).get("seed_index", 0) or 0)
        text = f"{text}; terrain seed {seed}" if text else f"terrain seed {seed}"
    return text


def _spacing(rec: dict) -> float | None:
    """Cell size (m) of a unit whose camera is nadir orthographic (a pixel is a cell)."""
    camera = ((rec.get("config") or {}).get("render") or {}).get("camera") or {}
    if camera.get("kind", "orthographic_nadir") != "orthographic_nadir":
        return None
    sp = (rec.get("meta") or {}).get("spacing_m")
    return float(sp) if sp else None


#: the figures' record of what they were drawn from (in the result folder, beside figures/)
STAMP = ".figures.json"
#: modules whose code draws the figures: a change of any of them redraws every figure
_DRAWING_MODULES = (
    "simlunar.plotting.figures",
    "simlunar.plotting.layout",
    "simlunar.plotting.density",
    "simlunar.plotting.images",
    "simlunar.plotting.scanner",
    "simlunar.plotting.lidar",
    "simlunar.plotting.style",
    "simlunar.results.figures",
    "simlunar.results.scanner_figures",
    "simlunar.results.lidar_figures",
    "simlunar.results.captions",
    "simlunar.results.aggregate",
)


def figure_inputs(res: dict, formats) -> str:
    """SHA-256 of everything the figures of a result folder are drawn from: the tables
    (``results.csv`` and the summary files, as ``provenance.json`` records their digests), the
    units (their keys), the configuration (less its description), the file formats, the
    drawing code and the matplotlib version."""
    import hashlib
    import importlib.metadata
    import importlib.util

    cfg = {k: v for k, v in res["config"].items() if k != "description"}
    code = {}
    for mod in _DRAWING_MODULES:
        spec = importlib.util.find_spec(mod)
        if spec is not None and spec.origin:
            code[mod] = file_sha256(spec.origin)
    blob = json.dumps(
        {
            "files": res["provenance"].get("files"),
            "units": res["provenance"].get("unit_keys"),
            "config": cfg,
            "formats": list(formats),
            "code": code,
            "matplotlib": importlib.metadata.version("matplotlib"),
        },
        sort_keys=True,
        default=str,
    )
    return hashlib.sha256(blob.encode()).hexdigest()


def _up_to_date(fig_dir: Path, digest: str) -> list[Path] | None:
    """The figure files of ``fig_dir`` when the stamp records ``digest`` and they all exist."""
    try:
        stamp = json.loads((fig_dir.parent / STAMP).read_text())
        names = list(stamp["files"])
        if stamp["inputs"] != digest:
            return None
    except (OSError, ValueError, KeyError, TypeError):
        return None
    paths = [fig_dir / n for n in names]
    return paths if all(p.is_file() for p in paths) else None


def write_figures(out_dir: str | Path, *, formats=None, force: bool = False) -> list[Path]:
    """Draw every figure the results support; returns the paths of the figure files.

    Figures are drawn only when their inputs (:func:`figure_inputs`) changed since they were
    last drawn (``.figures.json``), or with ``force``; ``formats`` (default: the
    folder's ``figures.formats``, PNG) names the files per figure.
    """
    res = load_results(out_dir)
    out = res["dir"]
    cfg = res["config"]
    formats = list(formats or (cfg.get("figures") or {}).get("formats") or ["png"])
    fig_dir = out / "figures"
    digest = figure_inputs(res, formats)
    if not force:
        kept = _up_to_date(fig_dir, digest)
        if kept is not None:
            return kept
    # a damaged unit is reported before anything of the folder changes
    cache = UnitCache(out)
    for rec in res["units"]:
        if not cache.arrays_readable(rec["key"]):
            cache.load_arrays(rec["key"], strict=True)  # raises, naming the file
    (out / STAMP).unlink(missing_ok=True)  # figures being redrawn belong to no inputs
    written = _draw(res, formats)
    atomic_write_bytes(
        out / STAMP,
        json.dumps({"inputs": digest, "files": [p.name for p in written]}, indent=1).encode(),
    )
    return written


def _draw(res: dict, formats: list[str]) -> list[Path]:
    from simlunar.plotting import figures as F

    out = res["dir"]
    cfg = res["config"]
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
        from simlunar.results import lidar_figures, scanner_figures

        lidar = study.get("kind") == "lidar"
        (lidar_figures.lidar_figures if lidar else scanner_figures.scanner_figures)(
            res, emit, captions
        )
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

    groups = aggregate.density_panels(units)[:MAX_UNIT_PANELS]
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
            spacing_m=_spacing(rec),
        )
        emit(fig, f"panels_unit{rec.get('index', 0)}")
        captions[f"panels_unit{rec.get('index', 0)}"] = captions_text.panels(
            label, _label(rec), metres=_spacing(rec) is not None
        )

    for rec, arr in zip(shown, shown_arrays):
        if "sparse_mesh_render" not in arr or "radiance" not in arr:
            continue
        fig_cfg = rec.get("config", {}).get("figures") or {}
        dens = fig_cfg.get("sparse_mesh_density")
        n = round(dens * arr["radiance"].size) if dens else None
        fig, _ = F.sparse_mesh_panels(
            arr["sparse_mesh_render"],
            arr["radiance"],
            arr.get("wavelet_energy"),
            rough=arr.get("sparse_mesh_render_rough"),
            n_samples=n,
            point=_label(rec) if len(units) > 1 else "",
            spacing_m=_spacing(rec),
        )
        emit(fig, f"sparse_mesh_unit{rec.get('index', 0)}")
        captions[f"sparse_mesh_unit{rec.get('index', 0)}"] = captions_text.sparse_mesh(
            n,
            "sparse_mesh_render_rough" in arr,
            threshold=fig_cfg.get("sparse_mesh_roughness_threshold"),
        )

    _samples_saved_figures(res, emit, captions)
    _score_figures(res, emit, captions)
    write_captions(fig_dir, captions, written)
    return written


def _score_figures(res: dict, emit, captions: dict[str, str]) -> None:
    """``score_vs_<axis>_<metric>`` of a one-axis sweep: each point's pooled score with its
    95 % interval, as ``scores.csv`` holds them (none without random: no scores)."""
    from simlunar.plotting import figures as F
    from simlunar.plotting.style import axis_name

    cfg = res["config"]
    study = cfg.get("study", {})
    sweep = {k: v for k, v in (cfg.get("sweep") or {}).items() if k != SEED_AXIS}
    path_csv = res["dir"] / "scores.csv"
    if len(sweep) != 1 or not path_csv.is_file():
        return
    (path,) = sweep
    groups = group_points(res["units"])
    if len(groups) < 2:
        return
    # scores.csv lists the points in results order (the order of group_points); matched by
    # position, since a label may spell a model's keys in another order than the records do
    cells: dict[tuple[int, str, str], tuple] = {}
    order: dict[str, int] = {}
    for r in read_csv(path_csv):
        if r.get("terrain_seed") == "all":
            i = order.setdefault(r["point"], len(order))
            cells[(i, r["metric"], r["strategy"])] = tuple(
                float(r[c]) if r[c] not in ("", None) else None
                for c in ("score", "ci_low", "ci_high")
            )
    if len(order) != len(groups):
        return
    strategies = list(study.get("strategies") or [])
    axis = path.rsplit(".", 1)[-1]
    for m in study.get("metrics") or []:
        points = []
        for i, p in enumerate(groups):
            scores = {s: cells[(i, m, s)] for s in strategies if (i, m, s) in cells}
            points.append((aggregate.sweep_value({"sweep": p.sweep}, path), {m: scores}))
        if not any(sc[m] for _, sc in points):
            continue
        fig, _ = F.score_vs_sweep(
            points, metric=m, strategies=strategies, axis_label=axis_name(path)
        )
        emit(fig, f"score_vs_{axis}_{m}")
        seeds = max(len(p.unit_indices) for p in groups)
        captions[f"score_vs_{axis}_{m}"] = captions_text.score_vs_sweep(m, path, study, seeds=seeds)


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


def write_figures_pruned(out_dir: str | Path, *, formats=None, force: bool = False) -> list[Path]:
    """:func:`write_figures`, then remove the figures of ``figures/`` it did not write."""

    written = write_figures(out_dir, formats=formats, force=force)
    prune_figures(Path(out_dir), keep=written)
    return written


def _samples_saved_figures(res: dict, emit, captions: dict[str, str]) -> None:
    """``samples_saved``: per sweep point (pooled over terrain seeds), one panel per reference
    (random, grid), the first metric; ``samples_saved_point<i>`` when there are several."""
    from simlunar.plotting import figures as F
    from simlunar.plotting.style import point_title

    points = aggregate.summarise(res["units"], res["rows"], seed=0, n_boot=10)
    points = [p for p in points if p.saved][:MAX_UNIT_PANELS]
    for i, p in enumerate(points):
        fig, axes = F.panel_row(len(p.saved), width=2.9 * len(p.saved) + 0.3, height=2.5)
        for ax, (ref, sv) in zip(axes, p.saved.items()):
            F.samples_saved_plot(
                p.densities,
                sv.factor,
                sv.flag,
                reference=ref,
                metric=p.saved_metric,
                strategies=p.strategies,
                ax=ax,
            )
        F.shared_legend(fig, axes, prune_labels=False, union=True)
        title = point_title(p.sweep)
        if len(points) > 1 and title:
            fig.suptitle(title, fontsize=8)
        stem = "samples_saved" if len(points) == 1 else f"samples_saved_point{i}"
        emit(fig, stem)
        captions[stem] = captions_text.samples_saved(p.saved_metric, list(p.saved), title)
