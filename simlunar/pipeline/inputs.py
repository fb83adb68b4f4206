"""A work unit's input files: which files it reads and their SHA-256 (the cache key), the size
budget of everything that scales with input, and the facts of its terrain (grid, extent, heights)
read from the files' headers and contents before anything is allocated or written."""

from __future__ import annotations

import contextlib
import dataclasses
import math
import os
import types
import typing
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import BaseModel

from simlunar.config.derived import ComponentList
from simlunar.config.schema import ExperimentCfg
from simlunar.config.terrain import PresetError, merged_preset, preset_path
from simlunar.config.translate import terrain_params
from simlunar.errors import ConfigError
from simlunar.pipeline.limits import (
    LIMIT_SETTINGS,
    MAX_CELLS,
    MAX_FRAME_PIXELS,
    MAX_UNITS,
    check_size,
    grid_file_shape,
    size_limit,
)
from simlunar.registry import FileOption, file_option, option_info
from simlunar.results.store import file_sha256
from simlunar.terrain.generate import refined_shape
from simlunar.terrain.io import load_albedo, load_dem

#: NaN heights (holes) a DEM may have. Holes leave the terrain mesh open; the rays that miss
#: it take the depth of their nearest valid pixel (``pipeline.unit.fill_invalid``) and are scored as
#: truth, so beyond a few per cent the ground truth is mostly invented and the run stops.
MAX_NAN_FRACTION = 0.05

#: Smallest grid spacing (m per cell) of a DEM: a micrometre. Below it (a sidecar's 1e-300)
#: every slope and roughness statistic divides by a number that is no length at all.
MIN_SPACING_M = 1e-6

#: Largest |coordinate| (heights, terrain extent, camera position) in metres: the renderer
#: works in float32, so a scene larger than this (1000 km) cannot resolve terrain relief.
MAX_ABS_COORD_M = 1e6


__all__ = [
    "LIMIT_SETTINGS",
    "MAX_CELLS",
    "MAX_FRAME_PIXELS",
    "MAX_UNITS",
    "MIN_SPACING_M",
    "TerrainFacts",
    "check_dem_file",
    "check_size",
    "declared_files",
    "gdal_files",
    "grid_file_shape",
    "input_files",
    "input_hashes",
    "model_files",
    "model_inputs",
    "size_limit",
    "terrain_facts",
]


def declared_files(config: Mapping[str, Any], model: type | None = None) -> dict[str, FileOption]:
    """Every option of a (resolved, plain) config that names a file, by key path, with its
    :class:`~simlunar.registry.FileOption`: found by walking the config along the declarations
    of its models (``model``, default :class:`~simlunar.config.schema.ExperimentCfg`): a field
    annotated with a ``FileOption``, an option declared with ``option(..., file=...)`` (in every
    model derived from an options class), and the options of each item of a
    :class:`~simlunar.config.derived.ComponentList` field (``study.reconstructions``). Nothing
    here names an option: a new file option is in the cache key by its declaration."""
    return {k: m for k, (m, _) in _declared(config, model).items()}


def _declared(config, model=None) -> dict[str, tuple[FileOption, Any]]:
    """:func:`declared_files` with each option's value."""
    out: dict[str, tuple[FileOption, Any]] = {}
    _walk_model(model or ExperimentCfg, config, "", out)
    return out


def _walk_model(model, data, prefix: str, out: dict) -> None:
    if not isinstance(data, Mapping):
        return
    for name, info in model.model_fields.items():
        key = info.alias or name
        if key in data:
            _walk_field(info.annotation, info.metadata, data[key], prefix + key, out)


def _walk_field(ann, metadata, value, path: str, out: dict) -> None:
    for m in metadata:
        if isinstance(m, FileOption):
            if value not in (None, ""):
                out[path] = (m, value)
            return
        if isinstance(m, ComponentList):
            for label, cls, opts in m.items(value):
                for fname, row in option_info(cls).items():
                    marker = file_option(row)
                    if marker is not None and opts.get(fname) not in (None, ""):
                        out[f"{path}.{label}.{fname}"] = (marker, opts[fname])
            return
    _walk_type(ann, value, path, out)


