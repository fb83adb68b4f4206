"""The figures of a sampling-study result folder (paper section 4): error against sampling
density per metric (one panel per sweep point, its terrain seeds pooled), the image panels and
sparse-mesh renders of the first units, the samples saved against each reference and, for a
one-axis sweep, the score against the swept value."""

from __future__ import annotations

from simlunar.planner import DEFAULT_PLANNER
from simlunar.plotting import figures as F
from simlunar.plotting.forest import saved_forest_plot
from simlunar.plotting.reconstructions import category_labels, reconstruction_saved_vs_sweep
from simlunar.plotting.style import axis_name, point_title
from simlunar.plotting.tables import seed_summary_numbers
from simlunar.results import aggregate
from simlunar.results import captions as captions_text
from simlunar.results.aggregate import SEED_AXIS, group_points
from simlunar.results.store import UnitCache, read_csv

__all__ = ["MAX_UNIT_PANELS", "sampling_figures"]

#: at most this many panels (sweep points, units) per figure, and units with figures of their own
MAX_UNIT_PANELS = 6


def sampling_figures(res: dict, emit, captions: dict[str, str]) -> None:
    """Draw the sampling figures through ``emit(fig, stem)``; captions into ``captions``."""
    units = res["units"]
    shown = units[:MAX_UNIT_PANELS]
    cache = UnitCache(res["dir"])
    # each .npz read once, before any figure is written; a corrupt one is an error naming it,
    # not a silently missing panel
    shown_arrays = [cache.load_arrays(rec["key"], strict=True) for rec in shown]
    _error_vs_density_figures(res, emit, captions)
    titled = len(units) > 1
    for rec, arr in zip(shown, shown_arrays):
        _image_panels(rec, arr, emit, captions, titled=titled)
    for rec, arr in zip(shown, shown_arrays):
        _sparse_mesh_panels(rec, arr, emit, captions, titled=titled)
    points = aggregate.summarise(res["units"], res["rows"], seed=0, n_boot=10)
    # the per-point figures draw the first reconstruction (linear's by default); the others
    # are compared with linear in reconstruction_saved_vs_<axis> and the tables
    first = aggregate.reconstruction_names(res["config"].get("study") or {})[0]
    firsts = [p for p in points if p.reconstruction == first]
    _samples_saved_figures(firsts, emit, captions)
    _headroom_figure(firsts, emit, captions)
    _forest_figure(firsts, emit, captions)
    _score_figures(res, emit, captions)
    _reconstruction_figure(res, points, emit, captions)


def _label(rec: dict) -> str:
    """Title of one unit: its sweep point (:func:`simlunar.plotting.style.point_title`) and,
    when the experiment repeats terrains, its terrain seed."""
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


def _error_vs_density_figures(res: dict, emit, captions: dict[str, str]) -> None:
    """``error_vs_density_<metric>``: one panel per sweep point, its units pooled."""
    study = res["config"].get("study", {})
    strategies = list(study.get("strategies") or [])
    units = res["units"]
    groups = aggregate.density_panels(units)[:MAX_UNIT_PANELS]
    pooled = any(len(members) > 1 for _, members in groups)
    # the first configured reconstruction's curves (linear's by default; the others are
    # compared with linear in the reconstruction tables and figure)
    first = aggregate.reconstruction_names(study)[0]
    only = {"reconstruction": first} if res["rows"] and "reconstruction" in res["rows"][0] else {}
    for m in study.get("metrics") or []:
        fig, axes = F.panel_grid(len(groups))
        for ax, (title, members) in zip(axes, groups):
            F.error_vs_density(
                res["rows"],
                metric=m,
                strategies=strategies,
                ax=ax,
                where={"unit": [rec.get("index", 0) for rec in members], **only},
                title=title if len(units) > 1 else None,
                band_label=F.BAND_LABEL_SEEDS if pooled else F.BAND_LABEL,
            )
        if len(axes) > 1:
            F.shared_legend(fig, axes)
        emit(fig, f"error_vs_density_{m}")
        captions[f"error_vs_density_{m}"] = captions_text.error_vs_density(
            m, study, len(groups), seeds=max(len(members) for _, members in groups)
        )


def _image_panels(rec: dict, arr: dict, emit, captions: dict[str, str], *, titled: bool) -> None:
    """``panels_unit<i>``: guide image, importance, plan, reconstruction and depth of a unit."""
    if not {"image", "wavelet_energy", "plan_rows", "reconstruction", "depth"} <= set(arr):
        return
    density = (rec.get("config", {}).get("figures") or {}).get("panel_density")
    label = f"k/N = 1/{round(1 / density)}" if density else ""
    fig, _ = F.image_panels(
        arr["image"],
        arr["wavelet_energy"],
        (arr["plan_rows"], arr["plan_cols"]),
        arr["reconstruction"],
        arr["depth"],
        text=F.PanelText(label, DEFAULT_PLANNER, _label(rec) if titled else ""),
        spacing_m=_spacing(rec),
    )
    stem = f"panels_unit{rec.get('index', 0)}"
    emit(fig, stem)
    captions[stem] = captions_text.panels(label, _label(rec), metres=_spacing(rec) is not None)


