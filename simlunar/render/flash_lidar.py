"""Flash LIDARs (mitransient): a receiver array lit by whole-field pulses, and the micromirror flash
that lights only the planned pixels.

A flash reads every receiver pixel of one rendered frame (:func:`flash_scan`, :func:`read_flash`);
its range gate comes from the reference plane (:func:`flash_window`, :mod:`simlunar.lidar.gate`),
never from the terrain. The micromirror flash (:func:`micromirror_flash`) fires as many frames as
dots share a receiver pixel (:func:`micromirror_frames`). Photon counts and ranges are read as for
every LIDAR here (:mod:`simlunar.render.lidar_scan`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Camera, Projector
from simlunar.lidar import (
    TimeBins,
)
from simlunar.lidar.gate import gate_bins, plane_ranges
from simlunar.lidar.hardware import pixel_solid_angles
from simlunar.render.lidar_scan import LidarScan, _counts, _ranges, _ReturnOptions
from simlunar.render.lights import ProjectorLight
from simlunar.render.transient import flash_frame

__all__ = [
    "FlashOptions",
    "flash_scan",
    "flash_window",
    "micromirror_flash",
    "micromirror_frames",
    "micromirror_lit_sr",
    "read_flash",
    "receiver_solid_angles",
]


@dataclass(frozen=True)
class FlashOptions(_ReturnOptions):
    """A flash LIDAR: a receiver array lit by whole-field pulses.

    Parameters
    ----------
    pulse, detector, ranging, transient, bin_range_m
        As for every LIDAR here (:class:`_ReturnOptions`); ``detector.pulses`` pulses per frame.
    margin_m : float
        Range margin (m) around the terrain's nearest and farthest point in view.
    pulse_rate_hz : float
        Pulse repetition rate (1/s): a frame takes ``detector.pulses / pulse_rate_hz``.
    """

    pulse_rate_hz: float = 30.0

    def __post_init__(self) -> None:
        if not (self.bin_range_m > 0 and self.margin_m >= 0 and self.pulse_rate_hz > 0):
            raise ValueError("need bin_range_m > 0, margin_m >= 0 and pulse_rate_hz > 0")


def flash_window(camera: Camera, *, options: FlashOptions) -> TimeBins:
    """The flash receiver's range gate: the ranges where its pixel rays meet the reference
    plane (``options.gate``), with ``options.margin_m`` on both sides (never the terrain)."""
    if options.gate.altimeter:
        raise ValueError("gate.altimeter: a flash takes its reference plane from gate.datum_z_m")
    _, d = camera.rays(camera.pixel_centers().reshape(-1, 2))
    r = plane_ranges(camera.pose.position, d, datum_z=options.gate.datum_z_m, options=options.gate)
    r = r[r < options.gate.max_range_m]  # pixels above the plane's horizon are not gated
    if r.size == 0:
        raise ValueError("gate: no receiver pixel meets the reference plane within max_range_m")
    return gate_bins(r, bin_range_m=options.bin_range_m, margin_m=options.margin_m)


def receiver_solid_angles(camera: Camera) -> np.ndarray:
    """Exact solid angle (sr) of every pixel of a receiver ``camera``, (rows, cols)."""
    k = camera.intrinsics
    return pixel_solid_angles(k.fx, k.fy, k.cx, k.cy, k.width, k.height)


def _read_frame(frame, camera: Camera, options: FlashOptions, rng, *, lit_sr=None):
    """Photon counts and ranges of a rendered frame through ``camera`` (its receiver).

    Every pixel collects in proportion to its own solid angle (``cos^3`` off axis): with
    hardware, ``Omega_pix`` itself and the pulse spread over ``lit_sr`` (default: the whole
    receiver field); with the expert override the photon scales are the boresight pixel's.
    """
    omega = receiver_solid_angles(camera)
    if options.hardware is None:
        weight, det = omega / omega.max(), options.detector
    else:
        lit = float(omega.sum()) if lit_sr is None else float(lit_sr)
        det = options.photon_detector(field_sr=1.0, lit_sr=lit, sun_irradiance=frame.sun_irradiance)
        weight = omega
    bg = 0.0 if frame.sun is None else frame.sun * weight
    hist = frame.histograms * weight[..., None].astype(np.float32)
    counts = _counts(hist, bg, frame.bins, options.pulse, det, rng, frame.oversample)
    return _ranges(counts, bg, frame.bins, options.pulse, det, options.ranging)


def flash_scan(
    terrain, camera: Camera, *, options: FlashOptions, rng=None, sun=None, bsdf=None
) -> LidarScan:
    """One flash frame read by every receiver pixel (arrays (rows, cols) of ``camera``).

    Parameters
    ----------
    terrain : Terrain
    camera : geometry.Camera
        The receiver array (e.g. 128 x 128), co-boresighted with the guide camera.
    options : FlashOptions
    rng : seed or Generator
    sun : SunLight or None
    bsdf : BSDF spec or None

    Returns
    -------
    LidarScan
        ``points`` along each pixel centre's ray; ``frames`` = 1.
    """
    bins = flash_window(camera, options=options)
    frame = flash_frame(terrain, camera, bins=bins, options=options.transient, bsdf=bsdf, sun=sun)
    return read_flash(frame, camera, options=options, rng=rng)


def read_flash(frame, camera: Camera, *, options: FlashOptions, rng=None) -> LidarScan:
    """Read a rendered flash frame (:func:`~simlunar.render.transient.flash_frame` through
    ``camera``) with fresh photon noise: a frame rendered once serves many noisy reads."""
    rng = np.random.default_rng(rng)
    res = _read_frame(frame, camera, options, rng)
    _, d = camera.rays(camera.pixel_centers())
    return LidarScan(
        ranges=res.range,
        valid=res.valid,
        points=camera.pose.position + res.range[..., None] * d,
        photons=res.photons,
        order=np.arange(res.range.size).reshape(res.range.shape),
        seconds=options.detector.pulses / options.pulse_rate_hz,
        frames=1,
        times=np.zeros(res.range.shape),
        returns=res.returns,
    )


def micromirror_lit_sr(camera: Camera) -> float:
    """The rendered micromirror's lit solid angle for the link budget (sr): ``W H / (fx fy)``,
    so that each of its ``W H`` mirrors carries ``E / (W H)`` of the pulse (``camera``: the
    projector's intrinsics = the guide camera's)."""
    k = camera.intrinsics
    return float(k.width * k.height / (k.fx * k.fy))


def micromirror_frames(pixels: np.ndarray, camera: Camera, receiver_shape) -> np.ndarray:
    """Frame index (k,) of each planned pixel: dots sharing a receiver pixel never share a frame.

    ``pixels`` (k, 2) are (u, v) in ``camera``; the receiver (rows, cols) sees the same field
    of view, so receiver pixel = floor of the scaled (u, v), at any depth (co-located).
    """
    rh, rw = receiver_shape
    h, w = camera.shape
    uv = np.asarray(pixels, float)
    cell = np.floor(uv[:, 1] * rh / h).astype(np.int64) * rw + np.floor(uv[:, 0] * rw / w)
    cell = cell.astype(np.int64)
    order = np.argsort(cell, kind="stable")
    sc = cell[order]
    first = np.searchsorted(sc, sc, side="left")
    frames = np.empty(len(uv), np.int64)
    frames[order] = np.arange(len(uv)) - first
    return frames


def micromirror_flash(
    terrain,
    camera: Camera,
    pixels: np.ndarray,
    *,
    options: FlashOptions,
    receiver_shape: tuple[int, int] = (64, 64),
    rng=None,
    sun=None,
    bsdf=None,
) -> LidarScan:
    """Micromirror-steered flash: light only the planned pixels, time them on a small receiver.

    A micromirror projector with ``camera``'s pose and intrinsics lights the planned pixels
    (one projector pixel each); a co-located receiver of ``receiver_shape`` with the same
    field of view times the returns. Dots in the same receiver pixel go to different frames
    (:func:`micromirror_frames`). Every receiver pixel ray only gets light where it meets a
    lit dot, so the render needs ``options.transient.spp`` of about
    ``(camera pixels / receiver pixels) x 16`` for a clean return.

    Parameters
    ----------
    terrain : Terrain
    camera : geometry.Camera
        The guide camera (centred principal point, square pixels).
    pixels : (k, 2) float
        Planned (u, v) pixel coordinates in ``camera``.
    options : FlashOptions
    receiver_shape : (rows, cols)
    rng, sun, bsdf
        As for :func:`flash_scan`.

    Returns
    -------
    LidarScan
        Arrays over the k planned pixels; ``frames`` = flash frames fired.

    Notes
    -----
    **Link budget** (with ``options.hardware``; :func:`micromirror_lit_sr`): the pulse lights
    the whole micromirror array and each mirror sends its equal share ``E / N_mirrors`` towards
    its dot when on (a digital micromirror device: amplitude, not phase, so energy on "off"
    mirrors is lost; the array's throughput is folded into ``optics_efficiency``, an
    assumption). The rendered projector gives every pixel the power ``scale / (fx fy)``, so the
    render's lit solid angle is ``W H / (fx fy)`` (the field's area on the plane at 1 m) and a
    receiver pixel's photons follow the flash's formula with it: on a Lambertian plane a dot
    seen whole by its receiver pixel gets ``(E / N_mirrors / h nu) (rho / pi) cos(theta) A / R^2
    eta`` (tested against this hand value).
    """
    rng = np.random.default_rng(rng)
    uv = np.asarray(pixels, float).reshape(-1, 2)
    h, w = camera.shape
    rh, rw = (int(x) for x in receiver_shape)
    receiver = Camera(camera.intrinsics.scaled(rw / w), camera.pose)
    if receiver.shape != (rh, rw):
        raise ValueError(f"receiver_shape {receiver_shape} must keep the aspect of {(h, w)}")
    ranges, photons, returns, times, n_frames = _fire_micromirror_frames(
        terrain, camera, receiver, uv, options=options, rng=rng, scene={"sun": sun, "bsdf": bsdf}
    )
    _, d = camera.rays(uv)
    valid = np.isfinite(ranges)
    return LidarScan(
        ranges=ranges,
        valid=valid,
        points=camera.pose.position + ranges[:, None] * d,
        photons=photons,
        order=np.arange(len(uv)),
        seconds=n_frames * options.detector.pulses / options.pulse_rate_hz,
        frames=n_frames,
        times=times,
        returns=returns,
    )


def _fire_micromirror_frames(terrain, camera: Camera, receiver: Camera, uv, *, options, rng, scene):
    """Render and read frame after frame of a micromirror flash: frame f lights the dots of
    :func:`micromirror_frames` f (one projector pixel each) and each dot reads its receiver
    pixel; ``scene``: the ``sun`` and ``bsdf`` of :func:`flash_frame`.

    Returns
    -------
    ranges, photons, returns, times : (k,) arrays of the dots (m, photons, count, s)
    n_frames : int
    """
    h, w = camera.shape
    rh, rw = receiver.shape
    frame_of = micromirror_frames(uv, camera, (rh, rw))
    n_frames = int(frame_of.max()) + 1 if len(uv) else 0
    projector = Projector(camera.intrinsics, camera.pose)
    bins = flash_window(camera, options=options)
    ranges, photons = np.full(len(uv), np.nan), np.zeros(len(uv))
    returns, times = np.zeros(len(uv), np.int64), np.zeros(len(uv))
    per_frame = options.detector.pulses / options.pulse_rate_hz
    col = np.clip(np.floor(uv[:, 0] * rw / w).astype(int), 0, rw - 1)
    row = np.clip(np.floor(uv[:, 1] * rh / h).astype(int), 0, rh - 1)
    for f in range(n_frames):
        sel = np.flatnonzero(frame_of == f)
        pattern = np.zeros((h, w), np.float32)
        pattern[
            np.clip(uv[sel, 1].astype(int), 0, h - 1), np.clip(uv[sel, 0].astype(int), 0, w - 1)
        ] = 1.0
        light = ProjectorLight(projector, pattern, scale=options.transient.laser_intensity)
        fr = flash_frame(
            terrain,
            receiver,
            bins=bins,
            options=options.transient,
            bsdf=scene["bsdf"],
            sun=scene["sun"],
            projector=light,
        )
        res = _read_frame(fr, receiver, options, rng, lit_sr=micromirror_lit_sr(camera))
        ranges[sel], photons[sel] = res.range[row[sel], col[sel]], res.photons[row[sel], col[sel]]
        returns[sel], times[sel] = res.returns[row[sel], col[sel]], f * per_frame
    return ranges, photons, returns, times, n_frames
