"""Scan export: what a full-field coded scan captured, in formats OpenCV pipelines read.

``study.save_scans: true`` (or ``simlunar run --save-scans``) writes, per unit, a folder
``scans/unit<i>/`` of the result folder with one folder per coding the study scanned
(``scans/unit<i>/<coding>/``) and a ``manifest.json`` naming them (written last)::

    frames8/NN_<name>.png    captured frames, 8-bit grey, in the coding's order
    frames16/NN_<name>.png   the same frames, 16-bit grey
    decode.exr               decoded projector maps: col, row, u, v, valid, lit (float32)
    phase.exr                fringe codings: the wrapped phase of every level
                             (<axis><level>_wrapped) and the absolute (unwrapped) phase of the
                             finest (<axis>_absolute), rad, float32
    cloud.ply                triangulated points (binary PLY, metres, world frame)
    calibration.yml          rig calibration in OpenCV's conventions (cv2.FileStorage)
    manifest.json            coding, frame list and order, thresholds, conventions

The frames, their names and order and the manifest's description of the coding come from the
scan's coding (:data:`simlunar.scanner.codings.CODINGS`). For the gray code the order is that
of ``cv2.structured_light.GrayCodePattern.generate()``: for each column
bit (most significant first) the pattern then its inverse, then the row bits the same way;
then the white frame and the black frame (``getImagesForShadowMasks`` order); for phase
shifting, per axis and level the N shifted frames (:mod:`simlunar.scanner.phase_shift`), then
white and black (OpenCV's ``SinusoidalPattern`` reads one level's frames). The frames are
the sensor model's output (noise, ADC) as the decoder used them; when the scan obtained the
inverse patterns by linearity of light transport (``bits + 2`` renders), the inverse frames are
those synthesised images, each with its own sensor noise draw.

Every exported pixel coordinate follows OpenCV's convention: pixel ``(col, row)`` has its
centre at integer ``(col, row)``. simlunar's own coordinates put it at ``(col + 0.5, row +
0.5)``; the export subtracts 0.5.

Two steps: :func:`scan_export_payload` (in the unit's process: small arrays and plain data,
picklable for any executor) and :func:`write_scan_export` (in the runner's process).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from simlunar.atomic import atomic_write
from simlunar.errors import ConfigError
from simlunar.imaging.exr import write_exr
from simlunar.results.lidar_exports import write_lidar_export
from simlunar.results.ply import XYZ_FIELDS, ply_records, write_ply
from simlunar.scanner.codings import CODINGS
from simlunar.scanner.gray_code import frame_names
from simlunar.scanner.triangulate import Correspondences, triangulate_plane, triangulate_rays
from simlunar.sensors.structured_light import DOT_MODES, MODES

__all__ = [
    "calibration_opencv",
    "check_save_scans",
    "export_unit_key",
    "frame_names",
    "quantize",
    "read_cloud_ply",
    "scan_export_payload",
    "scans_export_payload",
    "write_calibration_yaml",
    "write_cloud_ply",
    "write_scan_export",
]


def quantize(frames: np.ndarray, bits: int) -> np.ndarray:
    """Frames in [0, 1] of full scale to unsigned integers: ``round(clip(x, 0, 1) * (2**bits - 1))``.

    Parameters
    ----------
    frames : array of float
        Captured frames in sensor full-scale units (1 = the top of the ADC range).
    bits : 8 or 16

    Returns
    -------
    uint8 or uint16 array of the same shape
    """
    if bits not in (8, 16):
        raise ValueError(f"bits must be 8 or 16, got {bits}")
    top = (1 << bits) - 1
    dtype = np.uint8 if bits == 8 else np.uint16
    x = np.clip(np.asarray(frames, np.float64), 0.0, 1.0) * top
    return np.rint(x).astype(dtype)


def calibration_opencv(rig) -> dict[str, Any]:
    """The rig's calibration in OpenCV's conventions.

    Returns
    -------
    dict
        ``camera_matrix`` / ``projector_matrix`` (3x3 K, pixel centres at integers),
        ``camera_distortion`` / ``projector_distortion`` (1x5 zeros: simlunar's devices are
        ideal pinholes), ``camera_image_size`` / ``projector_image_size`` ([width, height]),
        ``R``, ``T`` (camera to projector: ``x_proj = R x_cam + T``, metres, as
        ``cv2.stereoCalibrate`` returns them with the camera as the first device),
        ``camera_R_world``, ``camera_t_world``, ``projector_R_world``, ``projector_t_world``
        (world to device: ``x_dev = R x_world + t``, as ``cv2.projectPoints`` takes them after
        ``cv2.Rodrigues``), ``baseline_m``, ``camera_aperture_radius_m`` and
        ``camera_focus_distance_m`` (thin lens; 0 and 0 for a pinhole).
    """
    cam, proj = rig.camera, rig.projector
    Rc, tc = cam.pose.extrinsics_opencv()
    Rp, tp = proj.pose.extrinsics_opencv()
    # x_proj = Rp x_w + tp, x_w = Rc^T (x_cam - tc)  =>  R = Rp Rc^T, T = tp - R tc
    R = Rp @ Rc.T
    T = tp - R @ tc
    ci, pi = cam.intrinsics, proj.intrinsics
    return {
        "camera_image_size": [int(ci.width), int(ci.height)],
        "camera_matrix": ci.to_opencv(),
        "camera_distortion": np.zeros((1, 5)),
        "projector_image_size": [int(pi.width), int(pi.height)],
        "projector_matrix": pi.to_opencv(),
        "projector_distortion": np.zeros((1, 5)),
        "R": R,
        "T": T.reshape(3, 1),
        "camera_R_world": Rc,
        "camera_t_world": tc.reshape(3, 1),
        "projector_R_world": Rp,
        "projector_t_world": tp.reshape(3, 1),
        "baseline_m": float(rig.baseline),
        "camera_aperture_radius_m": float(cam.aperture_radius),
        "camera_focus_distance_m": float(cam.focus_distance or 0.0),
    }


def _yaml_number(x: float) -> str:
    x = float(x)
    if not np.isfinite(x):
        raise ValueError(f"calibration value {x} is not finite")
    return repr(x)


def write_calibration_yaml(path, calib: dict[str, Any]) -> Path:
    """Write a calibration dict as a YAML file that ``cv2.FileStorage`` reads.

    2-D arrays become ``!!opencv-matrix`` nodes (``dt: d``), lists of ints sequences (as
    OpenCV writes a ``cv::Size``), floats scalars. Values keep full double precision.
    """
    lines = ["%YAML:1.0", "---"]
    for key, value in calib.items():
        if isinstance(value, np.ndarray):
            a = np.asarray(value, np.float64)
            if a.ndim != 2:
                raise ValueError(f"calibration entry {key!r} must be 2-D, got shape {a.shape}")
            data = ", ".join(_yaml_number(v) for v in a.ravel())
            lines += [
                f"{key}: !!opencv-matrix",
                f"   rows: {a.shape[0]}",
                f"   cols: {a.shape[1]}",
                "   dt: d",
                f"   data: [ {data} ]",
            ]
        elif isinstance(value, list | tuple):
            lines.append(f"{key}: [ {', '.join(str(int(v)) for v in value)} ]")
        else:
            lines.append(f"{key}: {_yaml_number(value)}")
    text = "\n".join(lines) + "\n"
    return atomic_write(path, lambda tmp: Path(tmp).write_text(text))


_PLY_FIELDS = [
    *XYZ_FIELDS,
    ("cam_col", "<i4", "int"),
    ("cam_row", "<i4", "int"),
    ("proj_u", "<f8", "double"),
    ("proj_v", "<f8", "double"),
]


def write_cloud_ply(path, points, cam_rc, proj_uv) -> Path:
    """Binary little-endian PLY of a triangulated cloud.

    Parameters
    ----------
    points : (n, 3) world positions (m)
    cam_rc : (n, 2) int camera pixel (row, col) each point was triangulated from
    proj_uv : (n, 2) projector coordinates, OpenCV convention (pixel centres at integers)

    Vertex properties: ``x y z`` (double, m), ``cam_col cam_row`` (int), ``proj_u proj_v``
    (double, NaN for a column-only match).
    """
    points = np.asarray(points, np.float64).reshape(-1, 3)
    cam_rc = np.asarray(cam_rc).reshape(-1, 2)
    proj_uv = np.asarray(proj_uv, np.float64).reshape(-1, 2)
    if not len(points) == len(cam_rc) == len(proj_uv):
        raise ValueError("points, cam_rc and proj_uv must have the same length")
    rec = ply_records(len(points), _PLY_FIELDS)
    rec["x"], rec["y"], rec["z"] = points.T
    rec["cam_row"], rec["cam_col"] = cam_rc.T
    rec["proj_u"], rec["proj_v"] = proj_uv.T
    comment = "simlunar gray-code scan: world frame, metres; pixel centres at integers"
    return write_ply(path, rec, fields=_PLY_FIELDS, comment=comment)


def read_cloud_ply(path) -> np.ndarray:
    """Read a cloud written by :func:`write_cloud_ply` as a structured array."""
    blob = Path(path).read_bytes()
    end = blob.find(b"end_header\n")
    if not blob.startswith(b"ply\n") or end < 0:
        raise ValueError(f"{path}: not a PLY file")
    header = blob[:end].decode("ascii").splitlines()
    n = next(int(h.split()[2]) for h in header if h.startswith("element vertex"))
    dtype = [(n_, t) for n_, t, _ in _PLY_FIELDS]
    return np.frombuffer(blob, dtype=dtype, count=n, offset=end + len(b"end_header\n"))


def scan_export_payload(scan, rig) -> dict[str, Any]:
    """Everything :func:`write_scan_export` writes, from a coded scan and its rig.

    Parameters
    ----------
    scan : :class:`simlunar.scanner.result.CodedScan`
        The scan (its captured frames, decode, cloud and coding); scanned with
        ``keep_frames=True`` (the streaming decoders keep no frame stack otherwise).
    rig : Rig
        The rig that scanned.

    Returns
    -------
    dict of arrays and plain data (picklable; no file is written)
    """
    coding = scan.coding
    if coding is None:
        raise ValueError("the scan names no coding (CodedScan.coding): nothing says its frames")
    dec = scan.decode
    fr = scan.frames
    if "images" not in fr:
        raise ValueError("the coded scan kept no frame stack: scan with keep_frames=True")
    frames = np.concatenate(
        [np.asarray(fr["images"]), np.asarray(fr["white"])[None], np.asarray(fr["black"])[None]]
    )
    names = coding.frame_names(dec.proj_shape)
    if len(frames) != len(names):
        raise ValueError(f"the coded scan has {len(names)} frames, got {len(frames)}")
    # per-pixel triangulation (the scan's cloud, with the camera pixel of every point)
    corr = Correspondences.from_gray(dec)
    if coding.method == "plane":
        pts = triangulate_plane(rig, corr.cam_uv, corr.proj_uv[:, 0])
    else:
        pts, _ = triangulate_rays(rig, corr.cam_uv, corr.proj_uv)
    keep = np.isfinite(pts).all(axis=-1)
    r, c = np.nonzero(dec.valid)
    uv = dec.proj_uv() - 0.5  # OpenCV convention
    valid = np.asarray(dec.valid)
    phase_maps = getattr(coding, "phase_maps", None)
    return {
        "phase": {} if phase_maps is None else phase_maps(np.asarray(fr["images"]), dec),
        "frame_names": names,
        "frames8": quantize(frames, 8),
        "frames16": quantize(frames, 16),
        "decode": {
            "col": np.where(valid, dec.col, -1).astype(np.float32),
            "row": np.where(valid, dec.row, -1).astype(np.float32),
            "u": uv[..., 0].astype(np.float32),
            "v": uv[..., 1].astype(np.float32),
            "valid": valid.astype(np.float32),
            "lit": np.asarray(dec.lit).astype(np.float32),
        },
        "cloud": {
            "points": pts[keep],
            "cam_rc": np.stack([r[keep], c[keep]], axis=-1).astype(np.int32),
            "proj_uv": corr.proj_uv[keep] - 0.5,
        },
        "calibration": calibration_opencv(rig),
        "meta": {
            "projector_size": [int(dec.proj_shape[1]), int(dec.proj_shape[0])],
            "camera_size": [int(valid.shape[1]), int(valid.shape[0])],
            **coding.export_meta(dec),
        },
        "coding": _coding_name(coding),
        "frame_order": coding.frame_order,
    }


def _coding_name(coding) -> str:
    """The registry name of a coding object: its class and its options' class (two codings
    may share a class, as the gray and binary codes do)."""
    return next(
        n
        for n, e in CODINGS.items()
        if isinstance(coding, e.target) and type(coding.options) is e.options
    )


def scans_export_payload(scans, rig) -> dict[str, Any]:
    """:func:`scan_export_payload` of every coded scan of a study (``scans``: coding name ->
    CodedScan), for :func:`write_scan_export` (one folder per coding)."""
    return {
        "kind": "codings",
        "codings": {name: scan_export_payload(scan, rig) for name, scan in scans.items()},
    }


def write_scan_export(folder, payload: dict[str, Any], *, unit_key: str | None = None) -> Path:
    """Write a scan export (module docstring) into ``folder`` (created).

    Parameters
    ----------
    folder : path
        E.g. ``<result folder>/scans/unit0``.
    payload : dict
        From :func:`scan_export_payload`.
    unit_key : str, optional
        The cache key of the unit that made the scan, recorded in ``manifest.json`` (written
        last): the runner keeps a folder only while its unit is part of the result folder.
    """
    if payload.get("kind") == "lidar":
        return write_lidar_export(folder, payload, unit_key=unit_key)
    if payload.get("kind") == "codings":
        folder = Path(folder)
        for name, one in payload["codings"].items():
            write_scan_export(folder / name, one)
        manifest = {"kind": "codings", "codings": list(payload["codings"])}
        if unit_key is not None:
            manifest["unit_key"] = unit_key
        text = json.dumps(manifest, indent=2) + "\n"
        atomic_write(folder / "manifest.json", lambda tmp: Path(tmp).write_text(text))
        return folder
    from PIL import Image

    folder = Path(folder)
    names = payload["frame_names"]
    width = len(str(len(names) - 1))
    files = []
    for sub, key in (("frames8", "frames8"), ("frames16", "frames16")):
        (folder / sub).mkdir(parents=True, exist_ok=True)
        for i, (name, frame) in enumerate(zip(names, payload[key])):
            path = folder / sub / f"{i:0{width}d}_{name}.png"
            img = Image.fromarray(np.ascontiguousarray(frame))
            atomic_write(path, lambda tmp, img=img: img.save(tmp, format="PNG"))
            if sub == "frames8":
                files.append(path.name)
    meta = payload["meta"]
    write_exr(
        folder / "decode.exr",
        payload["decode"],
        attrs={"convention": "OpenCV: pixel centres at integers", **meta},
    )
    if payload.get("phase"):
        write_exr(
            folder / "phase.exr",
            payload["phase"],
            attrs={"convention": "rad; absolute = 2 pi (u + offset) / period, u at col + 0.5"},
        )
    cl = payload["cloud"]
    write_cloud_ply(folder / "cloud.ply", cl["points"], cl["cam_rc"], cl["proj_uv"])
    write_calibration_yaml(folder / "calibration.yml", payload["calibration"])
    manifest = {
        **meta,
        "coding": payload.get("coding", ""),
        "frames": files,
        "frame_order": payload.get("frame_order", ""),
        "frame_units": "round(full scale * (2**bits - 1)) in frames8 (8 bit) and frames16 (16 bit)",
        "pixel_convention": "OpenCV: pixel (col, row) has its centre at integer (col, row)",
        "cloud_points": len(cl["points"]),
    }
    if unit_key is not None:
        manifest["unit_key"] = unit_key
    text = json.dumps(manifest, indent=2) + "\n"
    atomic_write(folder / "manifest.json", lambda tmp: Path(tmp).write_text(text))
    return folder


def export_unit_key(folder) -> str | None:
    """The unit key recorded in a scan export's ``manifest.json`` (None: no complete export,
    or one written before the key was recorded)."""
    try:
        key = json.loads((Path(folder) / "manifest.json").read_text()).get("unit_key")
    except (OSError, ValueError, AttributeError):
        return None
    return key if isinstance(key, str) else None


#: files of every scan export besides its frames (manifest.json is written last)
EXPORT_FILES = ("decode.exr", "cloud.ply", "calibration.yml", "manifest.json")


def export_complete(folder, unit_key: str) -> bool:
    """Whether ``folder`` holds the whole export of the unit ``unit_key``: its manifest names
    the unit and every file the manifest promises is there (a partly deleted export is
    written again by the next run)."""
    folder = Path(folder)
    if export_unit_key(folder) != unit_key:
        return False
    try:
        manifest = json.loads((folder / "manifest.json").read_text())
        kind = manifest.get("kind")
    except (OSError, ValueError, AttributeError):
        return False
    if kind == "codings":  # one complete export per coding
        names = manifest.get("codings")
        return isinstance(names, list) and all(
            isinstance(n, str) and _coding_complete(folder / n) for n in names
        )
    if kind == "lidar":  # results/lidar_exports.py: the files it lists
        files = manifest.get("files")
        ok = isinstance(files, list) and all(isinstance(f, str) for f in files)
        return ok and all((folder / f).is_file() for f in files)
    return _coding_complete(folder)


def _coding_complete(folder: Path) -> bool:
    """Whether one coding's export in ``folder`` has every file its manifest promises."""
    try:
        manifest = json.loads((folder / "manifest.json").read_text())
        frames = manifest.get("frames")
    except (OSError, ValueError, AttributeError):
        return False
    if not isinstance(frames, list) or not all(isinstance(f, str) for f in frames):
        return False
    wanted = [folder / name for name in EXPORT_FILES]
    wanted += [folder / sub / f for sub in ("frames8", "frames16") for f in frames]
    return all(p.is_file() for p in wanted)


def check_save_scans(cfg) -> None:
    """Refuse ``simlunar run --save-scans`` for an experiment whose scan cannot be exported.

    Checks the experiment as written; the CLI then validates it again with
    ``study.save_scans: true`` applied like a ``--set`` override, so every sweep point is
    checked too.

    Raises
    ------
    ConfigError
        The experiment's study is neither a lidar study nor a scanner study with a
        gray-code scan.
    """

    study = cfg.study
    if getattr(study, "kind", None) == "lidar":
        return  # point clouds and range images of every LIDAR (results/lidar_exports.py)
    if getattr(study, "kind", None) != "scanner":
        raise ConfigError(
            f"--save-scans: experiment {cfg.name!r} has a {study.kind} study; scans are "
            "exported by scanner and lidar studies only"
        )
    coded = [m for m in MODES if m not in DOT_MODES]  # the full-field codings' own modes
    if not set(study.modes) & {*coded, "ambiguity_enhancement"}:
        raise ConfigError(
            f"--save-scans: study.modes {list(study.modes)} has no full-field coded scan to "
            f"export (add one of {', '.join(coded)} or ambiguity_enhancement)"
        )