def _walk_type(ann, value, path: str, out: dict) -> None:
    origin = typing.get_origin(ann)
    args = typing.get_args(ann)
    if origin is typing.Annotated:
        _walk_field(args[0], args[1:], value, path, out)
    elif isinstance(ann, type) and issubclass(ann, BaseModel):
        _walk_model(ann, value, path + ".", out)
    elif origin in (typing.Union, types.UnionType):
        for a in args:  # every member: a key only one of them declares is walked once
            _walk_type(a, value, path, out)
    elif origin in (dict, Mapping) and len(args) == 2 and isinstance(value, Mapping):
        for k, v in value.items():
            _walk_type(args[1], v, f"{path}.{k}", out)
    elif origin in (list, tuple) and args and isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _walk_type(args[0], v, f"{path}[{i}]", out)


def input_files(config: dict[str, Any]) -> dict[str, Path]:
    """The files a unit (resolved plain config) reads, by the key path that names them.

    Every option :func:`declared_files` finds, with the files its kind reads beside it:
    ``preset`` -> the preset YAML (``scenes/<name>.yaml``); ``dem`` -> the file (and the
    ``.json`` side file of a ``.npy`` DEM when present); ``albedo`` -> the file; for a raster
    GDAL reads, every other file it reads (:func:`gdal_files`) as ``<key>+<name>``; ``model``
    -> the ``.joblib`` and its ``.json`` record (``<key>.json``).
    """
    out: dict[str, Path] = {}
    for key, (marker, value) in _declared(config).items():
        if not isinstance(value, (str, os.PathLike)):
            continue  # not a file name: the schema reports it
        if marker.kind == "preset":
            with contextlib.suppress(PresetError):  # a missing preset is reported by the checks
                out[key] = preset_path(str(value))
            continue
        p = Path(value)
        out[key] = p
        if marker.kind == "model":
            out[f"{key}.json"] = p.with_suffix(".json")
            continue
        if marker.kind == "dem" and p.suffix.lower() == ".npy":
            side = p.with_name(p.name + ".json")
            if side.is_file():
                out[f"{key}.json"] = side
        if marker.kind in ("dem", "albedo"):
            for extra in gdal_files(p):
                # named relative to the main file, so a moved data folder keeps its keys
                out[f"{key}+{os.path.relpath(extra, p.parent)}"] = extra
    return out


def model_inputs(config: dict[str, Any]) -> dict[str, FileOption]:
    """The model files of a unit (:func:`declared_files` of kind ``model``), by key path;
    each one's record is at ``<key>.json`` in :func:`input_files`."""
    return {k: m for k, m in declared_files(config).items() if m.kind == "model"}


def model_files(study: dict[str, Any]) -> dict[str, Path]:
    """The model files a study section reads (every option declared a ``model`` file, e.g. a
    learned map's ``feature_opts.model`` or the learned reconstruction's ``model``), the
    ``.joblib`` and its ``.json`` record, by key path. A retrained model at the same path is
    another input, so its units are computed again; a missing one is reported before any
    work."""
    files = input_files({"study": study})
    keys = model_inputs({"study": study})
    return {k: p for k, p in files.items() if k in keys or k.removesuffix(".json") in keys}


def gdal_files(path: Path) -> list[Path]:
    """The files other than ``path`` that GDAL reads for a raster (rasterio's ``src.files``):
    the sources of a ``.vrt``, the image of a PDS ``.lbl``, ``.tfw`` / ``.aux.xml`` sidecars.

    Empty for the formats simlunar reads itself (.npy, .npz, .exr) and for a file GDAL cannot
    open (the checks report that one).
    """
    if path.suffix.lower() in (".npy", ".npz", ".exr") or not path.is_file():
        return []
    try:
        import rasterio

        with rasterio.open(path) as src:
            files = list(src.files)
    except Exception:  # an unreadable raster is reported by the checks
        return []
    me = path.resolve()
    out = []
    for f in files:
        q = Path(f)
        if q.resolve() != me and q.is_file() and q not in out:
            out.append(q)
    return sorted(out)


