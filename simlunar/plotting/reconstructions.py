"""Samples each reconstruction saves over Delaunay-linear, against a sweep axis.

The figure of an ablation with the reconstruction axis (e.g. the sun elevation, or sun vs
camera-centred light): per planner layout (strategy) one panel, per reconstruction one series
of the samples linear needs for its error on the same samples (paired by terrain seed; the
geometric mean over seeds with its 95 % Student t interval, in log space). The shading
method's gain is expected to fall as the sun rises (REFERENCES, 2026-11-28: 1.73x at 30 deg,
1.08x at 60 deg, 1.00x under camera-centred light on aerial_1).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np

from simlunar.metrics import METRIC_NAMES
from simlunar.plotting.density import _category_ticks, _sweep_positions, ratio_axis
from simlunar.plotting.images import (
    DEPTH_CMAP,
    _cbar,
    _extent,
    _metre_labels,
    _panel_height,
    _scatter_samples,
    _show,
)
from simlunar.plotting.layout import (
    LABEL_PT,
    PAGE_W,
    TICK_PT,
    TITLE_PT,
    legend_outside,
    new_axes,
    panel_grid,
    shared_legend,
)
from simlunar.plotting.style import _UNIT_SUFFIXES, _with_unit, label, styles

__all__ = [
    "MAX_PANELS",
    "ROW_PANELS",
    "category_labels",
    "reconstruction_panels",
    "reconstruction_saved_by_planner",
    "reconstruction_saved_vs_sweep",
]

#: most strategy panels of one figure (the first ones in the study's order), in rows of
#: :data:`ROW_PANELS`; a study's planners all fit (a cap of 4 dropped the paper's own wavelet
#: planner, the fifth of ``ablation_light``)
MAX_PANELS = 12
ROW_PANELS = 4


def reconstruction_saved_vs_sweep(
    points: Sequence[tuple[object, dict]],
    *,
    strategies: Sequence[str],
    reconstructions: Sequence[str],
    metric: str = "mse",
    axis_label: str = "",
):
    """Samples saved vs linear against a sweep axis, one panel per strategy.

    Parameters
    ----------
    points : sequence of (x, saved)
        ``x`` a number (lines) or a label (markers per category); ``saved`` maps
        reconstruction -> strategy -> ``(value, low, high)`` (low / high NaN without an
        interval) or a number.
    strategies : the panels (at most :data:`MAX_PANELS`, in order)
    reconstructions : the series
    metric : the metric of the comparison (axis label)
    axis_label : readable name of the sweep axis

    Returns
    -------
    (Figure, list of Axes)
    """
    strategies = list(strategies)[:MAX_PANELS]
    if not strategies or not reconstructions or not points:
        raise ValueError("reconstruction_saved_vs_sweep needs points, strategies and series")
    xs = [p[0] for p in points]
    numeric, pos = _sweep_positions(xs)
    st = styles(reconstructions)
    n = len(reconstructions)
    w = 2.5 if numeric else 3.0  # room for category tick labels
    fig, axes = panel_grid(len(strategies), ncols=ROW_PANELS, panel_w=w, height=2.6)
    values: list[float] = [0.8, 1.25]  # at least 0.8 .. 1.25 in view, 1 (linear) among it
    for ax, s in zip(axes, strategies):
        for i, r in enumerate(reconstructions):
            cells = np.array([_cell(sv.get(r, {}).get(s)) for _, sv in points], float)
            dodge = (i - (n - 1) / 2) * (0.006 * float(np.ptp(pos)) if numeric else 0.1)
            x = pos + dodge
            values += _points_with_interval(ax, x, cells, st[r], capsize=1.5, elinewidth=0.7,
                                            ms=3.5, lw=1.1 if numeric else 0,
                                            ls="-" if numeric else "none")  # fmt: skip
        ax.axhline(1.0, color="k", lw=0.6, ls=":")
        if not numeric:
            _category_ticks(ax, pos, xs)
        ax.tick_params(labelsize=TICK_PT)
        ax.set_title(label(s), fontsize=TITLE_PT)
        ax.set_xlabel(axis_label, fontsize=LABEL_PT)
        ax.set_ylabel(
            f"samples saved vs linear (equal {METRIC_NAMES.get(metric, metric)})",
            fontsize=LABEL_PT,
        )
        ax.grid(True, which="both", alpha=0.3)
        legend_outside(ax)
    for ax in axes:  # one log2 range for every panel, 1 in view, plain-number ticks
        ratio_axis(ax, values)
    shared_legend(fig, axes)
    return fig, axes


def category_labels(values: Sequence) -> list:
    """Short tick labels of sweep values: a model (dict with ``kind``) by its kind and the
    values of only the parameters that differ between the values (``"Sun 30°"``,
    ``"Camera-centred light"``); anything else as it is."""
    dicts = [v for v in values if isinstance(v, dict)]
    varying = [
        k
        for k in dict.fromkeys(k for d in dicts for k in d)
        if k != "kind" and len({repr(d.get(k)) for d in dicts if k in d}) > 1
    ]
    out = []
    for v in values:
        if not isinstance(v, dict):
            out.append(v)
            continue
        parts = []
        for k in varying:
            if k in v and v[k] is not None and not isinstance(v[k], (dict, list)):
                unit = next((u for suf, u in _UNIT_SUFFIXES.items() if k.endswith(suf)), "")
                parts.append(_with_unit(v[k], unit))
        out.append(" ".join([label(str(v.get("kind", ""))), *parts]))
    return out


def _cell(v) -> tuple[float, float, float]:
    if isinstance(v, (tuple, list)):
        return tuple(math.nan if x is None else float(x) for x in v)
    return (math.nan if v is None else float(v), math.nan, math.nan)


def _error_row(fig, axes, errors: Mapping[str, np.ndarray], *, extent) -> None:
    """Each reconstruction's error map (its RMS in the title) on one symmetric scale, at the
    99th percentile of |error| over every map, with one colour bar (m)."""
    lim = float(np.nanpercentile(np.abs(np.stack(list(errors.values()))), 99)) or 1e-12
    for ax, (r, err) in zip(axes, errors.items()):
        rms = float(np.sqrt(np.nanmean(err**2)))
        im = _show(ax, err, f"{label(r)} - truth\nRMS {rms:.3g} m", cmap="coolwarm",
                   extent=extent, vmin=-lim, vmax=lim)  # fmt: skip
    _cbar(fig, im, list(axes), "error (m)")


def reconstruction_panels(
    image: np.ndarray,
    truth: np.ndarray,
    reconstructions: Mapping[str, np.ndarray],
    samples: tuple[np.ndarray, np.ndarray],
    *,
    planner: str,
    density_label: str = "",
    point: str = "",
    spacing_m: float | None = None,
):
    """Every reconstruction of one plan beside the truth, and their error maps.

    Top row: the true depth, then each reconstruction (configured order), all on the true
    depth's colour scale (one colour bar, m). Bottom row: the guide image with the planned
    samples (under the truth), then each reconstruction's error (reconstruction - truth) on
    one symmetric scale for all of them, at the 99th percentile of |error| over every map
    (one colour bar, m); each error panel's title gives its RMS error.

    Parameters
    ----------
    image : (rows, cols) float
        Guide (sensor) image.
    truth : (rows, cols) float
        True depth from the camera (m).
    reconstructions : mapping name -> (rows, cols) float
        The reconstructions of the same samples (at least one).
    samples : (plan_rows, plan_cols)
        The sampled pixels.
    planner : str
        The study's planner that placed them (its display label titles the samples panel).
    density_label, point : str
        ``"k/N = 1/32"`` and the sweep point (figure title), either may be empty.
    spacing_m : float, optional
        Cell size of a nadir orthographic view: axes in metres; None = pixels.

    Returns
    -------
    (Figure, ndarray of Axes (2, 1 + len(reconstructions)))
    """
    if not reconstructions:
        raise ValueError("reconstruction_panels needs at least one reconstruction")
    names = list(reconstructions)
    n = len(names) + 1
    ext = _extent(np.shape(truth), spacing_m)
    per = min(PAGE_W / n - 0.35, 2.6)
    fig, axes = plt.subplots(
        2, n, figsize=(max(PAGE_W, n * (per + 0.35)), _panel_height(np.shape(truth), per, 2, 0.55)),
        constrained_layout=True, squeeze=False,
    )  # fmt: skip
    truth = np.asarray(truth, float)
    vmin, vmax = float(np.nanmin(truth)), float(np.nanmax(truth))
    errors = {r: np.asarray(reconstructions[r], float) - truth for r in names}
    im = _show(axes[0, 0], truth, "true depth", cmap=DEPTH_CMAP, extent=ext, vmin=vmin, vmax=vmax)
    for j, r in enumerate(names, start=1):
        _show(axes[0, j], reconstructions[r], label(r), cmap=DEPTH_CMAP, extent=ext,
              vmin=vmin, vmax=vmax)  # fmt: skip
    _cbar(fig, im, axes[0, :].tolist(), "depth (m)")
    top = max(float(np.nanmax(image)), 1e-12)
    # two lines, as the error panels' titles beside it: one line ran into them
    dens = f"\n{density_label}" if density_label else ""
    _show(axes[1, 0], image, f"{label(planner)} samples{dens}", extent=ext, vmin=0, vmax=top)
    rows, cols = samples
    _scatter_samples(axes[1, 0], rows, cols, spacing_m if ext is not None else None)
    _error_row(fig, axes[1, 1:], errors, extent=ext)
    if ext is not None:
        flat = list(axes.ravel())
        _metre_labels(flat, left={0, n}, bottom=set(range(n, 2 * n)))
    if point:
        fig.suptitle(point, fontsize=TITLE_PT)
    return fig, axes


def reconstruction_saved_by_planner(
    saved: Mapping[str, Mapping[str, object]],
    *,
    strategies: Sequence[str],
    reconstructions: Sequence[str],
    metric: str = "mse",
    title: str = "",
):
    """Samples saved vs linear at one sweep point: the planners (layouts) along x, one marker
    per reconstruction beside each other, its interval as an error bar.

    Parameters
    ----------
    saved : mapping reconstruction -> strategy -> ``(value, low, high)`` or a number
        As a point of :func:`reconstruction_saved_vs_sweep` (low / high NaN: no interval).
    strategies, reconstructions : the categories and the series, in order
    metric : the metric of the comparison (axis label)
    title : the sweep point, if any

    Returns
    -------
    (Figure, Axes)
    """
    strategies = list(strategies)
    if not strategies or not reconstructions:
        raise ValueError("reconstruction_saved_by_planner needs strategies and series")
    st = styles(reconstructions)
    n = len(reconstructions)
    fig, ax = new_axes(None, (max(3.6, 0.42 * len(strategies) * max(n, 2) ** 0.5 + 1.8), 3.2))
    pos = np.arange(len(strategies), dtype=float)
    values: list[float] = [0.8, 1.25]
    for i, r in enumerate(reconstructions):
        cells = np.array([_cell(saved.get(r, {}).get(s)) for s in strategies], float)
        x = pos + (i - (n - 1) / 2) * min(0.6 / n, 0.2)
        values += _points_with_interval(ax, x, cells, st[r], capsize=2, elinewidth=0.8,
                                        ms=4.5, ls="none")  # fmt: skip
    ax.axhline(1.0, color="k", lw=0.6, ls=":")
    ax.set_xticks(pos, [label(s) for s in strategies], fontsize=TICK_PT, rotation=30, ha="right")
    ax.set_xlim(pos[0] - 0.6, pos[-1] + 0.6)
    ax.tick_params(axis="y", labelsize=TICK_PT)
    ax.set_xlabel("planner (layout the reconstructions share)", fontsize=LABEL_PT)
    ax.set_ylabel(
        f"samples saved vs linear\n(equal {METRIC_NAMES.get(metric, metric)})", fontsize=LABEL_PT
    )
    if title:
        ax.set_title(title, fontsize=TITLE_PT)
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ratio_axis(ax, values)
    # beside the axes: below them the rotated planner names would run into it
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, fontsize=TICK_PT,
              title="reconstruction", title_fontsize=TICK_PT)  # fmt: skip
    return fig, ax


def _points_with_interval(ax, x, cells, style, *, capsize, elinewidth, **line) -> list:
    """One reconstruction's points (``cells``: rows of value, interval low, interval high;
    ``line``: the plot's marker size and line keywords) and their interval as error bars where
    all three are finite; returns every value drawn, for the axis limits."""
    y, lo, hi = np.asarray(cells, float).T
    ax.plot(x, y, marker=style.marker, color=style.colour, label=style.label, **line)
    ok = np.isfinite(lo) & np.isfinite(hi) & np.isfinite(y)
    if ok.any():
        yerr = np.vstack([np.clip(y - lo, 0, None), np.clip(hi - y, 0, None)])
        ax.errorbar(x[ok], y[ok], yerr=yerr[:, ok], fmt="none", ecolor=style.colour,
                    capsize=capsize, elinewidth=elinewidth)  # fmt: skip
    return [float(v) for v in np.concatenate([y, lo, hi])]
