"""Score tables in the layout of the paper's Tables 1 and 2 (Markdown and LaTeX).

Scores follow the paper's eq. 4.3: the inverse-density-weighted mean of e_random / e_strategy,
so random scores exactly 1 and higher is better.

* One scene (paper Table 2): rows are metrics (MSE, GRAD, SAL), columns strategies.
* Several scenes or sweep points (paper Table 1): one block per scene (its name heading the
  strategy columns, one row per metric), then one table per metric with the scenes / sweep
  points as rows, for side-by-side comparison.
"""

from __future__ import annotations

import math

import numpy as np

from simlunar.metrics import METRIC_NAMES
from simlunar.plotting.seed_stats import _seed_summary, seed_summary_numbers, t_interval
from simlunar.plotting.style import label as display_label

__all__ = [
    "Cell",
    "headroom_tables",
    "paired_saved_tables",
    "samples_saved_tables",
    "score_tables",
    "seed_summary_numbers",
    "t_interval",
    "tex_escape",
]


def _name(table: dict, key: str) -> str:
    if key.endswith("_interior") and key.removesuffix("_interior") in table:
        return f"{table[key.removesuffix('_interior')]} (interior only)"
    return table.get(key, key.replace("_", " ").capitalize())


def _fmt(v) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    return f"{float(v):.2f}"


def _best(values: list) -> int | None:
    finite = [(v, i) for i, v in enumerate(values) if v is not None and math.isfinite(v)]
    return max(finite)[1] if finite else None


class Cell(float):
    """A score with its interval and whether to bold it (rows of :func:`score_tables`)."""

    low: float | None = None
    high: float | None = None
    bold: bool = False

    def __new__(cls, value, low=None, high=None, bold=False):
        obj = super().__new__(cls, value)
        obj.low, obj.high, obj.bold = low, high, bold
        return obj


def _fmt_cell(v) -> str:
    text = _fmt(v)
    if isinstance(v, Cell) and v.low is not None and v.high is not None:
        text += f" [{_fmt(v.low)}, {_fmt(v.high)}]"
    return text


def _bold_index(vals: list) -> int | None:
    """Cells say themselves whether they are bold; plain values: the row's maximum."""
    if any(isinstance(v, Cell) for v in vals):
        marked = [i for i, v in enumerate(vals) if isinstance(v, Cell) and v.bold]
        return marked[0] if marked else None
    return _best(vals)


def _md_table(header: list[str], rows: list[tuple[str, list]]) -> str:
    lines = [
        "| " + " | ".join(header) + " |",
        "|" + "|".join(["---"] + ["---:"] * (len(header) - 1)) + "|",
    ]
    for label, vals in rows:
        b = _bold_index(vals)
        cells = [f"**{_fmt_cell(v)}**" if i == b else _fmt_cell(v) for i, v in enumerate(vals)]
        lines.append("| " + " | ".join([label, *cells]) + " |")
    return "\n".join(lines) + "\n"


def tex_escape(s: str) -> str:
    for a, b in (
        ("\\", r"\textbackslash{}"),
        ("_", r"\_"),
        ("&", r"\&"),
        ("%", r"\%"),
        ("#", r"\#"),
        ("$", r"\$"),
        ("{", r"\{"),
        ("}", r"\}"),
    ):
        s = s.replace(a, b)
    return s


def _tex_table(header: list[str], rows: list[tuple[str, list]], caption: str) -> str:
    out = _tex_begin(caption, len(header))
    out += [" & ".join(tex_escape(h) for h in header) + " \\\\", "\\midrule"]
    out += _tex_rows(rows)
    return _tex_end(out)


def _tex_begin(caption: str, ncols: int) -> list[str]:
    """Opening lines of a booktabs table: a label column, then ncols - 1 numeric ones."""
    return [
        "\\begin{table}[t]",
        "\\centering",
        f"\\caption{{{tex_escape(caption)}}}",
        f"\\begin{{tabular}}{{l{'r' * (ncols - 1)}}}",
        "\\toprule",
    ]


