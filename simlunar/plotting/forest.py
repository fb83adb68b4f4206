"""Forest plot of samples saved per planner against the image-free uniform layout, with its
interval: the figure of the headroom and paired samples-saved tables.

One row per planner: its samples saved at equal error against uniform Lloyd (geometric mean
over terrain seeds, as :func:`simlunar.plotting.tables.paired_saved_tables` and the headroom
table print it), the two-sided 95 % Student t interval of that mean in log space as a
horizontal bar (two seeds or more), and every seed's value as a small dot. The line at 1 is
the uniform layout; right of it a planner needs fewer samples. The x axis is log2 with ticks
at plain ratios across the data; the planner names are the y tick labels, so no legend
covers the data.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from simlunar.metrics import METRIC_NAMES
from simlunar.plotting.density import ratio_ticks
from simlunar.plotting.layout import COLUMN_W, LABEL_PT, TICK_PT, TITLE_PT, panel_grid
from simlunar.plotting.style import styles
from simlunar.plotting.tables import t_interval

__all__ = ["forest_rows", "saved_forest_plot"]

#: inches of figure height per planner row
ROW_IN = 0.27


def forest_rows(entry: dict) -> list[tuple[str, float, float, float, np.ndarray]]:
    """``(strategy, geometric mean, low, high, per-seed values)`` per planner of one entry.

    Non-finite or non-positive seed values are left out; a planner with none is left out.
    One seed: low = high = the value (no interval).
    """
    rows = []
    for s in entry["strategies"]:
        v = np.asarray(entry["saved"].get(s, ()), dtype=float)
        v = v[np.isfinite(v) & (v > 0)]
        if v.size == 0:
            continue
        if v.size == 1:
            g = float(v[0])
            rows.append((s, g, g, g, v))
            continue
        m, lo, hi = t_interval(np.log(v))
        rows.append((s, float(np.exp(m)), float(np.exp(lo)), float(np.exp(hi)), v))
    return rows


def saved_forest_plot(entries: Sequence[dict], *, reference: str = "Uniform Lloyd"):
    """One panel per sweep point: samples saved vs the uniform layout, per planner.

    Parameters
    ----------
    entries : sequence of dict
        As :func:`simlunar.plotting.tables.paired_saved_tables` takes them: ``label`` (the
        sweep point, may be empty), ``metric``, ``strategies`` (row order), ``saved``
        (strategy -> per-seed samples saved, ratios > 0), ``seeds``.
    reference : str
        Display name of the layout the ratios are against.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        No entry, or no entry with a finite value.
    """
    tables = [(e, forest_rows(e)) for e in entries]
    tables = [(e, r) for e, r in tables if r]
    if not tables:
        raise ValueError("saved_forest_plot needs at least one entry with a finite value")
    n_rows = max(len(r) for _, r in tables)
    fig, axes = panel_grid(
        len(tables), ncols=2, panel_w=COLUMN_W * 1.4, height=1.25 + ROW_IN * n_rows
    )
    for ax, (e, rows) in zip(axes, tables):
        _panel(ax, e, rows, reference)
    return fig


def _panel(ax, e: dict, rows, reference: str) -> None:
    look = styles([r[0] for r in rows])
    y = np.arange(len(rows))[::-1]
    values = [1.0]
    for yi, (s, g, lo, hi, v) in zip(y, rows):
        st = look[s]
        if hi > lo:
            ax.plot([lo, hi], [yi, yi], "-", color=st.colour, lw=1.6, solid_capstyle="butt")
        ax.plot(v, np.full(v.size, yi), "o", ms=2.2, color="0.55", mew=0, zorder=2)
        ax.plot([g], [yi], st.marker, ms=5.5, color=st.colour, mec="k", mew=0.5, zorder=3)
        values += [lo, hi, *v.tolist()]
    ax.axvline(1.0, color="k", lw=0.8, ls=":")
    _ratio_x_axis(ax, values)
    ax.set_yticks(y, [look[r[0]].label for r in rows], fontsize=TICK_PT)
    ax.set_ylim(-0.7, len(rows) - 0.3)
    metric = METRIC_NAMES.get(e["metric"], e["metric"])
    ax.set_xlabel(f"samples saved vs {reference} at equal {metric}", fontsize=LABEL_PT - 0.5)
    n = len(e["seeds"])
    how = (
        f"marker: geometric mean, bar: 95 % t interval,\ndots: {n} terrain seeds"
        if n > 1
        else "one terrain seed: no interval"
    )
    where = f"{e['label']}\n" if e.get("label") else ""
    ax.set_title(f"{where}{how}", fontsize=TITLE_PT - 0.5)
    ax.grid(True, axis="x", alpha=0.3)


def _ratio_x_axis(ax, values) -> None:
    """Log2 x axis over the data and 1, ticks at plain ratios (:data:`NICE_RATIOS`)."""
    v = np.asarray([x for x in values if np.isfinite(x) and x > 0], float)
    lo, hi = float(v.min()), float(v.max())
    pad = (hi / lo) ** 0.06 if hi > lo else 1.1
    lo, hi = lo / pad, hi * pad
    ax.set_xscale("log", base=2)
    ax.set_xlim(lo, hi)
    ratio_ticks(ax.xaxis, lo, hi)
    ax.tick_params(axis="x", labelsize=TICK_PT)
