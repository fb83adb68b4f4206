"""The figures of a sampling-study result folder (paper section 4): error against sampling
density per metric (one panel per sweep point, its terrain seeds pooled; one curve per planner
and reconstruction), the image panels, the reconstruction panels (every reconstruction of one
plan of the study's planner beside the truth) and sparse-mesh renders of the first units, the
samples saved against each reference, the samples each reconstruction saves over linear (any
sweep shape) and, for a one-axis sweep, the score against the swept value.

A figure with nothing to show (no reference planner beside another, one reconstruction
only, units computed before the reconstruction panels existed) is not drawn; the reason goes
to ``captions.not_drawn`` (``figures/not_drawn.md`` and the report)."""

from __future__ import annotations

from simlunar.planner import DEFAULT_PLANNER
from simlunar.plotting import figures as F
from simlunar.plotting.forest import saved_forest_plot
from simlunar.plotting.reconstructions import (
    category_labels,
    reconstruction_panels,
    reconstruction_saved_by_planner,
    reconstruction_saved_vs_sweep,
)
from simlunar.plotting.style import axis_name, label, point_title
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
    study = res["config"].get("study") or {}
    for rec, arr in zip(shown, shown_arrays):
        _image_panels(rec, arr, emit, captions, titled=titled, study=study)
    for rec, arr in zip(shown, shown_arrays):
        _reconstruction_panels(rec, arr, emit, captions, titled=titled, study=study)
    for rec, arr in zip(shown, shown_arrays):
        _sparse_mesh_panels(rec, arr, emit, captions, titled=titled)
    points = aggregate.summarise(res["units"], res["rows"], seed=0, n_boot=10)
    # the samples saved between planners, the headroom and the forest compare planners on the
    # first reconstruction (linear's by default); the reconstructions are compared with
    # linear on each layout in reconstruction_saved* and the tables
    first = aggregate.reconstruction_names(study)[0]
    firsts = [p for p in points if p.reconstruction == first]
    _samples_saved_figures(firsts, emit, captions, first=first)
    named = first if len(aggregate.reconstruction_names(study)) > 1 else None
    _headroom_figure(firsts, emit, captions, reconstruction=named)
    _forest_figure(firsts, emit, captions, reconstruction=named)
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
    """``error_vs_density_<metric>``: one panel per sweep point, its units pooled; one curve
    per planner and reconstruction (line style by reconstruction)."""
    study = res["config"].get("study", {})
    strategies = list(study.get("strategies") or [])
    units = res["units"]
    groups = aggregate.density_panels(units)[:MAX_UNIT_PANELS]
    pooled = any(len(members) > 1 for _, members in groups)
    recons = aggregate.reconstruction_names(study)
    by_recon = len(recons) > 1 and bool(res["rows"]) and "reconstruction" in res["rows"][0]
    for m in study.get("metrics") or []:
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
                reconstructions=recons if by_recon else None,
            )
        if len(axes) > 1:
            F.shared_legend(fig, axes)
        emit(fig, f"error_vs_density_{m}")
        captions[f"error_vs_density_{m}"] = captions_text.error_vs_density(
            m,
            study,
            len(groups),
            seeds=max(len(members) for _, members in groups),
            reconstructions=recons if by_recon else recons[:1],
        )


def _image_panels(
    rec: dict, arr: dict, emit, captions: dict[str, str], *, titled: bool, study: dict
) -> None:
    """``panels_unit<i>``: guide image, wavelet energy, the wavelet plan, its linear
    reconstruction and depth of a unit; drawn when the study ran the wavelet planner (the
    plan these panels show), else not drawn (the reconstruction panels show the study's
    planner)."""
    if not {"image", "wavelet_energy", "plan_rows", "reconstruction", "depth"} <= set(arr):
        return
    stem = f"panels_unit{rec.get('index', 0)}"
    if DEFAULT_PLANNER not in (study.get("strategies") or []):
        captions.skip(stem, f"the study ran no {label(DEFAULT_PLANNER)} planner, the plan "
                      f"these panels show; recon_panels_unit{rec.get('index', 0)} shows the "
                      "plan of a planner the study ran")  # fmt: skip
        return
    density = (rec.get("config", {}).get("figures") or {}).get("panel_density")
    dlabel = f"k/N = 1/{round(1 / density)}" if density else ""
    fig, _ = F.image_panels(
        arr["image"],
        arr["wavelet_energy"],
        (arr["plan_rows"], arr["plan_cols"]),
        arr["reconstruction"],
        arr["depth"],
        text=F.PanelText(dlabel, DEFAULT_PLANNER, _label(rec) if titled else ""),
        spacing_m=_spacing(rec),
    )
    emit(fig, stem)
    captions[stem] = captions_text.panels(dlabel, _label(rec), metres=_spacing(rec) is not None)


