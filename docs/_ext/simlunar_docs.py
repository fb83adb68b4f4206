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
``_generated/api.rst`` (+ ``_generated/api/<module>.rst``)
    the API reference: one autodoc page per module of ``simlunar``.

The configuration reference is not generated here: it lives in ``experiments.md`` between
markers that ``make docs`` refreshes (``simlunar.config.docs.update_docs``).
"""

from __future__ import annotations

import dataclasses
import html
import re
import shutil
import subprocess
import sys
import typing
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # run as a script (make docs-gallery): this checkout's simlunar
    sys.path.insert(0, str(ROOT))

import simlunar  # noqa: E402
from simlunar.config.yamlio import load_yaml  # noqa: E402
from simlunar.registry import option_docs  # noqa: E402
from simlunar.results.report import read_captions, run_overrides  # noqa: E402

__all__ = [
    "GALLERY_RUN",
    "RESULT_ROOTS",
    "SMALL_RUN_SETS",
    "gallery_run",
    "setup",
    "write_generated",
]

#: where result folders are looked for, in order (relative to the repository root)
RESULT_ROOTS = ("results", "build/docs-runs")
#: the small quickstart run of a checkout with no results: its folder and ``--set`` overrides
#: (1/16 scale, 2 samples per pixel, 2 trials, 2 densities: about 30 s of CPU time)
GALLERY_RUN = "build/docs-runs/quickstart"
SMALL_RUN_SETS = (
    "terrain.scale=0.0625",
    "render.spp=2",
    "study.trials=2",
    'study.densities=["1/4","1/16"]',
)


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
        "`simlunar run experiments/<name>.yaml`; what each shows and its measured run time:",
        "the experiment catalogue of [Experiments](../experiments.md).",
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


def _modules() -> list[str]:
    """Every module of ``simlunar``, found in its files (``config/`` and ``results/`` are
    namespace packages, which ``pkgutil.walk_packages`` does not enter); ``__main__`` is left
    out: importing it would run the command line."""
    pkg = Path(simlunar.__file__).parent
    names = set()
    for f in pkg.rglob("*.py"):
        parts = f.relative_to(pkg.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if parts[-1] != "__main__" and "__pycache__" not in parts:
            names.add(".".join(parts))
    for d in pkg.rglob("*"):
        if d.is_dir() and d.name != "__pycache__" and any(d.glob("*.py")):
            names.add(".".join(d.relative_to(pkg.parent).parts))
    return sorted(names)


def _api(out: Path) -> str:
    """The API index (``api.rst``) and one page per module (``api/<module>.rst``): each page is
    the module's docstring and its own members (``:ignore-module-all:``: a package's
    re-exports are documented once, where they are defined)."""
    folder = out / "api"
    folder.mkdir(exist_ok=True)
    modules = _modules()
    for name in modules:
        title = f"``{name}``"
        _write_if_changed(
            folder / f"{name}.rst",
            f"{title}\n{'=' * len(title)}\n\n.. automodule:: {name}\n   :members:\n"
            "   :ignore-module-all:\n",
        )
    for stale in folder.glob("*.rst"):
        if stale.stem not in modules:
            stale.unlink()
    lines = [
        "API reference",
        "=============",
        "",
        "Generated from the numpydoc docstrings of every module of ``simlunar`` each time the",
        "site is built. The package contracts are in CONTRIBUTING.md.",
        "",
        ".. toctree::",
        "   :maxdepth: 1",
        "",
        "   api/simlunar",
        "",
    ]
    top = sorted({".".join(n.split(".")[:2]) for n in modules if n != "simlunar"})
    for pkg in top:
        heading = f"``{pkg}``"
        members = [n for n in modules if n == pkg or n.startswith(pkg + ".")]
        lines += [heading, "-" * len(heading), "", ".. toctree::", "   :maxdepth: 1", ""]
        lines += [f"   api/{n}" for n in members]
        lines.append("")
    return "\n".join(lines)


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
    _write_if_changed(out / "api.rst", _api(out))
    return out


_LITERAL = re.compile(r"(``.+?``|`[^`]*`)")


def _escape_bars(lines: list[str]) -> None:
    """Escape ``|`` in docstring prose, in place: the docstrings write absolute values and
    norms as ``|x|`` in plain text, which reStructuredText reads as a substitution reference.
    Inline literals, roles, doctests, tables, line blocks and literal blocks are left alone."""
    literal_indent = None
    for i, line in enumerate(lines):
        stripped = line.lstrip()
        indent = len(line) - len(stripped)
        if literal_indent is not None:
            if stripped and indent <= literal_indent:
                literal_indent = None
            else:
                continue
        table = stripped.startswith("+") or (
            stripped.startswith("|") and stripped.rstrip().endswith("|")
        )
        if table or stripped.startswith((">>>", "...")) or "|" not in line:
            if line.rstrip().endswith("::"):
                literal_indent = indent
            continue
        parts = _LITERAL.split(line)
        lines[i] = "".join(
            p if j % 2 else re.sub(r"(?<!\\)\|", r"\\|", p) for j, p in enumerate(parts)
        )
        if line.rstrip().endswith("::"):
            literal_indent = indent


def _on_docstring(app, what, name, obj, options, lines) -> None:
    _add_option_docs(what, obj, lines)
    _escape_bars(lines)


def _add_option_docs(what, obj, lines: list[str]) -> None:
    """Append an options dataclass's ``Attributes`` section, made from what each field's
    :func:`simlunar.registry.option` declares (doc, unit, bounds, default), in place: a field
    is documented where it is declared. A docstring that writes its own section keeps it."""
    if what != "class" or not dataclasses.is_dataclass(obj):
        return
    if any(line.strip() in ("Attributes", "Parameters") for line in lines):
        return
    extra = option_docs(obj)
    if extra:
        lines.extend(["", *extra])


def gallery_run(root: str | Path = ROOT) -> Path | None:
    """Make the small quickstart run (:data:`SMALL_RUN_SETS`) into :data:`GALLERY_RUN` unless
    ``results/quickstart`` or that folder already has figures; returns the folder made, or
    None when nothing had to be run. Raises ``RuntimeError`` with the run's output if it fails.
    """
    root = Path(root)
    if any((root / base / "quickstart/figures/captions.md").is_file() for base in RESULT_ROOTS):
        return None
    argv = [sys.executable, "-m", "simlunar.cli", "run", "experiments/quickstart.yaml"]
    argv += ["--out", GALLERY_RUN, "--no-progress"]
    for item in SMALL_RUN_SETS:
        argv += ["--set", item]
    r = subprocess.run(argv, cwd=root, capture_output=True, text=True, check=False)
    if r.returncode != 0:
        raise RuntimeError(f"the gallery's quickstart run failed:\n{r.stdout}\n{r.stderr}")
    return root / GALLERY_RUN


def _on_skip(app, what, name, obj, skip, options):
    # a module's imports (scipy's cKDTree, say) are not its API
    if isinstance(obj, typing.TypeVar):  # a generic's type variable is not API (numpydoc fails)
        return True
    module = getattr(obj, "__module__", None)
    if what == "module" and isinstance(module, str) and not module.startswith("simlunar"):
        return True
    return None


def _on_init(app, config) -> None:
    write_generated(app.srcdir)


def setup(app):
    app.connect("config-inited", _on_init)
    app.connect("autodoc-process-docstring", _on_docstring, priority=100)  # before numpydoc
    app.connect("autodoc-skip-member", _on_skip)
    return {"parallel_read_safe": True, "parallel_write_safe": True, "version": "1"}


if __name__ == "__main__":  # `make docs-gallery`
    made = gallery_run()
    print(f"gallery: {made}" if made else "gallery: result folders present, nothing to run")
