"""Checks that run before any render or write: input files, geometry, sizes, the result folder.

The schema (:mod:`simlunar.config.schema`) checks each value on its own; what needs a file
or the geometry of a sweep point is checked here, for every sweep point, before the first
unit starts, so a mistake costs a second instead of the units computed before it:

- the DEM and albedo files a unit reads: readable, 2-D, at least 2 x 2 cells, numeric, finite
  heights within :data:`MAX_ABS_COORD_M`, a scalar spacing, albedo of the DEM's shape in
  [0, 1], and at most :data:`MAX_NAN_FRACTION` of NaN heights (holes);
- the camera: a perspective camera must have a view direction and see the terrain;
- the sizes: every density must give at least 3 samples on the unit's image, a scanner's
  projector and camera sizes must be positive;
- the output folder: not a file, not below a file, writable, ``units/`` and ``figures/``
  folders where present.

Every problem is a :class:`~simlunar.errors.ConfigError` (or
:class:`~simlunar.errors.ResultFolderError`) whose one-line message names the key path or
the file. The same module hashes the files a unit reads (:func:`input_hashes`): they are part
of the unit's cache key, so a changed DEM is recomputed.
"""

from __future__ import annotations

import contextlib
import math
import os
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from simlunar.errors import ConfigError, ResultFolderError
from simlunar.results.store import file_sha256

#: NaN heights (holes) a DEM may have. Holes leave the terrain mesh open; the rays that miss
#: it take the depth of their nearest valid pixel (``stages.fill_invalid``) and are scored as
#: truth, so beyond a few per cent the ground truth is mostly invented and the run stops.
MAX_NAN_FRACTION = 0.05

#: Largest |coordinate| (heights, terrain extent, camera position) in metres: the renderer
#: works in float32, so a scene larger than this (1000 km) cannot resolve terrain relief.
MAX_ABS_COORD_M = 1e6

#: smallest sample count of a density (the planners and the Delaunay reconstruction need 3)
MIN_SAMPLES = 3


# --------------------------------------------------------------------------- result folder
def check_out_dir(out: str | Path, *, option: str = "--out") -> Path:
    """Raise :class:`ResultFolderError` unless ``out`` is (or can be made) a writable folder.

    Nothing is created. Checks: ``out`` is not a file; no ancestor is a file; the nearest
    existing ancestor is writable and not on a read-only filesystem; ``out/units`` and
    ``out/figures`` are folders where they exist.
    """
    p = Path(out)
    if p.exists() and not p.is_dir():
        raise ResultFolderError(f"{option} {p}: is a file, not a folder")
    anc = p
    while not anc.exists() and not anc.is_symlink():
        if anc.parent == anc:
            break
        anc = anc.parent
    if anc.exists() and not anc.is_dir():
        raise ResultFolderError(f"{option} {p}: {anc} is a file, so no folder can be made in it")
    if not anc.exists():
        raise ResultFolderError(f"{option} {p}: {anc} is a broken link")
    try:
        read_only = bool(os.statvfs(anc).f_flag & os.ST_RDONLY)
    except OSError:
        read_only = False
    if read_only:
        raise ResultFolderError(f"{option} {p}: {anc} is on a read-only filesystem")
    if not os.access(anc, os.W_OK | os.X_OK):
        raise ResultFolderError(f"{option} {p}: {anc} is not writable (permission denied)")
    if p.is_dir():
        for sub in ("units", "figures", "config.yaml"):
            q = p / sub
            want_dir = sub != "config.yaml"
            if q.exists() and q.is_dir() != want_dir:
                kind = "a folder" if want_dir else "a file"
                raise ResultFolderError(f"{option} {p}: {q} is not {kind}")
            if q.is_dir() and not os.access(q, os.W_OK | os.X_OK):
                raise ResultFolderError(f"{option} {p}: {q} is not writable (permission denied)")
    return p


# --------------------------------------------------------------------------- input hashes


