"""LIDAR figures: a return waveform with its detected returns; error against scan time (and
samples) per planner from a LIDAR study's tidy rows; one scan (guide image, beams in visiting
order, measured depths). The summary and the tables of those rows
are in :mod:`simlunar.plotting.lidar_tables` (no Matplotlib; re-exported here)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from simlunar.plotting.density import reconstruction_linestyles
from simlunar.plotting.images import DEPTH_CMAP
from simlunar.plotting.layout import LABEL_PT, PAGE_W, TICK_PT, TITLE_PT, legend_outside
from simlunar.plotting.lidar_tables import lidar_summary, lidar_tables
from simlunar.plotting.style import PLACEMENT_LINES, label, metric_axis, styles

__all__ = [
    "ORDER_CMAP",
    "RowSelection",
    "error_vs_time",
    "lidar_summary",
    "lidar_tables",
    "scan_figure",
    "waveform",
]

#: colour map of the visiting order (first beam dark, last bright; not the depth's map)
ORDER_CMAP = "plasma"
#: at most this many planners (columns) in a scan figure
MAX_SCAN_PLANNERS = 4

#: what the error bars of :func:`error_vs_time` show, by how many terrain seeds (units) it pools
BAND_TRIALS = "bars: ±1 s.d. over trials"
BAND_SEEDS = "bars: 95 % bootstrap interval over terrain seeds"


@dataclass(frozen=True)
class RowSelection:
    """The rows one :func:`error_vs_time` panel summarises (:func:`lidar_summary`).

    Attributes
    ----------
    where : dict, optional
        Column filters compared as strings (a list value keeps any of its items).
    by : str, optional
        A column whose values are separate points of each planner's curve.
    """

    where: dict | None = None
    by: str | None = None


def waveform(
    range_m: np.ndarray,
    counts: np.ndarray,
    *,
    expected: np.ndarray | None = None,
    returns: dict[str, float] | None = None,
    truth: dict[str, float] | None = None,
    title: str = "",
    ax=None,
):
    """Photon counts of one histogram against range, with the reported returns.

    Parameters
    ----------
    range_m : (bins,) float
        Range of each bin centre (m).
    counts : (bins,) int or float
        Detections per bin.
    expected : (bins,) float or None
        Mean counts per bin (drawn as a line).
    returns : dict name -> range (m) or None
        Reported returns (e.g. ``{"first": 49.0, "last": 50.0}``), drawn as dashed lines.
    truth : dict name -> range (m) or None
        True surface ranges, drawn as dotted lines.
    title : str
    ax : matplotlib Axes or None

    Returns
    -------
    (Figure, Axes)
    """
    if ax is None:
        fig = Figure(figsize=(6.0, 3.2))
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    r = np.asarray(range_m, float)
    ax.step(r, np.asarray(counts, float), where="mid", color="0.3", lw=0.8, label="counts")
    if expected is not None:
        ax.plot(r, expected, color="C0", lw=1.2, label="expected")
    for i, (name, value) in enumerate((returns or {}).items()):
        ax.axvline(value, color=f"C{i + 1}", ls="--", lw=1.0, label=f"{name} return")
    for name, value in (truth or {}).items():
        ax.axvline(value, color="k", ls=":", lw=0.8, label=f"true {name}")
    ax.set_xlabel("range (m)")
    ax.set_ylabel("photon counts per bin")
    if title:
        ax.set_title(title)
    ax.legend(fontsize=7, frameon=False)
    fig.tight_layout()
    return fig, ax


def error_vs_time(
    rows: Iterable[dict],
    *,
    metric: str = "mse",
    x: str = "seconds",
    planners: Sequence[str] | None = None,
    select: RowSelection | None = None,
    title: str = "",
    ax=None,
    reconstructions: Sequence[str] | None = None,
):
    """Mean error of each planner against modelled scan time (``x="seconds"``) or the range
    samples measured (``x="samples"``), log-log, with its interval as error bars
    (:func:`lidar_summary`; ``select`` the rows it pools and the column whose values are
    separate points, see :class:`RowSelection`).

    With two or more ``reconstructions`` (values of the rows' ``reconstruction`` column,
    ``linear`` for rows without one) each planner gets a curve per reconstruction: colour and
    marker name the planner, the line style the reconstruction, and the legend lists both.

    Returns
    -------
    (Figure, Axes)
    """
    if ax is None:
        fig = Figure(figsize=(3.4, 3.6), layout="constrained")
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    where, by = (select.where, select.by) if select is not None else (None, None)
    recons = list(reconstructions or [])
    by_recon = len(recons) >= 2
    if by_recon:
        rows = [r if r.get("reconstruction") else {**r, "reconstruction": "linear"} for r in rows]
    summaries = {
        r: lidar_summary(rows, metric=metric, where={**(where or {}), "reconstruction": r}, by=by)
        for r in recons
    } if by_recon else {None: lidar_summary(rows, metric=metric, where=where, by=by)}  # fmt: skip
    # the requested planners first, then any other label of the rows (a planless flash: none)
    found = [p for s in summaries.values() for p in s]
    names = [p for p in (planners or []) if p in found]
    names += [p for p in dict.fromkeys(found) if p not in names]
    st = styles(names)
    lines = reconstruction_linestyles(recons)
    pooled = False
    for r, summary in summaries.items():
        for p in (p for p in names if p in summary):
            d = summary[p]
            err = np.clip([d["value"] - d["lo"], d["hi"] - d["value"]], 0, None)
            # a truth-reading oracle is a bound: dotted, as in the sampling study's figures
            ls = PLACEMENT_LINES["oracle"] if p.startswith("oracle") else "-"
            ls = lines[r] if r is not None else ls
            name = st[p].label if r is None else f"{st[p].label}, {label(r)}"
            ax.errorbar(d[x], d["value"], yerr=err, marker=st[p].marker, color=st[p].colour,
                        label=name, lw=1.2, capsize=2, ms=4, ls=ls)  # fmt: skip
            pooled |= bool((d["units"] > 1).any())
    ax.set_xscale("log")
    ax.set_yscale("log")
    # 1-2-5 labels: a scan-time range within one decade still gets tick labels
    ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("scan time (s)" if x == "seconds" else "range samples measured")
    ax.set_ylabel(metric_axis(metric))
    if title:
        ax.set_title(title, fontsize=8)
    # below the axes: inside, the legend and its note ran through the error bars
    handles = labels = None
    if by_recon:  # one entry per planner (colour, marker) and per reconstruction (line)
        handles = [Line2D([], [], color=st[p].colour, marker=st[p].marker, ms=4, lw=1.2)
                   for p in names]  # fmt: skip
        labels = [f"planner: {st[p].label}" for p in names]
        handles += [Line2D([], [], color="0.2", lw=1.2, ls=lines[r]) for r in recons]
        labels += [f"reconstruction: {label(r)}" for r in recons]
    legend_outside(ax, handles=handles, labels=labels, title=BAND_SEEDS if pooled else BAND_TRIALS)
    return fig, ax


def scan_figure(
    image: np.ndarray,
    depth: np.ndarray,
    beams: dict[str, np.ndarray],
    *,
    title: str = "",
) -> Figure:
    """One LIDAR scan per planner: where the beams went, in which order, and what they measured.

    Left column: the guide image and the true z-depth of the guide view (its range image).
    One column per planner (at most :data:`MAX_SCAN_PLANNERS`): top, the guide image with
    the planned beams joined in visiting order by a line coloured from first (dark) to last
    (bright); bottom, the measured z-depth at each beam on the colour scale of the true depth
    (a grey x: a beam that returned no range).

    Parameters
    ----------
    image : (rows, cols) float
        Guide image in [0, 1].
    depth : (rows, cols) float
        True z-depth of the guide view (m; NaN where it misses the terrain).
    beams : dict planner label -> (n, 4) float
        :func:`simlunar.study.lidar.beam_table`: row, col, time (s), measured depth (m) per
        beam in visiting order.
    title : str
        Figure title (experiment, sensor, sweep point).

    Returns
    -------
    Figure
    """
    image = np.asarray(image, float)
    if image.ndim == 3:
        image = image.mean(axis=-1)
    depth = np.asarray(depth, float)
    labels = list(beams)[:MAX_SCAN_PLANNERS]
    if not labels:
        raise ValueError("scan_figure needs the beams of at least one planner")
    rows, cols = image.shape
    ncol = 1 + len(labels)
    panel_w = min(2.2, (PAGE_W - 0.9) / ncol)
    fig = Figure(
        figsize=(panel_w * ncol + 0.9, 2 * panel_w * rows / cols + 0.9), layout="constrained"
    )
    axes = fig.subplots(2, ncol, squeeze=False)
    finite = depth[np.isfinite(depth)]
    lo, hi = np.percentile(finite, [1, 99]) if finite.size else (0.0, 1.0)
    norm = Normalize(lo, hi if hi > lo else lo + 1.0)
    _image(axes[0, 0], image, "guide image")
    im = axes[1, 0].imshow(depth, cmap=DEPTH_CMAP, norm=norm, interpolation="nearest")
    _frame(axes[1, 0], "true z-depth")
    order = None
    for j, name in enumerate(labels, start=1):
        b = np.asarray(beams[name], float).reshape(-1, 4)
        n = len(b)
        measured = np.isfinite(b[:, 3])
        order = _path(axes[0, j], image, b)
        pct = 100.0 * measured.mean() if n else 0.0
        axes[0, j].set_title(_fit_title(label(name), f"{n} beams", panel_w, TITLE_PT - 1),
                             fontsize=TITLE_PT - 1)  # fmt: skip
        ax = axes[1, j]
        ax.imshow(np.ones_like(image), cmap="gray", vmin=0, vmax=1.25, interpolation="nearest")
        size = float(np.clip(2000.0 / max(n, 1), 1.0, 12.0))
        ax.scatter(b[measured, 1], b[measured, 0], c=b[measured, 3], cmap=DEPTH_CMAP,
                   norm=norm, s=size, linewidths=0)  # fmt: skip
        miss = ~measured & np.isfinite(b[:, 0])
        if miss.any():
            ax.scatter(b[miss, 1], b[miss, 0], marker="x", color="0.45", s=size, linewidths=0.5)
        _frame(ax, f"{pct:.0f} % returned")  # short: long titles ran into each other
    if order is not None:
        cb = fig.colorbar(order, ax=list(axes[0, 1:]), shrink=0.85, aspect=15, pad=0.02)
        cb.set_label("visiting order\n(share of the scan)", fontsize=TICK_PT)
        cb.ax.tick_params(labelsize=TICK_PT - 1)
    cb = fig.colorbar(im, ax=list(axes[1, :]), shrink=0.85, aspect=15, pad=0.02)
    cb.set_label("z-depth (m)", fontsize=TICK_PT)
    cb.ax.tick_params(labelsize=TICK_PT - 1)
    if title:
        fig.suptitle(title, fontsize=LABEL_PT)
    return fig


def _fit_title(name: str, count: str, width_in: float, size_pt: float) -> str:
    """``"name: count"`` on one line when it fits a panel of ``width_in`` inches at
    ``size_pt`` (an average glyph is about 0.55 of the font size wide), else the name wrapped
    to the panel and the count on a line of its own, so neighbouring panels' titles never run
    into each other."""
    import textwrap

    chars = max(8, int(width_in * 72.0 / (0.55 * size_pt)))
    one = f"{name}: {count}"
    if len(one) <= chars:
        return one
    return "\n".join([*textwrap.wrap(name, chars, break_long_words=False), count])


def _frame(ax, title: str) -> None:
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title(title, fontsize=TITLE_PT - 1)


def _image(ax, image, title: str) -> None:
    ax.imshow(image, cmap="gray", vmin=0.0, vmax=max(float(np.nanmax(image)), 1e-9),
              interpolation="nearest")  # fmt: skip
    _frame(ax, title)


def _path(ax, image, b: np.ndarray):
    """The guide image faded, the beams' tour as a line coloured by visiting order, the beams
    as dots; returns the line (its colour scale: the share of the scan, 0 to 1)."""
    top = max(float(np.nanmax(image)), 1e-9)
    # the image in mid greys (0.25-0.75): both ends of the order's colours stand out on it
    ax.imshow(image, cmap="gray", vmin=-0.5 * top, vmax=1.5 * top, interpolation="nearest")
    ax.set_xlim(-0.5, image.shape[1] - 0.5)
    ax.set_ylim(image.shape[0] - 0.5, -0.5)
    xy = b[:, [1, 0]]
    ok = np.isfinite(xy).all(axis=1)
    xy = xy[ok]
    share = np.linspace(0.0, 1.0, max(len(xy), 2))[: len(xy)]
    segs = np.stack([xy[:-1], xy[1:]], axis=1) if len(xy) > 1 else np.empty((0, 2, 2))
    line = LineCollection(segs, cmap=ORDER_CMAP, norm=Normalize(0.0, 1.0), linewidths=0.5)
    line.set_array(share[:-1] if len(share) > 1 else share[:0])
    ax.add_collection(line)
    size = float(np.clip(600.0 / max(len(xy), 1), 0.3, 6.0))
    ax.scatter(xy[:, 0], xy[:, 1], c=share, cmap=ORDER_CMAP, norm=Normalize(0.0, 1.0), s=size,
               linewidths=0, zorder=3)  # fmt: skip
    ax.set_xticks([])
    ax.set_yticks([])
    return line
