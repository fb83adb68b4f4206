"""Landing-site figures: hazard recall per sensor and hazard size (one panel per light), recall
against scan time and laser energy (what each sensor buys with its time and energy) and a
hazard-map panel (truth beside each sensor's reconstruction) (docs/landing.md)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.lines import Line2D

from simlunar.plotting.landing_tables import landing_summary

__all__ = ["hazard_map_panel", "landing_cost", "landing_recall"]


def _label(metric: str) -> str:
    if metric == "false_safe_site":
        return "false-safe site"
    kind, _, rest = metric.removeprefix("hazard_").partition("_")
    what, _, size = rest.partition("_")
    return f"{what} {size} {kind}"


def landing_recall(
    rows: Sequence[dict],
    *,
    sensor_key: str,
    light_key: str | None,
    reconstruction: str = "linear",
    title: str = "",
):
    """Grouped bars: per (sensor, planner) the mean rock recall per size, slope recall and the
    false-safe rate of the chosen site, with their 95 % intervals over terrain seeds; one panel
    per light (``light_key`` values). A black diamond on a recall bar is the mean precision of
    that hazard (a recall made of false alarms reads as such); a false-safe bar of a group
    that called no site safe on any seed is replaced by "no safe site" (its 0 would say
    nothing). Returns the figure."""
    keys = [sensor_key] + ([light_key] if light_key else [])
    summary = {g: c for g, c in landing_summary(rows, keys=keys).items()
               if g[len(keys)] == reconstruction}  # fmt: skip
    recalls = sorted({m for c in summary.values() for m in c if m.startswith("hazard_recall_")})
    metrics = [*recalls, "false_safe_site"]
    lights = sorted({g[1] for g in summary}, key=float) if light_key else [""]
    groups = sorted({(g[0], g[-1]) for g in summary})
    # one row per light, the groups along x: as wide as the groups need, within a page's reach
    wide = min(16.0, max(5.0, 0.75 * len(groups) + 1.5))
    tall = 3.0 * len(lights) + 1.6
    fig, axes = plt.subplots(len(lights), 1, figsize=(wide, tall), squeeze=False, sharex=True)
    width = 0.8 / len(metrics)
    colours = plt.get_cmap("tab10")
    for ax, light in zip(axes[:, 0], lights, strict=True):
        x = np.arange(len(groups))
        cells = [summary.get((s, light, reconstruction, pl) if light_key else
                             (s, reconstruction, pl), {}) for s, pl in groups]  # fmt: skip
        for j, m in enumerate(metrics):
            xs = x + (j - (len(metrics) - 1) / 2) * width
            vals, err = [], [[], []]
            for xi, c in zip(xs, cells, strict=True):
                mean, lo, hi = c.get(m, (np.nan, np.nan, np.nan))
                if m == "false_safe_site" and _never_safe(c):
                    mean = lo = hi = np.nan  # no site called safe: no false-safe rate
                    ax.text(xi, 0.02, "no safe site", rotation=90, ha="center", va="bottom",
                            fontsize=6, color=colours(j))  # fmt: skip
                vals.append(mean)
                err[0].append(mean - lo)
                err[1].append(hi - mean)
            ax.bar(xs, vals, width, yerr=err, capsize=2, color=colours(j), label=_label(m))
            if m.startswith("hazard_recall_"):
                prec = m.replace("hazard_recall_", "hazard_precision_")
                p = [_mean(c, prec) for c in cells]
                if np.isfinite(p).any():
                    ax.plot(xs, p, "D", color="black", ms=3, ls="none",
                            label="precision of that hazard" if j == 0 else None)  # fmt: skip
        ax.set_xticks(x, [f"{s.replace('_', ' ')}\n{p}" for s, p in groups], fontsize=7,
                      rotation=30, ha="right")  # fmt: skip
        ax.set_ylim(0, 1.05)
        ax.set_title(f"sun {light} deg" if light_key else "", fontsize=9)
        ax.grid(axis="y", alpha=0.3)
    for ax in axes[:, 0]:
        ax.set_ylabel("recall / rate")
    fig.suptitle(f"{title}\nbars: mean over terrain seeds; whiskers: 95 % interval over the seeds; "
                 "diamonds: mean precision", fontsize=10)  # fmt: skip
    handles, labels = axes[0][0].get_legend_handles_labels()
    # the bars' metrics in their order, then the precision marker (matplotlib lists lines first)
    order = sorted(range(len(labels)), key=lambda i: labels[i].startswith("precision"))
    handles, labels = [handles[i] for i in order], [labels[i] for i in order]
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 5), fontsize=8,
               frameon=False)  # fmt: skip
    fig.tight_layout(rect=(0, 0.35 / tall, 1, 1 - 0.55 / tall))
    return fig


def _mean(cells: dict, metric: str) -> float:
    """The mean of ``metric`` in a group's cells (NaN when the group has no such metric)."""
    return cells.get(metric, (np.nan,))[0]


