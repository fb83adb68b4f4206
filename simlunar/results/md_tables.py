"""The Markdown a run writes (``scores.md``) read back as blocks, and its tables as CSV.

``scores.md`` is made of ``### title`` headings, paragraphs and pipe tables (the score table,
the samples-saved tables, the headroom table, per-seed tables). :func:`parse_markdown` splits
it into those blocks; :func:`write_table_csvs` writes every table also as CSV, one file per
table in ``tables/`` beside ``scores.md``, named after its heading, so a spreadsheet or pandas
reads each table without parsing Markdown.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass, field
from pathlib import Path

from simlunar.results.store import atomic_write_text

__all__ = ["TABLES_DIR", "Block", "parse_markdown", "table_slug", "write_table_csvs"]

TABLES_DIR = "tables"


@dataclass(frozen=True)
class Block:
    """One block of a Markdown document.

    Attributes
    ----------
    kind : {"heading", "paragraph", "table"}
    text : str
        The heading's or paragraph's text (empty for a table).
    level : int
        Heading level (number of ``#``); 0 for other blocks.
    rows : list of list of str
        A table's rows, header first, the ``|---|`` separator removed; cells stripped.
    align : list of str
        A table's column alignment from its separator: ``"left"``, ``"right"`` or ``"center"``.
    """

    kind: str
    text: str = ""
    level: int = 0
    rows: list[list[str]] = field(default_factory=list)
    align: list[str] = field(default_factory=list)


_SEP = re.compile(r"^\|?\s*:?-{3,}:?\s*(\|\s*:?-{3,}:?\s*)*\|?\s*$")


def _cells(line: str) -> list[str]:
    s = line.strip()
    s = s[1:] if s.startswith("|") else s
    s = s[:-1] if s.endswith("|") and not s.endswith("\\|") else s
    return [c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", s)]


def _align(cell: str) -> str:
    c = cell.strip()
    if c.startswith(":") and c.endswith(":"):
        return "center"
    return "right" if c.endswith(":") else "left"


def parse_markdown(text: str) -> list[Block]:
    """Split Markdown into heading, paragraph and pipe-table blocks (in order).

    A table is a run of lines starting with ``|`` whose second line is a separator
    (``|---|---:|``); a paragraph is a run of other non-blank lines.
    """
    blocks: list[Block] = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if not line.strip():
            i += 1
        elif line.startswith("#"):
            level = len(line) - len(line.lstrip("#"))
            blocks.append(Block("heading", line[level:].strip(), level=level))
            i += 1
        elif line.lstrip().startswith("|") and i + 1 < len(lines) and _SEP.match(lines[i + 1]):
            rows = [_cells(line)]
            align = [_align(c) for c in _cells(lines[i + 1])]
            i += 2
            while i < len(lines) and lines[i].lstrip().startswith("|"):
                rows.append(_cells(lines[i]))
                i += 1
            blocks.append(Block("table", rows=rows, align=align))
        else:
            para = []
            while (
                i < len(lines)
                and lines[i].strip()
                and not lines[i].startswith("#")
                and not lines[i].lstrip().startswith("|")
            ):
                para.append(lines[i].strip())
                i += 1
            if not para:  # a lone "|" line that is not a table
                para.append(lines[i].strip())
                i += 1
            blocks.append(Block("paragraph", " ".join(para)))
    return blocks


def table_slug(title: str) -> str:
    """A file-name stem of a table's heading: lower case, ``[a-z0-9_]`` only.

    >>> table_slug("quickstart: samples saved vs Grid at equal MSE")
    'quickstart_samples_saved_vs_grid_at_equal_mse'
    """
    slug = re.sub(r"[^a-z0-9]+", "_", title.lower()).strip("_")
    return slug or "table"


def write_table_csvs(out_dir: str | Path, markdown: str) -> list[Path]:
    """Write every table of ``markdown`` as CSV in ``<out_dir>/tables/``; return the files.

    Each file is named after the heading above its table (``table_slug``; ``_2``, ``_3``, ...
    when two headings give one name; ``table_<i>`` for a table with no heading), holds the
    header row and the cells as shown (``**`` bold markers and ``*`` range flags kept as
    text). CSV files of ``tables/`` that this call did not write (tables of an earlier state
    of the folder) are removed, so the folder always matches ``scores.md``.
    """
    folder = Path(out_dir) / TABLES_DIR
    written: list[Path] = []
    title = ""
    seen: dict[str, int] = {}
    for b in parse_markdown(markdown):
        if b.kind == "heading":
            title = b.text
            continue
        if b.kind != "table":
            continue
        stem = table_slug(title) if title else f"table_{len(written) + 1}"
        seen[stem] = seen.get(stem, 0) + 1
        if seen[stem] > 1:
            stem = f"{stem}_{seen[stem]}"
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerows(b.rows)
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"{stem}.csv"
        atomic_write_text(path, buf.getvalue())
        written.append(path)
        title = ""
    if folder.is_dir():
        keep = {p.name for p in written}
        for p in folder.glob("*.csv"):
            if p.name not in keep:
                p.unlink()
        if not any(folder.iterdir()):
            folder.rmdir()
    return written