def _reconstruction_panels(
    rec: dict, arr: dict, emit, captions: dict[str, str], *, titled: bool, study: dict
) -> None:
    """``recon_panels_unit<i>``: one plan of the study's planner reconstructed by every
    configured reconstruction, beside the truth, and their error maps."""
    stem = f"recon_panels_unit{rec.get('index', 0)}"
    meta = (rec.get("meta") or {}).get("recon_panels")
    panels = f"panels_unit{rec.get('index', 0)}"
    if len(aggregate.reconstruction_names(study)) < 2 and panels not in captions.not_drawn:
        captions.skip(stem, f"the study ran one reconstruction, which {panels} shows")
        return
    if not meta:
        captions.skip(stem, "this unit was computed without the reconstruction panels' arrays "
                      "(an earlier simlunar, or a study with no planner that plans without the "
                      "truth); rerun into a fresh folder to draw them")  # fmt: skip
        return
    names = list(meta["reconstructions"])
    grids = {n: arr.get(f"recon_panel_{i}") for i, n in enumerate(names)}
    if any(g is None for g in grids.values()) or "depth" not in arr or "image" not in arr:
        captions.skip(stem, "the unit's arrays lack a reconstruction of the panels' plan")
        return
    dlabel = f"k/N = 1/{round(1 / meta['density'])}" if meta.get("density") else ""
    light = ((rec.get("config") or {}).get("render") or {}).get("light")
    fig, _ = reconstruction_panels(
        arr["image"],
        arr["depth"],
        grids,
        (arr["recon_panel_rows"], arr["recon_panel_cols"]),
        planner=meta["planner"],
        density_label=dlabel,
        point=_label(rec) if titled else "",
        spacing_m=_spacing(rec),
    )
    emit(fig, stem)
    captions[stem] = captions_text.reconstruction_panels(
        names, meta["planner"], int(meta["k"]), dlabel, _label(rec),
        metres=_spacing(rec) is not None, frames=(rec.get("meta") or {}).get("guide_frames"),
        light=point_title({"render.light": light}) if light else "",
    )  # fmt: skip


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


def _samples_saved_figures(points: list, emit, captions: dict[str, str], *, first: str) -> None:
    """``samples_saved``: per sweep point (pooled over terrain seeds), one panel per reference
    (random, grid, uniform Lloyd) with another planner beside it, the first metric;
    ``samples_saved_point<i>`` when there are several; not drawn when no point has a
    reference and another planner (a study of one planner)."""
    shown = []
    for p in points:
        refs = {ref: sv for ref, sv in p.saved.items()
                if any(s != ref and s in sv.factor for s in p.strategies)}  # fmt: skip
        if refs:
            shown.append((p, refs))
    shown = shown[:MAX_UNIT_PANELS]
    if not shown:
        planners = "; ".join(label(s) for s in (points[0].strategies if points else []))
        captions.skip("samples_saved", f"no reference planner (Random, Grid or Uniform Lloyd) "
                      f"ran beside another planner (the study's planners: {planners or 'none'}), "
                      f"so no planner's samples saved can be drawn; reconstruction_saved* "
                      f"compares the reconstructions on the same layout")  # fmt: skip
        return
    for i, (p, refs) in enumerate(shown):
        fig, axes = F.panel_row(len(refs), width=2.9 * len(refs) + 0.3, height=2.5)
        for ax, (ref, sv) in zip(axes, refs.items()):
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
        if len(shown) > 1 and title:
            fig.suptitle(title, fontsize=8)
        stem = "samples_saved" if len(shown) == 1 else f"samples_saved_point{i}"
        emit(fig, stem)
        captions[stem] = captions_text.samples_saved(
            p.saved_metric, list(refs), title, reconstruction=first
        )


