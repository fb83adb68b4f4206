"""LIDAR sections of the schema: the sensor options of a ``lidar`` study (docs/lidar.md).

Keys carry their unit (``_ns``, ``_mrad``, ``_deg_s``); :mod:`simlunar.config.translate`
turns them into the library's SI options (:class:`~simlunar.lidar.scan.SteeredBeamOptions`,
:class:`~simlunar.lidar.flash.FlashOptions`, ...). Only the block of the study's sensor
may differ from its defaults (``steered_beam``, ``flash`` or ``micromirror``).
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import Field, PositiveInt, model_validator

from simlunar.config.fields import Metres, _Model
from simlunar.config.landing import HazardCfg, SafeSiteCfg
from simlunar.config.planners import StrategyOptionsCfg

__all__ = [
    "MAX_BINS",
    "MAX_PHOTONS",
    "ApdCfg",
    "DetectorCfg",
    "FitCfg",
    "FlashCfg",
    "GateCfg",
    "HardwareCfg",
    "HazardCfg",
    "LidarOptionsCfg",
    "LidarPlannerOptsCfg",
    "MicromirrorCfg",
    "MotionCfg",
    "PulseCfg",
    "PulseRateHz",
    "RangingCfg",
    "ReceiverPx",
    "SafeSiteCfg",
    "SteeredBeamCfg",
    "TransientCfg",
]


#: most photons per pulse and unit radiance (and per second of background / dark counts) a
#: detector may be given: the photon counts are Poisson draws, whose sampler (NumPy) refuses a
#: mean above ~1e18, and a pulse of 1e12 photons saturates any real detector many times over
MAX_PHOTONS = 1e12
#: most time bins of one histogram (a rendered batch's window over ``bin_range_m``): each bin
#: is a film channel per beam or receiver pixel, so 1e5 bins x 4096 beams is already 6.5 GB
MAX_BINS = 100_000

#: a pulse repetition rate (1/s): every LIDAR block's ``pulse_rate_hz``
PulseRateHz = Annotated[
    float, Field(ge=1e-3, le=1e9, description="pulse repetition rate (1/s, 1e-3 .. 1e9)")
]
_SidePx = Annotated[int, Field(ge=1, le=8192)]
#: a flash receiver's pixel grid (width, height): ``flash`` and ``micromirror``
ReceiverPx = Annotated[
    tuple[_SidePx, _SidePx],
    Field(description="receiver (width, height), each 1 .. 8192; the guide camera's aspect"),
]


class PulseCfg(_Model):
    """Laser pulse and detector timing (:class:`simlunar.lidar.PulseOptions`)."""

    fwhm_ns: float = Field(
        2.0, gt=0, le=10_000, description="pulse full width at half maximum (ns, at most 10 us)"
    )
    jitter_ns: float = Field(
        0.0, ge=0, le=10_000, description="detector timing jitter, RMS (ns, at most 10 us)"
    )


class HardwareCfg(_Model):
    """The instrument's hardware (:class:`simlunar.lidar.hardware.LidarHardware`): every key
    overrides the chosen ``instrument`` preset's value (unset keys keep it); photons per pulse
    and the sun's background are derived from it (the lidar equation, docs/lidar.md)."""

    pulse_energy_uj: float | None = Field(None, gt=0, description="energy per pulse (uJ)")
    wavelength_nm: float | None = Field(None, gt=0, description="laser wavelength (nm)")
    pulse_fwhm_ns: float | None = Field(None, gt=0, description="pulse FWHM (ns)")
    jitter_ns: float | None = Field(None, ge=0, description="timing jitter, RMS (ns)")
    pulse_rate_hz: float | None = Field(None, gt=0, description="pulse repetition rate (1/s)")
    aperture_diameter_mm: float | None = Field(
        None, gt=0, description="receiver clear aperture (mm)"
    )
    optics_efficiency: float | None = Field(
        None, gt=0, le=1, description="receiver optics transmission, filter included"
    )
    detector_efficiency: float | None = Field(
        None, gt=0, le=1, description="photon detection efficiency"
    )
    filter_bandwidth_nm: float | None = Field(None, gt=0, description="filter bandwidth (nm)")
    divergence_urad: float | None = Field(
        None, gt=0, description="full beam divergence of a steered beam (urad)"
    )
    field_urad: float | None = Field(
        None, gt=0, description="full receiver field of view of a steered beam (urad)"
    )
    dark_count_rate_hz: float | None = Field(None, ge=0, description="dark counts (1/s)")
    solar_irradiance_w_m2_nm: float | None = Field(
        None, gt=0, description="solar spectral irradiance at the wavelength (W m^-2 nm^-1)"
    )