def _tex_rows(rows: list[tuple[str, list]]) -> list[str]:
    """Body lines of a LaTeX table, the best value of each row in bold."""
    out = []
    for label, vals in rows:
        b = _bold_index(vals)
        cells = [
            f"\\textbf{{{_fmt_cell(v)}}}" if i == b else _fmt_cell(v) for i, v in enumerate(vals)
        ]
        out.append(" & ".join([tex_escape(label), *cells]) + " \\\\")
    return out


def _tex_end(out: list[str]) -> str:
    out += ["\\bottomrule", "\\end{tabular}", "\\end{table}"]
    return "\n".join(out).replace("–", "--") + "\n"


def _tex_blocks(blocks: list[tuple[list[str], list[tuple[str, list]]]], caption: str) -> str:
    """One tabular of stacked blocks, each with its own header row (paper Table 1)."""
    out = _tex_begin(caption, len(blocks[0][0]))
    for k, (header, rows) in enumerate(blocks):
        if k:
            out.append("\\midrule")
        out += [" & ".join(tex_escape(h) for h in header) + " \\\\", "\\midrule"]
        out += _tex_rows(rows)
    return _tex_end(out)


def score_tables(
    units: list[tuple[str, dict]],
    *,
    strategies: list[str],
    metrics: list[str],
    title: str = "",
    note: str = "",
) -> tuple[str, str]:
    """Markdown and LaTeX score tables.

    Parameters
    ----------
    units : list of (label, scores)
        ``scores`` maps metric -> strategy -> score (eq. 4.3); one entry per scene / sweep point.
        A score given as a :class:`Cell` prints its interval (``1.29 [1.21, 1.37]``) and is
        bold only where the cell says so; plain floats: the best of each row is bold.
    strategies, metrics : list of str
        Column and row order.
    title : str
        Caption prefix (the experiment name).
    note : str
        A sentence printed under the first heading (Markdown) and as a LaTeX comment, e.g.
        how the intervals and the bold face were computed.

    Returns
    -------
    (markdown, latex) : tuple of str
    """
    header = ["", *[display_label(s) for s in strategies]]
    md, tex = [], []
    if note:
        md.append(note + "\n")
        tex.append("% " + note.replace("%", "\\%").replace("\n", "\n% ") + "\n")
    if len(units) == 1:
        _, scores = units[0]
        rows = [
            (_name(METRIC_NAMES, m), [scores.get(m, {}).get(s) for s in strategies])
            for m in metrics
        ]
        cap = f"{title}: scores (eq. 4.3, random = 1, higher is better)"
        md.append(f"### {cap}\n\n" + _md_table(["Metric", *header[1:]], rows))
        tex.append(_tex_table(["Metric", *header[1:]], rows, cap))
    else:
        # paper Table 1: one block per scene, the scene's name heading its strategy columns,
        # one row per metric
        cap = f"{title}: scores (eq. 4.3, random = 1, higher is better)"
        blocks = []
        md.append(f"### {cap}\n")
        for label, scores in units:
            rows = [
                (_name(METRIC_NAMES, m), [scores.get(m, {}).get(s) for s in strategies])
                for m in metrics
            ]
            md.append(_md_table([label, *header[1:]], rows))
            blocks.append(([label, *header[1:]], rows))
        tex.append(_tex_blocks(blocks, cap))
        # and per metric, the scenes / sweep points side by side (easier to compare)
        for m in metrics:
            rows = [
                (label, [scores.get(m, {}).get(s) for s in strategies]) for label, scores in units
            ]
            cap = (
                f"{title}: {_name(METRIC_NAMES, m)} scores (eq. 4.3, random = 1, higher is better)"
            )
            md.append(f"### {cap}\n\n" + _md_table(["Scene", *header[1:]], rows))
            tex.append(_tex_table(["Scene", *header[1:]], rows, cap))
    return "\n".join(md), "\n".join(tex)


