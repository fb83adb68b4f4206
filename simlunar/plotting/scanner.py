"""Figures of the structured-light scanner study: errors per scan mode / planner, their ratio
to the gray-code scan, errors against a sweep axis, gray-code bit error rates.

Error axes carry a unit scaled to the values (m², cm², mm², µm²; no ``1e-6`` offset text).
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence

import numpy as np

from simlunar.metrics import METRIC_NAMES
from simlunar.plotting.density import _category_ticks, _sweep_positions
from simlunar.plotting.layout import COLUMN_W, LABEL_PT, TICK_PT, TITLE_PT, legend_outside, new_axes
from simlunar.plotting.style import (
    METRIC_UNITS,
    label,
    metric_axis,
    pair_label,
    reference_mode,
    style,
)

__all__ = [
    "bit_error_rates",
    "error_scale",
    "scanner_bars",
    "scanner_relative_bars",
    "scanner_vs_sweep",
]

#: units of an error axis, largest first: (name, factor from the SI unit)
_SCALES = {
    "m²": (("m²", 1.0), ("cm²", 1e4), ("mm²", 1e6), ("µm²", 1e12)),
    "m": (("m", 1.0), ("cm", 1e2), ("mm", 1e3), ("µm", 1e6)),
}


def error_scale(metric: str, values) -> tuple[float, str]:
    """``(factor, unit)`` that brings a metric's values to 0.5 or more in the unit shown."""
    unit = METRIC_UNITS.get(metric)
    v = [abs(float(x)) for x in values if x is not None and np.isfinite(x) and x != 0]
    if unit not in _SCALES or not v:
        return 1.0, unit or ""
    top = max(v)
    for name, f in _SCALES[unit]:
        if top * f >= 0.5:
            return f, name
    return _SCALES[unit][-1][1], _SCALES[unit][-1][0]


def _entry_label(e: dict) -> str:
    return pair_label(e["mode"], e.get("planner")) if "mode" in e else e["label"]


def _is_reference(e: dict, ref: str | None) -> bool:
    return ref is not None and e.get("mode") == ref and not e.get("planner")


def scanner_bars(summary: Sequence[dict], *, metric: str = "mse", ax=None):
    """Bar chart of a scanner-study metric per (mode, planner).

    Each entry of ``summary`` has ``mode``, ``planner`` (or empty) and the mean of ``metric``;
    ``f"{metric}_sd"`` (standard deviation over trials and seeds) draws an error bar of +- one
    s.d. where ``n`` (the number of values, in the tick label) is 2 or more.
    """
    fig, ax = new_axes(ax, (COLUMN_W, 2.6))
    labels = [_entry_label(e) for e in summary]
    raw = [e.get(metric) if e.get(metric) is not None else math.nan for e in summary]
    k, unit = error_scale(metric, raw)
    vals = [v * k for v in raw]
    sds = [e.get(f"{metric}_sd") if (e.get("n") or 2) >= 2 else None for e in summary]
    yerr = None if all(s is None for s in sds) else [math.nan if s is None else s * k for s in sds]
    colors = [style(e.get("planner") or e.get("mode") or "").colour for e in summary]
    ax.bar(range(len(vals)), vals, color=colors, yerr=yerr, capsize=2, error_kw={"lw": 0.8})
    _bar_ticks(ax, labels, summary)
    ax.set_ylabel(metric_axis(metric, unit=unit), fontsize=LABEL_PT)
    ax.tick_params(axis="y", labelsize=TICK_PT)
    ax.grid(True, axis="y", alpha=0.3)
    return fig, ax


def _bar_ticks(ax, labels, summary) -> None:
    # horizontal, wrapped at word boundaries so a long pair label stays within its bar's width
    width = max(8, int(56 / max(len(labels), 1)))  # characters of 6 pt text per bar
    wrapped = [textwrap.fill(t, width, break_long_words=False) for t in labels]
    ticks = [f"{t}\n(n = {e['n']})" if e.get("n") else t for t, e in zip(wrapped, summary)]
    ax.set_xticks(range(len(labels)), ticks, fontsize=TICK_PT - 1)


