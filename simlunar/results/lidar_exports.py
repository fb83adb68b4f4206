"""LIDAR scan export: point clouds (LAS / LAZ, PLY) and range images (EXR) of a LIDAR study.

``simlunar run --save-scans`` (``study.save_scans: true``) on a ``lidar`` study writes, per
unit, ``scans/unit<i>/`` with one set of files per planner label of the unit's example
acquisitions (trial 0 at the largest density; the label ``none`` for a flash without a plan)::

    <label>.laz          the measured points, LAS 1.4 point format 6, LAZ-compressed (laspy)
    <label>.ply          the same points, binary little-endian PLY
    <label>_range.exr    guide-view images: slant range, z-depth, photons (NaN: not measured)
    manifest.json        files, frame, units, the unit's key (written last)

**Frame**: simlunar's world frame (right-handed, z up, metres; +x along the terrain's columns,
+y against its rows, ``Terrain.origin`` the top-left corner's (x, y)). The terrain's ``crs``
(WKT), when it has one, is written as the LAS 1.4 OGC WKT record (and the header's WKT bit);
without one the frame is local and no CRS is written.

Per point (LAS):

- ``intensity`` = estimated signal photons of the reported return times the file's
  ``intensity_scale``: 1 when the largest is at most 65535, else 65535 / the largest, so no
  point is clipped and the brightest is 65535 (a linear APD's returns hold up to millions of
  photoelectrons). The scale is in the extra-bytes description of ``photons``, in a text VLR
  (``simlunar`` / 1, ``intensity_scale=<value>``) and in manifest.json; the exact photons are
  the extra dimension ``photons``.
- ``time_from_start`` (extra dimension, seconds) = when the point was measured, from the
  acquisition's start (a steered beam's first pulse at that pointing, a flash frame's start).
  No absolute time is known, so ``gps_time`` is 0 (the header's GPS-time bit: GPS week time).
- ``scan_angle`` = the beam's angle off nadir (0.006 deg units), signed as its x component;
  ``origin_x``, ``origin_y``, ``origin_z`` (extra dimensions, m) = the sensor's position the
  beam left from (the guide camera's centre: the sensor at rest, or a moving platform's start).
- ``return_number`` 1 and ``number_of_returns`` = returns detected in the histogram (clipped to
  7; the reported one is ``RangeOptions.which``).

The PLY holds ``time`` (seconds from the start) and the exact ``photons``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from simlunar.atomic import atomic_write
from simlunar.imaging.exr import write_exr
from simlunar.results.ply import XYZ_FIELDS, ply_records, write_ply

__all__ = [
    "INTENSITY_MAX",
    "intensity_scale",
    "lidar_export_payload",
    "lidar_files",
    "scan_angles_deg",
    "write_las",
    "write_lidar_export",
    "write_lidar_ply",
]

_PLY = (
    *XYZ_FIELDS,
    ("time", "<f8", "double"),
    ("photons", "<f4", "float"),
    ("returns", "u1", "uchar"),
)


#: the largest LAS intensity (uint16)
INTENSITY_MAX = 65535


def intensity_scale(photons) -> float:
    """The factor from photons to LAS ``intensity`` (module docstring): 1 when the largest
    is at most :data:`INTENSITY_MAX`, else ``INTENSITY_MAX / largest`` (none clipped)."""
    ph = np.asarray(photons, float)
    top = float(np.nanmax(ph)) if ph.size and np.isfinite(ph).any() else 0.0
    return 1.0 if top <= INTENSITY_MAX else INTENSITY_MAX / top


def scan_angles_deg(points, origins) -> np.ndarray:
    """Each beam's angle off nadir (deg), signed as its x component, from ``origins`` (n, 3)
    or (3,) to ``points`` (n, 3)."""
    d = np.asarray(points, float).reshape(-1, 3) - np.asarray(origins, float)
    off = np.degrees(np.arctan2(np.hypot(d[:, 0], d[:, 1]), -d[:, 2]))
    return np.where(d[:, 0] < 0, -off, off)


def write_las(path, points, *, times, photons, returns, origins=None, crs: str | None = None,
              scale: float = 1e-4) -> Path:  # fmt: skip
    """Write points as LAS 1.4 (point format 6); LAZ-compressed when ``path`` ends in .laz.

    Parameters
    ----------
    points : (n, 3) float
        World points (m).
    times : (n,) float
        Seconds from the acquisition's start (the extra dimension ``time_from_start``).
    photons : (n,) float
        Signal photons (``intensity`` scaled by :func:`intensity_scale`; exact in the extra
        dimension ``photons``).
    returns : (n,) int
        Returns detected (``number_of_returns``, clipped to 1-7).
    origins : (n, 3) or (3,) float, optional
        The sensor's position each beam left from (``scan_angle``, ``origin_x/y/z``); None:
        scan angle 0 and no origin dimensions.
    crs : str, optional
        The terrain's CRS as WKT (the OGC WKT record); None: a local frame, none written.
    scale : float
        Coordinate resolution (m).
    """
    import laspy
    from laspy.vlrs.known import WktCoordinateSystemVlr

    p = np.asarray(points, float).reshape(-1, 3)
    ph = np.asarray(photons, float)
    k = intensity_scale(ph)
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales = np.array([scale] * 3)
    header.offsets = np.floor(p.min(axis=0)) if len(p) else np.zeros(3)
    header.add_extra_dim(laspy.ExtraBytesParams(
        name="photons", type=np.float64, description=f"intensity=photons*{k:.6g}"
    ))  # fmt: skip
    header.add_extra_dim(laspy.ExtraBytesParams(
        name="time_from_start", type=np.float64, description="s from acquisition start"
    ))  # fmt: skip
    if origins is not None:
        for axis in "xyz":
            header.add_extra_dim(laspy.ExtraBytesParams(
                name=f"origin_{axis}", type=np.float64, description=f"sensor {axis} (m)"
            ))  # fmt: skip
    header.vlrs.append(
        laspy.VLR("simlunar", 1, "intensity scale", f"intensity_scale={k!r}".encode())
    )
    if crs:
        header.vlrs.append(WktCoordinateSystemVlr(crs))
        header.global_encoding.wkt = True
    las = laspy.LasData(header)
    las.x, las.y, las.z = p[:, 0], p[:, 1], p[:, 2]
    las.gps_time = np.zeros(len(p))  # no absolute time: see time_from_start
    las.time_from_start = np.asarray(times, float)
    las.intensity = np.clip(np.round(ph * k), 0, INTENSITY_MAX).astype(np.uint16)
    las.return_number = np.ones(len(p), np.uint8)
    las.number_of_returns = np.clip(np.asarray(returns), 1, 7).astype(np.uint8)
    las.photons = ph
    if origins is not None:
        o = np.broadcast_to(np.asarray(origins, float), p.shape)
        las.scan_angle = np.round(scan_angles_deg(p, o) / 0.006).astype(np.int16)
        las.origin_x, las.origin_y, las.origin_z = o[:, 0], o[:, 1], o[:, 2]
    path = Path(path)
    return atomic_write(path, lambda tmp: las.write(str(tmp), do_compress=path.suffix == ".laz"))


def write_lidar_ply(path, points, *, times, photons, returns) -> Path:
    """Binary little-endian PLY: ``x y z time`` (double, m / s), ``photons`` (float),
    ``returns`` (uchar)."""
    p = np.asarray(points, float).reshape(-1, 3)
    rec = ply_records(len(p), _PLY)
    rec["x"], rec["y"], rec["z"] = p.T
    rec["time"], rec["photons"] = times, photons
    rec["returns"] = np.clip(np.asarray(returns), 0, 255)
    comment = "simlunar LIDAR scan: world frame (z up), metres; time s from the start"
    return write_ply(path, rec, fields=_PLY, comment=comment)


def lidar_export_payload(examples: dict, camera, shape, crs: str | None = None) -> dict[str, Any]:
    """What :func:`write_lidar_export` writes, from a LIDAR study's example acquisitions.

    Parameters
    ----------
    examples : dict label -> Acquisition
        Their ``detail`` is the :class:`~simlunar.lidar.returns.LidarScan`.
    camera : geometry.Camera
        The guide camera (the sensor's origin; the range images' grid).
    shape : (rows, cols)
        The guide view.
    crs : str, optional
        The terrain's CRS (WKT), written into the LAS; None: a local frame.
    """
    out = {}
    for label, acq in examples.items():
        scan = acq.detail
        valid = np.asarray(scan.valid).ravel()
        n = valid.size
        pts = scan.points.reshape(-1, 3)[valid]
        times = np.zeros(n) if scan.times is None else np.asarray(scan.times, float).ravel()
        rets = np.ones(n, int) if scan.returns is None else np.asarray(scan.returns).ravel()
        photons = np.asarray(scan.photons, float).ravel()
        images = {k: np.full(shape, np.nan, np.float32) for k in ("range", "depth", "photons")}
        rc = np.round(np.asarray(acq.rc, float)).astype(int)
        inside = (rc[:, 0] >= 0) & (rc[:, 0] < shape[0]) & (rc[:, 1] >= 0) & (rc[:, 1] < shape[1])
        rr, cc = rc[inside, 0], rc[inside, 1]
        slant = np.linalg.norm(pts - camera.pose.position, axis=1)
        images["range"][rr, cc] = slant[inside]
        images["depth"][rr, cc] = np.asarray(acq.values, float)[inside]
        images["photons"][rr, cc] = photons[valid][inside]
        out[str(label)] = {
            "points": pts,
            "times": times[valid],
            "photons": photons[valid],
            "returns": rets[valid],
            "images": images,
            "seconds": float(acq.seconds),
            "origin": np.asarray(camera.pose.position, float),
        }
    return {"kind": "lidar", "labels": out, "crs": crs}


def lidar_files(labels) -> list[str]:
    """The files an export of these planner labels holds (manifest.json last)."""
    files = []
    for label in labels:
        files += [f"{label}.laz", f"{label}.ply", f"{label}_range.exr"]
    return [*files, "manifest.json"]


def write_lidar_export(folder, payload: dict, *, unit_key: str | None = None) -> Path:
    """Write a LIDAR scan export (module docstring) into ``folder`` (created)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    labels = payload["labels"]
    for label, d in labels.items():
        kw = {"times": d["times"], "photons": d["photons"], "returns": d["returns"]}
        write_las(folder / f"{label}.laz", d["points"], **kw, origins=d.get("origin"),
                  crs=payload.get("crs"))  # fmt: skip
        write_lidar_ply(folder / f"{label}.ply", d["points"], **kw)
        write_exr(
            folder / f"{label}_range.exr",
            d["images"],
            attrs={"units": "range, depth: m; photons", "missing": "NaN"},
        )
    manifest = {
        "kind": "lidar",
        "files": lidar_files(labels),
        "frame": "simlunar world frame: right-handed, z up, metres (local unless the terrain "
        "has a crs)",
        "time": "seconds from the acquisition's start (LAS: time_from_start; gps_time 0)",
        "intensity_scale": {label: intensity_scale(d["photons"]) for label, d in labels.items()},
        "crs": payload.get("crs"),
        "points": {label: len(d["points"]) for label, d in labels.items()},
        "seconds": {label: d["seconds"] for label, d in labels.items()},
        "unit_key": unit_key,
    }
    text = json.dumps(manifest, indent=2)
    atomic_write(folder / "manifest.json", lambda tmp: Path(tmp).write_text(text))
    return folder