def _fmt_factor(v: float, flag: int) -> str:
    if v is None or not math.isfinite(v):
        return "–"
    text = f"{v:.2f}" if v < 10 else f"{v:.1f}"
    return text + ("*" if flag else "")


def samples_saved_tables(entries: list[dict], *, title: str = "") -> tuple[str, str]:
    """Markdown and LaTeX tables of samples saved at equal error.

    Parameters
    ----------
    entries : list of dict
        One per (sweep point, reference): ``label`` (point), ``reference`` (strategy name),
        ``metric``, ``strategies`` (row order), ``ks`` (sample counts per density column),
        ``densities``, ``factor`` / ``flag`` (strategy -> per-density arrays), ``summary`` /
        ``n_summary`` (strategy -> geometric mean and how many densities it averages).
    title : str
        Caption prefix.

    Returns
    -------
    (markdown, latex) : tuple of str
        Factor = samples the reference needs for the strategy's error / the strategy's samples
        (> 1: the strategy saves samples); ``*`` marks factors extrapolated beyond the
        reference's measured error range.
    """
    md, tex = [], []
    if not entries:
        return "", ""
    expl = (
        "Samples saved at equal error: at each density, the samples the reference needs to "
        "reach the strategy's mean error (its mean-error curve interpolated in log-log) over "
        "the strategy's samples; > 1 = the strategy needs fewer. * = beyond the reference's "
        "measured range (its end segment's power law extended, clipped to N samples); the "
        "geometric mean (n densities) leaves those out."
    )
    md.append(expl + "\n")
    tex.append("% " + expl + "\n")
    for e in entries:
        ref = display_label(e["reference"])
        metric = _name(METRIC_NAMES, e["metric"])
        cols = [f"1/{round(1 / d)}" if d < 1 else "1" for d in e["densities"]]
        header = ["Strategy", *cols, "geo. mean (n)"]
        rows = []
        for s in e["strategies"]:
            if s == e["reference"] or s not in e["factor"]:
                continue
            cells = [_fmt_factor(v, f) for v, f in zip(e["factor"][s], e["flag"][s])]
            g = e["summary"][s]
            cells.append("–" if not math.isfinite(g) else f"{g:.2f} ({e['n_summary'][s]})")
            rows.append((display_label(s), cells))
        if not rows:  # the reference is the only strategy: nothing to compare with it
            continue
        where = f"{e['label']}: " if e.get("label") else ""
        cap = f"{title}: {where}samples saved vs {ref} at equal {metric}"
        lines = ["| " + " | ".join(header) + " |", "|---" + "|---:" * (len(header) - 1) + "|"]
        lines += ["| " + " | ".join([lab, *c]) + " |" for lab, c in rows]
        md.append(f"### {cap}\n\n" + "\n".join(lines) + "\n")
        out = _tex_begin(cap, len(header))
        out += [" & ".join(tex_escape(h) for h in header) + " \\\\", "\\midrule"]
        out += [" & ".join([tex_escape(lab), *c]) + " \\\\" for lab, c in rows]
        tex.append(_tex_end(out))
    if len(md) == 1:  # every table empty: no explanation either
        return "", ""
    return "\n".join(md), "\n".join(tex)