def input_hashes(config: dict[str, Any]) -> dict[str, dict[str, str]]:
    """``{key path: {"path": str, "sha256": hex}}`` of :func:`input_files`."""
    out = {}
    models = model_inputs(config)
    for key, p in input_files(config).items():
        try:
            digest = file_sha256(p)
        except OSError as exc:
            hint = (
                " (a learned model: make it with `simlunar train <training yaml>`)"
                if key in models or key.removesuffix(".json") in models
                else ""
            )
            raise ConfigError(f"{key}: cannot read {p} ({exc.strerror or exc}){hint}") from None
        out[key] = {"path": str(p), "sha256": digest}
    return out


# --------------------------------------------------------------------------- terrain
@dataclass(frozen=True)
class TerrainFacts:
    """What the checks need to know of a unit's terrain, without generating it.

    ``zmin``/``zmax`` bound the heights (exact for a DEM; for a preset, a generous bound of
    half the larger side, since its relief is generated later).
    """

    rows: int
    cols: int
    spacing: float
    origin: tuple[float, float]
    zmin: float
    zmax: float
    nan_fraction: float = 0.0
    source: str = ""
    zmid: float = 0.0  # median height (a DEM's; 0 for a preset, generated around 0)

    @property
    def extent(self) -> tuple[float, float, float, float]:
        x0, y0 = self.origin
        return (x0, x0 + self.cols * self.spacing, y0 - self.rows * self.spacing, y0)


_TERRAIN_MEMO: dict[tuple, TerrainFacts] = {}


def terrain_facts(t: Any) -> TerrainFacts:
    """Check a unit's terrain section (a ``TerrainCfg``) and return its :class:`TerrainFacts`.

    Raises
    ------
    ConfigError
        One line naming ``terrain.<key>`` and, for files, the file.
    """
    if t.preset is not None:
        memo = ("preset", str(t.preset), t.scale, repr(t.overrides))
        if memo not in _TERRAIN_MEMO:
            try:
                p = _preset_params(t)
            except (ValueError, OSError) as exc:
                raise ConfigError(f"terrain.preset: {exc}") from None
            half = 0.5 * max(p.rows, p.cols) * p.spacing
            facts = TerrainFacts(
                p.rows, p.cols, p.spacing, tuple(p.origin), -half, half, 0.0, str(t.preset)
            )
            _check_extent(facts, "terrain.preset")
            _TERRAIN_MEMO[memo] = facts
        facts = _TERRAIN_MEMO[memo]
        # every time (not memoised): the limit is a setting of this run
        grid = getattr(t.overrides, "grid", None) if t.overrides is not None else None
        where = "terrain.overrides.grid" if grid is not None else "terrain.preset"
        check_size(where, f"{facts.rows} x {facts.cols} cells", facts.rows * facts.cols)
        return _TERRAIN_MEMO[memo]
    files = [Path(t.file)] + ([Path(t.albedo_file)] if t.albedo_file is not None else [])
    stamps = tuple(_stamp(p) for p in files)
    memo = ("file", *map(str, files), t.spacing_m, stamps)
    if memo not in _TERRAIN_MEMO:
        _TERRAIN_MEMO[memo] = _dem_facts(Path(t.file), t.spacing_m, t.albedo_file)
    facts = _TERRAIN_MEMO[memo]
    check_size(
        "terrain.file", f"{t.file}: {facts.rows} x {facts.cols} cells", facts.rows * facts.cols
    )
    return _refined_facts(t, facts)