def scanner_relative_bars(summary: Sequence[dict], *, metric: str = "mse", ax=None):
    """Each scan's ``metric`` divided by the gray-code scan's (the section 5 comparison:
    ambiguity enhancement lowered the MSE by 25 %), one bar per other (mode, planner), the
    change in per cent above it; dotted line at 1. Returns ``(fig, ax)`` or ``(fig, None)``
    when there is no gray-code entry to divide by."""
    mode = reference_mode(summary)
    ref = next((e for e in summary if _is_reference(e, mode)), None)
    if ref is None or not ref.get(metric):
        return None, None
    fig, ax = new_axes(ax, (COLUMN_W, 2.6))
    others = [e for e in summary if not _is_reference(e, mode)]
    ratio = [(e.get(metric) or math.nan) / ref[metric] for e in others]
    colors = [style(e.get("planner") or e.get("mode") or "").colour for e in others]
    ax.bar(range(len(others)), ratio, color=colors)
    for i, r in enumerate(ratio):
        if np.isfinite(r):
            ax.annotate(
                f"{100 * (r - 1):+.1f} %",
                (i, r),
                xytext=(0, 2),
                textcoords="offset points",
                ha="center",
                va="bottom",
                fontsize=TICK_PT - 1,
            )
    ax.axhline(1.0, color="k", lw=0.6, ls=":")
    finite = [r for r in ratio if np.isfinite(r)] + [1.0]
    lo, hi = min(finite), max(finite)
    pad = 0.15 * max(hi - lo, 0.02)
    ax.set_ylim(max(0.0, lo - 3 * pad) if lo > 0.5 else 0.0, hi + 2 * pad)
    _bar_ticks(ax, [_entry_label(e) for e in others], others)
    name = METRIC_NAMES.get(metric, metric)
    ax.set_ylabel(f"{name} / {label(mode).lower()}'s {name} (×)", fontsize=LABEL_PT)
    ax.tick_params(axis="y", labelsize=TICK_PT)
    ax.grid(True, axis="y", alpha=0.3)
    return fig, ax


def scanner_vs_sweep(
    points: Sequence[tuple[object, Sequence[dict]]],
    *,
    metric: str = "mse",
    axis_label: str = "",
    ax=None,
    title: str | None = None,
    secondary: tuple[float, str] | None = None,
):
    """A scanner-study metric against a sweep axis, one series per (mode, planner).

    Parameters
    ----------
    points : sequence of (x, summary)
        ``x`` a number or a label (one sweep point); ``summary`` entries as for
        :func:`scanner_bars` (``mode``, ``planner``, the mean of ``metric`` and optionally
        ``f"{metric}_sd"``, drawn as ±1 s.d. error bars).
    metric : str
        An error metric (log y axis when every value is positive and they span more than a
        factor of 20, else linear in a unit scaled to the values) or ``"valid_fraction"``
        (linear: 0 to 1, or zoomed in on the values when all are above 0.5).
    secondary : (factor, label), optional
        A second x axis on top, ``factor`` times the swept value (numeric axes), e.g. the
        sun-to-projector ratio the camera saw against the sun's irradiance.

    A numeric axis spanning more than a factor of 20 (all positive) is drawn on a log scale;
    a categorical one gets one tick per label, markers unconnected.
    """
    fig, ax = new_axes(ax, (COLUMN_W + 1.5, 2.6))
    xs = [p[0] for p in points]
    numeric, pos = _sweep_positions(xs)
    series = _sweep_series(points, metric)
    allv = [v for *_, y, _ in series for v in y if np.isfinite(v)]
    log_y = metric != "valid_fraction" and allv and min(allv) > 0 and max(allv) / min(allv) > 20
    k, unit = (1.0, "") if metric == "valid_fraction" or log_y else error_scale(metric, allv)
    if log_y:
        unit = METRIC_UNITS.get(metric, "")
    for mode, planner, y, sd in series:
        st = style(planner or mode)
        ax.errorbar(
            pos,
            y * k,
            yerr=sd * k if sd.any() else None,
            marker=st.marker,
            ms=3.5,
            lw=1.2 if numeric else 0,
            ls="-" if numeric else "none",
            color=st.colour,
            capsize=2,
            elinewidth=0.8,
            label=pair_label(mode, planner or None),
        )
    if numeric and pos.size and np.all(pos > 0) and pos.max() / pos.min() > 20:
        ax.set_xscale("log")
    if not numeric:
        _category_ticks(ax, pos, xs)
    if secondary is not None and numeric:
        f, text = secondary
        top = ax.secondary_xaxis("top", functions=(lambda x: x * f, lambda x: x / f))
        top.set_xlabel(text, fontsize=TICK_PT)
        top.tick_params(labelsize=TICK_PT - 1)
    _sweep_y_axis(ax, metric, allv, log_y, unit)
    ax.tick_params(labelsize=TICK_PT)
    ax.set_xlabel(axis_label, fontsize=LABEL_PT)
    if title:
        ax.set_title(title, fontsize=TITLE_PT)
    legend_outside(ax)
    ax.grid(True, alpha=0.3)
    return fig, ax


