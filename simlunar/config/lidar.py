"""LIDAR sections of the schema: the sensor options of a ``lidar`` study (docs/lidar.md).

Keys carry their unit (``_ns``, ``_mrad``, ``_deg_s``); :mod:`simlunar.config.translate`
turns them into the library's SI options (:class:`~simlunar.render.lidar_scan.SteeredBeamOptions`,
:class:`~simlunar.render.lidar_scan.FlashOptions`, ...). Only the block of the study's sensor
may differ from its defaults (``steered_beam``, ``flash`` or ``micromirror``).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, PositiveInt, field_validator

from simlunar.config.fields import Deg, Metres, _Model

__all__ = [
    "DetectorCfg",
    "FlashCfg",
    "HazardCfg",
    "LidarOptionsCfg",
    "MicromirrorCfg",
    "PulseCfg",
    "RangingCfg",
    "SteeredBeamCfg",
    "TransientCfg",
]


class PulseCfg(_Model):
    """Laser pulse and detector timing (:class:`simlunar.lidar.PulseOptions`)."""

    fwhm_ns: float = Field(2.0, gt=0, description="pulse full width at half maximum (ns)")
    jitter_ns: float = Field(0.0, ge=0, description="detector timing jitter, RMS (ns)")


class DetectorCfg(_Model):
    """Photon scales and detector (:class:`simlunar.lidar.DetectorOptions`)."""

    signal_photons: float = Field(
        100.0, gt=0, description="photons per unit rendered return radiance per pulse"
    )
    background_photons_per_s: float = Field(
        1e9, ge=0, description="photons/s per unit rendered sun radiance"
    )
    dark_count_rate_hz: float = Field(0.0, ge=0, description="dark counts (1/s)")
    pulses: PositiveInt = Field(
        1, description="pulses per flash frame (a steered beam uses pulses_per_point)"
    )
    dead_time_ns: float | None = Field(
        0.0,
        ge=0,
        description="SPAD dead time (ns); 0 = linear mode, null = one detection per pulse",
    )


class RangingCfg(_Model):
    """Range extraction (:class:`simlunar.lidar.RangeOptions`)."""

    method: Literal["matched", "peak"] = "matched"
    which: Literal["strongest", "first", "last"] = "strongest"
    threshold_sigma: float = Field(5.0, gt=0, description="detection threshold (Gaussian sigmas)")
    min_photons: float = Field(3.0, ge=0, description="least signal photons of a return")
    fit: Literal["ml", "parabola"] = Field(
        "ml", description="sub-bin position: maximum-likelihood pulse fit or parabola vertex"
    )


class TransientCfg(_Model):
    """Transient rendering of the returns (:class:`simlunar.render.transient.TransientOptions`);
    its sampler seed is the unit's render seed."""

    spp: PositiveInt = Field(64, description="samples per receiver pixel of a flash frame")
    max_depth: int = Field(2, ge=2, le=16, description="path depth (2 = direct only)")
    laser_intensity_w_sr: float = Field(1.0, gt=0, description="point laser intensity (W/sr)")
    oversample: PositiveInt = Field(
        2, le=16, description="rendered time bins per output bin (keeps sub-bin arrival times)"
    )


class SteeredBeamCfg(_Model):
    """A gimbaled altimeter / galvanometer scanner at the guide camera
    (:class:`simlunar.render.lidar_scan.SteeredBeamOptions`)."""

    divergence_mrad: float = Field(1.0, gt=0, description="full beam divergence (mrad)")
    profile: Literal["gaussian", "uniform"] = "gaussian"
    footprint_rays: PositiveInt = Field(16, description="rays traced per beam")
    max_rate_rad_s: float = Field(2.0, gt=0, description="slew rate limit per axis (rad/s)")
    max_accel_rad_s2: float = Field(50.0, gt=0, description="acceleration per axis (rad/s^2)")
    settle_ms: float = Field(1.0, ge=0, description="settle time after every move (ms)")
    pulse_rate_hz: float = Field(10_000.0, gt=0, description="pulse repetition rate (1/s)")
    pulses_per_point: PositiveInt = Field(1, description="pulses fired at each pointing")
    order: Literal["nn2opt", "raster", "given"] = Field(
        "nn2opt", description="visiting order: nearest neighbour + 2-opt, raster, the planner's"
    )
    window_m: Metres = Field(8.0, gt=0, description="range window of a rendered batch (m)")
    batch: PositiveInt = Field(4096, description="beams per render launch (memory only)")


class FlashCfg(_Model):
    """A flash LIDAR co-boresighted with the guide camera (:class:`simlunar.sensors.FlashLidar`)."""

    receiver_px: tuple[PositiveInt, PositiveInt] = Field(
        (64, 64), description="receiver (width, height); the guide camera's aspect"
    )
    pulse_rate_hz: float = Field(30.0, gt=0, description="pulse repetition rate (1/s)")
    revisits: int = Field(
        0, ge=0, le=64, description="plan-directed zoomed frames after the full frame"
    )
    zoom: int = Field(4, ge=2, le=16, description="a revisit sees 1/zoom of the field per axis")


class MicromirrorCfg(_Model):
    """A micromirror-steered flash (:class:`simlunar.sensors.MicromirrorFlash`)."""

    receiver_px: tuple[PositiveInt, PositiveInt] = Field(
        (64, 64), description="receiver (width, height); the guide camera's aspect"
    )
    pulse_rate_hz: float = Field(30.0, gt=0, description="pulse repetition rate (1/s)")


class LidarOptionsCfg(_Model):
    """Options shared by the LIDARs and the block of each sensor."""

    pulse: PulseCfg = Field(default_factory=PulseCfg)
    detector: DetectorCfg = Field(default_factory=DetectorCfg)
    ranging: RangingCfg = Field(default_factory=RangingCfg)
    transient: TransientCfg = Field(default_factory=TransientCfg)
    bin_range_m: Metres = Field(0.05, gt=0, description="range width of a time bin (m)")
    margin_m: Metres = Field(2.0, ge=0, description="range margin of the time window (m)")
    steered_beam: SteeredBeamCfg = Field(default_factory=SteeredBeamCfg)
    flash: FlashCfg = Field(default_factory=FlashCfg)
    micromirror: MicromirrorCfg = Field(default_factory=MicromirrorCfg)


class HazardCfg(_Model):
    """Landing hazards scored as detection precision / recall
    (:class:`simlunar.metrics.hazard.HazardOptions`)."""

    slope_deg: Deg = Field(15.0, gt=0, lt=90, description="largest safe slope")
    relief_m: Metres = Field(0.3, gt=0, description="largest safe height above the local median")
    window_px: int = Field(15, ge=3, le=255, description="median neighbourhood side (odd, px)")
    baseline_px: PositiveInt = Field(2, le=64, description="slope half-baseline (px)")

    @field_validator("window_px")
    @classmethod
    def _odd(cls, v: int) -> int:
        if v % 2 == 0:
            raise ValueError(f"must be odd (a centred window), got {v}")
        return v
