"""LIDAR figures and tables: a return waveform with its detected returns; error against scan
time (and samples) per planner from a LIDAR study's tidy rows."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Sequence

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from simlunar.metrics import METRIC_NAMES
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


def _bootstrap_mean(values: np.ndarray, n_boot: int = 2000) -> tuple[float, float]:
    """95 % percentile bootstrap interval of the mean of ``values`` (fixed seed: a figure
    redraws identically)."""
    rng = np.random.default_rng(0)
    means = values[rng.integers(0, len(values), (n_boot, len(values)))].mean(axis=1)
    lo, hi = np.percentile(means, [2.5, 97.5])
    return float(lo), float(hi)


def lidar_summary(
    rows: Iterable[dict], *, metric: str, where: dict | None = None, by: str | None = None
) -> dict:
    """Per planner and sample count: scan time, error and its interval.

    Parameters
    ----------
    rows : iterable of dict
        Tidy LIDAR rows (planner, k, trial, metric, value, seconds; ``unit`` when several
        units, e.g. terrain seeds; strings from CSV are fine).
    metric : str
    where : dict, optional
        Column filters compared as strings (a list value keeps any of its items).
    by : str, optional
        A column (e.g. a sweep axis that changes the acquisition, such as a flash's revisits)
        whose values are separate points of each planner's curve; units of the same point are
        pooled.

    Returns
    -------
    dict planner -> dict of float64 arrays over its points (k ascending, then scan time):
    ``k``, ``seconds`` and ``samples`` (means; ``samples`` = measured range samples, ``k``
    for rows without it), ``value`` (mean), ``lo``, ``hi`` (with several units, the 95 %
    bootstrap percentile interval of the mean of the per-unit means; else ±1 s.d. over
    trials) and ``units``.
    """
    ok = {
        c: {str(x) for x in v} if isinstance(v, list | tuple | set) else {str(v)}
        for c, v in (where or {}).items()
    }
    acc: dict = defaultdict(lambda: defaultdict(lambda: defaultdict(list)))
    for r in rows:
        if r["metric"] != metric or any(str(r.get(c)) not in a for c, a in ok.items()):
            continue
        point = (int(float(r["k"])), str(r.get(by)) if by else "")
        cell = acc[str(r["planner"])][point][str(r.get("unit", 0))]
        cell.append((float(r["seconds"]), float(r["value"]), float(r.get("samples") or r["k"])))
    return {planner: _curve(by_point) for planner, by_point in acc.items()}


def _curve(by_point: dict) -> dict:
    """One planner's points: (k, point) -> unit -> [(seconds, value, samples)]."""
    cols: dict = {c: [] for c in ("k", "seconds", "samples", "value", "lo", "hi", "units")}
    for (k, _), by_unit in by_point.items():
        units = [np.array(u, float) for u in by_unit.values()]
        allv = np.concatenate([u[:, 1] for u in units])
        mean = float(allv.mean())
        if len(units) > 1:
            lo, hi = _bootstrap_mean(np.array([u[:, 1].mean() for u in units]))
        else:
            lo, hi = mean - float(allv.std()), mean + float(allv.std())
        both = np.concatenate(units)
        for c, v in zip(cols, (k, both[:, 0].mean(), both[:, 2].mean(), mean, lo, hi, len(units))):
            cols[c].append(v)
    order = np.lexsort((cols["seconds"], cols["k"]))
    return {c: np.array(v, float)[order] for c, v in cols.items()}


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


def lidar_tables(
    rows: list[dict], *, metrics: Sequence[str], title: str = "", by: str | None = None
) -> tuple[str, str]:
    """Markdown and LaTeX tables of a LIDAR study: per (point, planner, k) the mean scan time
    and the mean of each metric over trials and units (``by``: a column splitting the rows
    into points, e.g. a sweep axis)."""
    extra = [m for m in ("valid_fraction", "hazard_precision", "hazard_recall")
             if m not in metrics and any(r["metric"] == m for r in rows)]  # fmt: skip
    names = [*metrics, *extra]
    points = sorted({str(r.get(by)) for r in rows}) if by else [None]
    header = [
        "Planner",
        "k",
        "scan time (s)",
        *[METRIC_NAMES.get(m, m.replace("_", " ")) for m in names],
    ]
    body = []
    for pt in points:
        where = {by: pt} if by else None
        sums = {m: lidar_summary(rows, metric=m, where=where) for m in names}
        first = sums[names[0]]
        for planner, d in first.items():
            for i, k in enumerate(d["k"]):
                cells = [f"{int(k)}", f"{d['seconds'][i]:.3g}"]
                for m in names:
                    v = sums[m].get(planner)
                    cells.append(
                        f"{v['value'][i]:.3g}" if v is not None and i < len(v["k"]) else "–"
                    )
                label = planner if pt is None else f"{by}={pt}: {planner}"
                body.append((label, cells))
    md = [f"### {title}: LIDAR study (means over trials and terrain seeds)", "",
          "| " + " | ".join(header) + " |", "|---" + "|---:" * (len(header) - 1) + "|"]  # fmt: skip
    md += ["| " + " | ".join([lab, *c]) + " |" for lab, c in body]
    esc = [h.replace("_", "\\_") for h in header]
    tex = ["\\begin{table}[t]", "\\centering", f"\\caption{{{title}: LIDAR study}}",
           f"\\begin{{tabular}}{{l{'r' * (len(header) - 1)}}}", "\\toprule",
           " & ".join(esc) + " \\\\", "\\midrule"]  # fmt: skip
    tex += [" & ".join([lab.replace("_", "\\_"), *c]) + " \\\\" for lab, c in body]
    tex += ["\\bottomrule", "\\end{tabular}", "\\end{table}"]
    return "\n".join(md) + "\n", "\n".join(tex).replace("–", "--") + "\n"
