"""Command-line interface (Typer): a thin front over the library and the pipeline.

Every user error (bad option, bad file, bad config) prints one line ``error: ...`` and exits
with code 2, without a traceback.
"""

from __future__ import annotations

import functools
import os
import platform
import sys

import typer

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="simlunar: image-directed range scanning of lunar terrain, simulated.",
)


@app.callback()
def _root() -> None:
    """simlunar: image-directed range scanning of lunar terrain, simulated."""


USER_ERRORS: tuple[type[BaseException], ...] = (
    ValueError,
    FileNotFoundError,
    KeyError,
    IsADirectoryError,
    PermissionError,
)


def user_errors(fn):
    """Turn user errors into one line on stderr and exit code 2."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except typer.Exit:
            raise
        except USER_ERRORS as exc:
            msg = str(exc).strip().splitlines()
            typer.echo(f"error: {' '.join(m.strip() for m in msg) or type(exc).__name__}", err=True)
            raise typer.Exit(2) from None

    return wrapper


@app.command()
@user_errors
def doctor(short: bool = typer.Option(False, "--short", help="One line only.")) -> None:
    """Versions, the chosen Mitsuba variant and why, libLLVM, kernel cache, cores, GPU."""
    from simlunar.render import backend

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


_SET_OPTION = typer.Option(None, "--set", help="override a key: --set render.spp=32 (repeatable)")


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
        None, "--scheduler", help="Dask scheduler address, e.g. tcp://host:8786"
    ),
    set_: list[str] | None = _SET_OPTION,
    no_progress: bool = typer.Option(False, "--no-progress", help="no progress bar"),
    no_figures: bool = typer.Option(False, "--no-figures", help="skip figures/"),
    save_scans: bool = typer.Option(
        False, "--save-scans", help="scanner studies: export each unit's scan to scans/unit<i>/"
    ),
) -> None:
    """Run (or resume) an experiment: results.csv, scores.md/.tex, provenance.json, figures/."""
    from pathlib import Path

    from simlunar.pipeline.config import load_experiment, parse_set
    from simlunar.pipeline.executors import make_executor
    from simlunar.pipeline.runner import run_experiment

    cfg = load_experiment(experiment, parse_set(set_ or []))
    if save_scans:
        from simlunar.pipeline.exports import with_save_scans

        cfg = with_save_scans(cfg)
    executor = make_executor(workers=workers, scheduler=scheduler)
    out_dir = Path(out) if out else Path("results") / cfg.name
    summary = run_experiment(
        cfg, out_dir, executor=executor, progress=not no_progress, figures=not no_figures
    )
    typer.echo(summary.scores_markdown)
    typer.echo(
        f"units: {summary.units_total} ({summary.units_cached} cached, "
        f"{summary.units_computed} computed) in {summary.elapsed_s:.1f} s"
    )
    typer.echo(f"results: {out_dir}")
    if summary.figures:
        typer.echo(f"figures: {summary.figures_dir}")


@app.command()
@user_errors
def figures(
    results_dir: str = typer.Argument(..., help="a result folder of `simlunar run`"),
) -> None:
    """Redraw the figures of a result folder (PNG and PDF) without recomputing."""
    from simlunar.pipeline.figures import write_figures

    paths = write_figures(results_dir)
    for p in paths:
        typer.echo(str(p))


@app.command()
@user_errors
def schema(
    out: str = typer.Option(None, "--out", help="write to this file instead of stdout"),
) -> None:
    """JSON Schema of experiment YAMLs (for editors: yaml-language-server)."""
    import json

    from simlunar.pipeline.config import json_schema

    text = json.dumps(json_schema(), indent=2)
    if out:
        from simlunar.pipeline.store import atomic_write_text

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

    from simlunar.pipeline.scene import load_scene, render_scene

    cfg = load_scene(scene)
    out_dir = Path(out) if out else Path("results") / "render" / cfg.name
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
        False, "--stats", help="print RMS slopes at several baselines, Hurst exponent, densities"
    ),
) -> None:
    """Generate a terrain: dem.<fmt>, albedo.png, hillshade.png, mesh.ply, features.json."""
    import time
    from pathlib import Path

    from simlunar.terrain import generate
    from simlunar.terrain.io import FORMATS, GDAL_FORMATS, load_dem, write_terrain_outputs
    from simlunar.terrain.stats import terrain_report

    if mesh.lower() not in ("ply", "obj", "none"):
        raise ValueError(f"--mesh must be ply, obj or none, got {mesh!r}")
    if out is None and not stats:
        raise ValueError("--out is required (unless --stats)")
    if Path(preset).suffix.lower() in FORMATS + GDAL_FORMATS:
        if not stats or out is not None:
            raise ValueError(f"{preset}: a DEM file is only read with --stats (and no --out)")
        import json
        from types import SimpleNamespace

        dem = load_dem(preset)
        typer.echo(f"{preset}: {dem.shape[0]} x {dem.shape[1]} cells at {dem.spacing} m")
        feats = {"craters": [], "rocks": []}
        side = Path(preset).with_name("features.json")  # written beside it by simlunar terrain
        if side.is_file():
            feats = json.loads(side.read_text())
            typer.echo(f"features: {side}")
        kw = {
            k: [SimpleNamespace(diameter=f["diameter"]) for f in feats.get(k, [])]
            for k in ("craters", "rocks")
        }
        for line in terrain_report(dem, **kw):
            typer.echo(line)
        return
    t0 = time.perf_counter()
    res = generate(preset, rng=seed, scale=scale)
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


def main() -> None:
    app(prog_name="simlunar")


if __name__ == "__main__":
    sys.exit(main())
