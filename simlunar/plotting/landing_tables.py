"""Landing-site tables (no Matplotlib): per sensor, light, reconstruction and planner the mean
scan time, laser energy and every landing score (:mod:`simlunar.metrics.landing`) with its interval over
terrain seeds, in Markdown and LaTeX (the runner appends them to a LIDAR study's tables)."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence

import numpy as np

from simlunar.plotting.lidar_tables import _bootstrap_mean

__all__ = [
    "LANDING_PREFIXES",
    "landing_columns",
    "landing_summary",
    "landing_tables",
    "paired_sign_flip_p",
    "paired_table",
]

#: the metric names of the landing scores start with one of these
LANDING_PREFIXES = (
    "hazard_recall_rock_",
    "hazard_precision_rock_",
    "hazard_recall_slope_",
    "hazard_precision_slope_",
    "false_safe_site",
    "safe_site_called",
    "height_rms",
    "slope_rms_deg",
)

_HEAD = {
    "false_safe_site": "false-safe site",
    "safe_site_called": "site called safe",
    "height_rms": "height RMS (m)",
    "slope_rms_deg": "slope RMS (deg)",
}


def landing_columns(rows: Sequence[dict]) -> list[str]:
    """The landing metrics present in ``rows``, in :data:`LANDING_PREFIXES` order."""
    present = {str(r["metric"]) for r in rows}
    out = []
    for p in LANDING_PREFIXES:
        out += sorted(m for m in present if m.startswith(p) and m not in out)
    return out


def _header(metric: str) -> str:
    if metric in _HEAD:
        return _HEAD[metric]
    kind, _, size = metric.removeprefix("hazard_").partition("_")
    what, _, size = size.partition("_")
    return f"{what} {size} {kind}"  # "rock 15cm recall"


def landing_summary(rows: Sequence[dict], *, keys: Sequence[str]) -> dict:
    """Per group (the values of ``keys``, then reconstruction and planner): mean scan time, mean
    laser energy (NaN where the rows do not price it) and, per landing metric, the mean over terrain seeds (units) with its 95 % bootstrap interval
    (the mean over trials first within a unit).

    Returns
    -------
    dict group tuple -> {"seconds": float, "energy_j": float, "units": int,
    metric: (mean, lo, hi)}
    """
    metrics = landing_columns(rows)
    acc: dict = defaultdict(lambda: defaultdict(lambda: defaultdict(list)))
    secs: dict = defaultdict(list)
    joules: dict = defaultdict(list)
    for r in rows:
        m = str(r["metric"])
        if m not in metrics:
            continue
        g = (*(str(r.get(k)) for k in keys), str(r.get("reconstruction") or "linear"),
             str(r["planner"]))  # fmt: skip
        acc[g][m][str(r.get("unit", 0))].append(float(r["value"]))
        secs[g].append(float(r["seconds"]))
        joules[g].append(float(r.get("energy_j", np.nan)))
    out = {}
    for g, by_metric in acc.items():
        cell: dict = {"seconds": float(np.mean(secs[g])), "energy_j": float(np.mean(joules[g]))}
        for m, by_unit in by_metric.items():
            per_unit = np.array([np.mean(v) for v in by_unit.values()])
            mean = float(per_unit.mean())
            lo, hi = _bootstrap_mean(per_unit) if len(per_unit) > 1 else (mean, mean)
            cell[m] = (mean, lo, hi)
            cell["units"] = len(per_unit)
        out[g] = cell
    return out


def landing_tables(
    rows: Sequence[dict], *, keys: Sequence[str], title: str = ""
) -> tuple[str, str]:
    """Markdown and LaTeX landing tables: a row per (``keys`` values, reconstruction, planner),
    a column per landing metric, ``mean [lo, hi]`` over terrain seeds ("" when ``rows`` hold
    no landing metric)."""
    metrics = landing_columns(rows)
    if not metrics:
        return "", ""
    summary = landing_summary(rows, keys=keys)
    short = [k.rsplit(".", 1)[-1] for k in keys]
    header = [*short, "reconstruction", "planner", "scan time (s)", "laser energy (J)",
              *map(_header, metrics)]  # fmt: skip
    body = []
    for g in sorted(summary, key=lambda g: tuple(_sort_key(v) for v in g)):
        c = summary[g]
        cells = [*g, f"{c['seconds']:.3g}", f"{c['energy_j']:.3g}"]
        for m in metrics:
            if m not in c:
                cells.append("–")
                continue
            mean, lo, hi = c[m]
            cells.append(f"{mean:.3g}" if lo == hi else f"{mean:.3g} [{lo:.3g}, {hi:.3g}]")
        body.append(cells)
    n = max(c.get("units", 1) for c in summary.values())
    md = [f"### {title}: landing site (means over {n} terrain seeds, 95 % bootstrap intervals)",
          "", "| " + " | ".join(header) + " |", "|---" * len(header) + "|"]  # fmt: skip
    md += ["| " + " | ".join(b) + " |" for b in body]
    md += ["", "Rock recall / precision count rocks (objects), slope ones pixels; false-safe "
           "site: the chosen site called safe but unsafe in the truth (docs/landing.md)."]  # fmt: skip
    esc = [h.replace("_", "\\_") for h in header]
    tex = ["\\begin{table}[t]", "\\centering", f"\\caption{{{title}: landing site}}",
           f"\\begin{{tabular}}{{{'l' * (len(short) + 2)}{'r' * (len(header) - len(short) - 2)}}}",
           "\\toprule", " & ".join(esc) + " \\\\", "\\midrule"]  # fmt: skip
    tex += [" & ".join(b).replace("_", "\\_") + " \\\\" for b in body]
    tex += ["\\bottomrule", "\\end{tabular}", "\\end{table}"]
    return "\n".join(md) + "\n", "\n".join(tex).replace("–", "--") + "\n"


def _sort_key(v: str):
    try:
        return (0, float(v), "")
    except ValueError:
        return (1, 0.0, v)


def paired_sign_flip_p(diffs) -> float:
    """Two-sided p value of a zero mean paired difference by the exact sign-flip
    (randomisation) test: the share of the ``2^n`` sign patterns whose mean is at least as far
    from 0 as the observed one (n <= 16; 1.0 for all-zero differences). With n pairs the
    smallest p is ``2 / 2^n`` (8 seeds: 0.0078)."""
    d = np.asarray(diffs, float)
    d = d[np.isfinite(d)]
    n = d.size
    if n == 0 or not np.any(d):
        return 1.0
    if n > 16:
        raise ValueError(f"paired_sign_flip_p: at most 16 pairs (exact), got {n}")
    signs = 1 - 2 * ((np.arange(2**n)[:, None] >> np.arange(n)) & 1)
    means = np.abs(signs @ np.abs(d)) / n
    return float(np.mean(means >= abs(d.mean()) - 1e-12))


#: the metrics of the paired table
PAIRED = ("hazard_recall_rock_", "hazard_recall_slope_", "false_safe_site", "height_rms",
          "slope_rms_deg")  # fmt: skip


def paired_table(
    rows: Sequence[dict],
    *,
    sensor_key: str,
    light_key: str | None,
    reference: str = "flash",
    seed_key: str = "terrain_seed",
    title: str = "",
) -> str:
    """Markdown: per (light, reconstruction, sensor, planner) the mean difference to the
    ``reference`` sensor under the same light and reconstruction on the same terrain seeds, and
    its exact sign-flip p value (:func:`paired_sign_flip_p`); "" without the reference or with
    one seed."""
    metrics = [m for m in landing_columns(rows) if m.startswith(PAIRED)]
    vals: dict = defaultdict(list)
    for r in rows:
        if str(r["metric"]) in metrics:
            g = (str(r.get(light_key)) if light_key else "", str(r.get("reconstruction") or
                 "linear"), str(r.get(sensor_key)), str(r["planner"]))  # fmt: skip
            vals[(g, str(r["metric"]), str(r.get(seed_key, 0)))].append(float(r["value"]))
    groups = sorted({k[0] for k in vals}, key=lambda g: tuple(_sort_key(v) for v in g))
    seeds = sorted({k[2] for k in vals})
    refs = {(g[0], g[1]): g for g in groups if g[2] == reference}
    if len(seeds) < 2 or not refs:
        return ""
    header = ["sun", "reconstruction", "sensor", "planner",
              *[f"{_header(m)} - {reference}" for m in metrics]]  # fmt: skip
    body = []
    for g in groups:
        ref = refs.get((g[0], g[1]))
        if ref is None or g == ref:
            continue
        cells = []
        for m in metrics:
            d = [np.mean(vals[(g, m, s)]) - np.mean(vals[(ref, m, s)]) for s in seeds
                 if vals.get((g, m, s)) and vals.get((ref, m, s))]  # fmt: skip
            cells.append(f"{np.mean(d):+.3g} (p = {paired_sign_flip_p(d):.2g})" if d else "–")
        body.append([*g, *cells])
    md = [f"### {title}: paired against the {reference} ({len(seeds)} terrain seeds, exact "
          "sign-flip p)", "", "| " + " | ".join(header) + " |", "|---" * len(header) + "|"]  # fmt: skip
    md += ["| " + " | ".join(b) + " |" for b in body]
    return "\n".join(md) + "\n"
