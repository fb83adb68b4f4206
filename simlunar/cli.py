"""Command-line interface (Typer): a thin front over the library and the pipeline.

Exit codes: 0 done; 2 a user error (bad option, config, input file or result folder), found
before anything is written, reported as one line ``error: ...`` without a traceback; 3 the
environment failed during a run (Dask scheduler or workers lost, a write refused): one line,
finished units kept; 130 interrupted (Ctrl-C): one line saying what was kept and how to
resume; 1 an internal error (a bug): the traceback and a line asking to report it.
"""

from __future__ import annotations

import contextlib
import errno
import functools
import os
import platform
import sys
import traceback

import typer

from simlunar.errors import InfrastructureError, SimlunarError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    # plain click help: rich markup would swallow the "[default: ...]" of the help strings
    # and print "<bool>" after every flag
    rich_markup_mode=None,
    help="simlunar: image-directed range scanning of lunar terrain, simulated.",
)

EXIT_USER, EXIT_INTERNAL, EXIT_INFRA, EXIT_INTERRUPTED = 2, 1, 3, 130
REPORT_URL = "https://github.com/simlunar/simlunar/issues"


def _version(value: bool) -> None:
    if value:
        import simlunar

        typer.echo(f"simlunar {simlunar.__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False,
        "--version",
        callback=_version,
        is_eager=True,
        help="Print the version and exit.",
        show_default=False,
    ),
) -> None:
    """simlunar: image-directed range scanning of lunar terrain, simulated."""


#: errors that mean "the user's input is wrong" when raised while the input is being read
#: and checked (inside :func:`user_input`); raised later, they are bugs
INPUT_ERRORS: tuple[type[BaseException], ...] = (ValueError, OSError)


@contextlib.contextmanager
def user_input():
    """Treat ValueError / OSError raised inside (reading and checking input) as user errors."""
    try:
        yield
    except SimlunarError:
        raise
    except INPUT_ERRORS as exc:
        raise SimlunarError(_one_line(exc)) from None


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.filename is not None and exc.strerror:
        return f"{exc.filename}: {exc.strerror}"
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    msg = " ".join(m.strip() for m in str(exc).strip().splitlines())
    return msg or type(exc).__name__


#: errno values that mean the environment failed (exit 3), even when no file is named
ENVIRONMENT_ERRNOS = frozenset(
    getattr(errno, name) for name in ("ENOSPC", "EDQUOT", "EROFS", "EIO") if hasattr(errno, name)
)


