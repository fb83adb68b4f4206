"""``simlunar run`` and ``simlunar figures``: an experiment into its result folder, and the
figures of a result folder redrawn."""

from __future__ import annotations

import logging
from pathlib import Path

import typer

from simlunar.cli.common import flag, user_input
from simlunar.config.yamlio import parse_set
from simlunar.errors import SimlunarError
from simlunar.pipeline.executors import make_executor

__all__ = ["figures", "run"]

_SET_OPTION = typer.Option(
    None,
    "--set",
    metavar="KEY=VALUE",
    help="override a key: --set render.spp=32 (repeatable)",
    show_default=False,
)

# The library is imported inside each command, not at the top: importing it takes about 3 s (the
# scientific stack, and config.registry, which reads every planner, sensor and renderer), which
# `simlunar run --help` and a mistyped option should not pay (0.3 s with these imports here).


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
    from simlunar.config.advice import config_warnings
    from simlunar.config.loading import load_experiment
    from simlunar.pipeline.runner import run_experiment
    from simlunar.results.array_exports import check_save_arrays
    from simlunar.results.exports import check_save_scans
    from simlunar.results.report import write_report

    with user_input():
        overrides = parse_set(set_ or [])
        if pdf:
            overrides = {**overrides, "figures.formats": ["png", "pdf"]}
        cfg = load_experiment(experiment, overrides)
        if save_scans:
            check_save_scans(cfg)
            # an override before validation, so every sweep point is checked with it
            overrides = {**overrides, "study.save_scans": True}
            cfg = load_experiment(experiment, overrides)
        if save_arrays:
            check_save_arrays(cfg)
            overrides = {**overrides, "study.save_arrays": True}
            cfg = load_experiment(experiment, overrides)
        for line in config_warnings(cfg):
            typer.echo(line, err=True)
        out_dir = Path(out) if out else Path("results") / cfg.name
        if dry_run:
            from simlunar.pipeline.estimate import estimate_run
            from simlunar.pipeline.preflight import check_out_dir

            check_out_dir(out_dir)
            est = estimate_run(cfg, out_dir, workers=workers or 1, figures=figures)
            for line in est.lines(out_dir):
                typer.echo(line)
            return
        executor = make_executor(workers=workers, scheduler=scheduler)
    if scheduler:
        # a lost scheduler or worker is reported in one line; Dask's own log would add pages
        logging.getLogger("distributed").setLevel(logging.CRITICAL)
    summary = run_experiment(cfg, out_dir, executor=executor, progress=progress, figures=figures)
    typer.echo(summary.scores_markdown)
    for note in summary.notes:
        typer.echo(note)
    typer.echo(
        f"work units: {summary.units_total} ({summary.units_cached} cached, "
        f"{summary.units_computed} computed) in {summary.elapsed_s:.1f} s"
    )
    typer.echo(f"results: {out_dir}")
    if summary.figures:
        typer.echo(f"figures: {summary.figures_dir}")
    typer.echo(f"report: {write_report(out_dir)}")


def figures(
    results_dir: str = typer.Argument(..., help="a result folder of `simlunar run`"),
    pdf: bool = flag("--pdf", "PDF besides PNG [default: the folder's figures.formats]"),
    force: bool = flag("--force", "redraw even when the figures' inputs are unchanged"),
) -> None:
    """Draw the figures of a result folder without recomputing (only those whose inputs changed)."""
    from simlunar.pipeline.preflight import check_out_dir
    from simlunar.results.figures import write_figures_pruned
    from simlunar.results.store import FolderLock

    check_out_dir(results_dir, option="figures")
    if not Path(results_dir).is_dir():
        raise SimlunarError(f"{results_dir}: no such folder")
    fig_dir = Path(results_dir) / "figures"
    before = {p: p.stat().st_mtime_ns for p in fig_dir.glob("*")} if fig_dir.is_dir() else {}
    with FolderLock(results_dir):  # not while a run writes into the folder
        paths = write_figures_pruned(
            results_dir, formats=("png", "pdf") if pdf else None, force=force
        )
    # a figure is redrawn when its file is new or rewritten; the others were up to date
    redrawn = [p for p in paths if before.get(p) != p.stat().st_mtime_ns]
    removed = sorted(set(before) - set(paths) - {fig_dir / "captions.md"})
    kept = [p for p in paths if p not in redrawn]
    if redrawn:
        typer.echo(f"redrew {len(redrawn)} file(s) in {fig_dir}:")
        for p in redrawn:
            typer.echo(f"  {p.name}")
    if kept:
        how = "use --force to redraw them" if not redrawn else "their inputs did not change"
        typer.echo(f"up to date, not redrawn: {len(kept)} file(s) ({how})")
    for p in removed:
        if not p.exists():
            typer.echo(f"removed {p.name} (no longer produced)")
    if not paths:
        typer.echo(f"no figures for {results_dir} (its study draws none)")
