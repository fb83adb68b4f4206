"""Error and score figures of the sampling study: error against density (paper Fig. 3),
samples saved at equal error, and the score (eq. 4.3) against a sweep axis.

Every function returns ``(Figure, Axes)`` and accepts ``ax=`` to draw into an existing axes.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterable, Sequence
from fractions import Fraction

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter, NullLocator

from simlunar.metrics import METRIC_NAMES
from simlunar.plotting.layout import LABEL_PT, TICK_PT, TITLE_PT, legend_outside, new_axes
from simlunar.plotting.style import label, metric_axis, styles

__all__ = [
    "BAND_LABEL",
    "BAND_LABEL_SEEDS",
    "LEGEND_RIGHT_SIZE",
    "NICE_RATIOS",
    "RECONSTRUCTION_LINES",
    "REFERENCE",
    "density_axis",
    "density_label",
    "error_vs_density",
    "mean_error_by_density",
    "ratio_axis",
    "ratio_ticks",
    "reconstruction_linestyles",
    "samples_saved_plot",
    "score_vs_sweep",
]

#: what the shaded band of :func:`error_vs_density` shows (legend entry and caption text)
BAND_LABEL = "band: ±1 s.d. over trials"
#: the band when each panel pools the realisations of several terrain seeds
BAND_LABEL_SEEDS = "band: ±1 s.d. over terrain seeds × trials"
#: the reference every score is relative to: drawn last (on top), dashed
REFERENCE = "random"
#: single-panel size (one column) with the legend below the axes
LEGEND_RIGHT_SIZE = (3.6, 3.6)


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
        groups[float(r["density"])].append(float(r["value"]))
    d = np.array(sorted(groups, reverse=True), float)
    vals = [np.asarray(groups[x], float) for x in d]
    mean = np.array([v.mean() for v in vals]) if vals else np.zeros(0)
    std = np.array([v.std(ddof=1) if v.size > 1 else 0.0 for v in vals]) if vals else np.zeros(0)
    return d, mean, std


def density_label(d: float) -> str:
    """``0.25`` -> ``"1/4"``; a density that is no unit fraction as ``1/n`` with n = 1/d
    rounded (``0.15`` -> ``"1/7"``): the column headings of the score and samples-saved
    tables (:mod:`simlunar.plotting.tables`), so a tick reads as the table it belongs to."""
    f = Fraction(float(d)).limit_denominator(1 << 16)
    if f.numerator == 1 and abs(float(f) - d) <= 1e-9 * d:
        return f"1/{f.denominator}"
    if not 0 < d < 1:
        return f"{d:g}"
    return f"1/{round(1 / d)}"


def log_axis_labels(ax) -> None:
    """Label a log y axis across its whole range: with fewer than three labelled powers of
    ten inside the limits (data spanning two decades or less), ticks at 1, 2 and 5 times each
    power, every one labelled, so no stretch of the data reads off an unlabelled axis."""
    from matplotlib.ticker import LogFormatterSciNotation, LogLocator

    lo, hi = ax.get_ylim()
    if not (lo > 0 and hi > lo):
        return
    powers = [p for p in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)
              if lo <= 10.0**p <= hi]  # fmt: skip
    if len(powers) >= 3:
        return
    ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    ax.yaxis.set_major_formatter(
        LogFormatterSciNotation(base=10, labelOnlyBase=False, minor_thresholds=(math.inf, math.inf))
    )
    ax.yaxis.set_minor_locator(LogLocator(base=10, subs=tuple(range(2, 10))))
    ax.yaxis.set_minor_formatter(NullFormatter())


def density_axis(ax, densities: Sequence[float]) -> None:
    """Log2 x axis of sampling densities, falling to the right (as the paper's Fig. 3), a tick
    and a ``1/n`` label at every density (every other one when there are more than 8)."""
    d = sorted({float(x) for x in densities}, reverse=True)
    ax.set_xscale("log", base=2)
    if not ax.xaxis_inverted():
        ax.invert_xaxis()
    if not d:
        return
    step = 1 if len(d) <= 8 else 2
    ax.xaxis.set_major_locator(FixedLocator(d))
    shown = {x for i, x in enumerate(d) if i % step == 0}
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: density_label(v) if v in shown else ""))
    ax.xaxis.set_minor_locator(NullLocator())
    ax.tick_params(axis="x", labelsize=TICK_PT - 0.5)
    ax.set_xlabel("sampling density k/N", fontsize=LABEL_PT)


#: tick values of ratio axes (samples saved), readable as plain numbers
NICE_RATIOS = (0.1, 0.125, 0.2, 0.25, 0.33, 0.4, 0.5, 0.67, 0.8, 1, 1.25, 1.5, 2, 3, 4, 5, 8, 10)


def ratio_axis(ax, values: Iterable[float]) -> None:
    """Log2 y axis of ratios with plain-number ticks (3 or more inside the data's range)."""
    v = np.asarray([x for x in values if np.isfinite(x) and x > 0], float)
    if v.size == 0:
        return
    lo, hi = min(v.min(), 1.0), max(v.max(), 1.0)
    pad = (hi / lo) ** 0.08
    lo, hi = lo / pad, hi * pad
    ax.set_yscale("log", base=2)
    ax.set_ylim(lo, hi)
    ratio_ticks(ax.yaxis, lo, hi)


def ratio_ticks(axis, lo: float, hi: float) -> list[float]:
    """Put plain-number ticks at the :data:`NICE_RATIOS` in ``[lo, hi]`` on a log ``axis``.

    More than 7 are thinned to every other one, 1 kept; no minor ticks.

    Parameters
    ----------
    axis : matplotlib.axis.Axis
        ``ax.xaxis`` or ``ax.yaxis``.
    lo, hi : float
        The axis range (ratios, > 0).

    Returns
    -------
    list of float
        The ticks set.
    """
    ticks = [t for t in NICE_RATIOS if lo <= t <= hi]
    if len(ticks) > 7:  # keep every other one, 1 included
        i1 = ticks.index(1)
        ticks = [t for i, t in enumerate(ticks) if (i - i1) % 2 == 0]
    axis.set_major_locator(FixedLocator(ticks))
    axis.set_major_formatter(FuncFormatter(lambda t, _: f"{t:g}"))
    axis.set_minor_locator(NullLocator())
    axis.set_minor_formatter(NullFormatter())
    return ticks


def _density_curve(ax, d, m, sd, style, *, ls, ref: bool, recon: str | None) -> bool:
    """One strategy's (and reconstruction's) mean error curve and its +- one standard
    deviation band; True when a band was drawn. ``ref``: the random reference (thicker, on
    top)."""
    ax.plot(
        d,
        m,
        marker=style.marker,
        ms=3,
        lw=1.5 if ref else 1.1,
        ls=ls,
        color=style.colour,
        # by reconstruction the legend is built apart (an entry per planner and per
        # reconstruction); the leading "_" keeps a curve's own label out of legends that
        # gather the artists (shared_legend of a multi-panel figure)
        label=style.label if recon is None else f"_{style.label}, {label(recon)}",
        zorder=4 if ref else 2,
    )
    if not np.any(sd > 0):
        return False
    lo = np.clip(m - sd, np.nanmin(m[m > 0]) * 0.5 if np.any(m > 0) else 1e-12, None)
    ax.fill_between(d, lo, m + sd, color=style.colour, alpha=0.12, lw=0, zorder=1)
    return True


def _by_reconstruction_legend(st, lines, drawn_s: Sequence[str], drawn_r: Sequence[str]):
    """Legend handles and labels of a figure by reconstruction: one entry per planner
    (colour, marker), then one per reconstruction (line style)."""
    handles = [Line2D([], [], color=st[s].colour, marker=st[s].marker, ms=3, lw=1.1)
               for s in drawn_s]  # fmt: skip
    labels = [f"planner: {st[s].label}" for s in drawn_s]
    handles += [Line2D([], [], color="0.2", lw=1.1, ls=lines[r]) for r in drawn_r]
    labels += [f"reconstruction: {label(r)}" for r in drawn_r]
    return handles, labels


def error_vs_density(
    rows: Sequence[dict],
    *,
    metric: str = "mse",
    strategies: Sequence[str] | None = None,
    where: dict | None = None,
    ax=None,
    title: str | None = None,
    band_label: str = BAND_LABEL,
    reconstructions: Sequence[str] | None = None,
):
    """Reconstruction error against sampling density per strategy (paper Fig. 3).

    Log-log axes; the line is the mean over the rows ``where`` selects (the trials of one unit,
    or of several pooled units), the band +- one standard deviation over them (``band_label``,
    also a legend entry). Density falls to the right, as in the paper. The random reference
    is drawn last and dashed, so no curve hides it. The legend sits below the axes.

    With two or more ``reconstructions`` (the values of the rows' ``reconstruction`` column;
    rows without one are ``linear``'s) every strategy gets one curve per reconstruction:
    colour and marker name the planner, the line style the reconstruction
    (:func:`reconstruction_linestyles`), and the legend has an entry for each planner and
    each reconstruction. One reconstruction, or none given: the curves of the rows as
    ``where`` selects them, line style by placement.
    """
    fig, ax = new_axes(ax, LEGEND_RIGHT_SIZE)
    if strategies is None:
        strategies = list(dict.fromkeys(r["strategy"] for r in rows))
    st = styles(strategies)
    recons = list(reconstructions or [])
    by_recon = len(recons) >= 2
    lines = reconstruction_linestyles(recons)
    series = [(s, r) for s in strategies for r in recons] if by_recon else [
        (s, None) for s in strategies]  # fmt: skip
    data = _with_reconstruction(rows) if by_recon else rows
    band = False
    all_d: list[float] = []
    drawn_s: list[str] = []
    drawn_r: list[str] = []
    for s, r in series:
        sel = dict(where or {})
        if r is not None:
            sel["reconstruction"] = r
        d, m, sd = mean_error_by_density(data, metric=metric,
                                         strategy=s, where=sel)  # fmt: skip
        if d.size == 0:
            continue
        all_d += d.tolist()
        ls = lines[r] if r is not None else ("--" if s == REFERENCE else st[s].linestyle)
        band |= _density_curve(ax, d, m, sd, st[s], ls=ls, ref=s == REFERENCE, recon=r)
        drawn_s += [s] if s not in drawn_s else []
        drawn_r += [r] if r is not None and r not in drawn_r else []
    if any(
        line.get_ydata().size and np.all(np.asarray(line.get_ydata()) > 0)
        for line in ax.get_lines()
    ):
        ax.set_yscale("log")
        log_axis_labels(ax)
    density_axis(ax, all_d)
    ax.set_ylabel(metric_axis(metric), fontsize=LABEL_PT)
    ax.tick_params(axis="y", labelsize=TICK_PT)
    if title:
        ax.set_title(title, fontsize=TITLE_PT)
    if by_recon:  # one entry per planner (colour, marker) and per reconstruction (line)
        handles, labels = _by_reconstruction_legend(st, lines, drawn_s, drawn_r)
    else:
        handles, labels = ax.get_legend_handles_labels()
    if band:
        handles.append(Patch(color="0.5", alpha=0.3, lw=0))
        labels.append(band_label)
    legend_outside(ax, handles=handles, labels=labels)
    ax.grid(True, which="major", alpha=0.3)
    return fig, ax


#: line styles of the reconstructions of one figure, in their configured order (the first,
#: linear by default, solid)
RECONSTRUCTION_LINES = ("-", (0, (5, 2)), (0, (1, 1.2)), (0, (5, 1.5, 1, 1.5)),
                        (0, (8, 2, 1, 2, 1, 2)), (0, (2, 2)))  # fmt: skip


def reconstruction_linestyles(names: Sequence[str]) -> dict[str, str | tuple]:
    """One line style per reconstruction name: :data:`RECONSTRUCTION_LINES` in order, then
    dashes that grow by one point per further name, so no two names of a figure share one."""
    out: dict[str, str | tuple] = {}
    n = len(RECONSTRUCTION_LINES)
    for i, name in enumerate(dict.fromkeys(names)):
        out[name] = RECONSTRUCTION_LINES[i] if i < n else (0, (3 + i - n, 1, 1, 1))
    return out


def _with_reconstruction(rows: Sequence[dict]) -> list[dict] | Sequence[dict]:
    """Rows with a ``reconstruction`` column (``linear`` where a row names none, as rows of a
    study of one reconstruction are written)."""
    if all("reconstruction" in r and r["reconstruction"] for r in rows):
        return rows
    return [r if r.get("reconstruction") else {**r, "reconstruction": "linear"} for r in rows]


def _sweep_positions(xs: Sequence) -> tuple[bool, np.ndarray]:
    """``(numeric, positions)`` of sweep values: numbers where they all are, else 0, 1, ..."""
    numeric = all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in xs)
    return numeric, np.asarray(xs, float) if numeric else np.arange(len(xs), dtype=float)


def _category_ticks(ax, pos: np.ndarray, xs: Sequence) -> None:
    """One tick per category (display labels), half a slot of margin either side."""
    ax.set_xticks(pos, [label(str(x)) for x in xs], fontsize=TICK_PT)
    ax.set_xlim(pos[0] - 0.5, pos[-1] + 0.5)


def _cell(v) -> tuple[float, float, float]:
    """``(score, low, high)`` of a score given as a number or as ``(score, low, high)``."""
    if isinstance(v, (tuple, list)):
        s, lo, hi = (math.nan if x is None else float(x) for x in v)
        return s, lo, hi
    s = math.nan if v is None else float(v)
    return s, math.nan, math.nan


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
    categories. A score given as ``(score, low, high)`` draws its interval as an error bar.

    Parameters
    ----------
    points : sequence of (x, scores)
        ``x`` a number or a label; ``scores`` maps metric -> strategy -> score or
        ``(score, low, high)`` (a 95 % interval).
    axis_label : str
        Readable axis name (see :func:`simlunar.plotting.style.axis_name`).
    """
    fig, ax = new_axes(ax, LEGEND_RIGHT_SIZE)
    xs = [p[0] for p in points]
    numeric, pos = _sweep_positions(xs)
    if strategies is None:
        strategies = list(dict.fromkeys(s for _, sc in points for s in sc.get(metric, {})))
    st = styles(strategies)
    n = max(len(strategies), 1)
    for i, s in enumerate(strategies):
        cells = np.array([_cell(sc.get(metric, {}).get(s)) for _, sc in points], float)
        y, lo, hi = cells.T if cells.size else (np.zeros(0),) * 3
        dodge = (i - (n - 1) / 2) * (min(0.6 / n, 0.12) if not numeric else 0.0)
        if numeric and pos.size > 1:
            dodge = (i - (n - 1) / 2) * 0.004 * float(np.ptp(pos))  # intervals side by side
        ax.plot(
            pos + dodge,
            y,
            marker=st[s].marker,
            ms=3.5 if numeric else 4,
            lw=1.1 if numeric else 0,
            ls="-" if numeric else "none",
            color=st[s].colour,
            label=st[s].label,
        )
        if np.isfinite(lo).any() and s != REFERENCE:
            yerr = np.vstack([np.clip(y - lo, 0, None), np.clip(hi - y, 0, None)])
            ax.errorbar(
                pos + dodge,
                y,
                yerr=np.where(np.isfinite(yerr), yerr, 0.0),
                fmt="none",
                ecolor=st[s].colour,
                capsize=1.5,
                elinewidth=0.7,
            )
    ax.axhline(1.0, color="k", lw=0.6, ls=":")
    if not numeric:
        _category_ticks(ax, pos, xs)
    else:
        ax.tick_params(axis="x", labelsize=TICK_PT)
    ax.tick_params(axis="y", labelsize=TICK_PT)
    ax.set_xlabel(axis_label, fontsize=LABEL_PT)
    ax.set_ylabel(f"{METRIC_NAMES.get(metric, metric)} score (random = 1)", fontsize=LABEL_PT)
    if title:
        ax.set_title(title, fontsize=TITLE_PT)
    legend_outside(ax)
    ax.grid(True, alpha=0.3)
    return fig, ax


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
        hollow markers, one legend entry says so).
    reference, metric : str
        Names for the labels; the reference itself is not drawn (its factor is 1, the
        dotted line).
    strategies : sequence of str, optional
        Order (default: ``factor``'s).
    """
    fig, ax = new_axes(ax, LEGEND_RIGHT_SIZE)
    d = np.asarray(densities, float)
    names = [s for s in (strategies or list(factor)) if s in factor and s != reference]
    look = styles(names)
    handles, labels = [], []
    allv: list[float] = []
    for s in names:
        y = np.asarray(factor[s], float)
        allv += y.tolist()
        extra = np.asarray(flag[s]) != 0
        c, mk = look[s].colour, look[s].marker
        ls = look[s].linestyle
        ax.plot(d, y, lw=1.1, color=c, ls=ls, label=look[s].label)
        ax.plot(d[~extra], y[~extra], mk, ms=3.2, color=c)
        ax.plot(d[extra], y[extra], mk, ms=3.6, mfc="none", mec=c, mew=0.8)
        handles.append(Line2D([], [], color=c, marker=mk, ms=3.5, lw=1.1, ls=ls))
        labels.append(look[s].label)
    if any(np.any(np.asarray(flag[s]) != 0) for s in names):
        handles.append(Line2D([], [], color="0.3", marker="o", ms=3.6, mfc="none", lw=0))
        labels.append("hollow: extrapolated (beyond\nthe reference's measured range)")
    ax.axhline(1.0, color="k", lw=0.6, ls=":")
    density_axis(ax, d.tolist())
    if allv and all(v > 0 for v in allv if np.isfinite(v)):
        ratio_axis(ax, allv)
    ax.tick_params(axis="y", labelsize=TICK_PT)
    ref = label(reference)
    mname = METRIC_NAMES.get(metric, metric)
    # the panel title names the reference and the metric; the label stays short enough not to
    # run into the figure's title
    ylabel = "samples saved (×)" if title is None else f"samples saved vs {ref} (×)"
    ax.set_ylabel(ylabel, fontsize=LABEL_PT - 0.5)
    ax.set_title(title or f"vs {ref}, at equal {mname}", fontsize=TITLE_PT)
    legend_outside(ax, handles=handles, labels=labels)
    ax.grid(True, which="major", alpha=0.3)
    return fig, ax
