"""``simlunar terrain``: a terrain preset generated into a folder, or the statistics of a DEM."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from types import SimpleNamespace

import typer

from simlunar.cli.common import echo, flag, user_input
from simlunar.errors import SimlunarError

__all__ = ["terrain"]

# The library is imported inside the command, not at the top: importing it takes about 3 s (the
# scientific stack, and config.registry, which reads every planner, sensor and renderer), which
# `simlunar terrain --help` and a mistyped option should not pay (0.3 s with these imports here).


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
    print_stats: bool = flag(
        "--stats", "print RMS slopes at several baselines, Hurst exponent, densities"
    ),
) -> None:
    """Generate a terrain: dem.<fmt>, albedo.png, hillshade.png, mesh.ply, features.json."""
    from simlunar.config.terrain import merged_preset
    from simlunar.config.translate import terrain_params
    from simlunar.pipeline.inputs import check_dem_file, check_size
    from simlunar.pipeline.preflight import check_out_dir
    from simlunar.terrain import generate, io, stats

    if mesh.lower() not in ("ply", "obj", "none"):
        raise SimlunarError(f"--mesh must be ply, obj or none, got {mesh!r}")
    if dem_format.lower() not in ("exr", "npz", "npy", "tif"):
        raise SimlunarError(f"--format must be exr, npz, npy or tif, got {dem_format!r}")
    if out is None and not print_stats:
        raise SimlunarError("--out is required (unless --stats)")
    if seed < 0:
        raise SimlunarError(f"--seed must be >= 0, got {seed}")
    if Path(preset).suffix.lower() in io.FORMATS + io.GDAL_FORMATS:
        if not print_stats or out is not None:
            raise SimlunarError(f"{preset}: a DEM file is only read with --stats (and no --out)")
        check_dem_file(preset, key="--stats")  # size, finite heights, spacing and extent
        with user_input():
            dem = io.load_dem(preset)
            side, features = _side_features(preset)
        echo(f"{preset}: {dem.shape[0]} x {dem.shape[1]} cells at {dem.spacing} m")
        if side is not None:
            echo(f"features: {side}")
        for line in stats.terrain_report(dem, **features):
            echo(line)
        return
    if not 0 < scale <= 1:
        raise SimlunarError(f"--scale must lie in (0, 1], got {scale}")
    with user_input():
        # the preset file through the schema's models (the same path as an experiment's terrain)
        params = terrain_params(merged_preset(preset), scale=scale)
        # the grid before anything is allocated (a preset of 2e7 x 2e7 cells)
        check_size(
            f"{preset}: grid", f"{params.rows} x {params.cols} cells", params.rows * params.cols
        )
    if out is not None:
        check_out_dir(out)
    t0 = time.perf_counter()
    res = generate(params, rng=seed)
    t_gen = time.perf_counter() - t0
    rows, cols = res.terrain.shape
    echo(
        f"{res.params.name}: {rows} x {cols} cells at {res.terrain.spacing} m, "
        f"{len(res.craters)} craters, {len(res.rocks)} rocks, generated in {t_gen:.2f} s"
    )
    if print_stats:
        for line in stats.terrain_report(res.terrain, craters=res.craters, rocks=res.rocks):
            echo(line)
    if out is None:
        return
    files = io.write_terrain_outputs(
        res, out, dem_format=dem_format, mesh_format=None if mesh.lower() == "none" else mesh
    )
    for name, path in files.items():
        echo(f"{name:<10} {path}")


def _side_features(path: str) -> tuple[Path | None, dict]:
    """The ``features.json`` beside a DEM file (as ``simlunar terrain`` writes it) and its
    craters and rocks as ``terrain_report`` takes them (objects with a ``diameter``); ``(None,
    no features)`` when there is none."""
    side = Path(path).with_name("features.json")
    if not side.is_file():
        return None, {"craters": [], "rocks": []}
    diameters = _feature_diameters(side)
    return side, {k: [SimpleNamespace(diameter=d) for d in v] for k, v in diameters.items()}


def _feature_diameters(path: Path) -> dict[str, list[float]]:
    """``{"craters": [diameter, ...], "rocks": [...]}`` of a features.json (as written by
    ``simlunar terrain``); a file of another layout raises ValueError naming it."""
    try:
        feats = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not valid JSON ({exc})") from None
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
