"""Size limits of a run: the most cells, frame pixels and work units it may allocate, with
environment overrides, and the header-only shape check of DEM / albedo grid files (split
from :mod:`simlunar.pipeline.inputs`, which re-exports these names)."""

from __future__ import annotations

import math
import os
import zipfile
from pathlib import Path

from simlunar.errors import ConfigError
from simlunar.terrain.io import GDAL_FORMATS

__all__ = [
    "LIMIT_SETTINGS",
    "MAX_CELLS",
    "MAX_FRAME_PIXELS",
    "MAX_UNITS",
    "check_size",
    "grid_file_shape",
    "size_limit",
]


#: most cells of one grid a run may allocate: terrain cells (a DEM, a preset with its grid
#: overrides), image, projector and camera pixels. A render costs some hundred bytes per
#: terrain cell (mesh, acceleration structure, ground truth), so 25 million cells is several
#: GB. Raise it on a machine with the memory: ``SIMLUNAR_MAX_CELLS=1e9``.
MAX_CELLS = 25_000_000


#: most pixels of the frames held at once (frames per render call x (projector + camera
#: pixels)); 5e8 float32 values are 2 GB. ``SIMLUNAR_MAX_FRAME_PIXELS`` raises it.
MAX_FRAME_PIXELS = 500_000_000


#: most work units of one experiment (the product of its sweep axes' lengths times its
#: terrain seeds): every unit is rendered and stored, and the sweep is expanded (and every
#: point checked) before anything runs. ``SIMLUNAR_MAX_UNITS`` raises it.
MAX_UNITS = 10_000


#: environment settings that override the limits above
LIMIT_SETTINGS = {
    "SIMLUNAR_MAX_CELLS": MAX_CELLS,
    "SIMLUNAR_MAX_FRAME_PIXELS": MAX_FRAME_PIXELS,
    "SIMLUNAR_MAX_UNITS": MAX_UNITS,
}


def size_limit(setting: str) -> int:
    """The limit named by ``setting`` (an environment variable of :data:`LIMIT_SETTINGS`)."""
    raw = os.environ.get(setting, "").strip()
    if not raw:
        return LIMIT_SETTINGS[setting]
    try:
        value = float(raw)
    except ValueError:
        value = float("nan")
    if not (math.isfinite(value) and value >= 1):
        raise ConfigError(f"{setting}={raw}: expected a positive count such as 1e9")
    return int(value)


def check_size(key: str, what: str, n: float, setting: str = "SIMLUNAR_MAX_CELLS") -> None:
    """Refuse ``n`` (cells, pixels) above the limit, in one line naming ``key`` and the size."""
    limit = size_limit(setting)
    if n > limit:
        raise ConfigError(
            f"{key}: {what} = {n:.3g}, more than the limit of {limit:.3g} "
            f"(set {setting} to raise it on a machine with the memory)"
        )


def grid_file_shape(path: Path, key: str) -> tuple[int, ...] | None:
    """The shape of the grid in a DEM / albedo file, read from its header without reading
    the data, and checked against :data:`MAX_CELLS` (None: a header not read here; the
    reader reports an unreadable file). A ``.npy`` / ``.npz`` whose header promises more
    bytes than the file holds is refused (``np.load`` would allocate the promised array
    before finding out)."""

    suf = path.suffix.lower()
    try:
        if suf == ".npy":
            with open(path, "rb") as f:
                shape, nbytes = _npy_header(f)
                have = path.stat().st_size - f.tell()
            _check_npy_bytes(key, path, shape, nbytes, have)
            return shape
        if suf == ".npz":
            with zipfile.ZipFile(path) as z:
                if "heights.npy" not in z.namelist():
                    return None  # the reader names what is missing
                info = z.getinfo("heights.npy")
                with z.open("heights.npy") as f:
                    shape, nbytes = _npy_header(f)
                    have = info.file_size - f.tell()
            _check_npy_bytes(key, f"{path} (heights)", shape, nbytes, have)
            return shape
        if suf == ".exr":
            import OpenEXR

            with OpenEXR.File(str(path), header_only=True) as f:
                (x0, y0), (x1, y1) = (tuple(v) for v in f.header()["dataWindow"])
            shape = (int(y1) - int(y0) + 1, int(x1) - int(x0) + 1)
        elif suf in (".tif", ".tiff", *GDAL_FORMATS):
            import rasterio

            with rasterio.open(path) as src:
                shape = (int(src.height), int(src.width))
        else:
            return None
    except ConfigError:
        raise
    except Exception:
        return None
    check_size(key, f"{path}: a {shape[0]} x {shape[1]} grid", shape[0] * shape[1])
    return shape


def _npy_header(f) -> tuple[tuple[int, ...], int]:
    from numpy.lib import format as npf

    version = npf.read_magic(f)
    read = {(1, 0): npf.read_array_header_1_0, (2, 0): npf.read_array_header_2_0}.get(version)
    if read is None:
        raise ValueError(f"unsupported .npy version {version}")
    shape, _fortran, dtype = read(f)
    n = 1
    for v in shape:
        n *= int(v)
    return tuple(int(v) for v in shape), n * dtype.itemsize


def _check_npy_bytes(key: str, path, shape, nbytes: int, have: int) -> None:
    cells = 1
    for v in shape:
        cells *= v
    check_size(key, f"{path}: a {' x '.join(map(str, shape)) or 'scalar'} array", cells)
    if nbytes > have:
        raise ConfigError(
            f"{key}: {path}: its header promises a {' x '.join(map(str, shape))} array "
            f"({nbytes} bytes) but the file holds {have} bytes (truncated or not a DEM)"
        )
