"""LIDAR benchmarks (see ``benchmarks/run.py``).

``lidar``: a steered-beam scan of the aerial scene (``aerial_1`` at quarter scale, 50 m x 80 m
at 0.2 m, seed 0) from 50 m above its centre: ``N_BEAMS`` beams towards uniformly random
points of a 512 x 512 guide view, each beam's footprint (1 mrad Gaussian) sampled by
``FOOTPRINT_SAMPLES`` rays, rendered with mitransient in batches of ``BATCH`` beams (direct
light, 5 cm bins over an 8 m window per batch), then pulse shaping, photon noise with the
sun's background, matched-filter ranging. ``ours_s`` is that scan's time without ordering
(after a warm-up scan that compiles the kernels); ``reference_s`` a plain ray cast of the same beams' centre
rays (Mitsuba ``ray_intersect``, one ray per beam, no transport). ``beams_per_s`` =
N_BEAMS / ours_s; ``scan_100k_s`` = 100 000 / beams_per_s + the measured ordering (NN + 2-opt)
of 100 000 random pointings in a 0.8 x 0.8 rad field, which is not linear and is timed at
full size (``order_100k_s``); ``scan_100k_simulated_s_*`` are the simulated mechanical scan
times (default :class:`SteeringOptions`) in the planner's (random) order and ordered.
``flash_128_s`` / ``flash_128_mb``: one 128 x 128 flash frame (64 spp, bins over the
terrain in view) and its transient film's size (rows x cols x bins x 4 channels x 4 bytes);
``flash_rss_mb`` the growth of the process's peak resident memory during that frame.
Beams are rendered on ``TransientOptions.oversample`` (2) fine bins per output bin with the
linear splat (docs/lidar.md, "How a return is made").

``rms_over_crlb``: a flat plane 50 m below the sensor is ranged by beams whose incidence puts
the range at 10 offsets across one 5 cm bin (rendered once), each read 200 times with photon
noise at 100 signal photons per pulse (1 ns FWHM pulse, 0.1 ns jitter, 0.01 background counts
per bin); the range RMS over all readings divided by the RMS of the Cramer-Rao bound at those
offsets (:func:`simlunar.lidar.range_crlb`). Goal: <= 1.3. ``smoke=True`` runs every part at a
tiny size in a few seconds (16 x 16 flash, 256 beams, 2 000 orderings, 20 readings).

``lidar_receiver``: one 128 x 128 flash frame of the same scene (64 spp) rendered once
(``render_s``) and read through the full receiver chain (``ours_s``): a linear APD (gain 100,
k = 0.02) saturating at 2.5e6 photons per pulse against a 1000 pe, 12-bit digitiser, its
pulse energy set by the gain control's probe pulses (target half the full scale), 16 pulses,
matched filter with the gate-edge guard (3 sigma); ``reference_s`` the same frame read by the
ideal (unsaturated, uncontrolled) APD. ``render_share`` = render / (render + full read): what a
frame of the study costs where the render dominates. ``smoke=True``: 16 x 16.

``micromirror_frames``: a micromirror flash over the same scene and sun lighting every pixel of
a 128 x 128 guide view through a 32 x 32 receiver (16 frames, spp 128: 8 samples per lit guide
pixel) at rest: ``ours_s`` its scan, the frames sharing one loaded scene
(:class:`~simlunar.render.transient.PatternFrames`: the pattern swapped, the sun image rendered
once); ``reference_s`` the same frames each rendered by a freshly loaded scene and sun image
(:func:`~simlunar.render.transient.flash_frame`, the path before) and read alike;
``same_ranges`` whether both read every dot identically. ``smoke=True``: 16 x 16 guide, 8 x 8
receiver (4 frames).
"""

from __future__ import annotations

import resource
import time

import numpy as np

N_BEAMS = 16_384
BATCH = 8192
FOOTPRINT_SAMPLES = 16
SCALE = 0.25
HEIGHT_M = 50.0


