"""The experiment catalogue: one row per shipped experiment (``experiments/*.yaml``), made from
the experiments' own ``catalogue`` blocks (:class:`simlunar.config.schema.CatalogueCfg`: what
it shows, one measured run time with the machine's load) and written between markers into
README.md and docs/experiments.md, so the table is kept in one place, the YAML beside the run
it describes.

``python -m simlunar.config.catalogue README.md docs/experiments.md`` rewrites the blocks
(``make docs`` does); ``--check`` exits 1 when one is stale.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import yaml

from simlunar.config.schema import CatalogueCfg, RunTimeCfg

__all__ = [
    "BEGIN",
    "END",
    "FIRST_RUN_NOTE",
    "Entry",
    "catalogue_block",
    "catalogue_markdown",
    "experiment_catalogue",
    "main",
    "run_time_text",
    "update_catalogue",
]

BEGIN = (
    "<!-- experiment-catalogue:begin (generated from experiments/*.yaml: "
    "python -m simlunar.config.catalogue) -->"
)
END = "<!-- experiment-catalogue:end -->"

#: said under every catalogue: what the times mean and what a first run costs on top
FIRST_RUN_NOTE = (
    "Run times are wall clock of `simlunar run` into an empty result folder, figures included "
    "unless stated, `--workers 1` unless stated, each with the machine's load beside it (a "
    "number measured on a shared machine is slower than on an idle one). A first run on a "
    "machine also compiles kernels once (the renderer's into `DRJIT_CACHE_DIR`, the Numba "
    "kernels into `__pycache__`) and reads the libraries from disk: what that cost when "
    "measured is in docs/install.md, and the quickstart's first run with an empty kernel "
    "cache is given beside its time. `simlunar run EXPERIMENT --dry-run` prints the units "
    "and an estimate of time and memory for your machine without running anything "
    "(docs/experiments.md)."
)


@dataclass(frozen=True)
class Entry:
    """One experiment of the catalogue.

    Attributes
    ----------
    name : str
        The file's stem (``quickstart``), as ``simlunar run experiments/<name>.yaml`` runs it.
    shows : str
        What it shows (``catalogue.shows``; empty when the file has no catalogue block).
    units : int
        Work units: the product of the sweep axes' lengths times ``study.terrain_seeds``.
    run_time : RunTimeCfg
        Its measured run time and the conditions.
    """

    name: str
    shows: str
    units: int
    run_time: RunTimeCfg


def _units(data: dict) -> int:
    n = 1
    for values in (data.get("sweep") or {}).values():
        n *= max(len(values or []), 1)
    seeds = (data.get("study") or {}).get("terrain_seeds") or 1
    return n * int(seeds)


def experiment_catalogue(directory: str | Path) -> list[Entry]:
    """The catalogue entries of every ``*.yaml`` directly in ``directory``: the quickstart
    first, then the others by name.

    Only each file's ``catalogue`` block is validated here (the whole experiment is checked
    when it runs, and by the tests of the shipped experiments).

    Raises
    ------
    ValueError
        A file whose ``catalogue`` block is invalid (naming the file and the problem).
    """
    out = []
    paths = sorted(Path(directory).glob("*.yaml"), key=lambda p: (p.stem != "quickstart", p.stem))
    for path in paths:
        data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
        try:
            cat = CatalogueCfg.model_validate(data.get("catalogue") or {})
        except ValueError as exc:
            raise ValueError(f"{path}: catalogue: {exc}") from None
        shows = " ".join(cat.shows.split())
        shows = shows[:1].upper() + shows[1:]  # every row a sentence
        out.append(Entry(path.stem, shows, _units(data), cat.run_time))
    return out


def _minutes(m: float) -> str:
    """``0.42`` -> ``"25 s"``, ``1.85`` -> ``"111 s"``, ``20.8`` -> ``"20.8 min"``."""
    if m < 2.0:
        return f"{round(m * 60)} s"
    return f"{m:.1f} min" if m < 100 else f"{m:.0f} min"


def run_time_text(rt: RunTimeCfg) -> str:
    """The catalogue's run-time cell: the time, the load and the note, and the first run with
    an empty kernel cache where it was measured; "not re-measured" without a time.

    >>> run_time_text(RunTimeCfg(wall_min=0.5, load="2 cores, load 1.9", first_run_min=1.2))
    '30 s (2 cores, load 1.9; first run, empty kernel cache: 72 s)'
    """
    if rt.wall_min is None:
        return f"not re-measured{f' ({rt.note})' if rt.note else ''}"
    parts = [rt.load, rt.note]
    if rt.first_run_min is not None:
        parts.append(f"first run, empty kernel cache: {_minutes(rt.first_run_min)}")
    return f"{_minutes(rt.wall_min)} ({'; '.join(p for p in parts if p)})"


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def catalogue_markdown(entries: list[Entry]) -> str:
    """The catalogue as a Markdown table (experiment, what it shows, units, run time) and the
    note on run times and first runs below it."""
    lines = ["| experiment | what it shows | units | run time |", "|---|---|---:|---|"]
    for e in entries:
        shows = e.shows or "**(no catalogue entry: add `catalogue.shows` to its YAML)**"
        lines.append(
            f"| `{e.name}` | {_cell(shows)} | {e.units} | {_cell(run_time_text(e.run_time))} |"
        )
    return "\n".join([*lines, "", FIRST_RUN_NOTE]) + "\n"


def catalogue_block(text: str) -> str | None:
    """The catalogue inside a document's markers (None without markers)."""
    if BEGIN not in text or END not in text:
        return None
    return text.split(BEGIN, 1)[1].split(END, 1)[0].strip("\n") + "\n"


def update_catalogue(path: str | Path, experiments: str | Path, *, check: bool = False) -> bool:
    """Rewrite the catalogue block of ``path`` from the YAMLs of ``experiments``; True when
    it changed (with ``check``, nothing is written: True = stale).

    Raises
    ------
    ValueError
        ``path`` has no catalogue markers.
    """
    path = Path(path)
    text = path.read_text(encoding="utf-8")
    block = catalogue_block(text)
    if block is None:
        raise ValueError(f"{path}: no {BEGIN} ... {END} markers")
    new = catalogue_markdown(experiment_catalogue(experiments))
    if block == new:
        return False
    if not check:
        head, rest = text.split(BEGIN, 1)
        tail = rest.split(END, 1)[1]
        path.write_text(f"{head}{BEGIN}\n{new}{END}{tail}", encoding="utf-8")
    return True


def main(argv: list[str] | None = None) -> int:
    """``python -m simlunar.config.catalogue [--check] FILE...`` (experiments/ of the current
    directory)."""
    args = list(sys.argv[1:] if argv is None else argv)
    check = "--check" in args
    files = [a for a in args if a != "--check"] or ["README.md", "docs/experiments.md"]
    stale = [f for f in files if update_catalogue(f, "experiments", check=check)]
    for f in stale:
        print(f"{f}: catalogue {'stale' if check else 'rewritten'}")
    return 1 if check and stale else 0


if __name__ == "__main__":
    raise SystemExit(main())
