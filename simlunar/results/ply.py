"""Binary little-endian PLY writing shared by the scan exports (structured light and LIDAR).

The format is Paul Bourke's / Greg Turk's PLY ("PLY - Polygon File Format", ascii header,
``format binary_little_endian 1.0``, one ``element vertex N`` with ``property TYPE NAME`` lines in
record order, ``end_header`` then the packed records).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from simlunar.atomic import atomic_write

__all__ = ["XYZ_FIELDS", "ply_records", "write_ply"]

XYZ_FIELDS = (("x", "<f8", "double"), ("y", "<f8", "double"), ("z", "<f8", "double"))
"""The position fields every cloud starts with: world ``x y z`` in metres, doubles."""


def ply_records(n: int, fields) -> np.ndarray:
    """An empty structured array of ``n`` vertices with ``fields``' names and dtypes.

    Parameters
    ----------
    n : int
        Number of vertices.
    fields : sequence of (name, numpy dtype string, PLY type)
        E.g. ``("x", "<f8", "double")``; the dtypes must be little-endian.
    """
    return np.empty(int(n), dtype=[(name, dt) for name, dt, _ in fields])


def write_ply(path, rec: np.ndarray, *, fields, comment: str) -> Path:
    """Write ``rec`` (from :func:`ply_records`) as a binary little-endian PLY, atomically.

    Parameters
    ----------
    path : path-like
    rec : structured ndarray, shape (n,)
        One record per vertex, fields in ``fields``' order.
    fields : sequence of (name, numpy dtype string, PLY type)
        The same as given to :func:`ply_records`.
    comment : str
        One ``comment`` header line (ascii, no newline).

    Returns
    -------
    Path
        ``path``.
    """
    if "\n" in comment:
        raise ValueError("a PLY comment must be one line")
    if [n for n, _, _ in fields] != list(rec.dtype.names or ()):
        raise ValueError(f"records have fields {rec.dtype.names}, not {[n for n, _, _ in fields]}")
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"comment {comment}\n"
        f"element vertex {len(rec)}\n"
        + "".join(f"property {ply} {name}\n" for name, _, ply in fields)
        + "end_header\n"
    )
    blob = header.encode("ascii") + rec.tobytes()
    return atomic_write(path, lambda tmp: Path(tmp).write_bytes(blob))
