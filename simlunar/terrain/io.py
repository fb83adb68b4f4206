"""DEM + albedo files (.npy, .npz, .exr, GeoTIFF and other GDAL rasters), mesh export, hillshade.

On disk heights and albedo are float32 (a float64 terrain is rounded once; a float32 terrain
round-trips bit-identically). Nodata is NaN in every format. Spacing and origin travel with the
data: inside the file for .npz (arrays), .exr (header) and .tif (GeoTIFF transform); in a
sidecar ``<file>.json`` for .npy. A CRS (``Terrain.crs``, WKT) travels the same way when set.

World frame (``Terrain``): the origin is the top-left (north-west) corner of cell (0, 0), columns
run to +x, rows to -y, z up, metres. This is a north-up GeoTIFF's frame: the transform
``(spacing, 0, x0, 0, -spacing, y0)`` maps pixel corner (col, row) to (x, y).

Layouts: .npy holds a (2, rows, cols) float32 stack [heights, albedo]; .npz holds ``heights``,
``albedo``, ``spacing``, ``origin`` (and ``crs``); .exr has channels ``Z`` (heights) and
``albedo``; .tif/.tiff is a two-band float32 GeoTIFF (band 1 ``height`` in metres, band 2
``albedo``, nodata NaN, the terrain's CRS or :data:`LUNAR_CRS`), written and read with rasterio.

Foreign DEMs: any raster GDAL opens (GeoTIFF, PDS3/PDS4 labels, ISIS cubes, ERDAS .img, VRT, ...)
loads with its transform (spacing, origin), nodata, CRS, band scale/offset and vertical unit (m,
km, cm or ft -> metres). A second band is taken as albedo only when its description is
``albedo``. Geographic CRSs (degrees), rotated transforms and non-square pixels are refused
with one line (non-square pixels are resampled with ``resample=True``). A 2-D .npy or a TIFF
without georeferencing needs ``spacing=`` (and ``origin=``; ``nodata=`` for a sentinel value).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from simlunar.atomic import atomic_write
from simlunar.imaging.exr import read_exr, write_exr
from simlunar.imaging.png import write_png_preview
from simlunar.terrain.geotiff import _meta, _read_gdal, _write_geotiff
from simlunar.terrain.mesh import grid_faces, grid_vertices
from simlunar.terrain.types import Terrain

__all__ = [
    "DEFAULT_ALBEDO",
    "FORMATS",
    "GDAL_FORMATS",
    "export_mesh",
    "features_json",
    "hillshade",
    "hillshade_png",
    "load_albedo",
    "load_dem",
    "save_dem",
    "write_terrain_outputs",
]

#: formats :func:`save_dem` writes (and :func:`load_dem` reads)
FORMATS = (".npy", ".npz", ".exr", ".tif", ".tiff")
#: further raster formats :func:`load_dem` reads through GDAL (rasterio)
GDAL_FORMATS = (".img", ".cub", ".lbl", ".xml", ".vrt", ".asc", ".dem", ".jp2", ".nc", ".hgt")
#: albedo given to a foreign DEM that has none (lunar soil mean)
DEFAULT_ALBEDO = 0.12


def _suffix(path: Path, *, read: bool = False) -> str:
    suf = path.suffix.lower()
    valid = FORMATS + GDAL_FORMATS if read else FORMATS
    if suf not in valid:
        raise ValueError(
            f"unsupported DEM format {suf or '(none)'!r} for {path}; valid: {', '.join(valid)}"
        )
    return suf


def save_dem(path, terrain: Terrain) -> Path:
    """Write heights and albedo (float32) with spacing, origin and CRS; format from the suffix.

    Parameters
    ----------
    path : str or Path
        ``.npy`` (+ sidecar ``.json``), ``.npz``, ``.exr``, ``.tif`` or ``.tiff`` (GeoTIFF:
        two float32 bands, height and albedo; CRS ``terrain.crs`` or :data:`LUNAR_CRS`).
    terrain : Terrain

    Returns
    -------
    Path
    """
    path = Path(path)
    suf = _suffix(path)
    h = terrain.heights.astype(np.float32)
    a = terrain.albedo.astype(np.float32)
    meta = _meta(terrain)
    if suf == ".npy":
        atomic_write(path, lambda t: np.save(t, np.stack([h, a])))
        side = path.with_name(path.name + ".json")
        atomic_write(side, lambda t: Path(t).write_text(json.dumps(meta)))
    elif suf == ".npz":
        extra = {} if terrain.crs is None else {"crs": np.array(terrain.crs)}
        atomic_write(
            path,
            lambda t: np.savez_compressed(
                t,
                heights=h,
                albedo=a,
                spacing=np.float64(terrain.spacing),
                origin=np.array(terrain.origin, dtype=np.float64),
                **extra,
            ),
        )
    elif suf == ".exr":
        write_exr(path, {"Z": h, "albedo": a}, attrs=meta)
    else:
        _write_geotiff(path, h, a, terrain)
    return path


def _check_array(arr, path: Path, what: str) -> np.ndarray:
    arr = np.asarray(arr)
    if arr.dtype.kind not in "fiu":
        raise ValueError(f"{path}: {what} must be a real numeric array, got dtype {arr.dtype}")
    return arr


def _split(arr: np.ndarray, path: Path) -> tuple[np.ndarray, np.ndarray | None]:
    if arr.ndim == 2:
        return arr, None
    if arr.ndim == 3 and arr.shape[0] == 2:
        return arr[0], arr[1]
    raise ValueError(
        f"{path}: a DEM array must be (rows, cols) heights or a (2, rows, cols) "
        f"[heights, albedo] stack, got shape {arr.shape}"
    )


def _read_npy(path: Path):
    """A .npy (heights or a [heights, albedo] stack) and the meta of its sidecar .json."""
    arr = _check_array(np.load(path, allow_pickle=False), path, "the array")
    heights, albedo = _split(arr, path)
    side = path.with_name(path.name + ".json")
    meta = json.loads(side.read_text()) if side.is_file() else {}
    return heights, albedo, meta


def _read_npz(path: Path):
    """A .npz: ``heights``, optional ``albedo``, and ``spacing``, ``origin``, ``crs`` as meta."""
    meta: dict = {}
    albedo = None
    with np.load(path, allow_pickle=False) as z:
        if "heights" not in z:
            raise ValueError(f"{path}: no 'heights' array (found {sorted(z.files)})")
        heights = _check_array(z["heights"], path, "heights")
        if "albedo" in z:
            albedo = _check_array(z["albedo"], path, "albedo")
        if "spacing" in z:
            meta["spacing"] = float(z["spacing"])
        if "origin" in z:
            meta["origin"] = [float(v) for v in z["origin"]]
        if "crs" in z:
            meta["crs"] = str(z["crs"])
    return heights, albedo, meta


def _read_exr_dem(path: Path):
    """An .exr: channel ``Z`` (or ``Y``) heights, optional ``albedo``, meta in the header."""
    chans, meta = read_exr(path, with_attrs=True)
    if "Z" in chans:
        heights = chans["Z"]
    elif "Y" in chans:
        heights = chans["Y"]
    else:
        raise ValueError(f"{path}: no 'Z' (or 'Y') height channel (found {sorted(chans)})")
    return heights, chans.get("albedo"), meta


def _read_file(path: Path, suf: str, *, resample: bool):
    """Heights, albedo (or None) and the file's meta (whichever of spacing, origin and crs it
    carries) of a DEM file in the format of suffix ``suf``."""
    if suf == ".npy":
        return _read_npy(path)
    if suf == ".npz":
        return _read_npz(path)
    if suf == ".exr":
        return _read_exr_dem(path)
    return _read_gdal(path, resample=resample)


def load_dem(
    path,
    *,
    spacing: float | None = None,
    origin=None,
    nodata: float | None = None,
    albedo_file=None,
    resample: bool = False,
) -> Terrain:
    """Read a DEM written by :func:`save_dem`, or a foreign DEM (any raster GDAL opens).

    Parameters
    ----------
    path : str or Path
    spacing : float, optional
        Cell size in metres; overrides the file's, required when the file carries none.
    origin : (x, y), optional
        World position of the top-left corner; default the file's or (0, 0).
    nodata : float, optional
        Sentinel height value to turn into NaN (the raster's own nodata is always honoured).
    albedo_file : str or Path, optional
        A second file (any format here) whose first band / heights array is the albedo grid.
    resample : bool
        Resample a raster with non-square pixels (bilinear) to square cells of the smaller
        size instead of refusing it.

    Returns
    -------
    Terrain
        ``crs`` is the raster's CRS as WKT (or the one saved with the file), else None.

    Raises
    ------
    FileNotFoundError
        Missing file (named).
    ValueError
        Unreadable file, wrong shape or dtype, missing spacing, geographic CRS, rotated
        transform, non-square pixels (message names the file).
    """
    path = Path(path)
    suf = _suffix(path, read=True)
    if not path.is_file():
        raise FileNotFoundError(f"DEM file not found: {path}")
    try:
        heights, albedo, meta = _read_file(path, suf, resample=resample)
    except (ValueError, OSError, KeyError, EOFError) as exc:
        msg = str(exc)
        raise ValueError(msg if str(path) in msg else f"cannot read DEM {path}: {msg}") from None
    if heights.ndim != 2:
        raise ValueError(f"{path}: heights must be 2-D, got shape {heights.shape}")
    if albedo_file is not None:
        valid = (
            np.isfinite(heights) if nodata is None else np.isfinite(heights) & (heights != nodata)
        )
        albedo = load_albedo(albedo_file, heights.shape, valid=valid)
    if albedo is not None and albedo.shape != heights.shape:
        raise ValueError(
            f"{path}: albedo shape {albedo.shape} differs from heights {heights.shape}"
        )
    sp = spacing if spacing is not None else meta.get("spacing")
    if sp is None:
        raise ValueError(f"{path}: the file carries no spacing; pass spacing= (metres per cell)")
    org = origin if origin is not None else meta.get("origin", (0.0, 0.0))
    h = heights.astype(np.float64)
    if nodata is not None:
        h[heights == nodata] = np.nan
    if albedo is None:
        albedo = np.full(h.shape, DEFAULT_ALBEDO, dtype=np.float32)
    crs = meta.get("crs")
    try:
        return Terrain(
            h, albedo.astype(np.float32), float(sp), tuple(org), crs=crs if crs else None
        )
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None


def load_albedo(path, shape: tuple[int, int], *, valid: np.ndarray | None = None) -> np.ndarray:
    """Read an albedo grid file for a DEM of ``shape``: the one reader of ``albedo_file``.

    A ``.npy`` must hold one (rows, cols) grid (a (2, rows, cols) [heights, albedo] stack is
    a DEM, not an albedo file); any other format :func:`load_dem` reads gives its first band
    (heights array).

    Parameters
    ----------
    path : str or Path
    shape : (rows, cols)
        The DEM's grid; the albedo grid must match it.
    valid : bool array of ``shape``, optional
        Cells where the DEM has heights; values must be finite and in [0, 1] there (default
        everywhere). Other cells (holes) are not checked.

    Returns
    -------
    (rows, cols) float32 array

    Raises
    ------
    FileNotFoundError
        Missing file.
    ValueError
        Unreadable file, not one 2-D numeric grid, a shape other than ``shape``, or values
        that are not finite numbers in [0, 1] (the message names the file).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"albedo file not found: {path}")
    if _suffix(path, read=True) == ".npy":
        try:
            arr = np.load(path, allow_pickle=False)
        except (OSError, ValueError, EOFError) as exc:
            raise ValueError(f"cannot read {path}: {' '.join(str(exc).split())}") from None
        arr = np.asarray(arr)
        if arr.ndim != 2 or arr.dtype.kind not in "fiu":
            raise ValueError(
                f"{path}: an albedo .npy must hold one (rows, cols) numeric grid, got "
                f"{arr.dtype} {arr.shape}"
            )
    else:
        arr = load_dem(path, spacing=1.0).heights
    if arr.shape != tuple(shape):
        raise ValueError(
            f"{path}: albedo shape {arr.shape[0]} x {arr.shape[1]} differs from the DEM's "
            f"{shape[0]} x {shape[1]}"
        )
    arr = arr.astype(np.float32)
    a = arr if valid is None else arr[np.asarray(valid, bool)]
    ok = np.isfinite(a) & (a >= 0) & (a <= 1)
    if not np.all(ok):
        raise ValueError(
            f"{path}: albedo must be finite and within [0, 1] where the DEM has heights, "
            f"found {a[~ok][0]}"
        )
    return arr


