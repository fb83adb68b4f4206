"""Paper figures from tidy results and unit arrays (matplotlib only).

Every function returns ``(Figure, Axes)`` (or an array of Axes for panels) and accepts ``ax=``
to draw into an existing axes, so figures compose into multi-panel layouts. Sizes are for a
single column (3.4 in) or a full page width (7.0 in) at 300 dpi.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterable, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from simlunar.metrics import METRIC_NAMES
from simlunar.planner import STRATEGY_NAMES

COLUMN_W = 3.4  # in, one column of a two-column paper
PAGE_W = 7.0  # in, full page width
#: fixed colours so a strategy looks the same in every figure
STRATEGY_COLORS = {
    "random": "#7f7f7f",
    "grid": "#1f77b4",
    "gradient": "#ff7f0e",
    "entropy": "#2ca02c",
    "wavelet": "#d62728",
    "saliency": "#9467bd",
}


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
        Extra column filters (e.g. ``{"unit": "0"}``), compared as strings.

    Returns
    -------
    densities (n,), mean (n,), std (n,) : float64 arrays, densities descending.
    """
    groups: dict[float, list[float]] = defaultdict(list)
    for r in rows:
        if r["metric"] != metric or r["strategy"] != strategy:
            continue
        if where and any(str(r.get(k)) != str(v) for k, v in where.items()):
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
):
    """Reconstruction error against sampling density per strategy (paper Fig. 3).

    Log-log axes; the band is +- one standard deviation over trials. Density falls to the
    right, as in the paper.
    """
    fig, ax = _axes(ax, (COLUMN_W, 2.6))
    if strategies is None:
        strategies = list(dict.fromkeys(r["strategy"] for r in rows))
    for s in strategies:
        d, m, sd = mean_error_by_density(rows, metric=metric, strategy=s, where=where)
        if d.size == 0:
            continue
        c = STRATEGY_COLORS.get(s)
        ax.plot(d, m, marker="o", ms=3, lw=1.2, color=c, label=STRATEGY_NAMES.get(s, s))
        lo = np.clip(m - sd, np.nanmin(m[m > 0]) * 0.5 if np.any(m > 0) else 1e-12, None)
        ax.fill_between(d, lo, m + sd, color=c, alpha=0.15, lw=0)
    ax.set_xscale("log", base=2)
    if any(
        line.get_ydata().size and np.all(np.asarray(line.get_ydata()) > 0)
        for line in ax.get_lines()
    ):
        ax.set_yscale("log")
    ax.invert_xaxis()
    ax.set_xlabel("sampling density k/N")
    ax.set_ylabel(f"{METRIC_NAMES.get(metric, metric)} error")
    if title:
        ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, frameon=False)
    ax.grid(True, which="major", alpha=0.3)
    return fig, ax


def score_vs_sweep(
    points: Sequence[tuple[object, dict]],
    *,
    metric: str = "mse",
    strategies: Sequence[str] | None = None,
    axis_label: str = "",
    ax=None,
    title: str | None = None,
):
    """Score (eq. 4.3) against a sweep axis, one line per strategy (ablations).

    Parameters
    ----------
    points : sequence of (x, scores)
        ``x`` a number or a label; ``scores`` maps metric -> strategy -> score.
    """
    fig, ax = _axes(ax, (COLUMN_W, 2.6))
    xs = [p[0] for p in points]
    numeric = all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in xs)
    pos = np.asarray(xs, float) if numeric else np.arange(len(xs), dtype=float)
    if strategies is None:
        strategies = list(dict.fromkeys(s for _, sc in points for s in sc.get(metric, {})))
    for s in strategies:
        y = np.array([sc.get(metric, {}).get(s, math.nan) for _, sc in points], float)
        ax.plot(
            pos,
            y,
            marker="o",
            ms=3,
            lw=1.2,
            color=STRATEGY_COLORS.get(s),
            label=STRATEGY_NAMES.get(s, s),
        )
    ax.axhline(1.0, color="k", lw=0.6, ls=":")
    if not numeric:
        ax.set_xticks(pos, [str(x) for x in xs], rotation=20, fontsize=7)
    ax.set_xlabel(axis_label)
    ax.set_ylabel(f"{METRIC_NAMES.get(metric, metric)} score (random = 1)")
    if title:
        ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, frameon=False)
    ax.grid(True, alpha=0.3)
    return fig, ax


def _show(ax, img, title, cmap="gray", **kw):
    im = ax.imshow(img, cmap=cmap, interpolation="nearest", **kw)
    ax.set_title(title, fontsize=8)
    ax.set_xticks([])
    ax.set_yticks([])
    return im


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
):
    """Guide image, wavelet energy map, sample locations, reconstruction and error map.

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
    axes : sequence of 5 Axes, optional

    Returns
    -------
    (Figure, ndarray of Axes)
    """
    if axes is None:
        fig, axes = plt.subplots(1, 5, figsize=(PAGE_W, 1.9), constrained_layout=True)
    else:
        fig = axes[0].figure
    axes = np.asarray(axes).ravel()
    _show(axes[0], image, "guide image", vmin=0, vmax=max(float(np.nanmax(image)), 1e-12))
    e = np.asarray(energy, float)
    pos = e[e > 0]
    floor = float(np.percentile(pos, 1)) if pos.size else 1e-12
    _show(axes[1], np.log10(np.maximum(e, floor)), "wavelet energy (log)", cmap="magma")
    _show(
        axes[2],
        image,
        f"samples {density_label}".strip(),
        vmin=0,
        vmax=max(float(np.nanmax(image)), 1e-12),
    )
    axes[2].scatter(np.asarray(plan_cols), np.asarray(plan_rows), s=0.8, c="#d62728", linewidths=0)
    vmin, vmax = float(np.nanmin(truth)), float(np.nanmax(truth))
    _show(axes[3], reconstruction, "reconstruction", cmap="terrain_r", vmin=vmin, vmax=vmax)
    err = np.asarray(reconstruction, float) - np.asarray(truth, float)
    lim = float(np.nanpercentile(np.abs(err), 99)) or 1e-12
    im = _show(axes[4], err, "error (m)", cmap="coolwarm", vmin=-lim, vmax=lim)
    fig.colorbar(im, ax=axes[4], shrink=0.8)
    return fig, axes


