"""Scanner-study tables (paper section 5): mode / planner x metrics with the MSE relative to the
gray-code scan, and with several units (terrain seeds) the key ratios with 95 % t intervals
over the units, paired against the random planner."""

from __future__ import annotations

from simlunar.metrics import METRIC_NAMES
from simlunar.plotting.style import label, pair_label, reference_mode
from simlunar.plotting.tables import _name, _tex_begin, _tex_end, t_interval, tex_escape

__all__ = ["scanner_interval_table", "scanner_summary", "scanner_tables"]

_SCANNER_ROW_KEYS = {
    "unit", "mode", "planner", "reconstruction", "guide_frames", "exposures", "budget", "trial",
    "metric", "value", "renders",
}  # fmt: skip


def scanner_summary(rows: list[dict], *, metrics: list[str]) -> list[dict]:
    """Mean of each metric over trials per (unit, mode, planner), in first-seen order.

    Returns
    -------
    list of dict
        ``label``, ``unit``, ``point`` (the unit's sweep values as ``key=value`` text, empty
        without a sweep), ``mode``, ``planner``, ``renders`` (mean frames) and one key per metric.
    """
    groups: dict[tuple, dict] = {}
    for r in rows:
        key = (str(r.get("unit", "0")), r["mode"], r.get("planner") or "")
        point = ", ".join(f"{k}={r[k]}" for k in r if k not in _SCANNER_ROW_KEYS)
        g = groups.setdefault(key, {"values": {}, "renders": [], "point": point})
        g["values"].setdefault(r["metric"], []).append(float(r["value"]))
        if r.get("renders") not in (None, ""):
            g["renders"].append(float(r["renders"]))
    out = []
    for (unit, mode, planner), g in groups.items():
        label = pair_label(mode, planner)
        entry = {
            "label": label,
            "unit": unit,
            "point": g["point"],
            "mode": mode,
            "planner": planner,
            "renders": sum(g["renders"]) / len(g["renders"]) if g["renders"] else None,
        }
        for m in metrics:
            vals = g["values"].get(m)
            entry[m] = sum(vals) / len(vals) if vals else None
        out.append(entry)
    return out


def _reference_label(mode: str | None) -> str:
    """How the ratio column names its reference scan (``gray code`` in the paper)."""
    return label(mode).lower() if mode else "the full-field scan"


def scanner_tables(rows: list[dict], *, metrics: list[str], title: str = "") -> tuple[str, str]:
    """Scanner-study tables: one row per (sweep point, mode, planner), metric means over trials.

    ``MSE / gray code`` is each row's MSE over the plain gray-code scan's MSE of the same unit
    (the paper reports ambiguity enhancement lowering MSE by about 25%, i.e. 0.75). With
    several units (a sweep, e.g. over terrain seeds) each row is labelled by its sweep point,
    and closing rows give the mean over units of each metric and of the per-unit ratio.
    """
    summary = scanner_summary(rows, metrics=[*metrics, "valid_fraction"])
    ref = reference_mode(summary)  # the gray code in the paper
    base = {e["unit"]: e.get("mse") for e in summary if e["mode"] == ref and not e["planner"]}
    for e in summary:
        e["base_label"] = e["label"]
        e["ratio"] = (
            e["mse"] / base[e["unit"]] if e.get("mse") is not None and base.get(e["unit"]) else None
        )
        if e["point"]:
            e["label"] = f"{e['point']}: {e['label']}"
    cols = [*metrics, "valid_fraction"]
    if len({e["unit"] for e in summary}) > 1:
        pooled: dict[str, list[dict]] = {}
        for e in summary:
            pooled.setdefault(e["base_label"], []).append(e)
        for label, group in pooled.items():

            def mean(key, group=group):
                vals = [g[key] for g in group if g.get(key) is not None]
                return sum(vals) / len(vals) if vals else None

            summary.append(
                {
                    "label": f"mean of {len(group)} units: {label}",
                    "renders": mean("renders"),
                    "ratio": mean("ratio"),
                    **{c: mean(c) for c in cols},
                }
            )
    header = [
        "Mode / planner",
        *[_name(METRIC_NAMES, m) for m in metrics],
        "valid fraction",
        "frames",
        f"MSE / {_reference_label(ref)}",
    ]

    def cell(v, digits="{:.3g}"):
        return "–" if v is None else digits.format(v)

    md_lines = ["| " + " | ".join(header) + " |", "|---" + "|---:" * (len(header) - 1) + "|"]
    tex_rows = []
    for e in summary:
        # a fraction near 1 at 3 significant digits reads "1" for 0.99958: 5 decimals
        cells = [cell(e[c], "{:.5f}" if c == "valid_fraction" else "{:.3g}") for c in cols] + [
            cell(e["renders"], "{:.0f}"),
            cell(e["ratio"], "{:.3f}"),
        ]
        md_lines.append("| " + " | ".join([e["label"], *cells]) + " |")
        tex_rows.append(" & ".join([tex_escape(e["label"]), *cells]) + " \\\\")
    cap = f"{title}: scanner study (means over trials; lower error is better)"
    md = f"### {cap}\n\n" + "\n".join(md_lines) + "\n"
    md_iv, tex_iv = scanner_interval_table(summary, title=title)
    tex = "\n".join(
        [
            "\\begin{table}[t]",
            "\\centering",
            f"\\caption{{{tex_escape(cap)}}}",
            f"\\begin{{tabular}}{{l{'r' * (len(header) - 1)}}}",
            "\\toprule",
            " & ".join(tex_escape(h) for h in header) + " \\\\",
            "\\midrule",
            *tex_rows,
            "\\bottomrule",
            "\\end{tabular}",
            "\\end{table}",
        ]
    )
    return md + md_iv, (tex + tex_iv).replace("–", "--") + "\n"


