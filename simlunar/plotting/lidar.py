"""LIDAR figures: a return waveform with its detected returns; error against scan time (and
samples) per planner from a LIDAR study's tidy rows. The summary and the tables of those rows
are in :mod:`simlunar.plotting.lidar_tables` (no Matplotlib; re-exported here)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from simlunar.plotting.lidar_tables import lidar_summary, lidar_tables
from simlunar.plotting.style import metric_axis, styles

__all__ = ["error_vs_time", "lidar_summary", "lidar_tables", "waveform"]

#: what the error bars of :func:`error_vs_time` show, by how many terrain seeds (units) it pools
BAND_TRIALS = "bars: ±1 s.d. over trials"
BAND_SEEDS = "bars: 95 % bootstrap interval over terrain seeds"


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
    where: dict | None = None,
    by: str | None = None,
    title: str = "",
    ax=None,
):
    """Mean error of each planner against modelled scan time (``x="seconds"``) or the range
    samples measured (``x="samples"``), log-log, with its interval as error bars
    (:func:`lidar_summary`; ``by`` a column whose values are separate points).

    Returns
    -------
    (Figure, Axes)
    """
    if ax is None:
        fig = Figure(figsize=(3.4, 2.8), layout="constrained")
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    summary = lidar_summary(rows, metric=metric, where=where, by=by)
    # the requested planners first, then any other label of the rows (a planless flash: none)
    names = [p for p in (planners or []) if p in summary]
    names += [p for p in summary if p not in names]
    st = styles(names)
    pooled = False
    for p in names:
        d = summary[p]
        err = np.clip([d["value"] - d["lo"], d["hi"] - d["value"]], 0, None)
        ax.errorbar(d[x], d["value"], yerr=err, marker=st[p].marker, color=st[p].colour,
                    label=st[p].label, lw=1.2, capsize=2, ms=4)  # fmt: skip
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
    ax.legend(fontsize=7, frameon=False, title=BAND_SEEDS if pooled else BAND_TRIALS,
              title_fontsize=6)  # fmt: skip
    return fig, ax