def sparse_mesh_panels(
    sparse: np.ndarray,
    full: np.ndarray,
    energy: np.ndarray | None = None,
    *,
    rough: np.ndarray | None = None,
    axes=None,
    n_samples: int | None = None,
):
    """Paper Fig. 4: sparse-mesh renderings next to the full-resolution ground truth.

    Panels, left to right: the sparse mesh with roughness modulated by wavelet energy (when
    ``rough`` is given), the sparse mesh with constant roughness, the full-resolution render,
    and the frequency map (when ``energy`` is given). All renders share one exposure (the
    99.5th percentile of ``full``), so brightness differences are real.

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
    """
    n = 2 + (rough is not None) + (energy is not None)
    if axes is None:
        fig, axes = plt.subplots(1, n, figsize=(PAGE_W, PAGE_W / n), constrained_layout=True)
    else:
        fig = axes[0].figure
    axes = list(np.asarray(axes).ravel())
    if len(axes) < n:
        raise ValueError(f"axes: {n} panels need {n} axes, got {len(axes)}")
    top = max(float(np.nanpercentile(full, 99.5)), 1e-12)
    label = f"sparse mesh ({n_samples} samples)" if n_samples else "sparse mesh"
    i = 0
    if rough is not None:
        _show(axes[i], np.clip(rough / top, 0, 1), f"{label},\nroughness from energy")
        i += 1
    _show(axes[i], np.clip(sparse / top, 0, 1), f"{label},\nconstant roughness")
    _show(axes[i + 1], np.clip(full / top, 0, 1), "full resolution")
    if energy is not None:
        e = np.asarray(energy, float)
        pos = e[e > 0]
        floor = float(np.percentile(pos, 1)) if pos.size else 1e-12
        _show(axes[i + 2], np.log10(np.maximum(e, floor)), "frequency map", cmap="magma")
    return fig, np.asarray(axes[:n])


def scanner_bars(summary: Sequence[dict], *, metric: str = "mse", ax=None):
    """Bar chart of a scanner-study metric per (mode, planner) (means over trials)."""
    fig, ax = _axes(ax, (COLUMN_W, 2.6))
    labels = [e["label"] for e in summary]
    vals = [e.get(metric) if e.get(metric) is not None else math.nan for e in summary]
    colors = [STRATEGY_COLORS.get(e.get("planner") or "", "#1f77b4") for e in summary]
    ax.bar(range(len(vals)), vals, color=colors)
    ax.set_xticks(range(len(vals)), labels, rotation=25, ha="right", fontsize=6)
    ax.set_ylabel(f"{METRIC_NAMES.get(metric, metric)} error")
    ax.grid(True, axis="y", alpha=0.3)
    return fig, ax


def bit_error_rates(rates: dict[str, float], *, ax=None):
    """Gray-code bit error rate per bit (``ber_c<i>`` columns, ``ber_r<i>`` rows; MSB = 0)."""
    fig, ax = _axes(ax, (COLUMN_W, 2.4))
    for prefix, label, color in (
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
                label=label,
            )
    ax.set_xlabel("bit (0 = most significant)")
    ax.set_ylabel("bit error rate")
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
    cycle = plt.rcParams["axes.prop_cycle"].by_key().get("color", ["k"])
    for i, s in enumerate(names):
        y = np.asarray(factor[s], float)
        extra = np.asarray(flag[s]) != 0
        c = STRATEGY_COLORS.get(s, cycle[i % len(cycle)])
        ax.plot(d, y, lw=1.2, color=c, label=STRATEGY_NAMES.get(s, s))
        ax.plot(d[~extra], y[~extra], "o", ms=3, color=c)
        ax.plot(d[extra], y[extra], "o", ms=3.5, mfc="none", mec=c, mew=0.8)
    ax.axhline(1.0, color="k", lw=0.6, ls=":")
    ax.set_xscale("log", base=2)
    if names and all(np.all(np.asarray(factor[s]) > 0) for s in names):
        ax.set_yscale("log", base=2)
    ax.invert_xaxis()
    ref = STRATEGY_NAMES.get(reference, reference)
    from matplotlib.ticker import FuncFormatter

    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.set_xlabel("sampling density k/N")
    ax.set_ylabel(f"{ref} samples / own, equal {METRIC_NAMES.get(metric, metric)}", fontsize=8)
    ax.set_title(title or f"samples saved vs {ref} (hollow: extrapolated)", fontsize=8)
    ax.legend(fontsize=6, frameon=False)
    ax.grid(True, which="major", alpha=0.3)
    return fig, ax