class ApdCfg(_Model):
    """A linear-mode avalanche photodiode (:class:`simlunar.lidar.apd.ApdOptions`)."""

    gain: float = Field(100.0, ge=1, description="mean avalanche gain M")
    ionisation_ratio: float = Field(
        0.02, ge=0, le=1, description="k: Si about 0.02, InGaAs about 0.45 (excess noise)"
    )
    amplifier_noise_pe: float = Field(
        0.5, ge=0, description="amplifier noise per bin and pulse, input-referred (photoelectrons)"
    )
    threshold_pe: float = Field(5.0, ge=0, description="discriminator threshold (photoelectrons)")


class DetectorCfg(_Model):
    """Detector (:class:`simlunar.lidar.DetectorOptions`): pulses per reading, dead time and,
    only without an instrument, the expert photon scales."""

    expert_signal_photons: float | None = Field(
        None,
        gt=0,
        le=MAX_PHOTONS,
        description="EXPERT OVERRIDE of the instrument's link budget: photons per pulse per "
        "unit rendered return radiance (then no instrument / hardware; micromirror: 100)",
    )
    expert_background_photons_per_s: float | None = Field(
        None,
        ge=0,
        le=MAX_PHOTONS * 1e6,
        description="EXPERT OVERRIDE: photons/s per unit rendered sun radiance (default 1e9 "
        "with expert_signal_photons)",
    )
    expert_dark_count_rate_hz: float | None = Field(
        None, ge=0, le=MAX_PHOTONS, description="EXPERT OVERRIDE: dark counts (1/s)"
    )
    pulses: PositiveInt = Field(
        1,
        le=1_000_000,
        description="pulses per flash frame (a steered beam uses pulses_per_point; at most 1e6)",
    )
    dead_time_ns: float | None = Field(
        0.0,
        ge=0,
        description="Geiger-mode SPAD dead time (ns, continuous time); 0 = none, null = one "
        "detection per pulse",
    )
    apd: ApdCfg | None = Field(
        None, description="a linear-mode APD receiver (gain, excess noise, threshold)"
    )

    @model_validator(mode="after")
    def _one_regime(self) -> DetectorCfg:
        if self.apd is not None and self.dead_time_ns != 0:
            raise ValueError("apd: a linear-mode APD has no dead time (set dead_time_ns: 0)")
        return self


class RangingCfg(_Model):
    """Range extraction (:class:`simlunar.lidar.RangeOptions`)."""

    method: Literal["matched", "peak"] = "matched"
    which: Literal["strongest", "first", "last"] = "strongest"
    threshold_sigma: float = Field(5.0, gt=0, description="detection threshold (Gaussian sigmas)")
    min_photons: float = Field(3.0, ge=0, description="least signal photons of a return")
    fit: Literal["ml", "parabola"] = Field(
        "ml", description="sub-bin position: maximum-likelihood pulse fit or parabola vertex"
    )
    pileup_correction: bool = Field(
        True, description="SPAD: refit each return through the dead time (no pile-up bias)"
    )


class TransientCfg(_Model):
    """Transient rendering of the returns (:class:`simlunar.lidar.returns.TransientOptions`);
    its sampler seed is the unit's render seed."""

    spp: PositiveInt = Field(
        64, le=65_536, description="samples per receiver pixel of a flash frame (at most 65536)"
    )
    max_depth: int = Field(2, ge=2, le=16, description="path depth (2 = direct only)")
    laser_intensity_w_sr: float = Field(1.0, gt=0, description="point laser intensity (W/sr)")
    oversample: PositiveInt = Field(
        2, le=16, description="rendered time bins per output bin (keeps sub-bin arrival times)"
    )


