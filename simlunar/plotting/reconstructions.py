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
from collections.abc import Sequence

import numpy as np

from simlunar.metrics import METRIC_NAMES
from simlunar.plotting.density import _category_ticks, _sweep_positions, ratio_axis
from simlunar.plotting.layout import (
    LABEL_PT,
    TICK_PT,
    TITLE_PT,
    legend_outside,
    panel_grid,
    shared_legend,
)
from simlunar.plotting.style import _UNIT_SUFFIXES, _with_unit, label, styles

__all__ = ["MAX_PANELS", "ROW_PANELS", "category_labels", "reconstruction_saved_vs_sweep"]

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
            y, lo, hi = cells.T
            dodge = (i - (n - 1) / 2) * (0.006 * float(np.ptp(pos)) if numeric else 0.1)
            x = pos + dodge
            ax.plot(x, y, marker=st[r].marker, ms=3.5, lw=1.1 if numeric else 0,
                    ls="-" if numeric else "none", color=st[r].colour,
                    label=st[r].label)  # fmt: skip
            ok = np.isfinite(lo) & np.isfinite(hi) & np.isfinite(y)
            if ok.any():
                yerr = np.vstack([np.clip(y - lo, 0, None), np.clip(hi - y, 0, None)])
                ax.errorbar(x[ok], y[ok], yerr=yerr[:, ok], fmt="none", ecolor=st[r].colour,
                            capsize=1.5, elinewidth=0.7)  # fmt: skip
            values += [float(v) for v in np.concatenate([y, lo, hi])]
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
