"""Sphinx extension: the generated pages of the simlunar site, written before each build.

``_generated/experiments.md``
    one row per shipped experiment (``experiments/*.yaml``): its name, study kind and the
    ``description`` of the file itself.
``_generated/gallery.md`` (+ ``_generated/gallery/<experiment>/*.png``)
    every figure of every shipped experiment that has a result folder in this checkout, with
    the caption ``simlunar run`` wrote beside it (``figures/captions.md``). Result folders are
    looked for in ``results/<name>/`` (what ``simlunar run`` writes) and then in
    ``build/docs-runs/<name>/`` (the small quickstart run ``make docs`` makes when a fresh
    clone has no results: figures are results, never committed); an experiment with no
    folder is listed with the command that makes its figures.
``_generated/api.rst``
    the API reference: one autosummary entry per package of ``simlunar``.

The configuration reference is not generated here: it lives in ``experiments.md`` between
markers that ``make docs`` refreshes (``simlunar.config.docs.update_docs``).
"""

from __future__ import annotations

import html
import pkgutil
import shutil
from pathlib import Path

import simlunar
from simlunar.config.yamlio import load_yaml
from simlunar.results.report import read_captions, run_overrides

__all__ = ["RESULT_ROOTS", "setup", "write_generated"]

ROOT = Path(__file__).resolve().parents[2]
#: where result folders are looked for, in order (relative to the repository root)
RESULT_ROOTS = ("results", "build/docs-runs")


def _experiments() -> list[tuple[str, dict]]:
    out = []
    for path in sorted((ROOT / "experiments").glob("*.yaml")):
        out.append((path.stem, load_yaml(path) or {}))
    return out


def _cell(text) -> str:
    return " ".join(str(text or "").split()).replace("|", "\\|")


def _experiment_table(exps) -> str:
    lines = [
        "# Shipped experiments",
        "",
        "Generated from `experiments/*.yaml` each time the site is built. Run one with",
        "`simlunar run experiments/<name>.yaml`; measured run times are in the README.",
        "",
        "| experiment | study | description |",
        "|---|---|---|",
    ]
    for name, cfg in exps:
        kind = (cfg.get("study") or {}).get("kind", "sampling")
        lines.append(f"| `{name}` | {kind} | {_cell(cfg.get('description'))} |")
    return "\n".join(lines) + "\n"


def _result_folder(name: str) -> Path | None:
    for base in RESULT_ROOTS:
        d = ROOT / base / name
        if (d / "figures" / "captions.md").is_file():
            return d
    return None


def _gallery(exps, out: Path) -> str:
    img_root = out / "gallery"
    shutil.rmtree(img_root, ignore_errors=True)
    lines = [
        "# Figure gallery",
        "",
        "Every figure of every shipped experiment that has a result folder in this checkout,",
        "with the caption `simlunar run` wrote for it. The gallery is generated when the site",
        "is built: from `results/<experiment>/` where the experiment was run, otherwise from",
        "`build/docs-runs/<experiment>/`, where `make docs` runs a small version of the",
        "quickstart when there are no results (figures are results: none is committed). The",
        "folder and the overrides it ran with are named above its figures.",
        "",
    ]
    missing = []
    for name, cfg in exps:
        folder = _result_folder(name)
        if folder is None:
            missing.append(name)
            continue
        captions = read_captions(folder / "figures")
        rel = folder.relative_to(ROOT)
        lines += [f"## {name}", "", _cell(cfg.get("description")), ""]
        lines += [f"Result folder `{rel}`."]
        over = run_overrides(folder)
        if over:
            shown = ", ".join(f"`{k}={v}`" for k, v in over.items())
            lines += [f"Run with overrides of the shipped file: {shown}."]
        lines.append("")
        for stem, caption in captions.items():
            png = folder / "figures" / f"{stem}.png"
            if not png.is_file():
                continue
            dest = img_root / name / png.name
            dest.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(png, dest)
            lines += [
                f"```{{figure}} gallery/{name}/{png.name}",
                f":alt: {name}: {stem}",
                f":name: gallery-{name}-{stem}",
                "",
                f"**{stem}**. {html.escape(_cell(caption), quote=False)}",
                "```",
                "",
            ]
    if missing:
        lines += [
            "## Not run in this checkout",
            "",
            "These experiments have no result folder here; "
            "`simlunar run experiments/<name>.yaml` makes their figures and the next "
            "`make docs` shows them:",
            "",
        ]
        lines += [f"- `{n}`" for n in missing]
        lines.append("")
    return "\n".join(lines)


def _api() -> str:
    packages = sorted(
        m.name
        for m in pkgutil.iter_modules(simlunar.__path__, "simlunar.")
        if m.ispkg or m.name in ("simlunar.registry", "simlunar.errors", "simlunar.atomic")
    )
    lines = [
        "API reference",
        "=============",
        "",
        "Generated from the numpydoc docstrings of every package of ``simlunar``.",
        "",
        ".. autosummary::",
        "   :toctree: api",
        "   :recursive:",
        "",
    ]
    lines += [f"   {p}" for p in packages]
    return "\n".join(lines) + "\n"


def _write_if_changed(path: Path, text: str) -> None:
    # unchanged sources keep their mtime, so an incremental build does not reread them
    if not path.is_file() or path.read_text() != text:
        path.write_text(text)


def write_generated(srcdir: str | Path) -> Path:
    """Write the generated pages under ``<srcdir>/_generated``; returns that folder."""
    out = Path(srcdir) / "_generated"
    out.mkdir(parents=True, exist_ok=True)
    exps = _experiments()
    _write_if_changed(out / "experiments.md", _experiment_table(exps))
    _write_if_changed(out / "gallery.md", _gallery(exps, out))
    _write_if_changed(out / "api.rst", _api())
    return out


def _on_init(app) -> None:
    write_generated(app.srcdir)


def setup(app):
    app.connect("builder-inited", _on_init)
    return {"parallel_read_safe": True, "parallel_write_safe": True, "version": "1"}
