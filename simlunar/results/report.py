"""A result folder as one self-contained HTML page (``report.html``).

What ran (experiment, configuration, versions, git commit, input and output file hashes from
``provenance.json``), the tables of ``scores.md`` (scores, samples saved, headroom, ...),
every figure of ``figures/`` with its caption (``figures/captions.md``) and the run's timings.
Figures are embedded as base64 PNG data and the style sheet is inline, so the one file can be
mailed, archived or opened anywhere without the folder.
"""

from __future__ import annotations

import base64
import html
import json
import re
from pathlib import Path
from typing import Any

from simlunar.config.loading import load_experiment, to_plain
from simlunar.errors import ResultFolderError, SimlunarError
from simlunar.results.folder import read_folder_config
from simlunar.results.md_tables import parse_markdown
from simlunar.results.store import atomic_write_text

__all__ = [
    "REPORT_NAME",
    "build_report",
    "config_differences",
    "read_captions",
    "run_overrides",
    "write_report",
]

REPORT_NAME = "report.html"

_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;max-width:70rem;margin:2rem auto;
padding:0 1rem;color:#222;line-height:1.45}
h1{margin-bottom:.2rem} h2{border-bottom:1px solid #ccc;padding-bottom:.2rem;margin-top:2.2rem}
table{border-collapse:collapse;margin:.8rem 0;font-size:.9rem}
th,td{border:1px solid #ccc;padding:.25rem .5rem} th{background:#f2f2f2}
td.right,th.right{text-align:right} td.center,th.center{text-align:center}
figure{margin:1.5rem 0} figure img{max-width:100%;height:auto;border:1px solid #ddd}
figcaption{font-size:.9rem;color:#333;max-width:60rem}
pre{background:#f6f6f6;padding:.6rem;overflow:auto;font-size:.8rem}
code{background:#f3f3f3;padding:0 .2rem} .muted{color:#666}
"""


def read_captions(fig_dir: str | Path, name: str = "captions.md") -> dict[str, str]:
    """``{figure stem: caption}`` from ``figures/captions.md`` (empty when there is none);
    with ``name="not_drawn.md"``, ``{figure stem: why it was not drawn}``.

    The files are the ones :func:`simlunar.results.figures.write_captions` writes: a
    ``## stem`` heading per figure followed by its paragraph.
    """
    path = Path(fig_dir) / name
    if not path.is_file():
        return {}
    out: dict[str, str] = {}
    stem = None
    for b in parse_markdown(path.read_text(encoding="utf-8")):
        if b.kind == "heading" and b.level == 2:
            stem = b.text
            out[stem] = ""
        elif b.kind == "paragraph" and stem is not None:
            out[stem] = f"{out[stem]} {b.text}".strip()
    return out


def config_differences(base: Any, other: Any, path: str = "") -> dict[str, Any]:
    """Leaf keys (``a.b.c``) whose value in ``other`` differs from ``base``, with ``other``'s value.

    >>> config_differences({"a": {"b": 1, "c": 2}}, {"a": {"b": 1, "c": 3}})
    {'a.c': 3}
    """
    if isinstance(base, dict) and isinstance(other, dict):
        out: dict[str, Any] = {}
        for k in other:
            sub = f"{path}.{k}" if path else str(k)
            if k not in base:
                out[sub] = other[k]
            else:
                out.update(config_differences(base[k], other[k], sub))
        return out
    return {} if base == other else {path: other}


def run_overrides(folder: str | Path, shipped: str | Path | None = None) -> dict[str, Any]:
    """The keys in which a result folder's configuration differs from an experiment file.

    ``shipped`` defaults to ``experiments/<name>.yaml`` of the current directory for the
    folder's experiment name. Empty when the file is missing or cannot be validated here
    (a learned map's model file absent, say): then nothing is claimed.
    """

    folder = Path(folder)
    cfg = read_folder_config(folder / "config.yaml")
    shipped = Path(shipped) if shipped else Path("experiments") / f"{cfg.get('name')}.yaml"
    if not shipped.is_file():
        return {}
    try:
        base = to_plain(load_experiment(shipped))
    except (SimlunarError, ValueError, OSError):
        return {}
    # the catalogue block (what it shows, its run time) is no part of what ran
    base.pop("catalogue", None)
    return config_differences(base, {k: v for k, v in cfg.items() if k != "catalogue"})


def _inline(text: str) -> str:
    s = html.escape(text, quote=False)
    s = re.sub(r"`([^`]+)`", r"<code>\1</code>", s)
    return re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", s)


def _table(rows: list[list[str]], align: list[str] | None = None, *, cls: str = "") -> str:
    if not rows:
        return ""
    align = align or []

    def cell(tag, i, c):
        a = align[i] if i < len(align) else "left"
        attr = f' class="{a}"' if a != "left" else ""
        return f"<{tag}{attr}>{_inline(c)}</{tag}>"

    head = "".join(cell("th", i, c) for i, c in enumerate(rows[0]))
    body = "".join(
        "<tr>" + "".join(cell("td", i, c) for i, c in enumerate(r)) + "</tr>" for r in rows[1:]
    )
    klass = f' class="{cls}"' if cls else ""
    return f"<table{klass}><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _markdown(text: str) -> str:
    parts = []
    for b in parse_markdown(text):
        if b.kind == "heading":
            level = min(max(b.level, 3), 4)
            parts.append(f"<h{level}>{_inline(b.text)}</h{level}>")
        elif b.kind == "table":
            parts.append(_table(b.rows, b.align, cls="scores"))
        else:
            parts.append(f"<p>{_inline(b.text)}</p>")
    return "\n".join(parts)


def _what_ran(prov: dict, cfg_text: str, description: str) -> str:
    git = prov.get("git") or {}
    commit = git.get("commit") or "unknown"
    if git.get("dirty"):
        commit += " (with uncommitted changes)"
    units = prov.get("units") or {}
    rows = [
        ["item", "value"],
        ["experiment", str(prov.get("experiment", ""))],
        ["description", description],
        ["simlunar", str(prov.get("simlunar", ""))],
        ["git commit", commit],
        ["python", str(prov.get("python", ""))],
        ["Mitsuba variant", str(prov.get("variant", ""))],
        ["executor", json.dumps(prov.get("executor", ""))],
        ["seed", str(prov.get("seed", ""))],
        [
            "work units",
            f"{units.get('total', '?')} ({units.get('cached', '?')} cached, "
            f"{units.get('computed', '?')} computed)",
        ],
    ]
    out = [_table(rows, cls="what-ran")]
    versions = prov.get("versions") or {}
    if versions:
        out += ["<h3>Versions</h3>", _table([["package", "version"], *sorted(versions.items())])]
    inputs = prov.get("inputs") or []
    if inputs:
        rows = [["input", "file", "sha256"]]
        rows += [[i.get("key", ""), i.get("path", ""), i.get("sha256", "")] for i in inputs]
        out += ["<h3>Input files</h3>", _table(rows)]
    files = prov.get("files") or {}
    if files:
        out += ["<h3>Files of this folder</h3>", _table([["file", "sha256"], *files.items()])]
    out += [
        "<h3>Configuration (config.yaml)</h3>",
        f"<details><summary>show</summary><pre>{html.escape(cfg_text)}</pre></details>",
    ]
    return "\n".join(out)


def _timings(prov: dict) -> str:
    t = prov.get("timings") or {}
    out = []
    top = [[k, f"{v:.1f}"] for k, v in t.items() if isinstance(v, int | float)]
    if top:
        out.append(_table([["run", "seconds"], *top], ["left", "right"]))
    units = t.get("units") or {}
    stages = sorted({s for u in units.values() for s in (u or {})})
    if stages:
        rows = [["unit", *stages]]
        for key, u in units.items():
            rows.append([key, *(f"{(u or {})[s]:.2f}" if s in (u or {}) else "" for s in stages)])
        out.append(_table(rows, ["left", *["right"] * len(stages)]))
    return "\n".join(out) or "<p class='muted'>No timings recorded.</p>"


def _figures(fig_dir: Path) -> str:
    captions = read_captions(fig_dir)
    pngs = sorted(fig_dir.glob("*.png")) if fig_dir.is_dir() else []
    order = {s: i for i, s in enumerate(captions)}
    pngs.sort(key=lambda p: (order.get(p.stem, len(order)), p.name))
    skipped = read_captions(fig_dir, "not_drawn.md")
    why = ""
    if skipped:
        items = "".join(
            f"<li><code>{html.escape(stem)}</code>: {_inline(text)}</li>"
            for stem, text in skipped.items()
        )
        why = f"<h3>Not drawn</h3><ul class='not-drawn'>{items}</ul>"
    if not pngs:
        return (
            "<p class='muted'>No figures (run without --no-figures, or `simlunar figures`).</p>"
            + why
        )
    out = []
    for p in pngs:
        data = base64.b64encode(p.read_bytes()).decode("ascii")
        cap = captions.get(p.stem, "")
        out.append(
            f'<figure id="fig-{html.escape(p.stem)}"><img alt="{html.escape(p.stem)}" '
            f'src="data:image/png;base64,{data}"><figcaption><strong>{html.escape(p.stem)}'
            f"</strong>. {_inline(cap)}</figcaption></figure>"
        )
    return "\n".join([*out, why] if why else out)


def build_report(folder: str | Path) -> str:
    """The HTML text of the report of a result folder (see the module docstring).

    Raises
    ------
    ResultFolderError
        When ``folder`` has no ``provenance.json`` (not a finished result folder).
    """
    folder = Path(folder)
    prov_path = folder / "provenance.json"
    try:
        prov = json.loads(prov_path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        raise ResultFolderError(
            f"{folder}: no readable provenance.json; not a finished result folder of `simlunar run`"
        ) from None
    cfg_path = folder / "config.yaml"
    cfg_text = cfg_path.read_text(encoding="utf-8") if cfg_path.is_file() else ""
    try:
        description = str(read_folder_config(cfg_path).get("description") or "")
    except ResultFolderError:
        description = ""
    scores = folder / "scores.md"
    name = html.escape(str(prov.get("experiment", folder.name)))
    sections = [
        ("what-ran", "What ran", _what_ran(prov, cfg_text, description)),
        (
            "tables",
            "Tables",
            _markdown(scores.read_text(encoding="utf-8"))
            if scores.is_file()
            else "<p class='muted'>No scores.md.</p>",
        ),
        ("figures", "Figures", _figures(folder / "figures")),
        ("timings", "Timings", _timings(prov)),
    ]
    nav = " · ".join(f'<a href="#{k}">{t}</a>' for k, t, _ in sections)
    body = "\n".join(f'<section id="{k}"><h2>{t}</h2>\n{c}\n</section>' for k, t, c in sections)
    return (
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
        f"<title>simlunar report: {name}</title><style>{_CSS}</style></head><body>"
        f"<h1>simlunar report: {name}</h1><p class='muted'>{_inline(description)}</p>"
        f"<p>{nav}</p>\n{body}\n</body></html>\n"
    )


def write_report(folder: str | Path) -> Path:
    """Write ``<folder>/report.html`` (:func:`build_report`); returns its path."""
    path = Path(folder) / REPORT_NAME
    atomic_write_text(path, build_report(folder))
    return path