def _never_safe(cells: dict) -> bool:
    """True when the group called no site safe on any seed (``safe_site_called`` = 0)."""
    called = cells.get("safe_site_called")
    return called is not None and called[0] == 0


def landing_cost(
    rows: Sequence[dict],
    *,
    sensor_key: str,
    light_key: str | None,
    metric: str | None = None,
    reconstruction: str = "linear",
    strategies: Mapping[str, str] | None = None,
    title: str = "",
):
    """Recall against cost: per light (a row of panels) the mean ``metric`` (default: the
    smallest rock size's recall) of each (sensor, planner) against its mean scan time (left)
    and mean laser energy (right), both log. Colour: the sensor; marker: the planner's strategy
    (``strategies``: label -> strategy, e.g. a budget-fitted ``wavelet_flash_time`` ->
    ``wavelet``; a label without one is its own), the points of one sensor and strategy joined
    in order of cost (what more time or energy buys it); whiskers: 95 % intervals over terrain
    seeds; dashed with open markers, the same plans' precision of that hazard (a recall bought
    with false alarms shows as one). A point whose energy is not priced (NaN or 0) is left out
    of the energy panel.
    Returns the figure, or None without the metric."""
    strategies = dict(strategies or {})
    keys = [sensor_key] + ([light_key] if light_key else [])
    summary = {g: c for g, c in landing_summary(rows, keys=keys).items()
               if g[len(keys)] == reconstruction}  # fmt: skip
    if metric is None:
        rocks = sorted({m for c in summary.values() for m in c
                        if m.startswith("hazard_recall_rock_")},
                       key=lambda m: float(m.rsplit("_", 1)[-1].removesuffix("cm")))  # fmt: skip
        metric = rocks[0] if rocks else None
    if metric is None or not any(metric in c for c in summary.values()):
        return None
    precision = metric.replace("hazard_recall_", "hazard_precision_")
    lights = sorted({g[1] for g in summary}, key=float) if light_key else [""]
    sensors = sorted({g[0] for g in summary})
    families = sorted({strategies.get(g[-1], g[-1]) for g in summary})
    colours = plt.get_cmap("tab10")
    markers = dict(zip(families, "osD^v<>ph*", strict=False))
    fig, axes = plt.subplots(len(lights), 2, figsize=(9.0, 3.4 * len(lights) + 0.6),
                             squeeze=False, sharey=True)  # fmt: skip
    for row, light in zip(axes, lights, strict=True):
        for ax, cost, xlabel in zip(row, ("seconds", "energy_j"),
                                    ("scan time (s)", "laser energy (J)"), strict=True):  # fmt: skip
            for i, sensor in enumerate(sensors):
                for fam in families:
                    pts = []
                    for g, c in summary.items():
                        if (g[0] != sensor or (light_key and g[1] != light) or metric not in c
                                or strategies.get(g[-1], g[-1]) != fam):  # fmt: skip
                            continue
                        if np.isfinite(c[cost]) and c[cost] > 0:
                            pts.append((c[cost], *c[metric], _mean(c, precision)))
                    if not pts:
                        continue
                    x, mean, lo, hi, prec = (np.array(v) for v in zip(*sorted(pts), strict=True))
                    label = sensor.replace("_", " ") + ("" if fam == "none" else f", {fam}")
                    ax.errorbar(x, mean, yerr=[mean - lo, hi - mean], marker=markers[fam], ms=5,
                                capsize=2, color=colours(i), label=label)  # fmt: skip
                    if np.isfinite(prec).any():  # the same plans' precision: dashed, open
                        ax.plot(x, prec, ls="--", marker=markers[fam], ms=4, mfc="none",
                                color=colours(i), alpha=0.7, gid="precision")  # fmt: skip
            ax.set_xscale("log")
            ax.set_xlabel(xlabel)
            ax.set_ylim(0, 1.05)
            ax.grid(alpha=0.3)
            ax.set_title(f"sun {light} deg" if light_key else "", fontsize=9)
    _cost_labels(fig, axes, title, metric, precision)
    return fig