def _sparse_mesh_panels(
    rec: dict, arr: dict, emit, captions: dict[str, str], *, titled: bool
) -> None:
    """``sparse_mesh_unit<i>``: the render of a unit's sparse mesh beside its radiance."""
    if "sparse_mesh_render" not in arr or "radiance" not in arr:
        return
    fig_cfg = rec.get("config", {}).get("figures") or {}
    dens = fig_cfg.get("sparse_mesh_density")
    n = round(dens * arr["radiance"].size) if dens else None
    fig, _ = F.sparse_mesh_panels(
        arr["sparse_mesh_render"],
        arr["radiance"],
        arr.get("wavelet_energy"),
        rough=arr.get("sparse_mesh_render_rough"),
        n_samples=n,
        point=_label(rec) if titled else "",
        spacing_m=_spacing(rec),
    )
    stem = f"sparse_mesh_unit{rec.get('index', 0)}"
    emit(fig, stem)
    captions[stem] = captions_text.sparse_mesh(
        n,
        "sparse_mesh_render_rough" in arr,
        threshold=fig_cfg.get("sparse_mesh_roughness_threshold"),
        light=((rec.get("config", {}).get("render") or {}).get("light") or {}).get("kind", "sun"),
    )


def _samples_saved_figures(points: list, emit, captions: dict[str, str]) -> None:
    """``samples_saved``: per sweep point (pooled over terrain seeds), one panel per reference
    (random, grid), the first metric; ``samples_saved_point<i>`` when there are several."""
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


def _reconstruction_figure(res: dict, points: list, emit, captions: dict[str, str]) -> None:
    """``reconstruction_saved_vs_<axis>`` of a one-axis sweep with reconstructions besides
    linear: the samples each saves over linear on the same layout, against the swept value
    (e.g. the sun elevation), one panel per strategy."""
    sweep = {k: v for k, v in (res["config"].get("sweep") or {}).items() if k != SEED_AXIS}
    if len(sweep) != 1:
        return
    entries = aggregate.reconstruction_saved_entries(points, res["rows"])
    if len(entries) < 2:
        return
    (path,) = sweep
    recons = list(dict.fromkeys(r for e in entries for r in e["reconstructions"]))
    xs = category_labels([e["sweep"][path] for e in entries])
    series = []
    for x, e in zip(xs, entries):
        saved = {r: {s: seed_summary_numbers(v, log=True)[:3] for s, v in by.items()}
                 for r, by in e["saved"].items()}  # fmt: skip
        series.append(("preset default" if x is None else x, saved))
    fig, _ = reconstruction_saved_vs_sweep(
        series,
        strategies=entries[0]["strategies"],
        reconstructions=recons,
        metric=entries[0]["metric"],
        axis_label=axis_name(path),
    )
    axis = path.rsplit(".", 1)[-1]
    stem = f"reconstruction_saved_vs_{axis}"
    emit(fig, stem)
    seeds = max(len(e["seeds"]) for e in entries)
    captions[stem] = captions_text.reconstruction_saved(
        entries[0]["metric"], axis_name(path), seeds, recons
    )


def _headroom_figure(points: list, emit, captions: dict[str, str]) -> None:
    """``headroom``: each strategy's headroom captured (vs uniform Lloyd, of each oracle), one
    panel per sweep point and oracle; drawn when the study has an oracle and uniform Lloyd."""
    entries = aggregate.headroom_entries(points)[:MAX_UNIT_PANELS]
    if not entries:
        return
    emit(F.headroom_plot(entries), "headroom")
    captions["headroom"] = captions_text.headroom(entries[0]["metric"], len(entries[0]["seeds"]))


def _forest_figure(points: list, emit, captions: dict[str, str]) -> None:
    """``samples_saved_forest``: each planner's samples saved vs uniform Lloyd with its 95 %
    interval over terrain seeds, one panel per sweep point; drawn when the study has the
    uniform layout (the figure of the headroom and paired samples-saved tables)."""
    entries = [
        {"label": p.label if len(points) > 1 else "", "metric": p.saved_metric,
         "strategies": [s for s in p.strategies if s != aggregate.HEADROOM_REFERENCE],
         "saved": p.saved_per_seed, "seeds": p.seeds}
        for p in points
        if p.saved_per_seed
    ][:MAX_UNIT_PANELS]  # fmt: skip
    try:
        fig = saved_forest_plot(entries)
    except ValueError:  # no planner with a finite saving (or no uniform layout)
        return
    emit(fig, "samples_saved_forest")
    captions["samples_saved_forest"] = captions_text.saved_forest(
        entries[0]["metric"], len(entries[0]["seeds"])
    )


def _score_figures(res: dict, emit, captions: dict[str, str]) -> None:
    """``score_vs_<axis>_<metric>`` of a one-axis sweep: each point's pooled score with its
    95 % interval, as ``scores.csv`` holds them (none without random: no scores)."""
    cfg = res["config"]
    study = cfg.get("study", {})
    sweep = {k: v for k, v in (cfg.get("sweep") or {}).items() if k != SEED_AXIS}
    path_csv = res["dir"] / "scores.csv"
    if len(sweep) != 1 or not path_csv.is_file():
        return
    (path,) = sweep
    # the first reconstruction's scores (linear's by default), as the error curves
    first = aggregate.reconstruction_names(study)[0]
    groups = [p for p in group_points(res["units"]) if p.reconstruction == first]
    if len(groups) < 2:
        return
    # scores.csv lists the points in results order (the order of group_points); matched by
    # position, since a label may spell a model's keys in another order than the records do
    cells: dict[tuple[int, str, str], tuple] = {}
    order: dict[str, int] = {}
    for r in read_csv(path_csv):
        if r.get("terrain_seed") == "all" and (r.get("reconstruction") or first) == first:
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