def _refined_facts(t: Any, facts: TerrainFacts) -> TerrainFacts:
    """A DEM file's facts after ``terrain.refine_m`` (finer cells over the same extent, as
    :func:`simlunar.terrain.generate.refine` makes them) and its ``rocks`` (up to their
    largest diameter above the DEM's highest point)."""
    refine_m = getattr(t, "refine_m", None)
    if refine_m is not None:
        if refine_m > facts.spacing:
            raise ConfigError(
                f"terrain.refine_m: {refine_m:g} m is coarser than the DEM's {facts.spacing:g} m "
                "cells (refine_m makes them finer; resample a DEM coarser with gdalwarp -tr)"
            )
        rows, cols = refined_shape((facts.rows, facts.cols), facts.spacing, refine_m)
        check_size("terrain.refine_m", f"{t.file} refined to {refine_m:g} m: {rows} x {cols} "
                   "cells", rows * cols)  # fmt: skip
        facts = dataclasses.replace(facts, rows=rows, cols=cols, spacing=float(refine_m))
    rocks = getattr(t, "rocks", None)
    if rocks is not None and rocks.enabled:
        facts = dataclasses.replace(facts, zmax=facts.zmax + float(rocks.d_max_m))
    return facts


def _preset_params(t: Any):
    """The preset's ``TerrainParams`` (grid size, spacing, origin) as the unit will build them."""

    return terrain_params(merged_preset(t.preset, t.overrides), scale=t.scale)


def _stamp(p: Path):
    try:
        st = p.stat()
        return (st.st_size, st.st_mtime_ns)
    except OSError:
        return None


def _check_extent(f: TerrainFacts, key: str) -> None:
    x0, x1, y0, y1 = f.extent
    big = max(abs(x0), abs(x1), abs(y0), abs(y1))
    if not math.isfinite(big) or big > MAX_ABS_COORD_M:
        raise ConfigError(
            f"{key}: the terrain reaches {big:.3g} m from the origin "
            f"(more than {MAX_ABS_COORD_M:.0e} m; check spacing_m and the file's units)"
        )


def _read_grid(path: Path, key: str, *, spacing: float | None):
    """``load_dem`` with every failure of the file turned into one line naming it."""

    def read():
        if path.suffix.lower() == ".npz":
            _check_npz_spacing(path, key)
        return load_dem(path, spacing=spacing)

    return _read_checked(path, key, read)


def _read_albedo(path: Path, key: str, shape, valid) -> np.ndarray:
    """:func:`simlunar.terrain.io.load_albedo` (the unit's reader) with every failure turned
    into one line naming ``key`` and the file."""
    return _read_checked(path, key, lambda: load_albedo(path, shape, valid=valid))


def _read_checked(path: Path, key: str, read):
    """``read()`` of a grid file after the checks every one passes first (not empty, the
    magic bytes of its format, its size), with every failure turned into one line naming
    ``key`` and the file."""

    try:
        if path.stat().st_size == 0:
            raise ConfigError(f"{key}: {path} is empty")
        _check_magic(path, key)
        grid_file_shape(path, key)  # its size, before reading it
        return read()
    except ConfigError:
        raise
    except (ValueError, TypeError, OSError, EOFError, KeyError, zipfile.BadZipFile) as exc:
        # a file the reader cannot make sense of (truncated, garbage, wrong layout)
        msg = " ".join(str(exc).split()) or type(exc).__name__
        if str(path) in msg:
            raise ConfigError(f"{key}: {msg}") from None
        raise ConfigError(f"{key}: cannot read {path}: {msg}") from None


_MAGIC = {".npy": (b"\x93NUMPY", "a NumPy .npy file"), ".npz": (b"PK", "a NumPy .npz archive")}


def _check_magic(path: Path, key: str) -> None:
    """A ``.npy``/``.npz`` must start as one (``np.load`` guesses the format from the bytes
    and leaves the file open when a guessed zip is not one)."""
    magic, what = _MAGIC.get(path.suffix.lower(), (None, ""))
    if magic is None:
        return
    with open(path, "rb") as f:
        head = f.read(len(magic))
    if head != magic or (path.suffix.lower() == ".npz" and not zipfile.is_zipfile(path)):
        raise ConfigError(f"{key}: {path} is not {what}")


