"""The figures of a LIDAR-study result folder: error against modelled scan time and against
the range samples measured, one curve per planner (docs/lidar.md)."""

from __future__ import annotations

from simlunar.plotting.layout import panel_grid
from simlunar.plotting.lidar import error_vs_time
from simlunar.results import captions as captions_text
from simlunar.results.aggregate import density_panels, first_reconstruction_rows

__all__ = ["lidar_figures"]

#: at most this many panels (sweep points) per figure
MAX_PANELS = 6


def lidar_figures(res: dict, emit, captions: dict) -> None:
    """``lidar_error_vs_time_<metric>`` and ``lidar_error_vs_samples_<metric>``: one panel per
    sweep point (its terrain seeds pooled into the interval), or, when the one swept key is a
    sensor option that changes each acquisition's cost (a flash's revisits), one panel whose
    curves run over its values. The first configured reconstruction's rows (linear's by
    default)."""
    res = {**res, "rows": first_reconstruction_rows(res)}
    study = res["config"].get("study", {})
    sweep = list(res["config"].get("sweep") or {})
    by = sweep[0] if len(sweep) == 1 and sweep[0].startswith("study.options.") else None
    groups = [("", res["units"])] if by else density_panels(res["units"])[:MAX_PANELS]
    seeds = max(len(members) for _, members in groups)
    if by:
        seeds = max(1, int(study.get("terrain_seeds", 1) or 1))
    for m in study.get("metrics") or []:
        for x, name in (("seconds", "time"), ("samples", "samples")):
            fig, axes = panel_grid(len(groups))
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
