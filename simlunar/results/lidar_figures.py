"""The figures of a LIDAR-study result folder: error against modelled scan time and against
the range samples measured, one curve per planner, and a picture of each unit's scan (guide
image, beams in visiting order, measured depths) (docs/lidar.md)."""

from __future__ import annotations

import itertools

from simlunar.plotting.landing import hazard_map_panel, landing_cost, landing_recall
from simlunar.plotting.landing_tables import landing_columns
from simlunar.plotting.layout import panel_grid
from simlunar.plotting.lidar import (
    MAX_SCAN_PLANNERS,
    RowSelection,
    error_vs_time,
    scan_figure,
)
from simlunar.plotting.style import point_title
from simlunar.results import captions as captions_text
from simlunar.results import captions_landing
from simlunar.results.aggregate import (
    density_panels,
    first_reconstruction_rows,
    reconstruction_names,
)
from simlunar.results.store import UnitCache

__all__ = ["hazard_units", "lidar_figures"]

#: at most this many panels (sweep points) per figure
MAX_PANELS = 6


def lidar_figures(res: dict, emit, captions: dict) -> None:
    """``lidar_error_vs_time_<metric>`` and ``lidar_error_vs_samples_<metric>``: one panel per
    sweep point (its terrain seeds pooled into the interval), or, when the one swept key is a
    sensor option that changes each acquisition's cost (a flash's revisits), one panel whose
    curves run over its values. With several reconstructions, a curve per planner and
    reconstruction (line style by reconstruction)."""
    study = res["config"].get("study", {})
    recons = reconstruction_names(study)
    by_recon = len(recons) > 1 and any(r.get("reconstruction") for r in res["rows"])
    if not by_recon:
        res = {**res, "rows": first_reconstruction_rows(res)}
    sweep = list(res["config"].get("sweep") or {})
    by = sweep[0] if len(sweep) == 1 and sweep[0].startswith("study.options.") else None
    groups = [("", res["units"])] if by else density_panels(res["units"])[:MAX_PANELS]
    seeds = max(len(members) for _, members in groups)
    if by:
        seeds = max(1, int(study.get("terrain_seeds", 1) or 1))
    for m in study.get("metrics") or []:
        for x, name in (("seconds", "time"), ("samples", "samples")):
            fig, axes = panel_grid(len(groups), height=3.6)  # room for the legend below
            for ax, (title, members) in zip(axes, groups):
                error_vs_time(
                    res["rows"],
                    metric=m,
                    x=x,
                    planners=study.get("planners"),
                    select=RowSelection(
                        where={"unit": [rec.get("index", 0) for rec in members]}, by=by
                    ),
                    title=title if len(groups) > 1 else "",
                    ax=ax,
                    reconstructions=recons if by_recon else None,
                )
            emit(fig, f"lidar_error_vs_{name}_{m}")
            captions[f"lidar_error_vs_{name}_{m}"] = captions_text.lidar_error(
                m, study, x, len(groups), seeds=seeds, by=by,
                reconstructions=recons if by_recon else None,
            )  # fmt: skip
    _landing_figure(res, emit, captions)
    if "dir" in res:
        _scan_figures(res, emit, captions)
        _hazard_figures(res, emit, captions)


def hazard_units(records: list[dict]) -> list[dict]:
    """The units of the first terrain seed in the order their hazard maps are drawn: sensors
    taken in turn (a sweep's first unit of each sensor, then the second of each, ...), so that
    the first :data:`MAX_PANELS` show every swept sensor, not the first sensor under every
    light."""
    by_sensor: dict[str, list[dict]] = {}
    for rec in records:
        terrain = (rec.get("config") or {}).get("terrain") or {}
        if int(terrain.get("seed_index", 0) or 0) == 0:
            sensor = str((rec.get("sweep") or {}).get("study.sensor", ""))
            by_sensor.setdefault(sensor, []).append(rec)
    turns = itertools.zip_longest(*by_sensor.values())
    return [rec for turn in turns for rec in turn if rec is not None]


