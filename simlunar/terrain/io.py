"""DEM + albedo files (.npy, .npz, .exr, .tif), mesh export (PLY/OBJ) and hillshade previews.

On disk heights and albedo are float32 (a float64 terrain is rounded once; a float32 terrain
round-trips bit-identically). Nodata is NaN in every format. Spacing and origin travel with the
data: inside the file for .npz (arrays), .exr (header) and .tif (JSON image description); in a
sidecar ``<file>.json`` for .npy. A foreign single-band DEM (2-D .npy or TIFF without our
metadata) loads as heights with a uniform albedo; pass ``spacing=`` (and ``origin=``, and
``nodata=`` for a sentinel value such as -9999).

Layouts: .npy holds a (2, rows, cols) float32 stack [heights, albedo]; .npz holds ``heights``,
``albedo``, ``spacing``, ``origin``; .exr has channels ``Z`` (heights) and ``albedo``; .tif holds
a (2, rows, cols) float32 stack.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from simlunar.atomic import atomic_write
from simlunar.terrain.mesh import grid_faces, grid_vertices
from simlunar.terrain.types import Terrain

FORMATS = (".npy", ".npz", ".exr", ".tif", ".tiff")
#: albedo given to a foreign DEM that has none (lunar soil mean)
DEFAULT_ALBEDO = 0.12


def _suffix(path: Path) -> str:
    suf = path.suffix.lower()
    if suf not in FORMATS:
        raise ValueError(
            f"unsupported DEM format {suf or '(none)'!r} for {path}; valid: {', '.join(FORMATS)}"
        )
    return suf


def _meta(terrain: Terrain) -> dict:
    return {"spacing": terrain.spacing, "origin": list(terrain.origin), "format": "simlunar-dem-1"}


def save_dem(path, terrain: Terrain) -> Path:
    """Write heights and albedo (float32) with spacing and origin; format from the suffix.

    Parameters
    ----------
    path : str or Path
        ``.npy`` (+ sidecar ``.json``), ``.npz``, ``.exr``, ``.tif`` or ``.tiff``.
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
        atomic_write(
            path,
            lambda t: np.savez_compressed(
                t,
                heights=h,
                albedo=a,
                spacing=np.float64(terrain.spacing),
                origin=np.array(terrain.origin, dtype=np.float64),
            ),
        )
    elif suf == ".exr":
        from simlunar.imaging.exr import write_exr

        write_exr(path, {"Z": h, "albedo": a}, attrs=meta)
    else:
        import tifffile

        atomic_write(
            path,
            lambda t: tifffile.imwrite(
                t,
                np.stack([h, a]),
                photometric="minisblack",
                metadata={"simlunar": json.dumps(meta)},
            ),
        )
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


def load_dem(
    path, *, spacing: float | None = None, origin=None, nodata: float | None = None
) -> Terrain:
    """Read a DEM written by :func:`save_dem`, or a foreign single-band DEM.

    Parameters
    ----------
    path : str or Path
    spacing : float, optional
        Cell size in metres; overrides the file's, required when the file carries none.
    origin : (x, y), optional
        World position of the top-left corner; default the file's or (0, 0).
    nodata : float, optional
        Sentinel height value to turn into NaN (foreign DEMs).

    Returns
    -------
    Terrain

    Raises
    ------
    FileNotFoundError
        Missing file (named).
    ValueError
        Unreadable file, wrong shape or dtype, missing spacing (message names the file).
    """
    path = Path(path)
    suf = _suffix(path)
    if not path.is_file():
        raise FileNotFoundError(f"DEM file not found: {path}")
    meta: dict = {}
    albedo = None
    try:
        if suf == ".npy":
            arr = _check_array(np.load(path, allow_pickle=False), path, "the array")
            heights, albedo = _split(arr, path)
            side = path.with_name(path.name + ".json")
            if side.is_file():
                meta = json.loads(side.read_text())
        elif suf == ".npz":
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
        elif suf == ".exr":
            from simlunar.imaging.exr import read_exr

            chans, meta = read_exr(path, with_attrs=True)
            if "Z" in chans:
                heights = chans["Z"]
            elif "Y" in chans:
                heights = chans["Y"]
            else:
                raise ValueError(f"{path}: no 'Z' (or 'Y') height channel (found {sorted(chans)})")
            albedo = chans.get("albedo")
        else:
            import tifffile

            with tifffile.TiffFile(path) as tf:
                arr = _check_array(tf.asarray(), path, "the image")
                desc = tf.pages[0].description if len(tf.pages) else ""
            heights, albedo = _split(np.squeeze(arr) if arr.ndim > 3 else arr, path)
            try:
                d = json.loads(desc) if desc else {}
                meta = json.loads(d["simlunar"]) if isinstance(d, dict) and "simlunar" in d else {}
            except (ValueError, TypeError):
                meta = {}
    except (ValueError, OSError, KeyError, EOFError) as exc:
        msg = str(exc)
        raise ValueError(msg if str(path) in msg else f"cannot read DEM {path}: {msg}") from None
    if heights.ndim != 2:
        raise ValueError(f"{path}: heights must be 2-D, got shape {heights.shape}")
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
    try:
        return Terrain(h, albedo.astype(np.float32), float(sp), tuple(org))
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None


def export_mesh(terrain: Terrain, path) -> Path:
    """Export the grid mesh (one vertex per cell, as ``terrain.mesh``) as PLY or OBJ.

    Vertex colour is the albedo as 8-bit grey (``round(255 * albedo)``). Triangles touching
    nodata cells are dropped; their vertices stay (NaN) so vertex ``r * cols + c`` is cell (r, c).
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
    colors = np.stack([g, g, g, np.full_like(g, 255)], axis=1)
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
    from simlunar.imaging.png import write_png_preview

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
    from simlunar.imaging.png import write_png_preview

    files = {"dem": save_dem(out / f"dem.{fmt}", result.terrain)}
    files["albedo"] = write_png_preview(out / "albedo.png", result.terrain.albedo, exposure=1.0)
    files["hillshade"] = hillshade_png(result.terrain, out / "hillshade.png")
    if mesh_format is not None:
        files["mesh"] = export_mesh(result.terrain, out / f"mesh.{mesh_format.lower().lstrip('.')}")
    blob = json.dumps(features_json(result), indent=1)
    atomic_write(out / "features.json", lambda t: Path(t).write_text(blob))
    files["features"] = out / "features.json"
    return files