def headroom_tables(entries: list[dict], *, title: str = "") -> tuple[str, str]:
    """Markdown and LaTeX tables of the headroom each strategy captures.

    Parameters
    ----------
    entries : list of dict
        One per (sweep point, oracle): ``label``, ``oracle`` (its label), ``metric``,
        ``strategies`` (row order), ``captured`` (strategy -> per-seed log(saved vs uniform
        Lloyd) / log(oracle saved vs uniform Lloyd)), ``saved`` (strategy -> per-seed
        geometric-mean samples saved vs uniform Lloyd, the oracle's included), ``seeds``.

    Returns
    -------
    (markdown, latex) : tuple of str
    """
    if not entries:
        return "", ""
    expl = (
        "Headroom captured, paired by terrain seed: log(samples saved vs Uniform Lloyd) / "
        "log(the oracle's samples saved vs Uniform Lloyd), per seed (geometric means over the "
        "interpolated densities); 1 = the oracle's saving, 0 = the uniform layout's, < 0 = "
        "worse than it. Samples saved: geometric mean over seeds [95 % Student t interval, in "
        "log space]; headroom captured: mean over seeds [95 % t interval]; the per-seed range "
        "beside each."
    )

    def table(e):
        metric = _name(METRIC_NAMES, e["metric"])
        header = ["Strategy", "saved vs Uniform Lloyd", "seeds: range", "headroom captured",
                  "seeds: range"]  # fmt: skip
        o_saved = np.asarray(e["saved"][e["oracle"]], dtype=float)
        rows = [(display_label(e["oracle"]),
                 [*_seed_summary(o_saved, log=True), "1 (bound)", ""])]  # fmt: skip
        for s in e["strategies"]:
            cap = np.asarray(e["captured"][s], dtype=float)
            rows.append((display_label(s), [*_seed_summary(np.asarray(e["saved"][s]), log=True),
                                            *_seed_summary(cap, log=False)]))  # fmt: skip
        return f"headroom captured vs {display_label(e['oracle'])} at equal {metric}", header, rows

    return _seed_tables(entries, expl, title, table)


def _seed_tables(entries: list[dict], expl: str, title: str, table) -> tuple[str, str]:
    """Markdown and LaTeX of per-seed tables: ``expl`` first (a LaTeX comment there), then one
    table per entry from ``table(entry) -> (what, header, rows)`` (see :func:`_seed_caption`,
    :func:`_append_seed_table`)."""
    md, tex = [expl + "\n"], ["% " + expl + "\n"]
    for e in entries:
        what, header, rows = table(e)
        if rows:  # a table with no row (the reference alone) is left out
            _append_seed_table(md, tex, _seed_caption(title, e, what), header, rows)
    if len(md) == 1:
        return "", ""
    return "\n".join(md), "\n".join(tex)


def _seed_caption(title: str, e: dict, what: str) -> str:
    """``title: point: what (n terrain seeds)`` of a per-seed table."""
    where = f"{e['label']}: " if e.get("label") else ""
    n = len(e["seeds"])
    return f"{title}: {where}{what} ({n} terrain seed{'s' * (n != 1)})"


def _append_seed_table(md: list, tex: list, cap: str, header: list, rows: list) -> None:
    """One Markdown and one LaTeX table of text cells (``rows``: (label, cells)); a column
    empty in every row (the seed range of a one-seed study) is left out."""
    keep = [j for j in range(len(header) - 1) if any(c[j] for _, c in rows)]
    header = [header[0], *(header[j + 1] for j in keep)]
    rows = [(lab, [c[j] for j in keep]) for lab, c in rows]
    lines = ["| " + " | ".join(header) + " |", "|---" + "|---:" * (len(header) - 1) + "|"]
    lines += ["| " + " | ".join([lab, *c]) + " |" for lab, c in rows]
    md.append(f"### {cap}\n\n" + "\n".join(lines) + "\n")
    out = _tex_begin(cap, len(header))
    out += [" & ".join(tex_escape(h) for h in header) + " \\\\", "\\midrule"]
    out += [" & ".join([tex_escape(lab), *(tex_escape(x) for x in c)]) + " \\\\"
            for lab, c in rows]  # fmt: skip
    tex.append(_tex_end(out).replace("–", "--"))