def _hazard_figures(res: dict, emit, captions: dict) -> None:
    """``landing_hazards_unit<i>`` of up to :data:`MAX_PANELS` units of the first terrain
    seed that kept hazard maps (every swept sensor first, :func:`hazard_units`): the guide
    image, the true hazards and each planner's and reconstruction's (trial 0, largest
    density)."""
    config = res["config"]
    cache = UnitCache(res["dir"])
    shown = 0
    for rec in hazard_units(res["units"]):
        if shown >= MAX_PANELS:
            break
        arrays = cache.load_arrays(rec["key"], strict=True)
        if "hazards_truth" not in arrays or "image" not in arrays:
            continue
        found = {k[len("hazards_"):].replace("__", ", "): v for k, v in arrays.items()
                 if k.startswith("hazards_") and k != "hazards_truth"}  # fmt: skip
        own = (rec.get("config") or {}).get("study") or config.get("study", {})
        sensor = str(own.get("sensor", "")).replace("_", " ")
        point = point_title(rec.get("sweep") or {})
        swept = "study.sensor" in (rec.get("sweep") or {})
        title = f"{config.get('name', '')}: " + (point if swept else f"{sensor} ({point})")
        fig = hazard_map_panel(arrays["image"], arrays["hazards_truth"], found, title=title)
        stem = f"landing_hazards_unit{rec.get('index', 0)}"
        emit(fig, stem)
        captions[stem] = captions_landing.landing_hazards(own)
        shown += 1


def _landing_figure(res: dict, emit, captions: dict) -> None:
    """``landing_recall`` (with landing scores): per sensor and planner the rock recall per
    size, the slope recall and the false-safe rate, one panel per light; ``landing_cost``: the
    smallest rock's recall against scan time and laser energy (first reconstruction)."""
    rows = res["rows"]
    if not landing_columns(rows):
        return
    config = res["config"]
    study = config.get("study", {})
    sweep = config.get("sweep") or {}
    sensor_key = "study.sensor"
    if sensor_key not in sweep:  # one sensor: its name on every row
        rows = [{**r, sensor_key: study.get("sensor", "steered_beam")} for r in rows]
    light_key = "render.light.elevation_deg" if "render.light.elevation_deg" in sweep else None
    recon = reconstruction_names(study)[0]
    fig = landing_recall(rows, sensor_key=sensor_key, light_key=light_key, reconstruction=recon,
                         title=f"{config.get('name', '')}: landing hazards ({recon})")  # fmt: skip
    emit(fig, "landing_recall")
    captions["landing_recall"] = captions_landing.landing_recall(study, recon)
    labels = {n: (o or {}).get("strategy") for n, o in (study.get("planner_opts") or {}).items()}
    fig = landing_cost(rows, sensor_key=sensor_key, light_key=light_key, reconstruction=recon,
                       strategies={n: s for n, s in labels.items() if s},
                       title=f"{config.get('name', '')}: what time and energy buy ({recon})")  # fmt: skip
    if fig is not None:
        emit(fig, "landing_cost")
        captions["landing_cost"] = captions_landing.landing_cost(study, recon)


def _scan_figures(res: dict, emit, captions: dict) -> None:
    """``lidar_scan_unit<i>`` of the first :data:`MAX_PANELS` units: the guide image, each
    planner's beams in visiting order and what they measured (a unit cached before the beams
    were kept draws none)."""
    config = res["config"]
    study = config.get("study", {})
    cache = UnitCache(res["dir"])
    for rec in res["units"][:MAX_PANELS]:
        arrays = cache.load_arrays(rec["key"], strict=True)
        beams = {k[len("beams_") :]: v for k, v in arrays.items() if k.startswith("beams_")}
        if not beams or "image" not in arrays or "depth" not in arrays:
            continue
        order = [p for p in study.get("planners") or [] if p in beams]
        beams = {p: beams[p] for p in [*order, *[p for p in beams if p not in order]]}
        own = (rec.get("config") or {}).get("study") or study  # a sweep over study.sensor
        sensor = str(own.get("sensor", "steered_beam")).replace("_", " ")
        point = point_title(rec.get("sweep") or {})
        densest = _densest(study)
        at = f", k/N = {_fraction(densest)}, trial 0" if densest else ", trial 0"
        title = f"{config.get('name', '')}: {sensor} scan{at}" + (f" ({point})" if point else "")
        fig = scan_figure(arrays["image"], arrays["depth"], beams, title=title)
        stem = f"lidar_scan_unit{rec.get('index', 0)}"
        emit(fig, stem)
        shown = list(beams)[:MAX_SCAN_PLANNERS]
        captions[stem] = captions_text.lidar_scan(study, shown, densest=densest)


def _fraction(d: float) -> str:
    """``1/16`` for a unit fraction, else ``0.3``."""
    inv = 1.0 / d
    return f"1/{round(inv)}" if abs(inv - round(inv)) < 1e-6 * inv else f"{d:.3g}"


def _densest(study: dict) -> float | None:
    dens = study.get("densities") or []
    try:
        return max(float(d) for d in dens) if dens else None
    except (TypeError, ValueError):
        return None