def scanner_interval_table(summary: list[dict], *, title: str = "") -> tuple[str, str]:
    """Intervals over units (terrain seeds) of the scanner study's key ratios.

    Per dot mode and planner: MSE / gray code (each unit's trial-mean MSE over its gray-code
    MSE) and, paired by unit, the MSE over the random planner's in the same mode and unit;
    each as the mean over units with its 95 % t interval, and the number of units where the
    planner's MSE is below random's. Empty with fewer than two units (nothing to pool).

    Parameters
    ----------
    summary : list of dict
        Per-unit rows of :func:`scanner_summary` with ``ratio`` (MSE / gray code) added.
    """
    per = [e for e in summary if e.get("unit") is not None and e.get("planner")]
    units = sorted({e["unit"] for e in per})
    if len(units) < 2:
        return "", ""
    by = {(e["mode"], e["planner"], e["unit"]): e for e in per}
    pairs = list(dict.fromkeys((e["mode"], e["planner"]) for e in per))
    has_random = any(p == "random" for _, p in pairs)
    ref = _reference_label(reference_mode(summary))
    header = ["Mode / planner", "units", f"MSE / {ref}", "MSE / random's, paired",
              "units below random"]  # fmt: skip
    rows = []
    for mode, planner in pairs:
        mine = [by.get((mode, planner, u)) for u in units]
        ratio = [e["ratio"] for e in mine if e is not None and e.get("ratio") is not None]
        cells = [str(len(ratio)), _interval_text(ratio)]
        rand = [by.get((mode, "random", u)) for u in units]
        paired = [
            a["mse"] / b["mse"]
            for a, b in zip(mine, rand)
            if a is not None and b is not None and a.get("mse") and b.get("mse")
        ]
        if planner == "random":
            cells += ["1 (reference)", "–"]
        elif has_random and paired:
            below = sum(1 for x in paired if x < 1.0)
            cells += [_interval_text(paired), f"{below} of {len(paired)}"]
        else:
            cells += ["– (no random planner)", "–"]
        rows.append((pair_label(mode, planner), cells))
    n = len(units)
    cap = (
        f"{title}: MSE ratios over {n} units (terrain seeds), mean [95 % t interval over units]; "
        "paired: each unit's MSE over the random planner's in the same unit and mode"
    )
    lines = ["| " + " | ".join(header) + " |", "|---" + "|---:" * (len(header) - 1) + "|"]
    lines += ["| " + " | ".join([lab, *c]) + " |" for lab, c in rows]
    md = f"\n### {cap}\n\n" + "\n".join(lines) + "\n"
    out = _tex_begin(cap, len(header))
    out += [" & ".join(tex_escape(h) for h in header) + " \\\\", "\\midrule"]
    out += [" & ".join([tex_escape(lab), *(tex_escape(x) for x in c)]) + " \\\\" for lab, c in rows]
    return md, "\n" + _tex_end(out)


def _interval_text(values: list[float]) -> str:
    """``mean [low, high]`` (3 decimals) of a t interval; the value alone for one unit."""
    if not values:
        return "–"
    if len(values) == 1:
        return f"{values[0]:.3f}"
    m, lo, hi = t_interval(values)
    return f"{m:.3f} [{lo:.3f}, {hi:.3f}]"