def user_errors(fn):
    """Map exceptions to the exit codes above (one line on stderr except for bugs)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        from simlunar import interrupts

        try:
            out = fn(*args, **kwargs)
        except typer.Exit as exc:
            if interrupts.interrupted() and exc.exit_code != EXIT_INTERRUPTED:
                raise _exit_for(KeyboardInterrupt()) from None
            raise
        except BaseException as exc:
            raise _exit_for(exc) from None
        if interrupts.interrupted():  # a Ctrl-C that the interrupted code swallowed
            raise _exit_for(KeyboardInterrupt())
        return out

    return wrapper


def _exit_for(exc: BaseException) -> typer.Exit:
    """Print the line for ``exc`` and return the :class:`typer.Exit` of its exit code.

    A Ctrl-C decides the exit whatever exception it caused (:mod:`simlunar.interrupts`).
    """
    from simlunar import interrupts
    from simlunar.errors import RunInterrupted

    if isinstance(exc, KeyboardInterrupt) or interrupts.interrupted():
        msg = _one_line(exc) if isinstance(exc, RunInterrupted) and str(exc) else "interrupted"
        typer.echo(msg, err=True)
        return typer.Exit(EXIT_INTERRUPTED)
    if isinstance(exc, BrokenPipeError):
        return _closed_stdout()
    if isinstance(exc, SimlunarError):
        typer.echo(f"error: {_one_line(exc)}", err=True)
        return typer.Exit(EXIT_USER)
    if isinstance(exc, InfrastructureError):
        typer.echo(f"error: {_one_line(exc)}", err=True)
        return typer.Exit(EXIT_INFRA)
    if isinstance(exc, OSError):
        if exc.filename is None and exc.errno not in ENVIRONMENT_ERRNOS:
            return _internal(exc)
        # a write refused after the checks passed (disk full, quota, read-only file
        # system, I/O error, permissions changed); the OS names no file for a full disk
        typer.echo(f"error: {_one_line(exc)}", err=True)
        return typer.Exit(EXIT_INFRA)
    if isinstance(exc, (SystemExit, GeneratorExit)):
        raise exc
    return _internal(exc)


#: exit code when stdout is closed early (``simlunar run ... | head -1``): quiet, as a shell
#: reports a program ended by SIGPIPE (128 + 13)
EXIT_PIPE = 141


def _closed_stdout() -> typer.Exit:
    """stdout's reader went away: nothing more can be said there, and nothing on stderr."""
    with contextlib.suppress(OSError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # the interpreter's last flush must not fail
    return typer.Exit(EXIT_PIPE)


def _internal(exc: BaseException) -> typer.Exit:
    traceback.print_exception(exc, file=sys.stderr)
    typer.echo(
        f"simlunar: internal error ({type(exc).__name__}); this is a bug in simlunar, please "
        f"report it with the traceback above at {REPORT_URL}",
        err=True,
    )
    return typer.Exit(EXIT_INTERNAL)


@app.command()
@user_errors
def doctor(
    short: bool = typer.Option(False, "--short", help="One line only.", show_default=False),
) -> None:
    """Versions, the chosen Mitsuba variant and why, libLLVM, kernel cache, cores, GPU."""
    from simlunar.pipeline.preflight import check_renderer
    from simlunar.render import backend

    check_renderer()  # a bad SIMLUNAR_VARIANT in one line
    info = backend.choose_variant()
    if short:
        typer.echo(f"simlunar doctor: variant {info.variant} ({info.reason})")
        return
    vers = backend.versions()
    typer.echo("simlunar doctor")
    for k, v in vers.items():
        typer.echo(f"  {k:<15} {v}")
    typer.echo(f"  {'variant':<15} {info.variant}")
    typer.echo(f"  {'why':<15} {info.reason}")
    for k, v in info.probes.items():
        typer.echo(f"  {'probe ' + k:<15} {v}")
    typer.echo(f"  {'libLLVM':<15} {info.libllvm or 'none'}")
    typer.echo(f"  {'kernel cache':<15} {info.cache_dir}")
    typer.echo(f"  {'cores':<15} {os.cpu_count()}")
    typer.echo(f"  {'machine':<15} {platform.machine()} {platform.system()}")
    gpu = "CUDA device present" if backend._cuda_present() else "none"
    typer.echo(f"  {'GPU':<15} {gpu}")


_SET_OPTION = typer.Option(
    None,
    "--set",
    metavar="KEY=VALUE",
    help="override a key: --set render.spp=32 (repeatable)",
    show_default=False,
)


@app.command()
@user_errors
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
    pdf: bool = typer.Option(
        False,
        "--pdf",
        help="figures as PDF too (as figures.formats: [png, pdf]) [default: PNG only]",
        show_default=False,
    ),
    save_scans: bool = typer.Option(
        False,
        "--save-scans",
        help="scanner studies: export each unit's scan to scans/unit<i>/",
        show_default=False,
    ),
) -> None:
    """Run (or resume) an experiment: results.csv, scores.md/.tex, provenance.json, figures/."""
    from pathlib import Path

    from simlunar.config.loading import load_experiment
    from simlunar.config.yamlio import parse_set
    from simlunar.pipeline.executors import make_executor
    from simlunar.pipeline.runner import run_experiment

    with user_input():
        overrides = parse_set(set_ or [])
        if pdf:
            overrides = {**overrides, "figures.formats": ["png", "pdf"]}
        cfg = load_experiment(experiment, overrides)
        if save_scans:
            from simlunar.results.exports import check_save_scans

            check_save_scans(cfg)
            # an override before validation, so every sweep point is checked with it
            cfg = load_experiment(experiment, {**overrides, "study.save_scans": True})
        executor = make_executor(workers=workers, scheduler=scheduler)
    if scheduler:
        import logging

        # a lost scheduler or worker is reported in one line; Dask's own log would add pages
        logging.getLogger("distributed").setLevel(logging.CRITICAL)
    out_dir = Path(out) if out else Path("results") / cfg.name
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


