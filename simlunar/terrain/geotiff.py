"""GeoTIFF (and other GDAL rasters) for DEMs through rasterio: writing with the north-up transform
and CRS, reading with nodata, resampling of non-square cells and the band layout."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from simlunar.atomic import atomic_write
from simlunar.terrain.types import Terrain

#: CRS written for a terrain without one: the IAU 2015 Moon sphere (IAU_2015:30100), projected
#: equirectangular in metres (IAU_2015:30110, whose base CRS is 30100), since the grid is in metres
LUNAR_CRS = "IAU_2015:30110"
#: vertical units understood in a raster band's ``units`` (factor to metres)
_VERTICAL_UNITS = {
    "": 1.0,
    "m": 1.0,
    "metre": 1.0,
    "metres": 1.0,
    "meter": 1.0,
    "meters": 1.0,
    "km": 1000.0,
    "kilometre": 1000.0,
    "kilometer": 1000.0,
    "kilometers": 1000.0,
    "cm": 0.01,
    "ft": 0.3048,
    "foot": 0.3048,
    "feet": 0.3048,
}


def _meta(terrain: Terrain) -> dict:
    meta = {"spacing": terrain.spacing, "origin": list(terrain.origin), "format": "simlunar-dem-1"}
    if terrain.crs is not None:
        meta["crs"] = terrain.crs
    return meta


__all__ = ["LUNAR_CRS", "float32_profile"]


def float32_profile(shape: tuple[int, int], *, count: int, transform) -> dict:
    """The rasterio write profile of a float32 GeoTIFF of ``count`` bands: NaN nodata, deflate
    with the floating-point predictor (lossless, smaller); no CRS (the caller adds one).

    Parameters
    ----------
    shape : (rows, cols)
        Band shape (pixels).
    count : int
        Number of bands.
    transform : 6 floats
        GDAL affine ``(a, b, c, d, e, f)``: x = a col + b row + c, y = d col + e row + f.

    Returns
    -------
    dict
        Keywords of ``rasterio.open(path, "w", **profile)``.
    """
    from rasterio.transform import Affine

    return {
        "driver": "GTiff",
        "width": shape[1],
        "height": shape[0],
        "count": count,
        "dtype": "float32",
        "transform": Affine(*transform),
        "nodata": float("nan"),
        "compress": "deflate",
        "predictor": 3,  # floating-point predictor
    }


def _write_geotiff(path: Path, h: np.ndarray, a: np.ndarray, terrain: Terrain) -> None:
    import rasterio
    from rasterio.crs import CRS

    x0, y0 = terrain.origin
    sp = terrain.spacing
    profile = float32_profile(h.shape, count=2, transform=(sp, 0.0, x0, 0.0, -sp, y0))
    profile["crs"] = CRS.from_wkt(terrain.crs) if terrain.crs else CRS.from_string(LUNAR_CRS)
    if min(h.shape) >= 256:  # 256 x 256 tiles (QGIS reads windows fast); else strips
        profile.update(tiled=True, blockxsize=256, blockysize=256)

    def write(tmp) -> None:
        with rasterio.open(tmp, "w", **profile) as dst:
            dst.write(h, 1)
            dst.write(a, 2)
            dst.set_band_description(1, "height")
            dst.set_band_description(2, "albedo")
            dst.units = ("m", "")
            dst.update_tags(simlunar=json.dumps(_meta(terrain)))

    atomic_write(path, write)


def _simlunar_meta(tags: dict) -> dict:
    """simlunar's own meta in a raster's tags (an old simlunar .tif, before GeoTIFF output,
    kept it in the image description); empty for a foreign raster."""
    for key in ("simlunar", "TIFFTAG_IMAGEDESCRIPTION"):
        try:
            d = json.loads(tags.get(key, ""))
        except ValueError:
            continue
        if key == "TIFFTAG_IMAGEDESCRIPTION" and isinstance(d, dict):
            d = json.loads(d["simlunar"]) if "simlunar" in d else {}
        if isinstance(d, dict) and d:
            return d
    return {}


def _square_grid(src, path: Path, *, resample: bool) -> tuple[tuple[int, int], float]:
    """Read shape and cell size of a georeferenced raster: north-up and projected, its cells
    made square (resampled to the smaller side when ``resample``), else a ValueError."""
    tr = src.transform
    if abs(tr.b) > 0 or abs(tr.d) > 0:
        raise ValueError(
            f"{path}: rotated or sheared geotransform {tuple(tr)[:6]}; "
            "warp it north-up first (gdalwarp)"
        )
    if src.crs is not None and src.crs.is_geographic:
        raise ValueError(
            f"{path}: CRS {src.crs.to_string()} is geographic (degrees); reproject "
            "to a projected CRS in metres first (gdalwarp -t_srs)"
        )
    shape = (src.height, src.width)
    sx, sy = abs(tr.a), abs(tr.e)
    if not math.isclose(sx, sy, rel_tol=1e-9):
        if not resample:
            raise ValueError(
                f"{path}: non-square pixels {sx} x {sy}; pass resample=True to "
                "resample to square cells, or resample with gdalwarp -tr"
            )
        sp = min(sx, sy)
        shape = (round(src.height * sy / sp), round(src.width * sx / sp))
        sx = sp
    return shape, sx


def _read_albedo(src, path: Path, *, ours: bool, georef: bool, kw: dict) -> np.ndarray | None:
    """The albedo band of a raster (a second band of ours or one described ``albedo``), or
    None."""
    if src.count >= 2 and (ours or (src.descriptions[1] or "").lower() == "albedo"):
        return np.ma.filled(src.read(2, masked=True, **kw).astype(np.float32), np.nan)
    if ours and src.driver == "GTiff" and not georef:
        # a pre-GeoTIFF simlunar .tif: albedo is the second page, which GDAL does not
        # show as a band
        import tifffile

        stack = tifffile.imread(path)
        if stack.ndim == 3 and stack.shape[0] == 2:
            return stack[1].astype(np.float32)
    return None


def _to_metres(src, path: Path, h: np.ndarray) -> np.ndarray:
    """Heights of band 1 in metres: its scale and offset, then its vertical unit."""
    unit = (src.units[0] or "").strip().lower()
    if unit not in _VERTICAL_UNITS:
        raise ValueError(
            f"{path}: unknown vertical unit {src.units[0]!r}; "
            f"valid: {', '.join(u for u in _VERTICAL_UNITS if u)}"
        )
    scale, offset = src.scales[0], src.offsets[0]
    if scale != 1.0 or offset != 0.0:
        h = h * scale + offset
    if _VERTICAL_UNITS[unit] != 1.0:
        h = h * _VERTICAL_UNITS[unit]
    return h


def _north_up(src, h, albedo, *, shape, sx: float):
    """Heights and albedo flipped into the north-up frame, and the meta of the transform
    (spacing and origin in metres, the CRS as WKT)."""
    tr = src.transform
    lin = 1.0
    if src.crs is not None and src.crs.is_projected:
        lin = float(src.crs.linear_units_factor[1])
    x0, y0 = tr.c, tr.f
    if tr.e > 0:  # south-up: flip the rows into the north-up frame
        h, y0 = h[::-1], tr.f + shape[0] * sx
        albedo = None if albedo is None else albedo[::-1]
    if tr.a < 0:  # east-to-west columns
        h, x0 = h[:, ::-1], tr.c - shape[1] * sx
        albedo = None if albedo is None else albedo[:, ::-1]
    meta = {"spacing": sx * lin, "origin": [x0 * lin, y0 * lin]}
    if src.crs is not None:
        meta["crs"] = src.crs.to_wkt()
    return h, albedo, meta


def _read_gdal(path: Path, *, resample: bool) -> tuple[np.ndarray, np.ndarray | None, dict]:
    """Heights (float64 metres, NaN holes), albedo or None, and meta of a GDAL raster."""
    import warnings

    import rasterio
    from rasterio.enums import Resampling
    from rasterio.errors import NotGeoreferencedWarning, RasterioIOError

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        try:
            src_cm = rasterio.open(path)
        except RasterioIOError as exc:
            raise ValueError(f"cannot read DEM {path}: {exc}") from None
        with src_cm as src:
            meta = _simlunar_meta(src.tags())
            georef = src.crs is not None or not src.transform.is_identity
            shape, sx = (src.height, src.width), None
            if georef:
                shape, sx = _square_grid(src, path, resample=resample)
            kw = {}
            if shape != (src.height, src.width):
                kw = {"out_shape": shape, "resampling": Resampling.bilinear}
            band = src.read(1, masked=True, **kw)
            h = np.ma.filled(band.astype(np.float64), np.nan)
            ours = meta.get("format") == "simlunar-dem-1"
            albedo = _read_albedo(src, path, ours=ours, georef=georef, kw=kw)
            h = _to_metres(src, path, h)
            if georef:
                h, albedo, meta = _north_up(src, h, albedo, shape=shape, sx=sx)
    return np.ascontiguousarray(h), albedo, meta