def _setup():
    from simlunar.config.translate import preset_params
    from simlunar.geometry import Camera, Pose
    from simlunar.terrain import generate

    t = generate(preset_params("aerial_1"), rng=0, scale=SCALE).terrain
    xmin, xmax, ymin, ymax = t.extent
    c = np.array([(xmin + xmax) / 2, (ymin + ymax) / 2, float(np.nanmean(t.heights))])
    pose = Pose.look_at(c + np.array([0.0, 0.0, HEIGHT_M]), c, up=(0.0, 1.0, 0.0))
    fov = 2 * np.degrees(np.arctan(0.45 * min(xmax - xmin, ymax - ymin) / HEIGHT_M))
    return t, pose, fov, Camera


def _plane_precision(trials: int) -> dict:
    """Range RMS of a rendered plane over its Cramer-Rao bound (module docstring)."""
    from simlunar.lidar import (
        FootprintOptions,
        PulseOptions,
        TimeBins,
        extract_ranges,
        range_crlb,
        shape_waveform,
    )
    from simlunar.render.beam_capture import BeamCapture, capture_beams
    from simlunar.terrain import Terrain

    h, n = 50.0, 64
    terrain = Terrain(
        heights=np.zeros((n, n)),
        albedo=np.full((n, n), 0.12, np.float32),
        spacing=1.0,
        origin=(-n / 2, n / 2),
    )
    offsets = (np.arange(10) + 0.05) / 10
    truth = h + offsets * 0.05
    theta = np.arccos(h / truth)
    d = np.stack([np.sin(theta), np.zeros(10), -np.cos(theta)], axis=1)
    window = TimeBins(0.0, 0.1, 80)
    cap = BeamCapture(
        terrain, [0.0, 0.0, h], footprint=FootprintOptions(1e-5, samples=4), window=window, batch=16
    )
    ret = capture_beams(cap, d, truth.round(1), margin_m=1.0)
    pulse = PulseOptions(fwhm_s=1e-9, jitter_s=0.1e-9)
    lam = shape_waveform(ret.histograms, window, pulse, oversample=ret.oversample)
    lam = 100.0 * lam / lam.sum(-1, keepdims=True) + 0.01
    counts = np.random.default_rng(0).poisson(np.repeat(lam[:, None], trials, axis=1))
    res = extract_ranges(counts, window, pulse=pulse)
    err = res.range + ret.start_opl[:, None] / 2 - truth[:, None]
    bound = range_crlb(100.0, pulse=pulse, bins=window, offset=offsets, background=0.01)
    rms = float(np.sqrt(np.nanmean(err**2)))
    return {
        "rms_over_crlb": round(rms / float(np.sqrt(np.mean(bound**2))), 3),
        "plane_rms_mm_100_photons": round(1e3 * rms, 3),
        "plane_max_abs_bias_mm_100_photons": round(
            1e3 * float(np.abs(np.nanmean(err, 1)).max()), 3
        ),
    }