def input_files(config: dict[str, Any]) -> dict[str, Path]:
    """The files a unit (resolved plain config) reads, by the key path that names them.

    ``terrain.preset`` -> the preset YAML (``scenes/<name>.yaml``), ``terrain.file`` (and the
    ``.json`` side file of a ``.npy`` DEM when present), ``terrain.albedo_file``; for a raster
    GDAL reads, every other file it reads (:func:`gdal_files`) as ``terrain.file+<name>``.
    """
    t = config.get("terrain") or {}
    out: dict[str, Path] = {}
    preset = t.get("preset")
    if preset:
        from simlunar.config.terrain import PresetError, preset_path

        with contextlib.suppress(PresetError):  # a missing preset is reported by the checks
            out["terrain.preset"] = preset_path(str(preset))
    for key in ("file", "albedo_file"):
        if t.get(key):
            out[f"terrain.{key}"] = Path(t[key])
    dem = out.get("terrain.file")
    if dem is not None and dem.suffix.lower() == ".npy":
        side = dem.with_name(dem.name + ".json")
        if side.is_file():
            out["terrain.file.json"] = side
    for key in ("terrain.file", "terrain.albedo_file"):
        main = out.get(key)
        if main is not None:
            for extra in gdal_files(main):
                # named relative to the main file, so a moved data folder keeps its keys
                out[f"{key}+{os.path.relpath(extra, main.parent)}"] = extra
    return out


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
    for key, p in input_files(config).items():
        try:
            digest = file_sha256(p)
        except OSError as exc:
            raise ConfigError(f"{key}: cannot read {p} ({exc.strerror or exc})") from None
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
        return _TERRAIN_MEMO[memo]
    files = [Path(t.file)] + ([Path(t.albedo_file)] if t.albedo_file is not None else [])
    stamps = tuple(_stamp(p) for p in files)
    memo = ("file", *map(str, files), t.spacing_m, stamps)
    if memo not in _TERRAIN_MEMO:
        _TERRAIN_MEMO[memo] = _dem_facts(Path(t.file), t.spacing_m, t.albedo_file)
    return _TERRAIN_MEMO[memo]


def _preset_params(t: Any):
    """The preset's ``TerrainParams`` (grid size, spacing, origin) as the unit will build them."""
    from simlunar.config.terrain import merged_preset
    from simlunar.config.translate import terrain_params

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
    from simlunar.terrain.io import load_dem

    try:
        if path.stat().st_size == 0:
            raise ConfigError(f"{key}: {path} is empty")
        _check_magic(path, key)
        if path.suffix.lower() == ".npz":
            _check_npz_spacing(path, key)
        return load_dem(path, spacing=spacing)
    except ConfigError:
        raise
    except (ValueError, TypeError, OSError, EOFError, KeyError, zipfile.BadZipFile) as exc:
        # a file the reader cannot make sense of (truncated, garbage, wrong layout)
        msg = " ".join(str(exc).split()) or type(exc).__name__
        if str(path) in msg:
            raise ConfigError(f"{key}: {msg}") from None
        raise ConfigError(f"{key}: cannot read {path}: {msg}") from None


def _read_albedo(path: Path, key: str, shape, valid) -> np.ndarray:
    """:func:`simlunar.terrain.io.load_albedo` (the unit's reader) with every failure turned
    into one line naming ``key`` and the file."""
    from simlunar.terrain.io import load_albedo

    try:
        if path.stat().st_size == 0:
            raise ConfigError(f"{key}: {path} is empty")
        _check_magic(path, key)
        return load_albedo(path, shape, valid=valid)
    except ConfigError:
        raise
    except (ValueError, TypeError, OSError, EOFError, KeyError, zipfile.BadZipFile) as exc:
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


def _dem_facts(path: Path, spacing: float | None, albedo_file) -> TerrainFacts:
    key = "terrain.file"
    if not path.is_file():
        raise ConfigError(f"{key}: file not found: {path}")
    terrain = _read_grid(path, key, spacing=spacing)
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
        rows, cols, terrain.spacing, tuple(terrain.origin), zmin, zmax, frac, str(path)
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