@app.command()
@user_errors
def train(
    config: str = typer.Argument(
        ..., help="training YAML (e.g. experiments/training/learned_quarter.yaml)"
    ),
    out: str = typer.Option(None, "--out", help="model file (.joblib) [default: the YAML's model]"),
) -> None:
    """Train the learned importance map: <model>.joblib and its record <model>.json."""
    import shlex

    from simlunar.config.training import load_training
    from simlunar.pipeline.train import train_from_config

    with user_input():
        cfg, experiments = load_training(config)
    if out is not None and not out.endswith(".joblib"):
        raise SimlunarError(f"--out {out}: a learned model file ends in .joblib")
    command = shlex.join(["simlunar", "train", config, *(["--out", out] if out else [])])
    model, record = train_from_config(cfg, experiments, out=out, command=command, log=typer.echo)
    typer.echo(f"model:  {model}")
    typer.echo(f"record: {record}")


@app.command()
@user_errors
def figures(
    results_dir: str = typer.Argument(..., help="a result folder of `simlunar run`"),
    pdf: bool = typer.Option(
        False,
        "--pdf",
        help="PDF besides PNG [default: the folder's figures.formats]",
        show_default=False,
    ),
    force: bool = typer.Option(
        False,
        "--force",
        help="redraw even when the figures' inputs are unchanged",
        show_default=False,
    ),
) -> None:
    """Draw the figures of a result folder without recomputing (only those whose inputs changed)."""
    from pathlib import Path

    from simlunar.pipeline.preflight import check_out_dir
    from simlunar.results.figures import write_figures_pruned
    from simlunar.results.store import FolderLock

    check_out_dir(results_dir, option="figures")
    if not Path(results_dir).is_dir():
        raise SimlunarError(f"{results_dir}: no such folder")
    with FolderLock(results_dir):  # not while a run writes into the folder
        paths = write_figures_pruned(
            results_dir, formats=("png", "pdf") if pdf else None, force=force
        )
    for p in paths:
        typer.echo(str(p))


@app.command()
@user_errors
def schema(
    out: str = typer.Option(None, "--out", help="write to this file instead of stdout"),
    kind: str = typer.Option(
        "experiment", "--kind", help="document kind: experiment, scene or preset"
    ),
    markdown: bool = typer.Option(
        False,
        "--markdown",
        help="the YAML reference as Markdown (docs/experiments.md)",
        show_default=False,
    ),
) -> None:
    """JSON Schema of experiment (scene, preset) YAMLs (for editors: yaml-language-server)."""
    import json
    from pathlib import Path

    from simlunar.config.docs import SCHEMA_KINDS, json_schema
    from simlunar.errors import ConfigError

    if kind not in SCHEMA_KINDS:
        raise ConfigError(
            f"--kind {kind}: unknown document kind (valid: {', '.join(SCHEMA_KINDS)})"
        )
    if markdown:
        from simlunar.config.docs import reference_markdown

        text = reference_markdown()
    else:
        text = json.dumps(json_schema(kind), indent=2)
    if out:
        from simlunar.pipeline.preflight import check_out_file
        from simlunar.results.store import atomic_write_text

        check_out_file(out)
        Path(out).parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(out, text + "\n")
    else:
        typer.echo(text)


