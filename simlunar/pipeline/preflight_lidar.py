"""Preflight checks of a LIDAR study's unit, before anything renders: its transient films
against the frame limit, its options built as the unit will build them, and a steered beam's
gate prior against its window; and the rays of a perspective camera config that the camera and
gate checks share (:mod:`simlunar.pipeline.preflight` runs them for every unit)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from simlunar.config import translate
from simlunar.config.lidar import receiver_wh
from simlunar.config.lidar_translate import lidar_options
from simlunar.errors import ConfigError
from simlunar.geometry import Camera
from simlunar.lidar.flash import micromirror_sampling
from simlunar.lidar.gate import prior_ranges
from simlunar.pipeline.inputs import TerrainFacts, check_size

__all__ = [
    "TRANSIENT_CHANNELS",
    "check_gate_prior",
    "check_lidar",
    "check_lidar_options",
    "check_micromirror_sampling",
    "check_time_bins",
    "grid_rays",
    "perspective_camera",
]


def check_lidar(cfg: Any, facts: TerrainFacts) -> None:
    """Every check of this module for one unit's validated config ``cfg``."""
    check_time_bins(cfg.study, facts)
    check_lidar_options(cfg.study)
    check_gate_prior(cfg, facts)
    check_micromirror_sampling(cfg)


def perspective_camera(cam: Any, key: str) -> Camera:
    """The :class:`~simlunar.geometry.Camera` of a perspective camera config, as the unit
    builds it (:func:`simlunar.config.translate.camera`); its errors name ``key``."""
    try:
        return translate.camera(cam, None)
    except ValueError as exc:
        raise ConfigError(f"{key}: {exc}") from None


def grid_rays(camera: Camera, most: int = 64):
    """Rays through a grid of at most ``most`` x ``most`` image points, corners included."""
    h, w = camera.shape
    uu, vv = np.meshgrid(np.linspace(0.0, float(w), min(w, most)),
                         np.linspace(0.0, float(h), min(h, most)))  # fmt: skip
    return camera.rays(np.stack([uu, vv], axis=-1).reshape(-1, 2))


#: time-histogram channels the transient film keeps per pixel and bin (mitransient's RGBA)
TRANSIENT_CHANNELS = 4


def check_time_bins(s: Any, facts: TerrainFacts) -> None:
    """A LIDAR study's transient films (pixels x time bins x channels) against
    :data:`MAX_FRAME_PIXELS`, before anything is rendered.

    A steered beam renders ``batch`` beams over ``window_m``; a flash receiver covers the
    terrain's depth span in view, bounded here by the diagonal of its bounding box, plus the
    margin on both sides (its exact window is known only after the guide render).
    """
    o = s.options
    if s.sensor == "steered_beam":
        bins = math.ceil(o.steered_beam.window_m / o.bin_range_m)
        pixels = o.steered_beam.batch
        what = f"{pixels} beams"
    else:
        xmin, xmax, ymin, ymax = facts.extent
        span = math.hypot(xmax - xmin, ymax - ymin, facts.zmax - facts.zmin)
        bins = math.ceil((span + 2 * o.margin_m) / o.bin_range_m)
        w, h = receiver_wh(o, "flash" if s.sensor == "flash" else "micromirror")
        pixels = w * h
        what = f"{w} x {h} receiver pixels"
    ov = o.transient.oversample  # rendered on oversample finer bins (docs/lidar.md)
    check_size(
        "study.options.bin_range_m",
        f"{what} x {bins} time bins x {TRANSIENT_CHANNELS} channels x {ov} (oversampled)",
        pixels * bins * TRANSIENT_CHANNELS * ov,
        "SIMLUNAR_MAX_FRAME_PIXELS",
    )


def check_lidar_options(study: Any) -> None:
    """Build a LIDAR study's library options as the unit will, so a rule of an options class
    that the schema does not state (a bound of :mod:`simlunar.lidar`'s options, a rule across
    fields) is one line before any render instead of a traceback in the unit."""
    try:
        lidar_options(study)
    except (ValueError, TypeError) as exc:
        raise ConfigError(f"study.options: {' '.join(str(exc).split())}") from None


def check_gate_prior(cfg: Any, facts: TerrainFacts) -> None:
    """A steered beam's gate prior (the datum's error, the slope) must fit its window, as the
    scan requires (:func:`simlunar.lidar.scan.steered_beam_scan` refuses it in the unit, after
    the guide render): the prior's largest half-width over the guide camera's rays (corners
    included), on the plane through the terrain's lowest point (the farthest, widest one),
    plus ``margin_m`` on both sides, within ``window_m``."""
    s = cfg.study
    cam = cfg.render.camera
    if s.sensor != "steered_beam" or getattr(cam, "kind", None) != "perspective":
        return
    opts = lidar_options(s).sensor_options
    g = opts.gate
    if g.datum_sigma_m == 0 and g.max_slope_rad == 0:
        return
    camera = perspective_camera(cam, "render.camera")
    _, d = grid_rays(camera)
    datum = facts.zmin if g.altimeter else g.datum_z_m
    lo, hi = prior_ranges(camera.position, d, datum_z=datum, boresight=camera.pose.forward,
                          options=g)  # fmt: skip
    half = 0.5 * float(np.max(hi - lo))
    need = 2.0 * (opts.margin_m + half)
    if not opts.window_m > need:
        raise ConfigError(
            f"study.options.steered_beam.window_m: {opts.window_m:g} m cannot hold the gate "
            f"prior: it needs more than {need:.3g} m (2 x (margin_m {opts.margin_m:g} m + the "
            f"prior's largest half-width over the view, {half:.3g} m)); widen window_m or "
            "narrow gate.max_slope_deg / gate.datum_sigma_m"
        )


def check_micromirror_sampling(cfg: Any) -> None:
    """A micromirror flash's render samples per lit guide pixel
    (:func:`~simlunar.lidar.flash.micromirror_sampling`), as its sensor checks them after the
    guide render: one line before it."""
    s, cam = cfg.study, cfg.render.camera
    if s.sensor != "micromirror_flash" or not hasattr(cam, "width"):
        return  # an orthographic guide view is refused by the sensor itself
    opts = lidar_options(s).sensor_options
    try:
        micromirror_sampling((cam.height, cam.width), opts.receiver_px, opts.flash.transient.spp)
    except ValueError as exc:
        raise ConfigError(f"study.options: {exc}") from None