def _reconstruction_figure(res: dict, points: list, emit, captions: dict[str, str]) -> None:
    """The samples each reconstruction saves over linear on the same layout, one panel per
    strategy: ``reconstruction_saved_vs_<axis>`` against the swept value of a one-axis sweep
    with two or more points (e.g. the sun elevation), else ``reconstruction_saved`` with one
    position per sweep point (one point: one position). Not drawn with linear alone."""
    study = res["config"].get("study") or {}
    recons = aggregate.reconstruction_names(study)
    entries = aggregate.reconstruction_saved_entries(points, res["rows"])
    if not entries:
        why = (
            "the study ran one reconstruction"
            if len(recons) < 2
            else "linear is not among the reconstructions, or fewer than two densities ran"
            if aggregate.BASELINE_RECONSTRUCTION not in recons or len(points[0].ks) < 2
            else "no point has a reconstruction besides linear with a finite comparison"
        )
        captions.skip("reconstruction_saved", f"{why}: nothing to compare with Delaunay-linear")
        return
    sweep = {k: v for k, v in (res["config"].get("sweep") or {}).items() if k != SEED_AXIS}
    recon_list = list(dict.fromkeys(r for e in entries for r in e["reconstructions"]))
    if len(sweep) == 1 and len(entries) >= 2:
        (path,) = sweep
        xs = category_labels([e["sweep"][path] for e in entries])
        xs = ["preset default" if x is None else x for x in xs]
        axis_label, axis = axis_name(path), path.rsplit(".", 1)[-1]
        stem = f"reconstruction_saved_vs_{axis}"
    else:  # any other shape, one point included: a position per sweep point
        xs = [point_title(e["sweep"]) or "this study" for e in entries]
        axis_label = "sweep point" if len(entries) > 1 else ""
        stem = "reconstruction_saved"
    series = []
    for x, e in zip(xs, entries):
        saved = {r: {s: seed_summary_numbers(v, log=True)[:3] for s, v in by.items()}
                 for r, by in e["saved"].items()}  # fmt: skip
        series.append((x, saved))
    if len(entries) == 1:  # one point: the planners along x, a marker per reconstruction
        fig, _ = reconstruction_saved_by_planner(
            series[0][1],
            strategies=entries[0]["strategies"],
            reconstructions=recon_list,
            metric=entries[0]["metric"],
            title=point_title(entries[0]["sweep"]),
        )
    else:
        fig, _ = reconstruction_saved_vs_sweep(
            series,
            strategies=entries[0]["strategies"],
            reconstructions=recon_list,
            metric=entries[0]["metric"],
            axis_label=axis_label,
        )
    emit(fig, stem)
    seeds = max(len(e["seeds"]) for e in entries)
    captions[stem] = captions_text.reconstruction_saved(
        entries[0]["metric"], axis_label if len(entries) > 1 else None, seeds, recon_list
    )


def _headroom_figure(
    points: list, emit, captions: dict[str, str], *, reconstruction: str | None = None
) -> None:
    """``headroom``: each strategy's headroom captured (vs uniform Lloyd, of each oracle), one
    panel per sweep point and oracle; drawn when the study has an oracle and uniform Lloyd."""
    entries = aggregate.headroom_entries(points)[:MAX_UNIT_PANELS]
    if not entries:
        return
    emit(F.headroom_plot(entries), "headroom")
    captions["headroom"] = captions_text.headroom(
        entries[0]["metric"], len(entries[0]["seeds"]), reconstruction=reconstruction
    )


def _forest_figure(
    points: list, emit, captions: dict[str, str], *, reconstruction: str | None = None
) -> None:
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
        if entries:  # the uniform layout ran, but nothing beside it can be compared
            captions.skip("samples_saved_forest", f"no planner besides "
                          f"{label(aggregate.HEADROOM_REFERENCE)} has a finite samples saved "
                          "against it (the study's other planners: "
                          f"{'; '.join(label(s) for s in entries[0]['strategies']) or 'none'})")  # fmt: skip
        return
    emit(fig, "samples_saved_forest")
    captions["samples_saved_forest"] = captions_text.saved_forest(
        entries[0]["metric"], len(entries[0]["seeds"]), reconstruction=reconstruction
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