@app.command()
@user_errors
def render(
    scene: str = typer.Argument(..., help="scene YAML (e.g. scenes/quickstart_scene.yaml)"),
    out: str = typer.Option(None, "--out", help="output folder [default: results/render/<name>]"),
) -> None:
    """Render a scene: radiance.exr (linear), preview.png, ground_truth.exr/.npz, scene.json."""
    from pathlib import Path

    from simlunar.config.scene import load_scene
    from simlunar.pipeline.preflight import (
        check_camera,
        check_out_dir,
        check_renderer,
        terrain_facts,
    )
    from simlunar.pipeline.scene import check_render_folder, render_scene

    with user_input():
        cfg = load_scene(scene)
    out_dir = Path(out) if out else Path("results") / "render" / cfg.name
    check_out_dir(out_dir)
    check_render_folder(out_dir)
    check_renderer()
    check_camera(
        cfg.render, terrain_facts(cfg.terrain)
    )  # DEM contents and the view, before rendering
    paths = render_scene(cfg, out_dir)
    for name, path in paths.items():
        typer.echo(f"{name:<17} {path}")
    typer.echo(f"rendered {cfg.name} into {out_dir}")


@app.command()
@user_errors
def terrain(
    preset: str = typer.Argument(
        ..., help="preset name (aerial_1..3, moonyard), a terrain YAML, or a DEM file with --stats"
    ),
    out: str = typer.Option(None, "--out", help="output folder (optional with --stats)"),
    seed: int = typer.Option(0, "--seed", help="random seed (same seed, same terrain)"),
    scale: float = typer.Option(1.0, "--scale", help="shrink the grid (same spacing), in (0, 1]"),
    dem_format: str = typer.Option(
        "exr", "--format", help="DEM file: exr, npz, npy or tif (GeoTIFF)"
    ),
    mesh: str = typer.Option("ply", "--mesh", help="mesh file: ply, obj or none"),
    stats: bool = typer.Option(
        False,
        "--stats",
        help="print RMS slopes at several baselines, Hurst exponent, densities",
        show_default=False,
    ),
) -> None:
    """Generate a terrain: dem.<fmt>, albedo.png, hillshade.png, mesh.ply, features.json."""
    import time
    from pathlib import Path

    from simlunar.config.terrain import merged_preset
    from simlunar.config.translate import terrain_params
    from simlunar.pipeline.preflight import check_out_dir
    from simlunar.terrain import generate
    from simlunar.terrain.io import FORMATS, GDAL_FORMATS, load_dem, write_terrain_outputs
    from simlunar.terrain.stats import terrain_report

    if mesh.lower() not in ("ply", "obj", "none"):
        raise SimlunarError(f"--mesh must be ply, obj or none, got {mesh!r}")
    if dem_format.lower() not in ("exr", "npz", "npy", "tif"):
        raise SimlunarError(f"--format must be exr, npz, npy or tif, got {dem_format!r}")
    if out is None and not stats:
        raise SimlunarError("--out is required (unless --stats)")
    if seed < 0:
        raise SimlunarError(f"--seed must be >= 0, got {seed}")
    if Path(preset).suffix.lower() in FORMATS + GDAL_FORMATS:
        if not stats or out is not None:
            raise SimlunarError(f"{preset}: a DEM file is only read with --stats (and no --out)")
        import json
        from types import SimpleNamespace

        from simlunar.pipeline.inputs import check_dem_file

        check_dem_file(preset, key="--stats")  # size, finite heights, spacing and extent
        with user_input():
            dem = load_dem(preset)
        kw = {"craters": [], "rocks": []}
        side = Path(preset).with_name("features.json")  # written beside it by simlunar terrain
        if side.is_file():
            with user_input():
                try:
                    feats = json.loads(side.read_text())
                except json.JSONDecodeError as exc:
                    raise ValueError(f"{side}: not valid JSON ({exc})") from None
                kw = _feature_diameters(side, feats)
        typer.echo(f"{preset}: {dem.shape[0]} x {dem.shape[1]} cells at {dem.spacing} m")
        if side.is_file():
            typer.echo(f"features: {side}")
        kw = {k: [SimpleNamespace(diameter=d) for d in v] for k, v in kw.items()}
        for line in terrain_report(dem, **kw):
            typer.echo(line)
        return
    if not 0 < scale <= 1:
        raise SimlunarError(f"--scale must lie in (0, 1], got {scale}")
    with user_input():
        # the preset file through the schema's models (the same path as an experiment's terrain)
        params = terrain_params(merged_preset(preset), scale=scale)
    if out is not None:
        check_out_dir(out)
    t0 = time.perf_counter()
    res = generate(params, rng=seed)
    t_gen = time.perf_counter() - t0
    rows, cols = res.terrain.shape
    typer.echo(
        f"{res.params.name}: {rows} x {cols} cells at {res.terrain.spacing} m, "
        f"{len(res.craters)} craters, {len(res.rocks)} rocks, generated in {t_gen:.2f} s"
    )
    if stats:
        for line in terrain_report(res.terrain, craters=res.craters, rocks=res.rocks):
            typer.echo(line)
    if out is None:
        return
    files = write_terrain_outputs(
        res, out, dem_format=dem_format, mesh_format=None if mesh.lower() == "none" else mesh
    )
    for name, path in files.items():
        typer.echo(f"{name:<10} {path}")


