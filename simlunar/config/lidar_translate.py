"""Configuration -> library objects for the LIDAR study: the sensor options (pulse, detector,
ranging, transient render, steering or receiver) in SI units, the hazard options and the
study options."""

from __future__ import annotations

from simlunar.config.lidar import HazardCfg, LidarOptionsCfg
from simlunar.config.studies import (
    LidarStudyCfg,
)
from simlunar.config.translate import planner_kwargs
from simlunar.lidar import (
    DetectorOptions,
    FootprintOptions,
    OrderOptions,
    PulseOptions,
    RangeOptions,
    SteeringOptions,
)
from simlunar.metrics.hazard import HazardOptions
from simlunar.render.lidar_scan import FlashOptions, SteeredBeamOptions
from simlunar.render.transient import TransientOptions
from simlunar.sensors.lidar import FlashLidarOptions, MicromirrorOptions
from simlunar.study.lidar import LidarStudyOptions

__all__ = ["hazard_options", "lidar_options", "lidar_sensor_options"]


def _lidar_common(o: LidarOptionsCfg, seed: int) -> dict:
    """Pulse, detector, ranging and transient options (SI) shared by the LIDARs."""
    d = o.detector
    dead = float("inf") if d.dead_time_ns is None else d.dead_time_ns * 1e-9
    return {
        "pulse": PulseOptions(fwhm_s=o.pulse.fwhm_ns * 1e-9, jitter_s=o.pulse.jitter_ns * 1e-9),
        "detector": DetectorOptions(
            signal_photons=d.signal_photons,
            background_photons_per_s=d.background_photons_per_s,
            dark_count_rate_hz=d.dark_count_rate_hz,
            pulses=d.pulses,
            dead_time_s=dead,
        ),
        "ranging": RangeOptions(**o.ranging.model_dump()),
        "transient": TransientOptions(
            spp=o.transient.spp,
            max_depth=o.transient.max_depth,
            seed=seed,
            laser_intensity=o.transient.laser_intensity_w_sr,
            oversample=o.transient.oversample,
        ),
        "bin_range_m": o.bin_range_m,
        "margin_m": o.margin_m,
    }


def lidar_sensor_options(study: LidarStudyCfg, *, seed: int = 0):
    """The options object of the study's LIDAR (:data:`simlunar.sensors.SENSORS`) in SI units;
    ``seed``: the transient renderer's sampler seed (the unit's render seed)."""
    o = study.options
    common = _lidar_common(o, seed)
    if study.sensor == "steered_beam":
        b = o.steered_beam
        return SteeredBeamOptions(
            footprint=FootprintOptions(b.divergence_mrad * 1e-3, b.profile, b.footprint_rays),
            steering=SteeringOptions(
                max_rate_rad_s=b.max_rate_rad_s,
                max_accel_rad_s2=b.max_accel_rad_s2,
                settle_s=b.settle_ms * 1e-3,
                pulse_rate_hz=b.pulse_rate_hz,
                pulses_per_point=b.pulses_per_point,
            ),
            order=OrderOptions(method=b.order),
            window_m=b.window_m,
            batch=b.batch,
            **common,
        )
    if study.sensor == "flash":
        f = o.flash
        flash = FlashOptions(pulse_rate_hz=f.pulse_rate_hz, **common)
        w, h = f.receiver_px
        return FlashLidarOptions(flash, receiver_px=(h, w), revisits=f.revisits, zoom=f.zoom)
    m = o.micromirror
    w, h = m.receiver_px
    return MicromirrorOptions(FlashOptions(pulse_rate_hz=m.pulse_rate_hz, **common), (h, w))


def hazard_options(cfg: HazardCfg | None) -> HazardOptions | None:
    """:class:`~simlunar.metrics.hazard.HazardOptions` of a config (None: no hazard scores)."""
    return None if cfg is None else HazardOptions(**cfg.model_dump())


def lidar_options(study: LidarStudyCfg, *, seed: int = 0) -> LidarStudyOptions:
    """:class:`~simlunar.study.lidar.LidarStudyOptions` of a config (``seed``: the transient
    renderer's sampler seed)."""
    return LidarStudyOptions(
        sensor=study.sensor,
        sensor_options=lidar_sensor_options(study, seed=seed),
        planners=tuple(study.planners),
        densities=tuple(study.densities),
        trials=study.trials,
        metrics=tuple(study.metrics),
        planner_opts={n: planner_kwargs(n, p) for n, p in study.planner_opts.items()},
        hazard=hazard_options(study.hazard),
    )
