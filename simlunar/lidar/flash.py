"""Flash LIDAR acquisition on arrays: a receiver array lit by whole-field pulses, and the
micromirror flash that lights only the planned pixels.

A flash reads every receiver pixel of one rendered frame (:func:`read_flash`, :func:`read_frame`);
its range gate comes from the reference plane (:func:`flash_window`, :mod:`simlunar.lidar.gate`),
never from the terrain. The micromirror flash fires as many frames as dots share a receiver pixel
(:func:`micromirror_frames`) and its link budget spreads the pulse over the lit micromirror field
(:func:`micromirror_lit_sr`). Photon counts and ranges are read as for every LIDAR
(:mod:`simlunar.lidar.returns`). The frames are rendered by :mod:`simlunar.render.flash_lidar`
(:func:`~simlunar.render.flash_lidar.flash_scan`,
:func:`~simlunar.render.flash_lidar.micromirror_flash`) on mitransient.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from simlunar.geometry import Camera
from simlunar.lidar.apd import agc_energy
from simlunar.lidar.gate import gate_bins, prior_ranges, read_datum
from simlunar.lidar.hardware import pixel_solid_angles
from simlunar.lidar.returns import (
    LidarScan,
    ReturnOptions,
    detect_counts,
    fired_energy_j,
    read_ranges,
)
from simlunar.lidar.waveform import TimeBins
from simlunar.registry import option

__all__ = [
    "FlashOptions",
    "flash_window",
    "micromirror_frames",
    "micromirror_lit_sr",
    "micromirror_sampling",
    "read_flash",
    "read_frame",
    "receiver_rc",
    "receiver_solid_angles",
]


#: the stream of the gate's datum reading drawn from a flash's render seed
DATUM_STREAM = 0x6A7E


@dataclass(frozen=True)
class FlashOptions(ReturnOptions):
    """A flash LIDAR: a receiver array lit by whole-field pulses.

    The fields of every LIDAR are :class:`~simlunar.lidar.returns.ReturnOptions`'s;
    ``detector.pulses`` is the pulses per frame.
    """

    pulse_rate_hz: float = option(
        30.0,
        doc="pulse repetition rate (1e-3 .. 1e9): a frame takes detector.pulses / pulse_rate_hz",
        unit="1/s",
        ge=1e-3,
        le=1e9,
    )


def flash_window(camera: Camera, *, options: FlashOptions, rng=None) -> TimeBins:
    """The flash receiver's range gate: the ranges where its pixel rays meet the reference
    plane (``options.gate``), with ``options.margin_m`` on both sides (never the terrain).

    With the gate's prior (``datum_sigma_m``, ``max_slope_rad``;
    :func:`~simlunar.lidar.gate.prior_ranges`) the plane is the datum as read
    (:func:`~simlunar.lidar.gate.read_datum`, its error drawn from ``rng``; None: from
    ``options.transient.seed``, so every frame rendered with these options shares one reading,
    a bias of the navigation's altitude) and each pixel's window covers the prior's planes
    through the boresight's footprint.
    """
    g = options.gate
    if g.altimeter:
        raise ValueError("gate.altimeter: a flash takes its reference plane from gate.datum_z_m")
    if rng is None and g.datum_sigma_m > 0:
        rng = np.random.default_rng((options.transient.seed, DATUM_STREAM))
    datum = read_datum(g, rng)
    _, d = camera.rays(camera.pixel_centers().reshape(-1, 2))
    lo, hi = prior_ranges(camera.pose.position, d, datum_z=datum, boresight=camera.pose.forward,
                          options=g)  # fmt: skip
    keep = lo < g.max_range_m  # pixels above the plane's horizon are not gated
    if not keep.any():
        raise ValueError("gate: no receiver pixel meets the reference plane within max_range_m")
    return gate_bins(lo[keep], far=hi[keep], bin_range_m=options.bin_range_m,
                     margin_m=options.margin_m)  # fmt: skip


def receiver_solid_angles(camera: Camera) -> np.ndarray:
    """Exact solid angle (sr) of every pixel of a receiver ``camera``, (rows, cols)."""
    k = camera.intrinsics
    return pixel_solid_angles(k.fx, k.fy, k.cx, k.cy, k.width, k.height)


def read_frame(frame, camera: Camera, options: FlashOptions, rng, *, lit_sr=None):
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
    probes, fired = 0, None
    if det.apd is not None and det.apd.agc_target is not None:
        if lit_sr is not None:
            raise ValueError("apd.agc_target: the micromirror flash has no gain control")
        det, probes, fired = _gain_control(hist, bg, frame, options, det, rng)
    counts = detect_counts(hist, bg, frame.bins, options.pulse, det, rng, frame.oversample)
    res = read_ranges(counts, bg, frame.bins, options.pulse, det, options.ranging)
    return dataclasses.replace(res, probe_pulses=probes, energy_pulses=fired)


def _gain_control(hist, bg, frame, options: FlashOptions, det, rng):
    """The detector of a frame whose pulse energy the APD's gain control set
    (:func:`~simlunar.lidar.apd.agc_energy`: one pulse slot read without firing, for the
    background, then probe pulses fired before the frame, each read in full and discarded), the
    number of pulse slots the control took and the energy fired, probes and frame, in
    full-energy pulses."""
    one = dataclasses.replace(det, pulses=1)
    # the receiver read for one pulse slot without firing: the sun and dark counts alone
    quiet = dataclasses.replace(one, signal_photons=0.0)
    background = detect_counts(hist, bg, frame.bins, options.pulse, quiet, rng, frame.oversample)
    energy, probes, fired = float(det.apd.agc_probe_energy), 1, 0.0
    for _ in range(det.apd.agc_max_probes):
        probe = dataclasses.replace(one, signal_photons=det.signal_photons * energy)
        w = detect_counts(hist, bg, frame.bins, options.pulse, probe, rng, frame.oversample)
        probes += 1
        fired += energy
        energy, again = agc_energy(w, background, energy, options=det.apd)
        if not again:
            break
    fired += det.pulses * energy
    return dataclasses.replace(det, signal_photons=det.signal_photons * energy), probes, fired


def read_flash(frame, camera: Camera, *, options: FlashOptions, rng=None) -> LidarScan:
    """Read a rendered flash frame (:func:`~simlunar.render.transient.flash_frame` through
    ``camera``) with fresh photon noise: a frame rendered once serves many noisy reads."""
    rng = np.random.default_rng(rng)
    res = read_frame(frame, camera, options, rng)
    pulses = options.detector.pulses if res.energy_pulses is None else res.energy_pulses
    _, d = camera.rays(camera.pixel_centers())
    return LidarScan(
        ranges=res.range,
        valid=res.valid,
        points=camera.pose.position + res.range[..., None] * d,
        photons=res.photons,
        order=np.arange(res.range.size).reshape(res.range.shape),
        # the gain control's probe pulses fire before the frame's
        seconds=(options.detector.pulses + res.probe_pulses) / options.pulse_rate_hz,
        frames=1,
        times=np.zeros(res.range.shape),
        returns=res.returns,
        energy_j=fired_energy_j(options, pulses),
    )


def micromirror_lit_sr(camera: Camera) -> float:
    """The rendered micromirror's lit solid angle for the link budget (sr): ``W H / (fx fy)``,
    so that each of its ``W H`` mirrors carries ``E / (W H)`` of the pulse (``camera``: the
    projector's intrinsics = the guide camera's)."""
    k = camera.intrinsics
    return float(k.width * k.height / (k.fx * k.fy))


#: the fewest render samples a micromirror's lit guide pixel may get: a receiver pixel's rays
#: land uniformly over it, so a dot's pixel gets spp / (guide pixels per receiver pixel) on
#: average and none with probability exp(-that) (a dot without light: a lost or false return)
MIN_SAMPLES_PER_DOT = 4.0


def micromirror_sampling(guide_shape, receiver_shape, spp: int) -> float:
    """Render samples per lit guide pixel of a micromirror flash: ``spp`` over the guide pixels
    one receiver pixel covers; ValueError below :data:`MIN_SAMPLES_PER_DOT`.

    Every receiver pixel's ``spp`` rays land uniformly over its ground and only those on the
    one lit guide pixel carry the dot's return, so with ``n`` guide pixels per receiver pixel
    a dot is rendered from about ``spp / n`` of them, and from none with probability
    ``exp(-spp / n)``: a return the Monte Carlo estimate lost, not the sensor (measured on the
    full-size landing site, 144 guide pixels per receiver pixel at spp 128: 27 % of dots
    without a return, 18 % ranged on the background alone; docs/lidar.md). About 16 samples
    per dot give a clean return.
    """
    (gh, gw), (rh, rw) = guide_shape, receiver_shape
    n = (gh * gw) / float(rh * rw)
    per_dot = float(spp) / n
    if per_dot < MIN_SAMPLES_PER_DOT:
        need = math.ceil(MIN_SAMPLES_PER_DOT * n)
        raise ValueError(
            f"transient.spp {spp} gives each lit guide pixel {per_dot:.2g} render samples (a "
            f"{rw} x {rh} receiver pixel covers {n:.3g} of the {gw} x {gh} guide pixels); at "
            f"least {MIN_SAMPLES_PER_DOT:g} are needed (about 16 for a clean return): spp >= "
            f"{need}, or a larger receiver_px"
        )
    return per_dot


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


def receiver_rc(receiver_shape, guide_shape) -> np.ndarray:
    """Receiver pixel centres as guide (row, col) index coordinates, (rows * cols, 2) float.

    A co-boresighted receiver of the same field of view: receiver pixel (i, j) has its centre at
    guide (u, v) = ((j + 1/2) W / w, (i + 1/2) H / h), i.e. index coordinates (v - 1/2, u - 1/2),
    row-major (the order of a flash scan's flattened arrays).
    """
    (h, w), (gh, gw) = receiver_shape, guide_shape
    i, j = np.mgrid[0:h, 0:w]
    v, u = (i.ravel() + 0.5) * gh / h, (j.ravel() + 0.5) * gw / w
    return np.stack([v - 0.5, u - 0.5], axis=1)