def _feature_diameters(path, feats) -> dict[str, list[float]]:
    """``{"craters": [diameter, ...], "rocks": [...]}`` of a features.json (as written by
    ``simlunar terrain``); a file of another layout raises ValueError naming it."""
    import math

    if not isinstance(feats, dict):
        raise ValueError(f"{path}: expected a mapping with 'craters' and 'rocks' lists")
    out = {}
    for key in ("craters", "rocks"):
        items = feats.get(key, [])
        if not isinstance(items, list):
            raise ValueError(f"{path}: {key}: expected a list, got {type(items).__name__}")
        out[key] = []
        for i, f in enumerate(items):
            d = f.get("diameter") if isinstance(f, dict) else None
            if isinstance(d, bool) or not isinstance(d, (int, float)) or not math.isfinite(d):
                raise ValueError(f"{path}: {key}[{i}].diameter: expected a number (metres)")
            out[key].append(float(d))
    return out


def _usage_errors():
    """Typer's click exceptions module (vendored as ``typer._click`` by newer Typer)."""
    try:
        from typer._click import exceptions
    except ImportError:  # Typer on the click package
        from click import exceptions
    return exceptions


def main() -> None:
    from simlunar import interrupts

    cx = _usage_errors()

    interrupts.clear()
    interrupts.install()
    try:
        code = app(prog_name="simlunar", standalone_mode=False)
        code = code if isinstance(code, int) else 0
    except cx.NoArgsIsHelpError as exc:
        typer.echo(exc.ctx.get_help() if exc.ctx else str(exc))
        code = EXIT_USER
    except cx.UsageError as exc:
        # one line (click draws a box of 5-6 lines): the command, the problem, where to look
        where = exc.ctx.command_path if exc.ctx else "simlunar"
        msg = " ".join(exc.format_message().split())
        typer.echo(f"error: {where}: {msg} (see {where} --help)", err=True)
        code = EXIT_USER
    except typer.Exit as exc:
        code = exc.exit_code
    except (KeyboardInterrupt, typer.Abort):
        typer.echo("interrupted", err=True)
        code = EXIT_INTERRUPTED
    except BrokenPipeError:
        code = _closed_stdout().exit_code
    if interrupts.interrupted() and code not in (EXIT_INTERRUPTED, EXIT_PIPE):
        typer.echo("interrupted", err=True)  # after the command's own handling
        code = EXIT_INTERRUPTED
    try:
        sys.stdout.flush()
    except (BrokenPipeError, ValueError):
        code = _closed_stdout().exit_code if code == 0 else code
    sys.stderr.flush()
    if code in (EXIT_INTERRUPTED, EXIT_INFRA):
        # threads of units still running (and their forked study processes) would be
        # waited for at interpreter exit; the message is out and the lock released
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    sys.exit(main())