class SteeredBeamCfg(_Model):
    """A gimbaled altimeter / galvanometer scanner at the guide camera
    (:class:`simlunar.lidar.scan.SteeredBeamOptions`)."""

    divergence_mrad: float = Field(
        1.0,
        gt=0,
        le=1000 * math.pi / 2,
        description="full beam divergence (mrad; at most pi/2 rad, a cone within a hemisphere)",
    )
    profile: Literal["gaussian", "uniform"] = "gaussian"
    footprint_rays: PositiveInt = Field(
        16, le=4096, description="rays traced per beam (at most 4096)"
    )
    # lower bounds keep every modelled scan time finite (a rate of 1e-300 made it infinite)
    max_rate_rad_s: float = Field(
        2.0, ge=1e-6, description="slew rate limit per axis (rad/s, at least 1e-6)"
    )
    max_accel_rad_s2: float = Field(
        50.0, ge=1e-6, description="acceleration per axis (rad/s^2, at least 1e-6)"
    )
    settle_ms: float = Field(
        1.0, ge=0, le=1e6, description="settle time after every move (ms, at most 1000 s)"
    )
    pulse_rate_hz: PulseRateHz = 10_000.0
    pulses_per_point: PositiveInt = Field(
        1, le=1_000_000, description="pulses fired at each pointing (at most 1e6)"
    )
    order: Literal["nn2opt", "raster", "given"] = Field(
        "nn2opt", description="visiting order: nearest neighbour + 2-opt, raster, the planner's"
    )
    model: Literal["gimbal", "galvanometer", "continuous_raster"] = Field(
        "gimbal",
        description="steering model: stop-and-stare gimbal (trapezoidal axes), stop-and-stare "
        "galvanometer (rate + small-step response settle_ms), continuous raster (lines swept "
        "at max_rate_rad_s, fired on the fly; docs/lidar.md)",
    )
    line_pitch_mrad: float | None = Field(
        None,
        gt=0,
        description="continuous raster: line height (mrad); none = the guide camera's pixel",
    )
    window_m: Metres = Field(
        8.0,
        gt=0,
        description="range window of a rendered batch (m); must exceed 2 x options.margin_m",
    )
    batch: PositiveInt = Field(
        4096, le=1_000_000, description="beams per render launch (memory only; at most 1e6)"
    )


class FlashCfg(_Model):
    """A flash LIDAR co-boresighted with the guide camera (:class:`simlunar.sensors.FlashLidar`)."""

    receiver_px: ReceiverPx = (64, 64)
    pulse_rate_hz: PulseRateHz = 30.0
    revisits: int = Field(
        0, ge=0, le=64, description="plan-directed zoomed frames after the full frame"
    )
    zoom: int = Field(4, ge=2, le=16, description="a revisit sees 1/zoom of the field per axis")
    revisit_from: Literal["plan", "ranges", "both"] = Field(
        "plan",
        description="what directs the revisits: the image plan's tiles, the roughest tiles of "
        "the first frame's own ranges, or both (range_weight)",
    )
    range_weight: float = Field(
        0.5, ge=0, le=1, description="revisit_from both: the ranges' share of a tile's score"
    )
    repoint_ms: float = Field(
        0.0, ge=0, le=1e6, description="time to re-point and re-zoom before each revisit (ms)"
    )


class MicromirrorCfg(_Model):
    """A micromirror-steered flash (:class:`simlunar.sensors.MicromirrorFlash`)."""

    receiver_px: ReceiverPx = (64, 64)
    pulse_rate_hz: PulseRateHz = 30.0


class MotionCfg(_Model):
    """The platform's motion during a steered-beam scan or between flash or micromirror frames
    (:class:`simlunar.lidar.trajectory.PlatformMotion`), starting at the guide camera."""

    kind: Literal["hover", "descent"] = Field("descent", description="hover or descent")
    descent_rate_m_s: float = Field(
        2.0, ge=0, le=1000, description="descent: vertical speed, down (m/s)"
    )
    horizontal_m_s: tuple[float, float] = Field(
        (0.0, 0.0), description="descent: horizontal velocity (x, y) (m/s)"
    )
    attitude_jitter_urad: float = Field(
        0.0, ge=0, le=1e5, description="RMS line-of-sight jitter per axis (urad)"
    )
    jitter_bandwidth_hz: float = Field(
        10.0, gt=0, le=1e5, description="highest frequency of the jitter (Hz)"
    )
    compensation: Literal["exact", "noisy", "start"] = Field(
        "exact",
        description="pose the points are placed with: the true one, the true one plus "
        "navigation noise, or the scan's start (no motion compensation)",
    )
    position_noise_m: float = Field(
        0.0, ge=0, le=1e3, description="noisy: navigation position error per axis, RMS (m)"
    )
    attitude_noise_urad: float = Field(
        0.0, ge=0, le=1e5, description="noisy: pointing knowledge error per axis, RMS (urad)"
    )
    retarget: bool = Field(
        True,
        description="steered beam: re-aim each beam at its planned point on the gate's "
        "reference plane from where the platform is (a micromirror keeps its planned mirrors)",
    )


class FitCfg(_Model):
    """A planner fitted to its sensor (:class:`simlunar.study.lidar.SensorFit`)."""

    kind: Literal["scan_time", "receiver"] = Field(
        "scan_time",
        description="scan_time: the most samples whose tour (visiting order of the sensor) "
        "fits the reference planner's scan time at the same density; receiver (micromirror): "
        "at most `frames` dots per receiver pixel",
    )
    reference: str = Field("grid", description="scan_time: the planner label setting the budget")
    frames: PositiveInt | None = Field(
        None, le=1024, description="receiver: dots per receiver pixel; none = the least for k"
    )