def _cost_labels(fig, axes, title: str, metric: str, precision: str) -> None:
    """The y labels, title and legend of :func:`landing_cost` (the precision's, where drawn)."""
    drawn = any(ln.get_gid() == "precision" for ax in axes.flat for ln in ax.lines)
    for row in axes:
        row[0].set_ylabel(_label(metric) + (" / precision" if drawn else ""))
    fig.suptitle(f"{title}\npoints: means over terrain seeds; lines: a strategy's plans in order "
                 "of cost; whiskers: 95 % intervals"
                 + ("; dashed, open: the same plans' precision" if drawn else ""),
                 fontsize=9)  # fmt: skip
    handles, labels = axes[0][0].get_legend_handles_labels()
    if drawn:
        handles.append(Line2D([], [], ls="--", marker="o", mfc="none", color="grey"))
        labels.append(_label(precision))
    fig.legend(handles, labels, loc="lower center", ncol=min(max(len(labels), 1), 4), fontsize=8,
               frameon=False)  # fmt: skip
    fig.tight_layout(rect=(0, 0.07, 1, 0.95))


#: the most panels :func:`hazard_map_panel` puts in one row
PANELS_PER_ROW = 7


def hazard_map_panel(image, truth_hazards, found: dict, *, title: str = ""):
    """The guide image, the true hazard map and each reconstruction's (name -> bool map), the
    misses red and the false alarms blue over the found hazards in black; at most
    :data:`PANELS_PER_ROW` panels a row, the rows filled evenly (a full landing unit's 6 plans x
    2 reconstructions were 14 panels in one row, 27 in wide). Returns the figure."""
    n = 2 + len(found)
    rows = -(-n // PANELS_PER_ROW)
    cols = -(-n // rows)
    fig, grid = plt.subplots(rows, cols, figsize=(2.6 * cols, 2.9 * rows), squeeze=False)
    for ax in grid.ravel()[n:]:
        fig.delaxes(ax)
    axes = grid.ravel()[:n]
    axes[0].imshow(np.asarray(image, float), cmap="gray")
    axes[0].set_title("guide image", fontsize=8)
    t = np.asarray(truth_hazards, bool)
    axes[1].imshow(t, cmap="gray_r", vmin=0, vmax=1)
    axes[1].set_title("true hazards", fontsize=8)
    for ax, (name, f) in zip(axes[2:], found.items(), strict=True):
        f = np.asarray(f, bool)
        rgb = np.ones((*t.shape, 3))
        rgb[f & t] = 0.0  # found
        rgb[t & ~f] = (0.85, 0.1, 0.1)  # missed
        rgb[f & ~t] = (0.2, 0.4, 0.9)  # false alarm
        ax.imshow(rgb)
        ax.set_title(name, fontsize=8)
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(title + "  (black found, red missed, blue false alarm)", fontsize=9)
    fig.tight_layout()
    return fig