def _sweep_series(points, metric: str) -> list[tuple]:
    """Per (mode, planner) in order of appearance: ``(mode, planner, y, sd)`` over the points
    (NaN where a point lacks the pair, s.d. 0 where it has none)."""
    keys = list(dict.fromkeys((e["mode"], e.get("planner") or "") for _, s in points for e in s))
    series = []
    for mode, planner in keys:
        y, sd = [], []
        for _, summary in points:
            e = next(
                (e for e in summary if (e["mode"], e.get("planner") or "") == (mode, planner)), {}
            )
            v = e.get(metric)
            y.append(math.nan if v is None else float(v))
            s_ = e.get(f"{metric}_sd")
            sd.append(0.0 if s_ is None else float(s_))
        series.append((mode, planner, np.asarray(y), np.asarray(sd)))
    return series


def _sweep_y_axis(ax, metric: str, allv: list, log_y: bool, unit: str) -> None:
    """The y scale, limits and label of :func:`scanner_vs_sweep`."""
    if metric == "valid_fraction":
        lo = min(allv) if allv else 0.0
        if lo > 0.5:  # all close to 1: zoom in so a change of a few tenths of a percent shows
            pad = max(0.15 * (1.0 - lo), 5e-4)
            ax.set_ylim(lo - pad, 1.0 + pad)
        else:
            ax.set_ylim(-0.02, 1.02)
        ax.set_ylabel("valid fraction of guide pixels", fontsize=LABEL_PT)
    else:
        if log_y:
            ax.set_yscale("log")
        ax.set_ylabel(metric_axis(metric, unit=unit), fontsize=LABEL_PT)


def _rate_unit(top: float) -> tuple[float, str]:
    """A readable unit for error rates up to ``top``: (its size as a fraction, its name).

    Rates of 1e-7 on an axis of fractions print as "1e-7" offset text above the axis, a unit
    nobody reads; per million (or billion) pixels gives the axis plain numbers.
    """
    for per, unit in ((1e-2, "per 100 pixels"), (1e-3, "per thousand pixels"),
                      (1e-6, "per million pixels")):  # fmt: skip
        if top >= per:
            return per, unit
    return 1e-9, "per billion pixels"


def bit_error_rates(rates: dict[str, float], *, ax=None):
    """Gray-code bit error rate per bit (``ber_c<i>`` columns, ``ber_r<i>`` rows; MSB = 0).

    When every rate is zero the figure says so in its axes (no curve on a meaningless axis);
    result folders draw no figure then (:mod:`simlunar.results.figures`).
    """
    fig, ax = new_axes(ax, (COLUMN_W, 2.4))
    vals = [float(v) for v in rates.values()]
    per, unit = _rate_unit(max(vals, default=0.0))
    drawn = False
    for prefix, name, color in (
        ("ber_c", "column bits", "#1f77b4"),
        ("ber_r", "row bits", "#ff7f0e"),
    ):
        items = sorted((int(k[len(prefix) :]), v) for k, v in rates.items() if k.startswith(prefix))
        if items:
            ax.plot(
                [i for i, _ in items],
                [v / per for _, v in items],
                marker="o",
                ms=3,
                color=color,
                label=name,
            )
            drawn = True
    ax.set_xlabel("bit (0 = most significant)", fontsize=LABEL_PT)
    ax.set_ylabel(f"bit errors {unit}", fontsize=LABEL_PT)
    ax.tick_params(labelsize=TICK_PT)
    if drawn and vals and max(vals) == 0:
        ax.set_ylim(-0.05, 1.0)
        ax.text(
            0.5,
            0.5,
            f"no bit errors: all {len(vals)} per-bit rates are 0",
            transform=ax.transAxes,
            ha="center",
            va="center",
            fontsize=LABEL_PT,
        )
    elif drawn:
        ax.set_ylim(0, max(vals) / per * 1.15)
    if drawn:
        ax.legend(fontsize=TICK_PT, frameon=False)
    ax.grid(True, alpha=0.3)
    return fig, ax