# --------------------------------------------------------------------------- camera
def image_shape(render: Any, facts: TerrainFacts) -> tuple[int, int]:
    """(rows, cols) of a unit's rendered image."""
    cam = render.camera
    if getattr(cam, "kind", None) != "orthographic_nadir" and hasattr(cam, "width"):
        return (int(cam.height), int(cam.width))
    return (facts.rows, facts.cols)


def check_camera(render: Any, facts: TerrainFacts, *, key: str = "render.camera") -> None:
    """A perspective camera must have a view direction and see part of the terrain.

    ``render`` is a ``RenderCfg`` (an experiment's or a scene's).

    Rays through a grid of pixels (the corners included) are intersected with the terrain's
    bounding box; if none meets it, no pixel can see the terrain.
    """
    cam = render.camera
    if getattr(cam, "kind", None) == "rover_mast":
        _check_site(cam, facts, key)
        return
    if getattr(cam, "kind", None) != "perspective":
        return
    from simlunar.geometry import Camera, Intrinsics, Pose

    pos = np.asarray(cam.position_m, float)
    target = np.asarray(cam.look_at_m, float)
    for name, v in (("position_m", pos), ("look_at_m", target)):
        if not np.all(np.isfinite(v)) or np.abs(v).max() > MAX_ABS_COORD_M:
            raise ConfigError(
                f"{key}.{name}: coordinates must be finite and within "
                f"{MAX_ABS_COORD_M:.0e} m, got {v.tolist()}"
            )
    if np.linalg.norm(target - pos) < 1e-9 * max(1.0, np.abs(pos).max()):
        raise ConfigError(
            f"{key}.look_at_m: equals position_m {pos.tolist()}; the camera has no view direction"
        )
    up = np.asarray(getattr(cam, "up", (0.0, 0.0, 1.0)), float)
    fov = getattr(cam, "fov_deg", None)
    try:
        if fov is not None:
            k = Intrinsics.from_fov(int(cam.width), int(cam.height), float(fov))
        else:
            k = Intrinsics(cam.fx, cam.fy, cam.cx, cam.cy, int(cam.width), int(cam.height))
        camera = Camera(k, Pose.look_at(pos, target, up))
    except ValueError as exc:
        raise ConfigError(f"{key}: {exc}") from None
    n_u = min(int(cam.width), 64)
    n_v = min(int(cam.height), 64)
    uu, vv = np.meshgrid(
        np.linspace(0.0, float(cam.width), n_u), np.linspace(0.0, float(cam.height), n_v)
    )
    o, d = camera.rays(np.stack([uu, vv], axis=-1).reshape(-1, 2))
    x0, x1, y0, y1 = facts.extent
    lo = np.array([x0, y0, facts.zmin])
    hi = np.array([x1, y1, facts.zmax])
    if not np.any(_ray_box(o, d, lo, hi)):
        raise ConfigError(
            f"{key}: the camera at {pos.tolist()} looking at {target.tolist()} sees no "
            f"terrain (the terrain spans x [{x0:g}, {x1:g}] m, y [{y0:g}, {y1:g}] m, "
            f"z [{facts.zmin:.3g}, {facts.zmax:.3g}] m)"
        )


def _check_site(cam: Any, facts: TerrainFacts, key: str) -> None:
    """A rover mast stands on the terrain: its site must lie within the cell centres."""
    site = getattr(cam, "site_m", None)
    if site is None:
        return  # the terrain's centre
    x0, x1, y0, y1 = facts.extent
    h = 0.5 * facts.spacing
    x, y = float(site[0]), float(site[1])
    if not (x0 + h <= x <= x1 - h and y0 + h <= y <= y1 - h):
        raise ConfigError(
            f"{key}.site_m: [{x:g}, {y:g}] m lies outside the terrain (cell centres span "
            f"x [{x0 + h:g}, {x1 - h:g}] m, y [{y0 + h:g}, {y1 - h:g}] m)"
        )


