"""Figure sizes, panel grids, shared legends and saving (matplotlib only).

Sizes are for a single column (3.4 in) or a full page width (7.0 in) at 300 dpi. Legends of
multi-panel figures go outside the data: into an empty grid cell when the grid has one, else
below the panels.
"""

from __future__ import annotations

import io
import math
from collections.abc import Sequence

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

__all__ = [
    "COLUMN_W",
    "LABEL_PT",
    "LEGEND_PT",
    "MAX_COLS",
    "PAGE_W",
    "TICK_PT",
    "TITLE_PT",
    "close",
    "legend_outside",
    "new_axes",
    "panel_grid",
    "panel_row",
    "save",
    "shared_legend",
]

COLUMN_W = 3.4  # in, one column of a two-column paper
PAGE_W = 7.0  # in, full page width
#: panels per row of a multi-panel figure (three single-column panels fill a page width)
MAX_COLS = 3
#: font sizes (pt) at print size: tick labels, axis labels, legends, titles
TICK_PT, LABEL_PT, LEGEND_PT, TITLE_PT = 7, 8, 7, 8


def new_axes(ax, figsize):
    """``(figure, axes)``: ``ax`` and its figure, or a new single-panel figure."""
    if ax is not None:
        return ax.figure, ax
    fig, ax = plt.subplots(figsize=figsize, constrained_layout=True)
    return fig, ax


def legend_outside(
    ax, *, handles=None, labels=None, ncols: int = 2, title: str | None = None
) -> None:
    """A single panel's legend below its axes, in ``ncols`` columns (never on the data), with
    an optional small ``title`` (what the bars or bands show)."""
    if handles is None:
        handles, labels = ax.get_legend_handles_labels()
    if not handles:
        return
    ax.legend(
        handles,
        labels,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.27),  # below the x label and its tick labels
        borderaxespad=0.0,
        fontsize=LEGEND_PT - 1,
        frameon=False,
        handlelength=1.8,
        ncols=min(ncols, len(labels)),
        title=title,
        title_fontsize=LEGEND_PT - 2,
    )


def panel_row(n: int, *, width: float | None = None, height: float = 2.6):
    """A figure with ``n`` panels side by side: (Figure, list of Axes).

    ``width`` defaults to one column width per panel.
    """
    fig, axes = plt.subplots(
        1,
        n,
        figsize=(width if width is not None else COLUMN_W * n, height),
        constrained_layout=True,
        squeeze=False,
    )
    return fig, list(axes[0])


def panel_grid(n: int, *, ncols: int = MAX_COLS, panel_w: float = COLUMN_W, height: float = 2.6):
    """A figure of ``n`` panels in rows of at most ``ncols``: (Figure, list of n Axes).

    Every panel keeps one column's width (``panel_w``), however many there are; grid cells
    past ``n`` in the last row are removed (:func:`shared_legend` puts the legend there).
    """
    if n < 1:
        raise ValueError(f"panel_grid needs at least one panel, got {n}")
    cols = min(n, ncols)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(
        rows, cols, figsize=(panel_w * cols, height * rows), constrained_layout=True, squeeze=False
    )
    flat = list(axes.ravel())
    for ax in flat[n:]:
        ax.remove()
    fig._simlunar_free = [(rows - 1, c) for c in range(n - (rows - 1) * cols, cols)]
    return fig, flat[:n]


def shared_legend(
    fig: Figure, axes: Sequence, *, prune_labels: bool = True, union: bool = False
) -> None:
    """Replace the panels' legends by one figure legend outside the data (multi-panel figures).

    The entries are the first panel's (panels of one figure share strategies and styles), or
    with ``union`` every panel's, each label once (panels that leave out their reference). The
    legend fills the free cells of a :func:`panel_grid` when it has some, else it goes below
    the panels in one row when that fits. With ``prune_labels`` (panels that share their axes'
    quantities) axis labels stay on the left column (y) and the bottom panel of each column (x).
    """
    handles, labels = [], []
    for ax in axes:
        leg = ax.get_legend()
        if leg is not None and union:
            for h, t in zip(leg.legend_handles, leg.get_texts()):
                if t.get_text() not in labels:
                    handles.append(h)
                    labels.append(t.get_text())
            leg.remove()
        elif leg is not None:
            if not handles:
                # the artists themselves (an errorbar keeps its marker and bars), then
                # entries only the legend has (the band's patch)
                handles, labels = (list(x) for x in ax.get_legend_handles_labels())
                for h, t in zip(leg.legend_handles, leg.get_texts()):
                    if t.get_text() not in labels:
                        handles.append(h)
                        labels.append(t.get_text())
            leg.remove()
    free = getattr(fig, "_simlunar_free", [])
    if handles and free and len(axes) > 1:
        gs = axes[0].get_subplotspec().get_gridspec()
        row, c0 = free[0]
        slot = fig.add_subplot(gs[row, c0 : free[-1][1] + 1])
        slot.axis("off")
        slot.legend(handles, labels, loc="center", fontsize=LEGEND_PT, frameon=False)
    elif handles:
        fig.legend(
            handles,
            labels,
            loc="outside lower center",
            ncols=min(len(labels), 4),
            fontsize=LEGEND_PT,
            frameon=False,
            handlelength=1.6,
        )
    if prune_labels and len(axes) > 1:
        grid = [ax.get_subplotspec() for ax in axes]
        last_row = {}
        for spec in grid:
            col = spec.colspan.start
            last_row[col] = max(last_row.get(col, 0), spec.rowspan.start)
        for ax, spec in zip(axes, grid):
            if spec.colspan.start != 0:
                ax.set_ylabel("")
            if spec.rowspan.start != last_row[spec.colspan.start]:
                ax.set_xlabel("")


def close(fig: Figure) -> None:
    """Free a figure's memory once it has been saved."""
    plt.close(fig)


def save(fig: Figure, path_stem, formats: Sequence[str] = ("png",), dpi: int = 300) -> list:
    """Render a figure to bytes per format: returns [(suffix, bytes)] (the caller writes them)."""
    out = []
    for fmt in formats:
        buf = io.BytesIO()
        # fixed metadata so the same data gives byte-identical files
        meta = {"Software": None} if fmt == "png" else {"CreationDate": None, "Producer": None}
        fig.savefig(buf, format=fmt, dpi=dpi, metadata=meta)
        out.append((fmt, buf.getvalue()))
    return out
