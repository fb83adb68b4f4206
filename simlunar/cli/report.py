"""``simlunar report``: a result folder as one self-contained HTML page."""

from __future__ import annotations

from pathlib import Path

import typer

from simlunar.cli.common import echo
from simlunar.errors import SimlunarError

__all__ = ["report"]

# The library is imported inside the command, not at the top: results.report imports the
# config loader (the scientific stack, about 4 s), which `simlunar report --help` should not pay.


def report(
    results_dir: str = typer.Argument(..., help="a result folder of `simlunar run`"),
) -> None:
    """Write report.html of a result folder: config, versions, tables, figures, timings."""
    from simlunar.results.report import write_report
    from simlunar.results.store import FolderLock

    if not Path(results_dir).is_dir():
        raise SimlunarError(f"{results_dir}: no such folder")
    with FolderLock(results_dir):  # not while a run writes into the folder
        path = write_report(results_dir)
    echo(str(path))