class LidarPlannerOptsCfg(StrategyOptionsCfg):
    """A LIDAR planner label's options: its strategy and planner options, and optionally a
    fit to the sensor."""

    fit: FitCfg | None = Field(None, description="fit the plan to the sensor (docs/lidar.md)")


class GateCfg(_Model):
    """The range gate (:class:`simlunar.lidar.gate.GateOptions`): a reference plane from the
    navigation datum or an altimeter reading; ``margin_m`` must cover the relief about it."""

    datum_z_m: Metres = Field(0.0, description="height of the reference plane (world z, m)")
    altimeter: bool = Field(
        False, description="steered beam: measure the plane along the boresight first"
    )
    max_range_m: Metres = Field(2000.0, gt=0, description="the instrument's largest range (m)")
    min_range_m: Metres = Field(0.1, ge=0, description="the instrument's smallest range (m)")


class LidarOptionsCfg(_Model):
    """Options shared by the LIDARs and the block of each sensor."""

    instrument: (
        Literal["lola_beam", "alhat_flash", "rover_mast_scanner", "micromirror_flash"] | None
    ) = Field(
        None,
        description="instrument preset (docs/lidar.md, Instruments); none = generic hardware "
        "with the pulse, rate and divergence keys; an instrument or hardware key sets them",
    )
    hardware: HardwareCfg = Field(default_factory=HardwareCfg)
    pulse: PulseCfg = Field(default_factory=PulseCfg)
    detector: DetectorCfg = Field(default_factory=DetectorCfg)
    ranging: RangingCfg = Field(default_factory=RangingCfg)
    transient: TransientCfg = Field(default_factory=TransientCfg)
    gate: GateCfg = Field(default_factory=GateCfg)
    bin_range_m: Metres = Field(0.05, gt=0, description="range width of a time bin (m)")
    margin_m: Metres = Field(
        2.0,
        ge=0,
        description="range margin of the time window (m); a steered beam needs "
        "steered_beam.window_m > 2 x margin_m",
    )
    steered_beam: SteeredBeamCfg = Field(default_factory=SteeredBeamCfg)
    motion: MotionCfg | None = Field(
        None,
        description="the platform's motion during the scan (a steered beam's pose per pulse, a "
        "flash or micromirror frame's per frame; none: at rest)",
    )
    flash: FlashCfg = Field(default_factory=FlashCfg)
    micromirror: MicromirrorCfg = Field(default_factory=MicromirrorCfg)

    @model_validator(mode="after")
    def _one_photon_model(self) -> LidarOptionsCfg:
        d = self.detector
        expert = [k for k in type(d).model_fields if k.startswith("expert_") and getattr(d, k)
                  is not None]  # fmt: skip
        hardware = self.instrument is not None or self.hardware != HardwareCfg()
        if expert and hardware:
            raise ValueError(
                f"detector.{expert[0]}: an expert photon scale replaces the instrument's link "
                "budget; remove it or the instrument / hardware keys"
            )
        if hardware:
            # the instrument's hardware sets these: a second value would be silently ignored
            # (compared with the defaults: a config written back keeps every key)
            clash = [
                f"{block}.{k}"
                for block, keys in _HARDWARE_SET.items()
                for k in keys
                if getattr(getattr(self, block), k) != getattr(_DEFAULTS[block], k)
            ]
            if clash:
                raise ValueError(
                    f"{clash[0]}: set by the instrument's hardware (set hardware."
                    f"{_HARDWARE_KEY[clash[0].split('.')[1]]} instead, or use the expert photon "
                    "scales without an instrument)"
                )
        return self


#: keys of the other blocks that an instrument's hardware sets
_HARDWARE_SET = {
    "pulse": ("fwhm_ns", "jitter_ns"),
    "steered_beam": ("divergence_mrad", "pulse_rate_hz"),
    "flash": ("pulse_rate_hz",),
    "micromirror": ("pulse_rate_hz",),
}
_DEFAULTS = {"pulse": PulseCfg(), "steered_beam": SteeredBeamCfg(), "flash": FlashCfg(),
             "micromirror": MicromirrorCfg()}  # fmt: skip
_HARDWARE_KEY = {
    "fwhm_ns": "pulse_fwhm_ns",
    "jitter_ns": "jitter_ns",
    "divergence_mrad": "divergence_urad",
    "pulse_rate_hz": "pulse_rate_hz",
}
