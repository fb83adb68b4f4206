"""LIDAR study tables (no Matplotlib): per planner and sample count the mean scan time and
error with its interval, and the Markdown and LaTeX tables of a LIDAR study's tidy rows (the
runner writes them; :mod:`simlunar.plotting.lidar` draws the same summary)."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Sequence

import numpy as np

from simlunar.metrics import METRIC_NAMES

__all__ = ["lidar_summary", "lidar_tables"]


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


#: a planner label of a truth-reading oracle starts with this (as in the sampling study)
ORACLE = "oracle"
#: the note under a LIDAR table with oracle rows
ORACLE_NOTE = (
    "Oracle rows read the guide view's true depth in the planner step (the LIDAR then ranges "
    "their beams as any planner's): bounds, not planners."
)


def lidar_tables(
    rows: list[dict],
    *,
    metrics: Sequence[str],
    title: str = "",
    by: str | Sequence[str] | None = None,
) -> tuple[str, str]:
    """Markdown and LaTeX tables of a LIDAR study: per (point, planner, k) the mean measured
    samples (``k`` is the plan's nominal count: a plan fitted to a budget measures another),
    the mean scan time and the mean of each metric over trials and units (``by``: a column
    splitting the rows into points, e.g. a sweep axis, labelled ``column=value``; or several
    columns, e.g. every
    axis of a sweep, each point labelled by their last name parts, ``sensor=flash,
    elevation_deg=5``: the units of a point, its terrain seeds, pooled)."""
    extra = [m for m in ("valid_fraction", "hazard_precision", "hazard_recall", "safe_site")
             if m not in metrics and any(r["metric"] == m for r in rows)]  # fmt: skip
    names = [*metrics, *extra]
    cols = [by] if isinstance(by, str) else list(by or [])
    points = _points(rows, cols) if len(cols) > 1 else sorted({str(r.get(by)) for r in rows})
    points = points if cols else [None]
    header = [
        "Planner",
        "k",
        "samples",
        "scan time (s)",
        *[METRIC_NAMES.get(m, m.replace("_", " ")) for m in names],
    ]
    body = []
    for pt in points:
        where = dict(zip(cols, pt)) if len(cols) > 1 else ({by: pt} if cols else None)
        sums = {m: lidar_summary(rows, metric=m, where=where) for m in names}
        first = sums[names[0]]
        for planner, d in first.items():
            for i, k in enumerate(d["k"]):
                cells = [f"{int(k)}", f"{d['samples'][i]:.0f}", f"{d['seconds'][i]:.3g}"]
                for m in names:
                    v = sums[m].get(planner)
                    cells.append(
                        f"{v['value'][i]:.3g}" if v is not None and i < len(v["k"]) else "–"
                    )
                name = f"{planner} (a bound)" if planner.startswith(ORACLE) else planner
                label = name if pt is None else f"{_point_label(cols, pt)}: {name}"
                body.append((label, cells))
    md = [f"### {title}: LIDAR study (means over trials and terrain seeds)", "",
          "| " + " | ".join(header) + " |", "|---" + "|---:" * (len(header) - 1) + "|"]  # fmt: skip
    md += ["| " + " | ".join([lab, *c]) + " |" for lab, c in body]
    if any(lab.endswith("(a bound)") for lab, _ in body):
        md += ["", ORACLE_NOTE]
    esc = [h.replace("_", "\\_") for h in header]
    tex = ["\\begin{table}[t]", "\\centering", f"\\caption{{{title}: LIDAR study}}",
           f"\\begin{{tabular}}{{l{'r' * (len(header) - 1)}}}", "\\toprule",
           " & ".join(esc) + " \\\\", "\\midrule"]  # fmt: skip
    tex += [" & ".join([lab.replace("_", "\\_"), *c]) + " \\\\" for lab, c in body]
    tex += ["\\bottomrule", "\\end{tabular}", "\\end{table}"]
    return "\n".join(md) + "\n", "\n".join(tex).replace("–", "--") + "\n"


def _natural(v: str):
    """Sort key of a column value: numbers by value before text."""
    try:
        return (0, float(v), "")
    except ValueError:
        return (1, 0.0, v)


def _points(rows: list[dict], cols: list[str]) -> list[tuple[str, ...]]:
    """The distinct value tuples of ``cols`` in ``rows``, in the order of the columns' values
    (numbers by value)."""
    pts = {tuple(str(r.get(c)) for c in cols) for r in rows}
    return sorted(pts, key=lambda p: tuple(_natural(v) for v in p))


def _point_label(cols: list[str], pt) -> str:
    """``column=value`` of one column; ``name=value, ...`` (a dotted column's last part) of
    several."""
    if len(cols) == 1:
        return f"{cols[0]}={pt}"
    return ", ".join(f"{c.rsplit('.', 1)[-1]}={v}" for c, v in zip(cols, pt))