def _check_npz_spacing(path: Path, key: str) -> None:
    try:
        with open(path, "rb") as f, np.load(f, allow_pickle=False) as z:
            if "spacing" not in z.files:
                return
            sp = np.asarray(z["spacing"])
    except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
        raise ConfigError(f"{key}: cannot read {path}: {exc}") from None
    if sp.size != 1 or sp.dtype.kind not in "fiu":
        raise ConfigError(
            f"{key}: {path}: 'spacing' must be one number (metres per cell), "
            f"got shape {list(sp.shape)} of {sp.dtype}"
        )
    v = float(sp.reshape(()))
    if not (math.isfinite(v) and v > 0):
        raise ConfigError(f"{key}: {path}: 'spacing' must be a positive number, got {v}")


def check_dem_file(path: str | Path, *, key: str) -> TerrainFacts:
    """A DEM file read by a command other than ``run`` (``simlunar terrain --stats``), with
    the checks of an experiment's ``terrain.file``; errors name ``key``."""
    return _dem_facts(Path(path), None, None, key=key)


def _dem_facts(
    path: Path, spacing: float | None, albedo_file, *, key: str = "terrain.file"
) -> TerrainFacts:
    if not path.is_file():
        raise ConfigError(f"{key}: file not found: {path}")
    terrain = _read_grid(path, key, spacing=spacing)
    if not terrain.spacing >= MIN_SPACING_M:
        raise ConfigError(
            f"{key}: {path}: a spacing of {terrain.spacing:.3g} m per cell is below "
            f"{MIN_SPACING_M:g} m (check the spacing's units: metres)"
        )
    h = np.asarray(terrain.heights)
    rows, cols = h.shape
    if rows < 2 or cols < 2:
        raise ConfigError(f"{key}: {path}: a DEM needs at least 2 x 2 cells, got {rows} x {cols}")
    finite = np.isfinite(h)
    n_nan = int(h.size - finite.sum())
    if n_nan == h.size:
        raise ConfigError(f"{key}: {path}: every height is NaN (no terrain)")
    frac = n_nan / h.size
    if frac > MAX_NAN_FRACTION:
        raise ConfigError(
            f"{key}: {path}: {100 * frac:.1f}% of the heights are NaN (holes); at most "
            f"{100 * MAX_NAN_FRACTION:g}% are filled from the nearest valid pixel"
        )
    zmin, zmax = float(h[finite].min()), float(h[finite].max())
    if max(abs(zmin), abs(zmax)) > MAX_ABS_COORD_M:
        raise ConfigError(
            f"{key}: {path}: heights reach {max(abs(zmin), abs(zmax)):.3g} m "
            f"(more than {MAX_ABS_COORD_M:.0e} m; check the file's units)"
        )
    facts = TerrainFacts(
        rows,
        cols,
        terrain.spacing,
        tuple(terrain.origin),
        zmin,
        zmax,
        frac,
        str(path),
        float(np.median(h[finite])),
    )
    _check_extent(facts, key)
    if albedo_file is not None:
        akey, apath = "terrain.albedo_file", Path(albedo_file)
        if not apath.is_file():
            raise ConfigError(f"{akey}: file not found: {apath}")
        _read_albedo(apath, akey, h.shape, finite)  # the reader the unit uses
        return facts
    a = np.asarray(terrain.albedo)[finite]
    if not np.all(np.isfinite(a)) or a.min() < 0 or a.max() > 1:
        bad = a[~(np.isfinite(a) & (a >= 0) & (a <= 1))][0]
        raise ConfigError(
            f"{key}: {path}: albedo must be finite and within [0, 1] where the DEM has "
            f"heights, found {bad}"
        )
    return facts