def lidar(*, smoke: bool = False) -> dict:
    from simlunar.geometry import Intrinsics
    from simlunar.lidar import (
        DetectorOptions,
        FootprintOptions,
        OrderOptions,
        SteeringOptions,
        order_scan,
        pointing_angles,
        scan_timing,
    )
    from simlunar.lidar.flash import FlashOptions, flash_window
    from simlunar.lidar.scan import SteeredBeamOptions, steered_beam_scan
    from simlunar.render import backend
    from simlunar.render.beam_capture import beam_capture
    from simlunar.render.flash_lidar import flash_scan
    from simlunar.render.lights import SunLight
    from simlunar.render.transient import TransientOptions

    backend.init()
    n_beams, batch = (256, 256) if smoke else (N_BEAMS, BATCH)
    n_order, flash_px = (2_000, 16) if smoke else (100_000, 128)
    precision = _plane_precision(20 if smoke else 200)
    t, pose, fov, Camera = _setup()
    guide = Camera(Intrinsics.from_fov(512, 512, fov), pose)
    rng = np.random.default_rng(0)
    _, d = guide.rays(rng.uniform(0, 512, (n_beams, 2)))
    sun = SunLight(elevation=np.radians(20.0), azimuth=np.radians(90.0))
    opts = SteeredBeamOptions(
        footprint=FootprintOptions(1e-3, samples=FOOTPRINT_SAMPLES),
        detector=DetectorOptions(signal_photons=2e6, background_photons_per_s=1e9),
        steering=SteeringOptions(),
        order=OrderOptions(method="given"),  # ordering is timed at full size below
        batch=batch,
    )
    cap = beam_capture(t, pose.position, options=opts, sun=sun)
    steered_beam_scan(cap, d[:batch], options=opts, rng=0)  # warm-up: kernels compiled
    t0 = time.perf_counter()
    scan = steered_beam_scan(cap, d, options=opts, rng=1)
    ours_s = time.perf_counter() - t0
    cap.cast(d)
    t0 = time.perf_counter()
    truth = cap.cast(d)
    reference_s = time.perf_counter() - t0
    err = np.abs(scan.ranges - truth)[scan.valid]

    big = pose.rotation @ np.vstack([rng.uniform(-0.4, 0.4, (2, n_order)), np.ones(n_order)])
    ang = pointing_angles((big / np.linalg.norm(big, axis=0)).T, pose)
    order_scan(ang[:500], steering=opts.steering)  # warm-up: numba kernels loaded
    t0 = time.perf_counter()
    order = order_scan(ang, steering=opts.steering)
    order_100k_s = time.perf_counter() - t0
    planner_100k = scan_timing(ang, options=opts.steering).total_s
    ordered_100k = scan_timing(ang, order, options=opts.steering).total_s

    flash_cam = Camera(Intrinsics.from_fov(flash_px, flash_px, fov), pose)
    fopts = FlashOptions(transient=TransientOptions(spp=64))
    bins = flash_window(flash_cam, options=fopts)
    flash_scan(t, flash_cam, options=fopts, rng=0)  # warm-up
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.perf_counter()
    flash_scan(t, flash_cam, options=fopts, rng=0)
    flash_s = time.perf_counter() - t0
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    beams_per_s = n_beams / ours_s
    return {
        "reference_s": round(reference_s, 4),
        "ours_s": round(ours_s, 3),
        **precision,
        "smoke": smoke,
        "beams": n_beams,
        "batch": batch,
        "oversample": opts.transient.oversample,
        "footprint_samples": FOOTPRINT_SAMPLES,
        "terrain": f"aerial_1 x{SCALE} ({t.shape[0]}x{t.shape[1]} cells)",
        "beams_per_s": round(beams_per_s, 1),
        "orderings": n_order,
        "order_100k_s": round(order_100k_s * 1e5 / n_order, 2),
        "scan_100k_s": round(1e5 / beams_per_s + order_100k_s * 1e5 / n_order, 2),
        "valid_fraction": round(float(scan.valid.mean()), 4),
        "median_abs_range_error_m": round(float(np.median(err)), 4),
        "scan_16k_simulated_s_planner_order": round(scan.seconds, 2),
        "scan_100k_simulated_s_planner_order": round(planner_100k, 1),
        "scan_100k_simulated_s_ordered": round(ordered_100k, 1),
        "flash_px": flash_px,
        "flash_128_s": round(flash_s, 3),
        "flash_bins": bins.count,
        "flash_128_mb": round(
            flash_px**2 * bins.count * fopts.transient.oversample * 4 * 4 / 2**20, 1
        ),
        "flash_rss_mb": round((rss1 - rss0) / 1024, 1),
        "variant": backend.info().variant,
    }


