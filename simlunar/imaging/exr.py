"""Float32 OpenEXR read/write (OpenEXR 3.x Python API, ``OpenEXR.File``).

Files are written atomically (a temporary file in the target folder, then ``os.replace``) so a
reader never sees a half-written image. Metadata such as the grid spacing travels in the header:
user attributes are stored as one JSON string attribute (``simlunar_attrs``) so that Python
floats round-trip exactly (native EXR float attributes are only 32-bit).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from simlunar.atomic import atomic_write

__all__ = ["read_exr", "write_exr"]

_ATTR_KEY = "simlunar_attrs"
# standard EXR header entries: structure, not user metadata
_STANDARD = {
    "channels",
    "compression",
    "dataWindow",
    "displayWindow",
    "lineOrder",
    "pixelAspectRatio",
    "screenWindowCenter",
    "screenWindowWidth",
    "type",
    "name",
    "version",
    "chunkCount",
    "tiles",
}


def _as_channels(channels) -> dict[str, np.ndarray]:
    if isinstance(channels, dict):
        if not channels:
            raise ValueError("write_exr needs at least one channel")
        out = {}
        for name, arr in channels.items():
            if not isinstance(name, str) or not name:
                raise ValueError(f"EXR channel names must be non-empty strings, got {name!r}")
            a = np.asarray(arr)
            if a.ndim != 2:
                raise ValueError(
                    f"EXR channel {name!r} must be 2-D (rows, cols), got shape {a.shape}"
                )
            out[name] = a
    else:
        a = np.asarray(channels)
        if a.ndim == 2:
            out = {"Y": a}
        elif a.ndim == 3 and a.shape[2] in (3, 4):
            out = {n: a[..., i] for i, n in enumerate("RGBA"[: a.shape[2]])}
        else:
            raise ValueError(
                f"an EXR image array must be (rows, cols) or (rows, cols, 3|4), got shape {a.shape}"
            )
    shapes = {a.shape for a in out.values()}
    if len(shapes) != 1:
        raise ValueError(f"EXR channels must all have the same shape, got {sorted(shapes)}")
    if 0 in next(iter(shapes)):
        raise ValueError(f"EXR channels must not be empty, got shape {next(iter(shapes))}")
    return {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in out.items()}


def write_exr(path, channels, *, attrs: dict | None = None) -> Path:
    """Write float32 channels to an OpenEXR file, atomically.

    Parameters
    ----------
    path : str or Path
        Target file (``.exr``). Its folder must exist.
    channels : dict[str, (rows, cols) array] or (rows, cols) / (rows, cols, 3|4) array
        Named channels, converted to float32. A 2-D array becomes channel ``Y``; an
        (H, W, 3) array becomes ``R``, ``G``, ``B`` (and ``A`` for a 4th plane).
    attrs : dict, optional
        JSON-serialisable metadata (e.g. ``{"spacing": 0.2}``) stored in the header and returned by
        ``read_exr(path, with_attrs=True)`` unchanged (floats exactly).

    Returns
    -------
    Path
        The written path.
    """
    import OpenEXR

    path = Path(path)
    chans = _as_channels(channels)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    if attrs:
        try:
            header[_ATTR_KEY] = json.dumps(attrs, allow_nan=True)
        except TypeError as exc:
            raise ValueError(f"EXR attrs for {path} must be JSON-serialisable: {exc}") from None

    def write(tmp: str) -> None:
        with OpenEXR.File(header, chans) as f:
            f.write(tmp)
        # OpenEXR loses a failed last flush (a small file on a full disk): read the header
        # back, so such a file is an error here (atomic_write tells a full disk by its space)
        try:
            with OpenEXR.File(tmp, header_only=True):
                pass
        except Exception as exc:
            raise RuntimeError(f"{path}: the EXR written is unreadable ({exc})") from None

    atomic_write(path, write)
    return path


def read_exr(path, *, with_attrs: bool = False):
    """Read every channel of an OpenEXR file as float32 arrays.

    Parameters
    ----------
    path : str or Path
        An EXR file.
    with_attrs : bool
        Also return the metadata dict written by :func:`write_exr` (plus any plain str / int /
        float header attributes of foreign files).

    Returns
    -------
    dict[str, (rows, cols) float32 array] or (dict, dict)
        Channels by name (``R``, ``G``, ``B`` for an RGB image), and the attrs if requested.

    Raises
    ------
    FileNotFoundError
        If the file does not exist (message names it).
    ValueError
        If the file is not a readable EXR image (message names it).
    """
    import OpenEXR

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"EXR file not found: {path}")
    try:
        with OpenEXR.File(str(path), separate_channels=True) as f:
            chans = {
                name: np.array(ch.pixels, dtype=np.float32, copy=True)
                for name, ch in f.channels().items()
            }
            header = dict(f.header())
    except (RuntimeError, OSError, ValueError) as exc:
        raise ValueError(f"cannot read EXR file {path}: {exc}") from None
    if not chans:
        raise ValueError(f"EXR file {path} has no channels")
    if not with_attrs:
        return chans
    attrs: dict = {}
    for k, v in header.items():
        if (
            k not in _STANDARD
            and k != _ATTR_KEY
            and isinstance(v, (str, int, float))
            and not isinstance(v, bool)
        ):
            attrs.setdefault(k, v)
    if _ATTR_KEY in header:
        try:
            attrs.update(json.loads(header[_ATTR_KEY]))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"EXR file {path} has a corrupt {_ATTR_KEY} header: {exc}") from None
    return chans, attrs