def export_mesh(terrain: Terrain, path) -> Path:
    """Export the grid mesh (one vertex per cell, as ``terrain.mesh``) as PLY or OBJ.

    PLY carries the albedo as 8-bit grey vertex colour (``round(255 * albedo)``); OBJ is plain
    (``v x y z`` and ``f`` lines, no colour extension), so every reader sees (n, 3) points.
    Triangles touching nodata cells are dropped; their vertices stay (NaN) so vertex
    ``r * cols + c`` is cell (r, c).
    """
    import trimesh

    path = Path(path)
    suf = path.suffix.lower()
    if suf not in (".ply", ".obj"):
        raise ValueError(
            f"unsupported mesh format {suf or '(none)'!r} for {path}; valid: .ply, .obj"
        )
    v = grid_vertices(terrain.heights, terrain.spacing, terrain.origin)
    f = grid_faces(terrain.shape, terrain.nodata)
    g = np.round(np.clip(terrain.albedo.ravel(), 0, 1) * 255).astype(np.uint8)
    colors = np.stack([g, g, g, np.full_like(g, 255)], axis=1) if suf == ".ply" else None
    mesh = trimesh.Trimesh(vertices=v, faces=f, vertex_colors=colors, process=False, validate=False)
    data = mesh.export(file_type=suf[1:])
    blob = data if isinstance(data, bytes) else data.encode()
    atomic_write(path, lambda t: Path(t).write_bytes(blob))
    return path


