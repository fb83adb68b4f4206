"""Paper figures from tidy results and unit arrays (matplotlib only).

Every function returns ``(Figure, Axes)`` (or an array of Axes for panels) and accepts ``ax=``
to draw into an existing axes, so figures compose into multi-panel layouts. Sizes are for a
single column (3.4 in) or a full page width (7.0 in) at 300 dpi.
"""

from __future__ import annotations

import math
import textwrap
from collections import defaultdict
from collections.abc import Iterable, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from simlunar.metrics import METRIC_NAMES
from simlunar.plotting.style import label, metric_axis, pair_label, style, styles

COLUMN_W = 3.4  # in, one column of a two-column paper
PAGE_W = 7.0  # in, full page width
#: fixed colours so a strategy looks the same in every figure (see simlunar.plotting.style)
STRATEGY_COLORS = {
    n: style(n).colour for n in ("random", "grid", "gradient", "entropy", "wavelet", "saliency")
}
#: what the shaded band of :func:`error_vs_density` shows (legend entry and caption text)
BAND_LABEL = "band: ±1 s.d. over trials"
#: the band when each panel pools the realisations of several terrain seeds
BAND_LABEL_SEEDS = "band: ±1 s.d. over terrain seeds × trials"
#: panels per row of a multi-panel figure (three single-column panels fill a page width)
MAX_COLS = 3


def _axes(ax, figsize):
    if ax is not None:
        return ax.figure, ax
    fig, ax = plt.subplots(figsize=figsize, constrained_layout=True)
    return fig, ax


def _f(v) -> float:
    return float(v)