def paired_saved_tables(entries: list[dict], *, title: str = "") -> tuple[str, str]:
    """Markdown and LaTeX tables of the samples saved vs Uniform Lloyd, paired by terrain
    seed, for studies without an oracle (with one, :func:`headroom_tables` holds them).

    Parameters
    ----------
    entries : list of dict
        One per sweep point: ``label``, ``metric``, ``strategies`` (row order), ``saved``
        (strategy -> per-seed geometric-mean samples saved vs uniform Lloyd), ``seeds``.
    """
    if not entries:
        return "", ""
    expl = (
        "Samples saved vs Uniform Lloyd, paired by terrain seed (per seed, the geometric mean "
        "over the interpolated densities): geometric mean over seeds [95 % Student t "
        "interval, in log space], and the per-seed range."
    )
    header = ["Strategy", "saved vs Uniform Lloyd", "seeds: range"]

    def table(e):
        rows = [(display_label(s), list(_seed_summary(np.asarray(e["saved"][s]), log=True)))
                for s in e["strategies"] if s in e["saved"]]  # fmt: skip
        what = (f"samples saved vs Uniform Lloyd at equal {_name(METRIC_NAMES, e['metric'])}, "
                "paired by seed")  # fmt: skip
        return what, header, rows

    return _seed_tables(entries, expl, title, table)


def reconstruction_saved_tables(entries: list[dict], *, title: str = "") -> tuple[str, str]:
    """Markdown and LaTeX tables of the samples each reconstruction saves over ``linear`` on
    the same layouts, paired by terrain seed.

    Parameters
    ----------
    entries : list of dict
        One per sweep point (:func:`simlunar.results.aggregate.reconstruction_saved_entries`):
        ``label``, ``metric``, ``strategies`` (row order), ``reconstructions`` (column order),
        ``saved`` (reconstruction -> strategy -> per-seed geometric-mean samples saved vs
        linear), ``seeds``.

    Returns
    -------
    (markdown, latex) : tuple of str
        Per strategy (layout) and reconstruction: the geometric mean over seeds [95 % Student
        t interval, in log space] (one seed: the value) and the per-seed range; > 1: linear
        needs more samples for that reconstruction's error.
    """
    if not entries:
        return "", ""
    expl = (
        "Samples saved by each reconstruction vs Delaunay-linear on the same layout (the same "
        "planned samples), paired by terrain seed: per seed, the samples linear needs for the "
        "reconstruction's mean error over the reconstruction's samples (geometric mean over "
        "the interpolated densities); geometric mean over seeds [95 % Student t interval, in "
        "log space], and the per-seed range. > 1: the reconstruction needs fewer samples."
    )

    def table(e):
        header, rows = _saved_columns(
            e["strategies"], e["saved"], e["reconstructions"], "{} vs linear"
        )
        what = (
            f"samples saved vs linear at equal {_name(METRIC_NAMES, e['metric'])}, paired by seed"
        )
        return what, header, rows

    md, tex = _seed_tables(entries, expl, title, table)
    joint = [e for e in entries if e.get("joint")]
    if not joint:
        return md, tex
    expl2 = (
        "Samples saved by each layout and reconstruction together vs Uniform Lloyd "
        "reconstructed by linear (the image-free layout with the paper's reconstruction), "
        "paired by terrain seed, as above. Oracle rows read the truth: bounds, not planners "
        "(an oracle that reads one reconstruction's error is the bound for that one)."
    )

    def table2(e):
        header, rows = _saved_columns(e["strategies"], e["joint"], e["joint"], "with {}")
        what = (
            f"layout + reconstruction vs Uniform Lloyd + linear at equal "
            f"{_name(METRIC_NAMES, e['metric'])}, paired by seed"
        )
        return what, header, rows

    md2, tex2 = _seed_tables(joint, expl2, title, table2)
    return md + "\n" + md2, tex + "\n" + tex2


def _saved_columns(strategies, saved: dict, columns, head: str) -> tuple[list[str], list]:
    """Header and rows of a per-seed table with a (samples saved, seed range) column pair per
    key of ``columns`` (a reconstruction), headed ``head.format(its display label)``.

    A strategy's cells in a column pair are the per-seed summary (:func:`_seed_summary`, in
    log space) of ``saved[column][strategy]`` (per-seed samples saved, ratios > 0).
    """
    header = ["Strategy"]
    for r in columns:
        header += [head.format(display_label(r)), "seeds: range"]
    rows = []
    for s in strategies:
        cells = []
        for r in columns:
            cells += list(_seed_summary(np.asarray(saved[r][s], dtype=float), log=True))
        rows.append((display_label(s), cells))
    return header, rows