def hillshade(
    heights: np.ndarray,
    spacing: float,
    *,
    azimuth: float = np.radians(315.0),
    elevation: float = np.radians(45.0),
) -> np.ndarray:
    """Lambertian shading ``max(0, n . l)`` of a height grid (NaN where the height is NaN).

    Parameters
    ----------
    heights : (rows, cols) array, metres
    spacing : float, metres per cell
    azimuth : float
        Sun azimuth in radians from +y (north) clockwise towards +x (east).
    elevation : float
        Sun elevation above the horizon, radians.

    Returns
    -------
    (rows, cols) float64 in [0, 1]
    """
    h = np.asarray(heights, dtype=np.float64)
    dzdr, dzdc = np.gradient(h, spacing)
    # rows run to -y: dz/dy = -dz/drow
    nx, ny = -dzdc, dzdr
    norm = np.sqrt(nx**2 + ny**2 + 1.0)
    lx = np.cos(elevation) * np.sin(azimuth)
    ly = np.cos(elevation) * np.cos(azimuth)
    lz = np.sin(elevation)
    return np.clip((nx * lx + ny * ly + lz) / norm, 0.0, 1.0)


def hillshade_png(
    terrain: Terrain,
    path,
    *,
    azimuth: float = np.radians(315.0),
    elevation: float = np.radians(45.0),
    with_albedo: bool = True,
) -> Path:
    """Write a hillshade preview PNG (sRGB, nodata black), optionally modulated by albedo."""

    img = hillshade(terrain.heights, terrain.spacing, azimuth=azimuth, elevation=elevation)
    if with_albedo:
        a = terrain.albedo.astype(np.float64)
        m = float(np.nanmean(a)) or 1.0
        img = img * a / m * 0.8
    return write_png_preview(path, img, exposure=1.0)