def mean_error_by_density(
    rows: Iterable[dict], *, metric: str, strategy: str, where: dict | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean and standard deviation over trials of a metric, per density.

    Parameters
    ----------
    rows : iterable of dict
        Tidy rows (strategy, density, trial, metric, value; strings from CSV are fine).
    metric, strategy : str
        Which curve.
    where : dict, optional
        Extra column filters (e.g. ``{"unit": "0"}``), compared as strings; a list, tuple or
        set value keeps rows whose column is any of its items (``{"unit": [0, 3]}`` pools two
        units).

    Returns
    -------
    densities (n,), mean (n,), std (n,) : float64 arrays, densities descending.
    """
    groups: dict[float, list[float]] = defaultdict(list)
    allowed = {
        k: {str(x) for x in v} if isinstance(v, list | tuple | set | frozenset) else {str(v)}
        for k, v in (where or {}).items()
    }
    for r in rows:
        if r["metric"] != metric or r["strategy"] != strategy:
            continue
        if any(str(r.get(k)) not in ok for k, ok in allowed.items()):
            continue
        groups[_f(r["density"])].append(_f(r["value"]))
    d = np.array(sorted(groups, reverse=True), float)
    vals = [np.asarray(groups[x], float) for x in d]
    mean = np.array([v.mean() for v in vals]) if vals else np.zeros(0)
    std = np.array([v.std(ddof=1) if v.size > 1 else 0.0 for v in vals]) if vals else np.zeros(0)
    return d, mean, std


def error_vs_density(
    rows: Sequence[dict],
    *,
    metric: str = "mse",
    strategies: Sequence[str] | None = None,
    where: dict | None = None,
    ax=None,
    title: str | None = None,
    band_label: str = BAND_LABEL,
):
    """Reconstruction error against sampling density per strategy (paper Fig. 3).

    Log-log axes; the line is the mean over the rows ``where`` selects (the trials of one unit,
    or of several pooled units), the band +- one standard deviation over them (``band_label``,
    also a legend entry). Density falls to the right, as in the paper. Colours, markers and
    labels come from :mod:`simlunar.plotting.style`.
    """
    from matplotlib.patches import Patch

    fig, ax = _axes(ax, (COLUMN_W, 2.6))
    if strategies is None:
        strategies = list(dict.fromkeys(r["strategy"] for r in rows))
    st = styles(strategies)
    band = False
    for s in strategies:
        d, m, sd = mean_error_by_density(rows, metric=metric, strategy=s, where=where)
        if d.size == 0:
            continue
        c = st[s].colour
        ax.plot(d, m, marker=st[s].marker, ms=3, lw=1.2, color=c, label=st[s].label)
        if np.any(sd > 0):
            lo = np.clip(m - sd, np.nanmin(m[m > 0]) * 0.5 if np.any(m > 0) else 1e-12, None)
            ax.fill_between(d, lo, m + sd, color=c, alpha=0.15, lw=0)
            band = True
    ax.set_xscale("log", base=2)
    if any(
        line.get_ydata().size and np.all(np.asarray(line.get_ydata()) > 0)
        for line in ax.get_lines()
    ):
        ax.set_yscale("log")
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi * (hi / lo) ** 0.25)  # headroom for the legend
    ax.invert_xaxis()
    ax.set_xlabel("sampling density k/N")
    ax.set_ylabel(metric_axis(metric))
    if title:
        ax.set_title(title, fontsize=9)
    handles, labels = ax.get_legend_handles_labels()
    if band:
        handles.append(Patch(color="0.5", alpha=0.3, lw=0))
        labels.append(band_label)
    # errors rise to the right (density falls), so the upper left is empty
    ax.legend(handles, labels, fontsize=5.5, frameon=False, loc="upper left", handlelength=1.6)
    ax.grid(True, which="major", alpha=0.3)
    return fig, ax


def _sweep_positions(xs: Sequence) -> tuple[bool, np.ndarray]:
    """``(numeric, positions)`` of sweep values: numbers where they all are, else 0, 1, ..."""
    numeric = all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in xs)
    return numeric, np.asarray(xs, float) if numeric else np.arange(len(xs), dtype=float)


def _category_ticks(ax, pos: np.ndarray, xs: Sequence) -> None:
    """One tick per category (display labels), half a slot of margin either side."""
    ax.set_xticks(pos, [label(str(x)) for x in xs], fontsize=7)
    ax.set_xlim(pos[0] - 0.5, pos[-1] + 0.5)


def score_vs_sweep(
    points: Sequence[tuple[object, dict]],
    *,
    metric: str = "mse",
    strategies: Sequence[str] | None = None,
    axis_label: str = "",
    ax=None,
    title: str | None = None,
):
    """Score (eq. 4.3) against a sweep axis, one series per strategy (ablations).

    A numeric axis draws lines; a categorical one (labels such as ``"sun"``, ``"camera"``)
    draws unconnected markers per category, side by side, since nothing lies between two
    categories.

    Parameters
    ----------
    points : sequence of (x, scores)
        ``x`` a number or a label; ``scores`` maps metric -> strategy -> score.
    axis_label : str
        Readable axis name (see :func:`simlunar.plotting.style.axis_name`).
    """
    fig, ax = _axes(ax, (COLUMN_W, 2.6))
    xs = [p[0] for p in points]
    numeric, pos = _sweep_positions(xs)
    if strategies is None:
        strategies = list(dict.fromkeys(s for _, sc in points for s in sc.get(metric, {})))
    st = styles(strategies)
    n = max(len(strategies), 1)
    for i, s in enumerate(strategies):
        y = np.array([sc.get(metric, {}).get(s, math.nan) for _, sc in points], float)
        if numeric:
            ax.plot(
                pos, y, marker=st[s].marker, ms=3, lw=1.2, color=st[s].colour, label=st[s].label
            )
        else:
            dodge = (i - (n - 1) / 2) * min(0.6 / n, 0.12)
            ax.plot(
                pos + dodge,
                y,
                marker=st[s].marker,
                ms=4,
                ls="none",
                color=st[s].colour,
                label=st[s].label,
            )
    ax.axhline(1.0, color="k", lw=0.6, ls=":")
    if not numeric:
        _category_ticks(ax, pos, xs)
    ax.set_xlabel(axis_label)
    ax.set_ylabel(f"{_metric_name(metric)} score (random = 1)")
    if title:
        ax.set_title(title, fontsize=9)
    ax.legend(fontsize=6, frameon=False)
    ax.grid(True, alpha=0.3)
    return fig, ax


def _metric_name(metric: str) -> str:
    """Display name of a metric (``"mse"`` -> ``"MSE"``)."""
    return METRIC_NAMES.get(metric, metric)


def _show(ax, img, title, cmap="gray", **kw):
    im = ax.imshow(img, cmap=cmap, interpolation="nearest", **kw)
    ax.set_title(title, fontsize=7)
    ax.set_xticks([])
    ax.set_yticks([])
    return im


def _cbar(fig, im, ax, text):
    cb = fig.colorbar(im, ax=ax, shrink=0.7, pad=0.02)
    cb.set_label(text, fontsize=6)
    cb.ax.tick_params(labelsize=6)
    return cb


#: at most this share of a samples panel is covered by sample markers (the rest shows the
#: image under them, so where samples concentrate stays visible at any density)
SAMPLE_INK = 0.15


def sample_marker_area(ax, k: int, *, ink: float = SAMPLE_INK) -> float:
    """Scatter marker area (pt²) for ``k`` samples on ``ax``: ``ink`` of the axes' area over
    ``k``, between 0.05 pt² (a dot still visible at 300 dpi) and 4 pt² (few samples)."""
    w, h = ax.bbox.width, ax.bbox.height  # display pixels at the figure's dpi
    area_pt2 = w * h * (72.0 / ax.figure.dpi) ** 2
    return float(np.clip(ink * area_pt2 / max(int(k), 1), 0.05, 4.0))


def image_panels(
    image: np.ndarray,
    energy: np.ndarray,
    plan_rows: np.ndarray,
    plan_cols: np.ndarray,
    reconstruction: np.ndarray,
    truth: np.ndarray,
    *,
    axes=None,
    density_label: str = "",
    planner: str = "wavelet",
    point: str = "",
):
    """Guide image, wavelet energy map, sample locations, truth, reconstruction and error map.

    Panels (2 x 3): guide image | wavelet energy (log10, colour bar) | the planner's samples on
    the guide image; true depth | reconstruction (same colour scale, colour bar in m) | error
    reconstruction - truth (m, symmetric scale at the 99th percentile of |error|).

    Parameters
    ----------
    image : (rows, cols) float
        Guide (sensor) image.
    energy : (rows, cols) float
        Frequency map (wavelet energy), shown on a log scale.
    plan_rows, plan_cols : (k,) int
        Sampled pixels.
    reconstruction, truth : (rows, cols) float
        Reconstructed and true depth (m); the error map is their difference.
    axes : sequence of 6 Axes, optional
    density_label : str
        Sweep-independent density text for the samples panel, e.g. ``"k/N = 1/32"``.
    planner : str
        Strategy that placed the samples (its display label titles the samples panel).
    point : str
        Sweep point or scene the panels show (figure title), e.g. ``"elevation_deg=30"``.

    Returns
    -------
    (Figure, ndarray of Axes)
    """
    if axes is None:
        fig, axes = plt.subplots(2, 3, figsize=(PAGE_W, 3.9), constrained_layout=True)
    else:
        fig = axes[0].figure if isinstance(axes, (list, tuple)) else np.ravel(axes)[0].figure
    axes = np.asarray(axes).ravel()
    if len(axes) < 6:
        raise ValueError(f"axes: 6 panels need 6 axes, got {len(axes)}")
    top = max(float(np.nanmax(image)), 1e-12)
    im = _show(axes[0], image, "guide image", vmin=0, vmax=top)
    _cbar(fig, im, axes[0], "sensor value (0-1)")
    e = np.asarray(energy, float)
    pos = e[e > 0]
    floor = float(np.percentile(pos, 1)) if pos.size else 1e-12
    im = _show(axes[1], np.log10(np.maximum(e, floor)), "wavelet energy", cmap="magma")
    _cbar(fig, im, axes[1], "log10 energy")
    dens = f", {density_label.strip('() ')}" if density_label else ""
    _show(axes[2], image, f"{label(planner)} samples{dens}", vmin=0, vmax=top)
    k = len(np.asarray(plan_rows))
    axes[2].scatter(
        np.asarray(plan_cols),
        np.asarray(plan_rows),
        s=sample_marker_area(axes[2], k),
        c="#d62728",
        linewidths=0,
        rasterized=k > 2000,  # a PDF of tens of thousands of vector dots is slow to open
    )
    vmin, vmax = float(np.nanmin(truth)), float(np.nanmax(truth))
    _show(axes[3], truth, "true depth", cmap="terrain_r", vmin=vmin, vmax=vmax)
    im = _show(
        axes[4],
        reconstruction,
        f"reconstruction ({len(np.asarray(plan_rows))} samples)",
        cmap="terrain_r",
        vmin=vmin,
        vmax=vmax,
    )
    _cbar(fig, im, axes[3:5].tolist(), "depth (m)")
    err = np.asarray(reconstruction, float) - np.asarray(truth, float)
    lim = float(np.nanpercentile(np.abs(err), 99)) or 1e-12
    im = _show(axes[5], err, "error: reconstruction - truth", cmap="coolwarm", vmin=-lim, vmax=lim)
    _cbar(fig, im, axes[5], "error (m)")
    if point:
        fig.suptitle(point, fontsize=8)
    return fig, axes


def sparse_mesh_panels(
    sparse: np.ndarray,
    full: np.ndarray,
    energy: np.ndarray | None = None,
    *,
    rough: np.ndarray | None = None,
    axes=None,
    n_samples: int | None = None,
    point: str = "",
):
    """Paper Fig. 4: sparse-mesh renderings next to the full-resolution ground truth.

    Panels, left to right: the sparse mesh with roughness modulated by wavelet energy and
    the difference of that render from the constant-roughness one (when ``rough`` is given),
    the sparse mesh with constant roughness, the full-resolution render, and the frequency
    map (when ``energy`` is given). All renders share one exposure (the 99.5th percentile of
    ``full``), so brightness differences are real; the difference panel is in units of that
    exposure, on a symmetric scale.

    Parameters
    ----------
    sparse, full : (rows, cols) or (rows, cols, 3) float
        Renders of the reconstructed (sparse) mesh with constant roughness and of the
        full-resolution terrain, linear.
    energy : (rows, cols) float, optional
        The frequency map that modulated the roughness (log scale).
    rough : (rows, cols) or (rows, cols, 3) float, optional
        Render of the sparse mesh with per-cell roughness from ``energy``, linear.
    axes : sequence of Axes, optional
        One per panel.
    n_samples : int, optional
        Number of samples of the sparse mesh (shown in the titles).
    point : str
        Sweep point or scene (figure title).
    """
    n = 2 + 2 * (rough is not None) + (energy is not None)
    if axes is None:
        nr = 1 if n <= 3 else 2
        nc = -(-n // nr)
        fig, grid = plt.subplots(
            nr, nc, figsize=(PAGE_W, nr * PAGE_W / nc * 0.78), constrained_layout=True
        )
        for extra in np.ravel(grid)[n:]:
            extra.axis("off")
        axes = np.ravel(grid)[:n]
    else:
        fig = np.ravel(axes)[0].figure
    axes = list(np.asarray(axes).ravel())
    if len(axes) < n:
        raise ValueError(f"axes: {n} panels need {n} axes, got {len(axes)}")
    top = max(float(np.nanpercentile(full, 99.5)), 1e-12)
    label_ = f"sparse mesh ({n_samples} samples)" if n_samples else "sparse mesh"
    i = 0
    if rough is not None:
        _show(axes[i], np.clip(rough / top, 0, 1), f"{label_},\nroughness from energy")
        diff = np.asarray(rough, float) / top - np.asarray(sparse, float) / top
        if diff.ndim == 3:
            diff = diff.mean(axis=2)
        lim = float(np.nanmax(np.abs(diff))) or 1e-12
        im = _show(
            axes[i + 1],
            diff,
            f"energy - constant roughness\n(max {100 * lim:.2g} % of exposure)",
            cmap="coolwarm",
            vmin=-lim,
            vmax=lim,
        )
        _cbar(fig, im, axes[i + 1], "Δ radiance / exposure")
        i += 2
    _show(axes[i], np.clip(sparse / top, 0, 1), f"{label_},\nconstant roughness")
    _show(axes[i + 1], np.clip(full / top, 0, 1), "full resolution")
    if energy is not None:
        e = np.asarray(energy, float)
        pos = e[e > 0]
        floor = float(np.percentile(pos, 1)) if pos.size else 1e-12
        im = _show(axes[i + 2], np.log10(np.maximum(e, floor)), "frequency map", cmap="magma")
        _cbar(fig, im, axes[i + 2], "log10 wavelet energy")
    if point:
        fig.suptitle(point, fontsize=8)
    return fig, np.asarray(axes[:n])


def scanner_bars(summary: Sequence[dict], *, metric: str = "mse", ax=None):
    """Bar chart of a scanner-study metric per (mode, planner).

    Each entry of ``summary`` has ``mode``, ``planner`` (or empty) and the mean of ``metric``;
    an optional ``f"{metric}_sd"`` (standard deviation over trials and seeds) draws an error
    bar of +- one s.d., and ``n`` (the number of values) goes into the tick label.
    """
    fig, ax = _axes(ax, (COLUMN_W, 2.6))
    labels = [
        pair_label(e["mode"], e.get("planner")) if "mode" in e else e["label"] for e in summary
    ]
    vals = [e.get(metric) if e.get(metric) is not None else math.nan for e in summary]
    sds = [e.get(f"{metric}_sd") for e in summary]
    yerr = None if all(s is None for s in sds) else [math.nan if s is None else s for s in sds]
    colors = [style(e.get("planner") or e.get("mode") or "").colour for e in summary]
    ax.bar(range(len(vals)), vals, color=colors, yerr=yerr, capsize=2, error_kw={"lw": 0.8})
    # horizontal, wrapped at word boundaries so a long pair label stays within its bar's width
    width = max(8, int(56 / max(len(vals), 1)))  # characters of 6 pt text per bar
    wrapped = [textwrap.fill(t, width, break_long_words=False) for t in labels]
    ticks = [f"{t}\n(n = {e['n']})" if e.get("n") else t for t, e in zip(wrapped, summary)]
    ax.set_xticks(range(len(vals)), ticks, fontsize=6)
    ax.set_ylabel(metric_axis(metric))
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
        factor of 20) or ``"valid_fraction"`` (linear: 0 to 1, or zoomed in on the values
        when all are above 0.5).
    secondary : (factor, label), optional
        A second x axis on top, ``factor`` times the swept value (numeric axes), e.g. the
        sun-to-projector ratio the camera saw against the sun's irradiance.

    A numeric axis spanning more than a factor of 20 (all positive) is drawn on a log scale;
    a categorical one gets one tick per label, markers unconnected.
    """
    fig, ax = _axes(ax, (COLUMN_W, 2.6))
    xs = [p[0] for p in points]
    numeric, pos = _sweep_positions(xs)
    keys = list(dict.fromkeys((e["mode"], e.get("planner") or "") for _, s in points for e in s))
    allv = []
    for mode, planner in keys:
        name = planner or mode
        st = style(name)
        y, sd = [], []
        for _, summary in points:
            e = next(
                (e for e in summary if (e["mode"], e.get("planner") or "") == (mode, planner)), {}
            )
            v = e.get(metric)
            y.append(math.nan if v is None else float(v))
            s_ = e.get(f"{metric}_sd")
            sd.append(0.0 if s_ is None else float(s_))
        y = np.asarray(y)
        allv += [v for v in y if np.isfinite(v)]
        ax.errorbar(
            pos,
            y,
            yerr=np.asarray(sd) if any(sd) else None,
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
        k, text = secondary
        top = ax.secondary_xaxis("top", functions=(lambda x: x * k, lambda x: x / k))
        top.set_xlabel(text, fontsize=7)
        top.tick_params(labelsize=6)
    if metric == "valid_fraction":
        lo = min(allv) if allv else 0.0
        if lo > 0.5:  # all close to 1: zoom in so a change of a few tenths of a percent shows
            pad = max(0.15 * (1.0 - lo), 5e-4)
            ax.set_ylim(lo - pad, 1.0 + pad)
        else:
            ax.set_ylim(-0.02, 1.02)
        ax.set_ylabel("valid fraction of guide pixels")
    else:
        if allv and min(allv) > 0 and max(allv) / min(allv) > 20:
            ax.set_yscale("log")
        ax.set_ylabel(metric_axis(metric))
    ax.set_xlabel(axis_label)
    if title:
        ax.set_title(title, fontsize=9)
    ax.legend(fontsize=6, frameon=False)
    ax.grid(True, alpha=0.3)
    return fig, ax


def bit_error_rates(rates: dict[str, float], *, ax=None):
    """Gray-code bit error rate per bit (``ber_c<i>`` columns, ``ber_r<i>`` rows; MSB = 0).

    When every rate is zero the figure says so in its axes (no curve on a meaningless axis).
    """
    fig, ax = _axes(ax, (COLUMN_W, 2.4))
    drawn = False
    for prefix, name, color in (
        ("ber_c", "column bits", "#1f77b4"),
        ("ber_r", "row bits", "#ff7f0e"),
    ):
        items = sorted((int(k[len(prefix) :]), v) for k, v in rates.items() if k.startswith(prefix))
        if items:
            ax.plot(
                [i for i, _ in items],
                [v for _, v in items],
                marker="o",
                ms=3,
                color=color,
                label=name,
            )
            drawn = True
    ax.set_xlabel("bit (0 = most significant)")
    ax.set_ylabel("bit error rate (fraction)")
    vals = [float(v) for v in rates.values()]
    if drawn and vals and max(vals) == 0:
        ax.set_ylim(-0.05, 1.0)
        ax.text(
            0.5,
            0.5,
            f"no bit errors: all {len(vals)} per-bit rates are 0",
            transform=ax.transAxes,
            ha="center",
            va="center",
            fontsize=8,
        )
    elif drawn:
        ax.set_ylim(0, max(vals) * 1.15)
    if drawn:
        ax.legend(fontsize=7, frameon=False)
    ax.grid(True, alpha=0.3)
    return fig, ax


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
    past ``n`` in the last row are removed.
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
    return fig, flat[:n]


def shared_legend(fig: Figure, axes: Sequence, *, prune_labels: bool = True) -> None:
    """Replace the panels' legends by one figure legend below them (multi-panel figures).

    The entries are the first panel's (panels of one figure share strategies and styles), in
    one row when they fit, so no legend covers a curve in a small panel. With
    ``prune_labels`` (panels that share their axes' quantities) axis labels stay on the left
    column (y) and the bottom panel of each column (x) only.
    """
    handles, labels = [], []
    for ax in axes:
        leg = ax.get_legend()
        if leg is not None:
            if not handles:
                # the artists themselves (an errorbar keeps its marker and bars), then
                # entries only the legend has (the band's patch)
                handles, labels = (list(x) for x in ax.get_legend_handles_labels())
                for h, t in zip(leg.legend_handles, leg.get_texts()):
                    if t.get_text() not in labels:
                        handles.append(h)
                        labels.append(t.get_text())
            leg.remove()
    if handles:
        fig.legend(
            handles,
            labels,
            loc="outside lower center",
            ncols=min(len(labels), 4),
            fontsize=7,
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


def save(fig: Figure, path_stem, formats: Sequence[str] = ("png", "pdf"), dpi: int = 300) -> list:
    """Render a figure to bytes per format: returns [(suffix, bytes)] (the caller writes them)."""
    import io

    out = []
    for fmt in formats:
        buf = io.BytesIO()
        # fixed metadata so the same data gives byte-identical files
        meta = {"Software": None} if fmt == "png" else {"CreationDate": None, "Producer": None}
        fig.savefig(buf, format=fmt, dpi=dpi, metadata=meta)
        out.append((fmt, buf.getvalue()))
    return out


def samples_saved_plot(
    densities: Sequence[float],
    factor: dict,
    flag: dict,
    *,
    reference: str = "random",
    metric: str = "mse",
    strategies: Sequence[str] | None = None,
    ax=None,
    title: str | None = None,
):
    """Samples saved at equal error against ``reference``, per density and strategy.

    Parameters
    ----------
    densities : sequence of float (n,)
        k / N of each point.
    factor : dict of str -> array (n,)
        Samples the reference needs for the strategy's error / the strategy's samples
        (:func:`simlunar.study.stats.samples_saved`); > 1 = the strategy saves samples.
    flag : dict of str -> array (n,)
        0 where interpolated on the reference's measured curve, else extrapolated (drawn as
        hollow markers).
    reference, metric : str
        Names for the labels; the reference itself is not drawn (its factor is 1, the
        dotted line).
    strategies : sequence of str, optional
        Order (default: ``factor``'s).
    """
    fig, ax = _axes(ax, (COLUMN_W, 2.6))
    d = np.asarray(densities, float)
    names = [s for s in (strategies or list(factor)) if s in factor and s != reference]
    look = styles(names)
    for s in names:
        y = np.asarray(factor[s], float)
        extra = np.asarray(flag[s]) != 0
        c, mk = look[s].colour, look[s].marker
        ax.plot(d, y, lw=1.2, color=c, label=look[s].label)
        ax.plot(d[~extra], y[~extra], mk, ms=3, color=c)
        ax.plot(d[extra], y[extra], mk, ms=3.5, mfc="none", mec=c, mew=0.8)
    ax.axhline(1.0, color="k", lw=0.6, ls=":")
    ax.set_xscale("log", base=2)
    if names and all(np.all(np.asarray(factor[s]) > 0) for s in names):
        ax.set_yscale("log", base=2)
    ax.invert_xaxis()
    ref = label(reference)
    from matplotlib.ticker import FuncFormatter

    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.set_xlabel("sampling density k/N")
    ax.set_ylabel(f"{ref} samples / own, equal {METRIC_NAMES.get(metric, metric)}", fontsize=8)
    ax.set_title(title or f"samples saved vs {ref} (hollow: extrapolated)", fontsize=8)
    ax.legend(fontsize=6, frameon=False)
    ax.grid(True, which="major", alpha=0.3)
    return fig, ax
