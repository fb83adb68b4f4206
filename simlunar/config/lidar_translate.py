"""Configuration -> library objects for the LIDAR study: the sensor options (pulse, detector,
ranging, transient render, steering or receiver) in SI units, the hazard options and the
study options."""

from __future__ import annotations

import dataclasses

from simlunar.config.derived import reconstruction_mapping
from simlunar.config.lidar import HardwareCfg, HazardCfg, LidarOptionsCfg, MotionCfg
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
from simlunar.lidar.apd import ApdOptions
from simlunar.lidar.flash import FlashOptions
from simlunar.lidar.gate import GateOptions
from simlunar.lidar.hardware import INSTRUMENTS, LidarHardware
from simlunar.lidar.returns import TransientOptions
from simlunar.lidar.scan import SteeredBeamOptions, with_hardware
from simlunar.lidar.trajectory import Navigation, PlatformMotion
from simlunar.metrics.hazard import HazardOptions
from simlunar.metrics.safe_site import SiteOptions
from simlunar.sensors.lidar import FlashLidarOptions
from simlunar.sensors.micromirror import MicromirrorOptions
from simlunar.study.lidar import LidarStudyOptions, SensorFit

__all__ = [
    "hazard_options",
    "lidar_hardware",
    "lidar_options",
    "lidar_sensor_options",
    "motion_options",
]


#: YAML key of :class:`~simlunar.config.lidar.HardwareCfg` -> (LidarHardware field, SI factor)
_HARDWARE_SI = {
    "pulse_energy_uj": ("pulse_energy_j", 1e-6),
    "wavelength_nm": ("wavelength_m", 1e-9),
    "pulse_fwhm_ns": ("pulse_fwhm_s", 1e-9),
    "jitter_ns": ("jitter_s", 1e-9),
    "pulse_rate_hz": ("pulse_rate_hz", 1.0),
    "aperture_diameter_mm": ("aperture_diameter_m", 1e-3),
    "optics_efficiency": ("optics_efficiency", 1.0),
    "detector_efficiency": ("detector_efficiency", 1.0),
    "filter_bandwidth_nm": ("filter_bandwidth_m", 1e-9),
    "divergence_urad": ("divergence_rad", 1e-6),
    "field_urad": ("field_rad", 1e-6),
    "dark_count_rate_hz": ("dark_count_rate_hz", 1.0),
    "solar_irradiance_w_m2_nm": ("solar_irradiance_w_m2_nm", 1.0),
}


def lidar_hardware(o: LidarOptionsCfg, sensor: str) -> LidarHardware | None:
    """The instrument of a config (preset + hardware overrides, SI) or None where the expert
    photon scales are used (set, or a micromirror flash without an instrument or hardware
    keys)."""
    d = o.detector
    expert = any(getattr(d, k) is not None for k in type(d).model_fields if k.startswith("expert_"))
    if expert or (
        sensor == "micromirror_flash" and o.instrument is None and o.hardware == HardwareCfg()
    ):
        return None
    if o.instrument is not None:
        base = INSTRUMENTS[o.instrument]
    else:  # generic hardware timed and steered by the pulse and sensor blocks
        rate = {"flash": o.flash.pulse_rate_hz, "micromirror_flash": o.micromirror.pulse_rate_hz}
        rate = rate.get(sensor, o.steered_beam.pulse_rate_hz)
        base = LidarHardware(
            pulse_fwhm_s=o.pulse.fwhm_ns * 1e-9,
            jitter_s=o.pulse.jitter_ns * 1e-9,
            pulse_rate_hz=rate,
            divergence_rad=o.steered_beam.divergence_mrad * 1e-3,
            field_rad=o.steered_beam.divergence_mrad * 1e-3,
        )
    over = {
        _HARDWARE_SI[k][0]: v * _HARDWARE_SI[k][1]
        for k, v in o.hardware.model_dump().items()
        if v is not None
    }
    return dataclasses.replace(base, **over)