def lidar_receiver(*, smoke: bool = False) -> dict:
    from simlunar.geometry import Intrinsics
    from simlunar.lidar import DetectorOptions, RangeOptions
    from simlunar.lidar.apd import ApdOptions
    from simlunar.lidar.flash import FlashOptions, flash_window, read_flash
    from simlunar.render import backend
    from simlunar.render.lights import SunLight
    from simlunar.render.transient import TransientOptions, flash_frame

    backend.init()
    px = 16 if smoke else 128
    t, pose, fov, Camera = _setup()
    cam = Camera(Intrinsics.from_fov(px, px, fov), pose)
    sun = SunLight(elevation=np.radians(20.0), azimuth=np.radians(90.0))
    ideal_apd = ApdOptions(gain=100.0, ionisation_ratio=0.02)
    full_apd = ApdOptions(gain=100.0, ionisation_ratio=0.02, full_scale_pe=1000.0, bits=12,
                          agc_target=0.5)  # fmt: skip

    def options(apd, edge):
        det = DetectorOptions(signal_photons=2.5e6, background_photons_per_s=1e9, pulses=16,
                              apd=apd)  # fmt: skip
        return FlashOptions(detector=det, transient=TransientOptions(spp=64),
                            ranging=RangeOptions(edge_sigma=edge))  # fmt: skip

    ideal, full = options(ideal_apd, 0.0), options(full_apd, 3.0)
    bins = flash_window(cam, options=full)
    flash_frame(t, cam, bins=bins, options=full.transient, sun=sun)  # warm-up: kernels compiled
    t0 = time.perf_counter()
    frame = flash_frame(t, cam, bins=bins, options=full.transient, sun=sun)
    render_s = time.perf_counter() - t0
    read_flash(frame, cam, options=full, rng=0)  # warm-up
    t0 = time.perf_counter()
    ref = read_flash(frame, cam, options=ideal, rng=1)
    reference_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    got = read_flash(frame, cam, options=full, rng=1)
    ours_s = time.perf_counter() - t0
    both = ref.valid & got.valid
    return {
        "reference_s": round(reference_s, 4),
        "ours_s": round(ours_s, 4),
        "smoke": smoke,
        "flash_px": px,
        "flash_bins": bins.count,
        "render_s": round(render_s, 3),
        "render_share": round(render_s / (render_s + ours_s), 3),
        "valid_fraction_full": round(float(got.valid.mean()), 4),
        "valid_fraction_ideal": round(float(ref.valid.mean()), 4),
        "median_abs_range_diff_m": round(
            float(np.median(np.abs(got.ranges - ref.ranges)[both])), 4
        ),
        "agc_probe_seconds": round(got.seconds - ref.seconds, 6),
        "variant": backend.info().variant,
    }


def micromirror_frames(*, smoke: bool = False) -> dict:
    from unittest import mock

    from simlunar.geometry import Intrinsics
    from simlunar.lidar import DetectorOptions
    from simlunar.lidar.flash import FlashOptions
    from simlunar.render import backend
    from simlunar.render import flash_lidar as fl
    from simlunar.render.lights import SunLight
    from simlunar.render.transient import TransientOptions, flash_frame

    backend.init()
    px, rx = (16, 8) if smoke else (128, 32)
    t, pose, fov, Camera = _setup()
    cam = Camera(Intrinsics.from_fov(px, px, fov), pose)
    sun = SunLight(elevation=np.radians(20.0), azimuth=np.radians(90.0))
    det = DetectorOptions(signal_photons=2e7, background_photons_per_s=1e9, pulses=4)
    opts = FlashOptions(detector=det, transient=TransientOptions(spp=128))
    rr, cc = np.mgrid[0:px, 0:px]
    uv = np.c_[cc.ravel(), rr.ravel()] + 0.5  # every guide pixel: (px / rx)^2 frames

    def scan():
        return fl.micromirror_flash(t, cam, uv, options=opts, receiver_shape=(rx, rx), rng=0,
                                    scene={"sun": sun})  # fmt: skip

    class _Fresh:
        """The path before: every frame a freshly loaded scene and sun image."""

        def __init__(self, terrain, camera, **kw):
            self.args, self.kw = (terrain, camera), kw

        def render(self, pattern=None):
            kw = dict(self.kw)
            if pattern is not None:
                kw["projector"] = fl.ProjectorLight(kw["projector"].projector, pattern,
                                                    scale=kw["projector"].scale)  # fmt: skip
            return flash_frame(*self.args, **kw)

    scan()  # warm-up: kernels compiled
    t0 = time.perf_counter()
    ours = scan()
    ours_s = time.perf_counter() - t0
    with mock.patch.object(fl, "PatternFrames", _Fresh):
        t0 = time.perf_counter()
        ref = scan()
        reference_s = time.perf_counter() - t0
    return {
        "reference_s": round(reference_s, 3),
        "ours_s": round(ours_s, 3),
        "smoke": smoke,
        "guide_px": px,
        "receiver_px": rx,
        "frames": int(ours.frames),
        "terrain_cells": int(t.heights.size),
        "same_ranges": bool(np.array_equal(ours.ranges, ref.ranges, equal_nan=True)),
        "variant": backend.info().variant,
    }


BENCHMARKS = {
    "lidar": lidar,
    "lidar_receiver": lidar_receiver,
    "micromirror_frames": micromirror_frames,
}
