"""The work of ``simlunar run`` and ``simlunar figures``, with the library imported at the top.

:mod:`simlunar.cli.run` holds the two commands' signatures (what ``--help`` reads: Typer and
the options only, in 0.3 s) and imports this module when a command is invoked; the library
(the scientific stack and config.registry, about 3 s) is imported here, once. The pipeline's
modules are used through their module objects (``runner.run_experiment``), so a test that
replaces a library function replaces it for the command too.
"""

from __future__ import annotations

import logging
from pathlib import Path

import typer

from simlunar.cli.common import echo, user_input
from simlunar.config import advice, loading
from simlunar.config.yamlio import parse_set
from simlunar.errors import SimlunarError
from simlunar.pipeline import estimate, preflight, runner
from simlunar.pipeline.executors import make_executor
from simlunar.results import array_exports, exports, report, store
from simlunar.results import figures as result_figures

__all__ = ["redraw_figures", "run_experiment_command"]


def _load(experiment: str, set_: list[str], *, pdf: bool, save_scans: bool, save_arrays: bool):
    """The validated experiment with its ``--set`` overrides, ``--pdf`` and the export flags
    (each an override before validation, so every sweep point is checked with it)."""
    overrides = parse_set(set_)
    if pdf:
        overrides = {**overrides, "figures.formats": ["png", "pdf"]}
    cfg = loading.load_experiment(experiment, overrides)
    for wanted, check, key in (
        (save_scans, exports.check_save_scans, "study.save_scans"),
        (save_arrays, array_exports.check_save_arrays, "study.save_arrays"),
    ):
        if wanted:
            check(cfg)
            overrides = {**overrides, key: True}
            cfg = loading.load_experiment(experiment, overrides)
    return cfg


def run_experiment_command(
    experiment: str,
    *,
    out: str | None,
    workers: int | None,
    scheduler: str | None,
    set_: list[str],
    progress: bool,
    figures: bool,
    flags: dict[str, bool],
) -> None:
    """``simlunar run``: check, then run (or only estimate, ``flags["dry_run"]``) and print
    the summary. ``flags``: ``pdf``, ``save_scans``, ``save_arrays``, ``dry_run``."""
    with user_input():
        cfg = _load(
            experiment,
            set_,
            pdf=flags["pdf"],
            save_scans=flags["save_scans"],
            save_arrays=flags["save_arrays"],
        )
        for line in advice.config_warnings(cfg):
            typer.echo(line, err=True)
        out_dir = Path(out) if out else Path("results") / cfg.name
        if flags["dry_run"]:
            preflight.check_out_dir(out_dir)
            est = estimate.estimate_run(cfg, out_dir, workers=workers or 1, figures=figures)
            for line in est.lines(out_dir):
                echo(line)
            return
        executor = make_executor(workers=workers, scheduler=scheduler)
    if scheduler:
        # a lost scheduler or worker is reported in one line; Dask's own log would add pages
        logging.getLogger("distributed").setLevel(logging.CRITICAL)
    summary = runner.run_experiment(
        cfg, out_dir, executor=executor, progress=progress, figures=figures
    )
    echo(summary.scores_markdown)
    for note in summary.notes:
        echo(note)
    echo(
        f"work units: {summary.units_total} ({summary.units_cached} cached, "
        f"{summary.units_computed} computed) in {summary.elapsed_s:.1f} s"
    )
    echo(f"results: {out_dir}")
    if summary.figures:
        echo(f"figures: {summary.figures_dir}")
    echo(f"report: {report.write_report(out_dir)}")


def redraw_figures(results_dir: str, *, pdf: bool, force: bool) -> None:
    """``simlunar figures``: redraw what changed and say what was redrawn, kept or removed."""
    preflight.check_out_dir(results_dir, option="figures")
    if not Path(results_dir).is_dir():
        raise SimlunarError(f"{results_dir}: no such folder")
    fig_dir = Path(results_dir) / "figures"
    before = {p: p.stat().st_mtime_ns for p in fig_dir.glob("*")} if fig_dir.is_dir() else {}
    with store.FolderLock(results_dir):  # not while a run writes into the folder
        paths = result_figures.write_figures_pruned(
            results_dir, formats=("png", "pdf") if pdf else None, force=force
        )
    # a figure is redrawn when its file is new or rewritten; the others were up to date
    redrawn = [p for p in paths if before.get(p) != p.stat().st_mtime_ns]
    removed = sorted(set(before) - set(paths) - {fig_dir / "captions.md"})
    kept = [p for p in paths if p not in redrawn]
    if redrawn:
        echo(f"redrew {len(redrawn)} file(s) in {fig_dir}:")
        for p in redrawn:
            echo(f"  {p.name}")
    if kept:
        how = "use --force to redraw them" if not redrawn else "their inputs did not change"
        echo(f"up to date, not redrawn: {len(kept)} file(s) ({how})")
    for p in removed:
        if not p.exists():
            echo(f"removed {p.name} (no longer produced)")
    if not paths:
        echo(f"no figures for {results_dir} (its study draws none)")
