"""``simlunar run`` and ``simlunar figures``: an experiment into its result folder, and the
figures of a result folder redrawn."""

from __future__ import annotations

import typer

from simlunar.cli.common import flag

__all__ = ["figures", "run"]

_SET_OPTION = typer.Option(
    None,
    "--set",
    metavar="KEY=VALUE",
    help="override a key: --set render.spp=32 (repeatable)",
    show_default=False,
)

# The commands' work is in simlunar.cli.run_actions, imported when a command runs: the library
# takes about 3 s to import (the scientific stack, and config.registry, which reads every
# planner, sensor and renderer), which `simlunar run --help` and a mistyped option should not
# pay (0.3 s with the signatures alone).


def run(
    experiment: str = typer.Argument(..., help="experiment YAML (see experiments/)"),
    out: str = typer.Option(None, "--out", help="result folder [default: results/<name>]"),
    workers: int = typer.Option(
        None,
        "--workers",
        help="units at a time, as threads of this process; each sampling study on N forked processes [default: 1]",
    ),
    scheduler: str = typer.Option(
        None,
        "--scheduler",
        help="Dask scheduler address, e.g. tcp://host:8786 [default: none, this machine]",
    ),
    set_: list[str] | None = _SET_OPTION,
    progress: bool = typer.Option(
        True, "--progress/--no-progress", help="progress bar with ETA on stderr"
    ),
    figures: bool = typer.Option(
        True,
        "--figures/--no-figures",
        help="draw figures/ (redrawn only when the tables they read changed)",
    ),
    pdf: bool = flag(
        "--pdf", "figures as PDF too (as figures.formats: [png, pdf]) [default: PNG only]"
    ),
    save_scans: bool = flag(
        "--save-scans", "scanner and lidar studies: export each unit's scan to scans/unit<i>/"
    ),
    save_arrays: bool = flag(
        "--save-arrays",
        "sampling and lidar studies: write each unit's reconstructions and error maps "
        "(GeoTIFF, EXR) to arrays/unit<i>/",
    ),
    dry_run: bool = flag(
        "--dry-run",
        "check everything, list the units, estimate time and memory; write nothing",
    ),
) -> None:
    """Run (or resume) an experiment: results.csv, scores.md/.tex, provenance.json, figures/."""
    from simlunar.cli import run_actions

    flags = {"pdf": pdf, "save_scans": save_scans, "save_arrays": save_arrays, "dry_run": dry_run}
    run_actions.run_experiment_command(
        experiment,
        out=out,
        workers=workers,
        scheduler=scheduler,
        set_=set_ or [],
        progress=progress,
        figures=figures,
        flags=flags,
    )


def figures(
    results_dir: str = typer.Argument(..., help="a result folder of `simlunar run`"),
    pdf: bool = flag("--pdf", "PDF besides PNG [default: the folder's figures.formats]"),
    force: bool = flag("--force", "redraw even when the figures' inputs are unchanged"),
) -> None:
    """Draw the figures of a result folder without recomputing (only those whose inputs changed)."""
    from simlunar.cli import run_actions

    run_actions.redraw_figures(results_dir, pdf=pdf, force=force)
