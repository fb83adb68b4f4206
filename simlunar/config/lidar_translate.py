"""Configuration -> library objects for the LIDAR study: the sensor options (pulse, detector,
ranging, transient render, steering or receiver) in SI units, the hazard options and the
study options."""

from __future__ import annotations

import dataclasses

from simlunar.config.derived import reconstruction_mapping
from simlunar.config.lidar import (
    BLOCKS,
    FIT,
    HardwareCfg,
    HazardCfg,
    LidarOptionsCfg,
    MotionCfg,
    instrument_hardware,
)
from simlunar.config.studies import LidarStudyCfg
from simlunar.config.translate import planner_kwargs
from simlunar.lidar.hardware import LidarHardware
from simlunar.lidar.scan import SteeredBeamOptions, generic_hardware, with_hardware
from simlunar.lidar.trajectory import PlatformMotion
from simlunar.metrics.hazard import HazardOptions
from simlunar.metrics.landing import LandingOptions
from simlunar.metrics.safe_site import SiteOptions
from simlunar.study.lidar import LidarStudyOptions

__all__ = [
    "hazard_options",
    "landing_options",
    "lidar_hardware",
    "lidar_options",
    "lidar_sensor_options",
    "motion_options",
]


def lidar_hardware(o: LidarOptionsCfg, sensor: str, options=None) -> LidarHardware | None:
    """The instrument of a config (preset + hardware overrides, SI) or None where the expert
    photon scales are used (set, or a micromirror flash without an instrument or hardware
    keys). Without an instrument: the generic hardware of the sensor's ``options`` (its
    pulse, rate and divergence, :func:`~simlunar.lidar.scan.generic_hardware`) with the
    hardware overrides."""
    d = o.detector
    expert = any(getattr(d, k) is not None for k in type(d).model_fields if k.startswith("expert_"))
    if expert or (
        sensor == "micromirror_flash" and o.instrument is None and o.hardware == HardwareCfg()
    ):
        return None
    if o.instrument is not None:
        return instrument_hardware(o)
    base = generic_hardware(options)
    return dataclasses.replace(base, **BLOCKS["hardware"].library(o.hardware, "hardware"))


def _lidar_common(o: LidarOptionsCfg, seed: int) -> dict:
    """Pulse, detector, ranging, transient and gate options (SI) shared by the LIDARs."""
    return {
        "pulse": BLOCKS["pulse"].options(o.pulse),
        "detector": BLOCKS["detector"].options(o.detector),
        "ranging": BLOCKS["ranging"].options(o.ranging),
        "transient": BLOCKS["transient"].options(o.transient, seed=seed),
        "bin_range_m": o.bin_range_m,
        "margin_m": o.margin_m,
        "gate": BLOCKS["gate"].options(o.gate),
    }


def lidar_sensor_options(study: LidarStudyCfg, *, seed: int = 0):
    """The options object of the study's LIDAR (:data:`simlunar.sensors.SENSORS`) in SI units;
    ``seed``: the transient renderer's sampler seed (the unit's render seed)."""
    o = study.options
    common = _lidar_common(o, seed)
    motion = motion_options(o.motion)
    if study.sensor == "steered_beam":
        b, cfg = BLOCKS["steered_beam"], o.steered_beam
        beam = SteeredBeamOptions(
            footprint=b.options(cfg, "footprint"),
            steering=b.options(cfg, "steering"),
            order=b.options(cfg, "order"),
            motion=motion,
            **b.library(cfg, "beam"),
            **common,
        )
        hardware = lidar_hardware(o, study.sensor, beam)
        return beam if hardware is None else with_hardware(beam, hardware)
    name = "flash" if study.sensor == "flash" else "micromirror"
    b, cfg = BLOCKS[name], getattr(o, name)
    flash = b.options(cfg, "flash", **common)
    hardware = lidar_hardware(o, study.sensor, flash)
    flash = flash if hardware is None else with_hardware(flash, hardware)
    sensor = b.library(cfg, "sensor", hardware=hardware)
    return b.parts["sensor"].options(**sensor, flash=flash, motion=motion)


def motion_options(cfg: MotionCfg | None) -> PlatformMotion | None:
    """:class:`~simlunar.lidar.trajectory.PlatformMotion` of a config (None: at rest): the
    block's keys, its navigation, and the velocity from ``kind``, ``descent_rate_m_s`` and
    ``horizontal_m_s``."""
    if cfg is None:
        return None
    v = (0.0, 0.0, 0.0)
    if cfg.kind == "descent":
        v = (cfg.horizontal_m_s[0], cfg.horizontal_m_s[1], -cfg.descent_rate_m_s)
    b = BLOCKS["motion"]
    return b.options(cfg, "motion", velocity_m_s=v, navigation=b.options(cfg, "navigation"))


def hazard_options(cfg: HazardCfg | None) -> HazardOptions | None:
    """:class:`~simlunar.metrics.hazard.HazardOptions` of a config (None: no hazard scores)."""
    return None if cfg is None else HazardOptions(**cfg.model_dump())


def landing_options(cfg) -> LandingOptions | None:
    """:class:`~simlunar.metrics.landing.LandingOptions` of a ``study.landing`` block (None: no
    landing scores)."""
    if cfg is None:
        return None
    d = cfg.model_dump()
    return LandingOptions(**{**d, "rock_heights_m": tuple(d["rock_heights_m"])})


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
        fits={n: FIT.options(p.fit) for n, p in study.planner_opts.items() if p.fit is not None},
        hazard=hazard_options(study.hazard),
        safe_site=None if study.safe_site is None else SiteOptions(**study.safe_site.model_dump()),
        landing=landing_options(study.landing),
        reconstructions=reconstruction_mapping(study.reconstructions),
    )
