"""The "headroom captured" figure: how much of a truth-reading oracle's saving each planner gets.

Headroom captured, per terrain seed, is log(samples saved vs the uniform layout) / log(the
oracle's samples saved vs the uniform layout) (:func:`simlunar.results.aggregate`): 1 is the
oracle's saving, 0 the uniform layout's, below 0 worse than the uniform layout. The figure
shows one horizontal bar per planner (the mean over seeds) with every seed's value as a dot,
so a reader sees both the level and how much it moves with the terrain.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from simlunar.metrics import METRIC_NAMES
from simlunar.plotting.layout import COLUMN_W, LABEL_PT, TICK_PT, TITLE_PT, panel_grid
from simlunar.plotting.style import label, styles

__all__ = ["headroom_plot"]

#: inches of figure height per planner row (bars and the seed dots beside them)
ROW_IN = 0.26


def headroom_plot(entries: Sequence[dict]):
    """One panel per (sweep point, oracle): each planner's headroom captured, paired by seed.

    Parameters
    ----------
    entries : sequence of dict
        As :func:`simlunar.plotting.tables.headroom_tables` takes them: ``label`` (the sweep
        point, may be empty), ``oracle``, ``metric``, ``strategies`` (row order), ``captured``
        (strategy -> per-seed headroom captured), ``seeds``.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        No entry (there is nothing to draw: the study had no oracle or no uniform layout).
    """
    if not entries:
        raise ValueError("headroom_plot needs at least one (point, oracle) entry")
    rows = max(len(e["strategies"]) for e in entries)
    fig, axes = panel_grid(
        len(entries), ncols=2, panel_w=COLUMN_W * 1.4, height=1.2 + ROW_IN * rows
    )
    for ax, e in zip(axes, entries):
        _panel(ax, e)
    return fig


def _panel(ax, e: dict) -> None:
    names = list(e["strategies"])
    look = styles(names)
    y = np.arange(len(names))[::-1]
    lo, hi = 0.0, 1.0
    for yi, s in zip(y, names):
        v = np.asarray(e["captured"][s], dtype=float)
        v = v[np.isfinite(v)]
        if v.size == 0:
            continue
        ax.barh(yi, v.mean(), height=0.6, color=look[s].colour, alpha=0.55, lw=0)
        ax.plot(v, np.full(v.size, yi), "o", ms=2.6, color=look[s].colour, mec="k", mew=0.3)
        lo, hi = min(lo, float(v.min())), max(hi, float(v.max()))
    ax.axvline(0.0, color="k", lw=0.7)
    ax.axvline(1.0, color="k", lw=0.7, ls=":")
    pad = 0.05 * (hi - lo)
    ax.set_xlim(lo - pad, hi + pad)
    ax.set_yticks(y, [look[s].label for s in names], fontsize=TICK_PT)
    ax.tick_params(axis="x", labelsize=TICK_PT)
    n = len(e["seeds"])
    metric = METRIC_NAMES.get(e["metric"], e["metric"])
    ax.set_xlabel(f"headroom captured at equal {metric}", fontsize=LABEL_PT - 0.5)
    where = f"{e['label']}\n" if e.get("label") else ""
    ax.set_title(
        f"{where}1 = {label(e['oracle'])}, 0 = Uniform Lloyd\n"
        f"bar: mean, dots: {n} terrain seed{'s' * (n != 1)}",
        fontsize=TITLE_PT - 0.5,
    )
    ax.grid(True, axis="x", alpha=0.3)