def features_json(result) -> dict:
    """JSON-ready summary of a generated terrain: grid, preset name, craters and rocks."""
    t = result.terrain
    return {
        "name": result.params.name,
        "description": result.params.description,
        "shape": list(t.shape),
        "spacing": t.spacing,
        "origin": list(t.origin),
        "craters": [c.to_dict() for c in result.craters],
        "rocks": [r.to_dict() for r in result.rocks],
    }


def write_terrain_outputs(
    result, out_dir, *, dem_format: str = "exr", mesh_format: str | None = "ply"
) -> dict[str, Path]:
    """Write a generated terrain's files into ``out_dir`` (created if needed).

    Files: ``dem.<fmt>`` (heights + albedo + spacing), ``albedo.png`` (sRGB preview),
    ``hillshade.png``, ``mesh.<ply|obj>`` (unless ``mesh_format`` is None) and
    ``features.json`` (placed craters and rocks, world metres).

    Returns
    -------
    dict name -> Path of the files written.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    fmt = dem_format.lower().lstrip(".")
    if f".{fmt}" not in FORMATS:
        raise ValueError(f"unknown DEM format {dem_format!r}; valid: npy, npz, exr, tif")

    files = {"dem": save_dem(out / f"dem.{fmt}", result.terrain)}
    files["albedo"] = write_png_preview(out / "albedo.png", result.terrain.albedo, exposure=1.0)
    files["hillshade"] = hillshade_png(result.terrain, out / "hillshade.png")
    if mesh_format is not None:
        files["mesh"] = export_mesh(result.terrain, out / f"mesh.{mesh_format.lower().lstrip('.')}")
    blob = json.dumps(features_json(result), indent=1)
    atomic_write(out / "features.json", lambda t: Path(t).write_text(blob))
    files["features"] = out / "features.json"
    return files
