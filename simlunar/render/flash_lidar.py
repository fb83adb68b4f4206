"""Flash LIDARs rendered on mitransient: a receiver array lit by whole-field pulses, and the
micromirror flash that lights only the planned pixels.

Only the frames' rendering lives here: :func:`flash_scan` renders one flash frame and reads it
with :func:`simlunar.lidar.flash.read_flash`; :func:`micromirror_flash` renders one frame per
group of dots (:func:`simlunar.lidar.flash.micromirror_frames`) through a projector that lights
them and reads each with :func:`simlunar.lidar.flash.read_frame`; on a moving platform each of
its frames is rendered from the platform's pose at that frame's time
(:mod:`simlunar.lidar.trajectory`). The range gate, photon counts, ranges and the options are
:mod:`simlunar.lidar.flash`'s.

The micromirror's **link budget** (with ``options.hardware``;
:func:`~simlunar.lidar.flash.micromirror_lit_sr`): the pulse lights the whole micromirror array and each mirror sends its equal share ``E /
N_mirrors`` towards its dot when on (a digital micromirror device: amplitude, not phase, so
energy on "off" mirrors is lost; the array's throughput is folded into ``optics_efficiency``, an
assumption). The rendered projector gives every pixel the power ``scale / (fx fy)``, so the
render's lit solid angle is ``W H / (fx fy)`` (the field's area on the plane at 1 m) and a
receiver pixel's photons follow the flash's formula with it: on a Lambertian plane a dot seen
whole by its receiver pixel gets ``(E / N_mirrors / h nu) (rho / pi) cos(theta) A / R^2 eta``
(tested against this hand value).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from simlunar.geometry import Camera, Projector
from simlunar.lidar.flash import (
    FlashOptions,
    flash_window,
    micromirror_frames,
    micromirror_lit_sr,
    read_flash,
    read_frame,
)
from simlunar.lidar.returns import LidarScan, fired_energy_j
from simlunar.lidar.trajectory import Flight, camera_at, place_points
from simlunar.render.lights import ProjectorLight
from simlunar.render.transient import PatternFrames, flash_frame

__all__ = [
    "flash_scan",
    "micromirror_flash",
]


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


def micromirror_flash(
    terrain,
    camera: Camera,
    pixels: np.ndarray,
    *,
    options: FlashOptions,
    receiver_shape: tuple[int, int] = (64, 64),
    rng=None,
    scene: Mapping | None = None,
    flight: Flight | None = None,
) -> LidarScan:
    """Micromirror-steered flash: light only the planned pixels, time them on a small receiver.

    A micromirror projector with ``camera``'s pose and intrinsics lights the planned pixels
    (one projector pixel each); a co-located receiver of ``receiver_shape`` with the same
    field of view times the returns. Dots in the same receiver pixel go to different frames
    (:func:`~simlunar.lidar.flash.micromirror_frames`). Every receiver pixel ray only gets
    light where it meets a lit dot, so the render needs ``options.transient.spp`` of about
    ``(camera pixels / receiver pixels) x 16`` for a clean return. Its link budget: the module
    docstring.

    Parameters
    ----------
    terrain : Terrain
    camera : geometry.Camera
        The guide camera (centred principal point, square pixels).
    pixels : (k, 2) float
        Planned (u, v) pixel coordinates in ``camera``.
    options : FlashOptions
    receiver_shape : (rows, cols)
    rng : seed or Generator
        Photon noise (and the navigation's errors).
    scene : mapping or None
        ``sun`` and ``bsdf`` as for :func:`flash_scan` (None: no sun, the default BSDF).
    flight : Flight or None
        The platform's motion (:class:`~simlunar.lidar.trajectory.Flight`; None: at rest at
        ``camera``): frame ``f`` fires at ``flight.start_s + f x pulses / pulse_rate_hz`` and
        is rendered with projector and receiver at the platform's position then, turned by
        the jitter then (:func:`~simlunar.lidar.trajectory.camera_at`; ``camera``'s own
        position is not used). The mirrors stay the planned pixels (no re-aiming), so a dot's
        receiver pixel is the same in every pose; its point is placed by ``flight.navigation``
        along ``camera``'s ray of its planned pixel (the commanded direction). ``times`` count
        from ``flight.start_s``.

    Returns
    -------
    LidarScan
        Arrays over the k planned pixels; ``frames`` = flash frames fired; ``times`` each dot's
        frame's firing time (s).
    """
    rng = np.random.default_rng(rng)
    uv = np.asarray(pixels, float).reshape(-1, 2)
    h, w = camera.shape
    rh, rw = (int(x) for x in receiver_shape)
    receiver = Camera(camera.intrinsics.scaled(rw / w), camera.pose)
    if receiver.shape != (rh, rw):
        raise ValueError(f"receiver_shape {receiver_shape} must keep the aspect of {(h, w)}")
    ranges, photons, returns, times, n_frames = _fire_micromirror_frames(
        terrain, camera, receiver, uv, options=options, rng=rng,
        scene=dict(scene or {}), flight=flight,
    )  # fmt: skip
    _, d = camera.rays(uv)
    valid = np.isfinite(ranges)
    if flight is None:
        points = camera.pose.position + ranges[:, None] * d
    else:
        points = place_points(ranges, d, flight.start_s + times, flight.trajectory,
                              flight.navigation, rng=rng)  # fmt: skip
    return LidarScan(
        ranges=ranges,
        valid=valid,
        points=points,
        photons=photons,
        order=np.arange(len(uv)),
        seconds=n_frames * options.detector.pulses / options.pulse_rate_hz,
        frames=n_frames,
        times=times,
        returns=returns,
        energy_j=fired_energy_j(options, n_frames * options.detector.pulses),
    )


def _fire_micromirror_frames(
    terrain, camera: Camera, receiver: Camera, uv, *, options, rng, scene, flight=None
):
    """Render and read frame after frame of a micromirror flash: frame f lights the dots of
    :func:`~simlunar.lidar.flash.micromirror_frames` f (one projector pixel each) and each dot
    reads its receiver pixel; ``scene``: the ``sun`` and ``bsdf`` of
    :func:`~simlunar.render.transient.flash_frame` (missing: none); with a ``flight`` projector, receiver
    and range gate are those of the platform's pose at the frame's time (``flight.start_s`` +
    its time in the scan).

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
    frames = None  # at rest: one scene, frame after frame a new pattern (PatternFrames)
    for f in range(n_frames):
        if flight is not None:
            # projector and receiver move together: a dot keeps its receiver pixel
            moved = camera_at(camera, flight.trajectory, flight.start_s + f * per_frame)
            projector = Projector(camera.intrinsics, moved.pose)
            receiver = Camera(receiver.intrinsics, moved.pose)
            bins = flash_window(moved, options=options)
        sel = np.flatnonzero(frame_of == f)
        pattern = np.zeros((h, w), np.float32)
        pattern[
            np.clip(uv[sel, 1].astype(int), 0, h - 1), np.clip(uv[sel, 0].astype(int), 0, w - 1)
        ] = 1.0
        if frames is None or flight is not None:
            light = ProjectorLight(projector, pattern, scale=options.transient.laser_intensity)
            frames = PatternFrames(terrain, receiver, bins=bins, options=options.transient,
                                   bsdf=scene.get("bsdf"), sun=scene.get("sun"), projector=light)  # fmt: skip
            fr = frames.render()
        else:
            fr = frames.render(pattern)
        res = read_frame(fr, receiver, options, rng, lit_sr=micromirror_lit_sr(camera))
        ranges[sel], photons[sel] = res.range[row[sel], col[sel]], res.photons[row[sel], col[sel]]
        returns[sel], times[sel] = res.returns[row[sel], col[sel]], f * per_frame
    return ranges, photons, returns, times, n_frames