def _ray_box(o: np.ndarray, d: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Whether each ray ``o + t d`` (t >= 0) meets the box [lo, hi] (slab method)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t1 = (lo - o) * inv
        t2 = (hi - o) * inv
    tmin = np.where(np.isnan(t1), -np.inf, np.minimum(t1, t2))
    tmax = np.where(np.isnan(t2), np.inf, np.maximum(t1, t2))
    # a ray parallel to a slab (d = 0) misses unless its origin lies inside the slab
    par = d == 0
    inside = (o >= lo) & (o <= hi)
    tmin = np.where(par, np.where(inside, -np.inf, np.inf), tmin)
    tmax = np.where(par, np.where(inside, np.inf, -np.inf), tmax)
    near = tmin.max(axis=-1)
    far = tmax.min(axis=-1)
    return (far >= np.maximum(near, 0.0)) & np.isfinite(far)


# --------------------------------------------------------------------------- sizes
def check_study_sizes(cfg: Any, shape: tuple[int, int]) -> None:
    """Densities give at least :data:`MIN_SAMPLES` samples; scanner sizes are positive."""
    s = cfg.study
    n = shape[0] * shape[1]
    if getattr(s, "kind", "sampling") == "sampling":
        for i, d in enumerate(s.densities):
            k = round(d * n)
            if k < MIN_SAMPLES:
                raise ConfigError(
                    f"study.densities[{i}]: density {d:g} gives {k} samples on the "
                    f"{shape[0]} x {shape[1]} image (at least {MIN_SAMPLES} needed: "
                    f"density >= {MIN_SAMPLES / n:.3g})"
                )
        return
    for name in ("projector_px", "camera_px"):
        size = getattr(s, name, None)
        if size is None:
            continue
        if len(size) != 2 or any(int(v) < 2 for v in size):
            raise ConfigError(
                f"study.{name}: (width, height) must be at least 2 pixels each, got {list(size)}"
            )
    budget = getattr(s, "budget", None)
    cam = getattr(s, "camera_px", None)
    if budget is not None and cam is not None:
        k = round(budget * cam[0] * cam[1])
        if k < 1:
            raise ConfigError(
                f"study.budget: {budget:g} of the {cam[0]} x {cam[1]} camera gives no sample"
            )


# --------------------------------------------------------------------------- all units
@dataclass(frozen=True)
class Preflight:
    """What the checks found: per unit its terrain facts (holes reported in provenance)."""

    terrain: tuple[TerrainFacts, ...]

    def holes(self) -> list[dict[str, Any]]:
        """Terrain files with NaN holes: file, share and how they are filled (deduplicated)."""
        seen: dict[str, dict[str, Any]] = {}
        for f in self.terrain:
            if f.nan_fraction > 0 and f.source not in seen:
                seen[f.source] = {
                    "file": f.source,
                    "nan_fraction": f.nan_fraction,
                    "filled": "ground-truth pixels without a hit take the depth of the "
                    "nearest valid pixel",
                    "max_nan_fraction": MAX_NAN_FRACTION,
                }
        return list(seen.values())


def check_units(units: list[Any]) -> Preflight:
    """Check every unit (sweep point) before any of them runs.

    ``units`` are :class:`~simlunar.results.records.WorkUnit` (their plain ``config``).
    Errors of a sweep point name the point: ``sweep point 3 (elevation_deg=0): ...``.
    """
    from simlunar.config.schema import ExperimentCfg

    facts = []
    for u in units:
        cfg = ExperimentCfg.model_validate(u.config)
        try:
            f = terrain_facts(cfg.terrain)
            check_camera(cfg.render, f)
            check_study_sizes(cfg, image_shape(cfg.render, f))
        except ConfigError as exc:
            if len(units) > 1 and u.sweep:
                from simlunar.results.records import unit_label

                raise ConfigError(f"sweep point {u.index} ({unit_label(u)}): {exc}") from None
            raise
        facts.append(f)
    return Preflight(tuple(facts))
