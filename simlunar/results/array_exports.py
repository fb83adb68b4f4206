"""Reconstruction export: every reconstruction of a unit and its error map, as GeoTIFF and EXR.

``simlunar run EXPERIMENT --save-arrays`` (``study.save_arrays: true``) on a sampling or LIDAR
study writes, per unit, a folder ``arrays/unit<i>/`` of the result folder with, for every
planner (strategy) label, density and reconstruction of the unit's trial 0::

    <planner>_<density>_<reconstruction>_<quantity>.tif   the reconstruction (GeoTIFF, float32)
    <planner>_<density>_<reconstruction>_<quantity>.exr   the same grid (OpenEXR, float32, one
                                                         channel named <quantity>)
    <planner>_<density>_<reconstruction>_error.tif        reconstruction - truth (m)
    <planner>_<density>_<reconstruction>_error.exr        the same (one channel named "error")
    truth_<quantity>.tif / truth_<quantity>.exr           the ground truth they are scored against
    manifest.json                                          every file with its planner, density,
                                                         k, reconstruction, trial; written last

``<density>`` is ``1-64`` for k / N = 1/64 (``0.3`` for a density that is no unit fraction,
``all`` for a flash LIDAR without a plan); the manifest names each field exactly, so labels
holding ``_`` are never ambiguous. Characters other than letters, digits, ``_.+-`` become
``-`` in a file name, so two labels may make one name (``a b`` and ``a-b``): the later one's
files get ``+2`` (``+3``, ...) after the name, and no file is written twice.

**Quantity and georeference.** For an orthographic nadir view (``render.camera.kind:
ortho_nadir``, the sampling studies' default), pixel (r, c) looks straight down at terrain
cell (r, c) (:meth:`simlunar.geometry.OrthoCamera.nadir_for_grid`), so the measured depth is
converted to height, ``height = camera z - depth`` (m; exact for vertical rays), and the
GeoTIFF carries the terrain's north-up transform ``(s, 0, x0, 0, -s, y0)`` and, where the
terrain has one (a DEM read with a CRS), its CRS (CONTRIBUTING.md, terrain conventions). For
any other view (perspective, rover mast, a LIDAR's camera) the grid is the guide camera's
image: the quantity is ``depth`` (z-depth along the camera axis, m), the transform the pixel
grid ``(1, 0, 0, 0, -1, rows)`` (:func:`pixel_transform`: one unit per pixel, the image's
bottom-left corner at (0, 0); GDAL treats an identity matrix as "no transform") and no CRS is
written. The
error map is of the same quantity: for heights, a positive error is a reconstruction above
the true surface.

The EXR header carries the same transform, CRS, quantity and labels in simlunar's JSON
attribute (:mod:`simlunar.imaging.exr`). NaN marks a cell the reconstruction left empty (a
``nan`` outside policy).

Two steps, as the scan export (:mod:`simlunar.results.exports`): :func:`array_export_payload`
in the unit's process (arrays and plain data, picklable for any executor) and
:func:`write_array_export` in the runner's process. Every file is written atomically.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np

from simlunar.atomic import atomic_write
from simlunar.errors import ConfigError
from simlunar.geometry import OrthoCamera
from simlunar.imaging.exr import write_exr
from simlunar.terrain.geotiff import float32_profile

__all__ = [
    "ARRAY_EXPORT_KINDS",
    "array_export_complete",
    "array_export_payload",
    "check_save_arrays",
    "density_tag",
    "export_view",
    "pixel_transform",
    "read_geotiff",
    "write_array_export",
    "write_geotiff",
]

#: the study kinds whose units export their reconstructions
ARRAY_EXPORT_KINDS = ("sampling", "lidar")


def pixel_transform(rows: int) -> tuple[float, ...]:
    """The GeoTIFF transform of a grid that is no terrain grid: one unit per pixel, north up,
    the bottom-left corner at (0, 0): x = col, y = rows - row (pixel corners), as GDAL's
    affine ``(a, b, c, d, e, f)`` (x = a col + b row + c, y = d col + e row + f).

    Not the identity (nor its flip), which GDAL may drop as "no geotransform" and rasterio
    reports as not georeferenced."""
    return (1.0, 0.0, 0.0, 0.0, -1.0, float(rows))


def density_tag(density: float) -> str:
    """A file-name tag of a density: ``1-64`` for 1/64, ``0.3`` otherwise, ``all`` for 0.

    Examples
    --------
    >>> density_tag(1 / 64), density_tag(0.3), density_tag(0.0)
    ('1-64', '0.3', 'all')
    """
    d = float(density)
    if d == 0.0:
        return "all"
    if not 0.0 < d <= 1.0:
        raise ValueError(f"density must be in (0, 1] (or 0: no plan), got {density}")
    inv = 1.0 / d
    if abs(inv - round(inv)) < 1e-9 * inv:
        return f"1-{round(inv)}"
    return f"{d:.4g}"


def _safe(label: str) -> str:
    """A label as a file-name part (characters other than letters, digits, ``.+-`` become
    ``-``; ``_`` is kept)."""
    return re.sub(r"[^A-Za-z0-9_.+-]", "-", str(label)) or "-"


def export_view(camera, terrain, shape=None) -> dict[str, Any]:
    """What a unit's grids are exported as, from its guide camera and terrain.

    Parameters
    ----------
    camera : geometry camera (``OrthoCamera`` or ``Camera``)
        The guide view the study's grids are on.
    terrain : :class:`simlunar.terrain.Terrain`
    shape : (rows, cols), optional
        The grids' shape (default: the camera's image shape).

    Returns
    -------
    dict
        ``quantity`` (``"height"`` or ``"depth"``), ``offset`` (m: height = offset - depth for
        a nadir view; None otherwise), ``transform`` (6 floats, GDAL order) and ``crs`` (WKT
        string or None).
    """

    nadir = (
        isinstance(camera, OrthoCamera)
        and camera.shape == tuple(terrain.shape)
        and np.isclose(camera.pixel_size, terrain.spacing)
        and np.allclose(camera.pose.forward, (0.0, 0.0, -1.0))
    )
    if not nadir:
        rows = (shape or camera.shape)[0]
        return {
            "quantity": "depth",
            "offset": None,
            "transform": pixel_transform(rows),
            "crs": None,
        }
    s = float(terrain.spacing)
    x0, y0 = (float(v) for v in terrain.origin)
    return {
        "quantity": "height",
        "offset": float(camera.position[2]),
        "transform": (s, 0.0, x0, 0.0, -s, y0),
        "crs": terrain.crs,
    }


def array_export_payload(
    grids: dict, truth, *, densities, ks, view: dict, trial: int = 0
) -> dict[str, Any]:
    """Everything :func:`write_array_export` writes, from a study's kept grids.

    Parameters
    ----------
    grids : dict (planner label, density index, reconstruction) -> (rows, cols) float
        Reconstructed depth (m) of one trial, as the study measured it.
    truth : (rows, cols) float
        True depth (m) on the same grid (NaN where the view misses the terrain).
    densities, ks : sequence
        Density (k / N) and planned pixel count of each density index.
    view : dict
        From :func:`export_view`.
    trial : int
        The trial the grids are of.

    Returns
    -------
    dict of arrays and plain data (picklable; no file is written)
    """
    off = view["offset"]

    def quantity(depth):
        d = np.asarray(depth, np.float64)
        return (d if off is None else off - d).astype(np.float32)

    items = [
        {
            "planner": str(label),
            "density": float(densities[di]),
            "k": int(ks[di]),
            "reconstruction": str(recon),
            "trial": int(trial),
            "grid": quantity(grid),
        }
        for (label, di, recon), grid in grids.items()
    ]
    return {
        "kind": "arrays",
        "quantity": view["quantity"],
        "transform": [float(v) for v in view["transform"]],
        "crs": view["crs"],
        "truth": quantity(truth),
        "items": items,
    }


def write_geotiff(path, grid, *, transform=None, crs=None, name="value", tags=None):
    """Write one float32 band as a GeoTIFF, atomically.

    Parameters
    ----------
    path : path
    grid : (rows, cols) float
        Values (m); NaN is the nodata value.
    transform : 6 floats, optional
        GDAL affine ``(a, b, c, d, e, f)``: x = a col + b row + c, y = d col + e row + f
        (pixel corner coordinates); default :func:`pixel_transform`.
    crs : str or None
        WKT (or any string rasterio's ``CRS.from_user_input`` reads); None writes no CRS.
    name : str
        The band's description.
    tags : dict, optional
        Extra metadata (strings) stored as GDAL tags.
    """
    import rasterio
    from rasterio.crs import CRS

    a = np.asarray(grid, np.float32)
    if a.ndim != 2:
        raise ValueError(f"a GeoTIFF band must be 2-D (rows, cols), got shape {a.shape}")
    if transform is None:
        transform = pixel_transform(a.shape[0])
    profile = float32_profile(a.shape, count=1, transform=transform)
    if crs is not None:
        profile["crs"] = CRS.from_user_input(crs)

    def write(tmp) -> None:
        with rasterio.open(tmp, "w", **profile) as dst:
            dst.write(a, 1)
            dst.set_band_description(1, name)
            dst.units = ("m",)
            if tags:
                dst.update_tags(**{k: str(v) for k, v in tags.items()})

    return atomic_write(path, write)


def read_geotiff(path) -> tuple[np.ndarray, tuple, str | None, str]:
    """Read a single-band GeoTIFF: ``(grid float32, transform (6 floats), crs WKT or None,
    band description)``."""
    import rasterio

    with rasterio.open(path) as src:
        grid = src.read(1)
        t = src.transform
        crs = src.crs.to_wkt() if src.crs else None
        return grid, (t.a, t.b, t.c, t.d, t.e, t.f), crs, src.descriptions[0] or ""


def write_array_export(folder, payload: dict[str, Any], *, unit_key: str | None = None) -> Path:
    """Write an array export (module docstring) into ``folder`` (created).

    Parameters
    ----------
    folder : path
        E.g. ``<result folder>/arrays/unit0``.
    payload : dict
        From :func:`array_export_payload`.
    unit_key : str, optional
        The cache key of the unit, recorded in ``manifest.json`` (written last): the runner
        keeps a folder only while its unit is part of the result folder.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    q, transform, crs = payload["quantity"], payload["transform"], payload["crs"]
    truth = np.asarray(payload["truth"], np.float64)
    geo = {"transform": list(transform), "crs": crs or "", "units": "m"}
    files: list[dict] = []
    used: set[str] = set()

    def unique(stem: str) -> str:
        # labels that differ only where _safe changes them ("a b", "a-b") would share a file
        # name: the later one gets "+2", "+3", ... (its labels in the manifest say which)
        out, n = stem, 1
        while out in used:
            n += 1
            out = f"{stem}+{n}"
        used.add(out)
        return out

    def pair(stem: str, name: str, grid, labels: dict) -> None:
        tif, exr = f"{stem}.tif", f"{stem}.exr"
        write_geotiff(folder / tif, grid, transform=transform, crs=crs, name=name, tags=labels)
        write_exr(folder / exr, {name: np.asarray(grid, np.float32)}, attrs={**geo, **labels})
        files.append({"tif": tif, "exr": exr, "channel": name, **labels})

    pair(f"truth_{q}", q, truth, {"what": f"true {q}"})
    for it in payload["items"]:
        stem = "_".join(
            (_safe(it["planner"]), density_tag(it["density"]), _safe(it["reconstruction"]))
        )
        stem = unique(stem)
        labels = {k: it[k] for k in ("planner", "density", "k", "reconstruction", "trial")}
        grid = np.asarray(it["grid"], np.float64)
        pair(f"{stem}_{q}", q, grid, {"what": f"reconstructed {q}", **labels})
        pair(
            f"{stem}_error", "error", grid - truth, {"what": f"reconstructed - true {q}", **labels}
        )
    manifest = {
        "kind": "arrays",
        "quantity": q,
        "units": "m",
        "transform": list(transform),
        "transform_order": "GDAL (a, b, c, d, e, f): x = a col + b row + c, y = d col + e row + f",
        "crs": crs,
        "error": f"reconstruction - truth ({q})",
        "files": files,
    }
    if unit_key is not None:
        manifest["unit_key"] = unit_key
    text = json.dumps(manifest, indent=2) + "\n"
    atomic_write(folder / "manifest.json", lambda tmp: Path(tmp).write_text(text))
    return folder


def array_export_complete(folder, unit_key: str) -> bool:
    """Whether ``folder`` holds the whole array export of the unit ``unit_key``: its manifest
    names the unit and every file it lists is there."""
    folder = Path(folder)
    try:
        manifest = json.loads((folder / "manifest.json").read_text())
        files = manifest["files"]
        if manifest.get("unit_key") != unit_key or not isinstance(files, list):
            return False
        names = [f[k] for f in files for k in ("tif", "exr")]
    except (OSError, ValueError, KeyError, TypeError):
        return False
    return all(isinstance(n, str) and (folder / n).is_file() for n in names)


def check_save_arrays(cfg) -> None:
    """Refuse ``simlunar run --save-arrays`` for a study that keeps no reconstruction grid.

    Raises
    ------
    ConfigError
        The experiment's study is not one of :data:`ARRAY_EXPORT_KINDS`.
    """
    kind = getattr(cfg.study, "kind", None)
    if kind not in ARRAY_EXPORT_KINDS:
        raise ConfigError(
            f"--save-arrays: experiment {cfg.name!r} has a {kind} study; reconstructions are "
            f"exported by {' and '.join(ARRAY_EXPORT_KINDS)} studies only"
        )