def _lidar_common(o: LidarOptionsCfg, seed: int) -> dict:
    """Pulse, detector, ranging and transient options (SI) shared by the LIDARs."""
    d = o.detector
    dead = float("inf") if d.dead_time_ns is None else d.dead_time_ns * 1e-9
    expert = {}
    if d.expert_signal_photons is not None:
        expert["signal_photons"] = d.expert_signal_photons
    if d.expert_background_photons_per_s is not None:
        expert["background_photons_per_s"] = d.expert_background_photons_per_s
    if d.expert_dark_count_rate_hz is not None:
        expert["dark_count_rate_hz"] = d.expert_dark_count_rate_hz
    return {
        "pulse": PulseOptions(fwhm_s=o.pulse.fwhm_ns * 1e-9, jitter_s=o.pulse.jitter_ns * 1e-9),
        "detector": DetectorOptions(
            pulses=d.pulses,
            dead_time_s=dead,
            apd=None if d.apd is None else ApdOptions(**d.apd.model_dump()),
            **expert,
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
        "gate": GateOptions(**o.gate.model_dump()),
    }


def lidar_sensor_options(study: LidarStudyCfg, *, seed: int = 0):
    """The options object of the study's LIDAR (:data:`simlunar.sensors.SENSORS`) in SI units;
    ``seed``: the transient renderer's sampler seed (the unit's render seed)."""
    o = study.options
    common = _lidar_common(o, seed)
    hardware = lidar_hardware(o, study.sensor)
    if study.sensor == "steered_beam":
        b = o.steered_beam
        beam = SteeredBeamOptions(
            footprint=FootprintOptions(b.divergence_mrad * 1e-3, b.profile, b.footprint_rays),
            steering=SteeringOptions(
                max_rate_rad_s=b.max_rate_rad_s,
                max_accel_rad_s2=b.max_accel_rad_s2,
                settle_s=b.settle_ms * 1e-3,
                pulse_rate_hz=b.pulse_rate_hz,
                pulses_per_point=b.pulses_per_point,
                model=b.model,
                line_pitch_rad=None if b.line_pitch_mrad is None else b.line_pitch_mrad * 1e-3,
            ),
            motion=motion_options(o.motion),
            order=OrderOptions(method=b.order),
            window_m=b.window_m,
            batch=b.batch,
            **common,
        )
        return beam if hardware is None else with_hardware(beam, hardware)
    if study.sensor == "flash":
        f = o.flash
        flash = FlashOptions(pulse_rate_hz=f.pulse_rate_hz, **common)
        flash = flash if hardware is None else with_hardware(flash, hardware)
        w, h = f.receiver_px
        return FlashLidarOptions(flash, receiver_px=(h, w), revisits=f.revisits, zoom=f.zoom,
                                 revisit_from=f.revisit_from, range_weight=f.range_weight,
                                 repoint_s=f.repoint_ms * 1e-3,
                                 motion=motion_options(o.motion))  # fmt: skip
    m = o.micromirror
    w, h = m.receiver_px
    mm = FlashOptions(pulse_rate_hz=m.pulse_rate_hz, **common)
    mm = mm if hardware is None else with_hardware(mm, hardware)
    return MicromirrorOptions(mm, (h, w), motion=motion_options(o.motion))


def motion_options(cfg: MotionCfg | None) -> PlatformMotion | None:
    """:class:`~simlunar.lidar.trajectory.PlatformMotion` of a config (None: at rest)."""
    if cfg is None:
        return None
    v = (0.0, 0.0, 0.0)
    if cfg.kind == "descent":
        v = (cfg.horizontal_m_s[0], cfg.horizontal_m_s[1], -cfg.descent_rate_m_s)
    nav = Navigation(cfg.compensation, cfg.position_noise_m, cfg.attitude_noise_urad * 1e-6)
    return PlatformMotion(v, cfg.attitude_jitter_urad * 1e-6, cfg.jitter_bandwidth_hz, nav,
                          cfg.retarget)  # fmt: skip


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
        planner_opts={n: planner_kwargs(p.strategy or n, p) for n, p in study.planner_opts.items()},
        strategies={n: p.strategy for n, p in study.planner_opts.items() if p.strategy},
        fits={
            n: SensorFit(p.fit.kind, p.fit.reference, p.fit.frames)
            for n, p in study.planner_opts.items()
            if p.fit is not None
        },
        hazard=hazard_options(study.hazard),
        safe_site=None if study.safe_site is None else SiteOptions(**study.safe_site.model_dump()),
        reconstructions=reconstruction_mapping(study.reconstructions),
    )
