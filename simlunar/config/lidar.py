"""LIDAR sections of the schema: the sensor options of a ``lidar`` study (docs/lidar.md).

Each block is derived from the library's options classes (:mod:`simlunar.config.option_blocks`):
a key's type, default, bounds and description are the field's declaration, its name carries
the unit the field declares for the YAML (``_ns``, ``_mrad``, ``_urad``, ``_uj``), and
:mod:`simlunar.config.lidar_translate` turns a block back into the library's SI options
through the same declarations. Only the block of the study's sensor may differ from its
defaults (``steered_beam``, ``flash`` or ``micromirror``).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Literal

from pydantic import Field, model_validator

from simlunar.config.fields import Metres, _Model
from simlunar.config.landing import HazardCfg, SafeSiteCfg
from simlunar.config.option_blocks import Block, Part
from simlunar.config.planners import StrategyOptionsCfg
from simlunar.lidar.apd import ApdOptions
from simlunar.lidar.detector import MAX_PHOTONS, DetectorOptions
from simlunar.lidar.flash import FlashOptions
from simlunar.lidar.footprint import FootprintOptions
from simlunar.lidar.gate import GateOptions
from simlunar.lidar.hardware import INSTRUMENTS, LidarHardware
from simlunar.lidar.ordering import OrderOptions
from simlunar.lidar.ranging import RangeOptions
from simlunar.lidar.returns import ReturnOptions, TransientOptions
from simlunar.lidar.scan import HARDWARE_SETS, SteeredBeamOptions
from simlunar.lidar.steering import SteeringOptions
from simlunar.lidar.trajectory import Navigation, PlatformMotion
from simlunar.lidar.waveform import PulseOptions
from simlunar.sensors.lidar import FlashLidarOptions
from simlunar.sensors.micromirror import MicromirrorOptions
from simlunar.study.lidar_planners import SensorFit

__all__ = [
    "BLOCKS",
    "FIT",
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
    "RangingCfg",
    "SafeSiteCfg",
    "SteeredBeamCfg",
    "TransientCfg",
    "instrument_hardware",
    "receiver_wh",
]


#: most time bins of one histogram (a rendered batch's window over ``bin_range_m``): each bin
#: is a film channel per beam or receiver pixel, so 1e5 bins x 4096 beams is already 6.5 GB
MAX_BINS = 100_000

PULSE = Block(
    "PulseCfg",
    "Laser pulse and detector timing (:class:`simlunar.lidar.PulseOptions`).",
    (Part("pulse", PulseOptions),),
)
HARDWARE = Block(
    "HardwareCfg",
    "The instrument's hardware (:class:`simlunar.lidar.hardware.LidarHardware`): every key "
    "overrides the chosen ``instrument`` preset's value (unset keys keep it); photons per pulse "
    "and the sun's background are derived from it (the lidar equation, docs/lidar.md).",
    (Part("hardware", LidarHardware, optional=True),),
    set_keys_only=True,
)
APD = Block(
    "ApdCfg",
    "A linear-mode avalanche photodiode (:class:`simlunar.lidar.apd.ApdOptions`).",
    (Part("apd", ApdOptions),),
)
#: the detector's photon scales in the YAML: an expert override of the instrument's link budget
_EXPERT = ("signal_photons", "background_photons_per_s", "dark_count_rate_hz")
DETECTOR = Block(
    "DetectorCfg",
    "Detector (:class:`simlunar.lidar.DetectorOptions`): pulses per reading, dead time and, "
    "only without an instrument, the expert photon scales (``expert_*``: EXPERT OVERRIDES of "
    "the instrument's link budget).",
    (
        Part(
            "detector",
            DetectorOptions,
            rename={k: f"expert_{k}" for k in _EXPERT},
            optional=_EXPERT,
            null={"dead_time_s": math.inf},
            nested={"apd": APD},
            # an expert scale's sanity limits (the photon counts are Poisson draws)
            limits={
                "signal_photons": {"le": MAX_PHOTONS},
                "background_photons_per_s": {"le": MAX_PHOTONS * 1e6},
            },
        ),
    ),
)
RANGING = Block(
    "RangingCfg", "Range extraction (:class:`simlunar.lidar.RangeOptions`).",
    (Part("ranging", RangeOptions),),
)  # fmt: skip
TRANSIENT = Block(
    "TransientCfg",
    "Transient rendering of the returns (:class:`simlunar.lidar.returns.TransientOptions`); "
    "its sampler seed is the unit's render seed.",
    (Part("transient", TransientOptions, skip=("seed",)),),
)
GATE = Block(
    "GateCfg",
    "The range gate (:class:`simlunar.lidar.gate.GateOptions`): a reference plane from the "
    "navigation datum or an altimeter reading; ``margin_m`` must cover the relief about it.",
    (Part("gate", GateOptions),),
)
STEERED_BEAM = Block(
    "SteeredBeamCfg",
    "A gimbaled altimeter / galvanometer scanner at the guide camera "
    "(:class:`simlunar.lidar.scan.SteeredBeamOptions`).",
    (
        Part("footprint", FootprintOptions, rename={"samples": "footprint_rays"}),
        Part("steering", SteeringOptions),
        Part("order", OrderOptions, only=("method",), rename={"method": "order"}),
        # window_m > 2 margin_m reads the block above: checked with it (config.lidar_checks)
        Part("beam", SteeredBeamOptions, only=("window_m", "field_clip", "batch"), check=False),
    ),
)
FLASH = Block(
    "FlashCfg",
    "A flash LIDAR co-boresighted with the guide camera (:class:`simlunar.sensors.FlashLidar`).",
    (
        Part("sensor", FlashLidarOptions, null={"receiver_px": "hardware"}),
        Part("flash", FlashOptions, only=("pulse_rate_hz",)),
    ),
)
MICROMIRROR = Block(
    "MicromirrorCfg",
    "A micromirror-steered flash (:class:`simlunar.sensors.MicromirrorFlash`).",
    (
        Part("sensor", MicromirrorOptions, null={"receiver_px": "hardware"}),
        Part("flash", FlashOptions, only=("pulse_rate_hz",)),
    ),
)
MOTION = Block(
    "MotionCfg",
    "The platform's motion during a steered-beam scan or between flash or micromirror frames "
    "(:class:`simlunar.lidar.trajectory.PlatformMotion`), starting at the guide camera.",
    (
        Part("motion", PlatformMotion, skip=("velocity_m_s",)),
        Part("navigation", Navigation),
    ),
    # the velocity as the YAML writes it (lidar_translate.motion_options makes velocity_m_s)
    extra={
        "kind": (Literal["hover", "descent"], Field("descent", description="hover or descent")),
        "descent_rate_m_s": (
            float,
            Field(2.0, ge=0, le=1000, description="descent: vertical speed, down (m/s)"),
        ),
        "horizontal_m_s": (
            tuple[float, float],
            Field((0.0, 0.0), description="descent: horizontal velocity (x, y) (m/s)"),
        ),
    },
)
#: the YAML blocks of ``study.options`` derived from the library's options classes
BLOCKS = {
    "hardware": HARDWARE,
    "pulse": PULSE,
    "detector": DETECTOR,
    "ranging": RANGING,
    "transient": TRANSIENT,
    "gate": GATE,
    "steered_beam": STEERED_BEAM,
    "motion": MOTION,
    "flash": FLASH,
    "micromirror": MICROMIRROR,
}

PulseCfg = PULSE.model
HardwareCfg = HARDWARE.model
ApdCfg = APD.model
DetectorCfg = DETECTOR.model
RangingCfg = RANGING.model
TransientCfg = TRANSIENT.model
GateCfg = GATE.model
SteeredBeamCfg = STEERED_BEAM.model
FlashCfg = FLASH.model
MicromirrorCfg = MICROMIRROR.model
MotionCfg = MOTION.model


FIT = Block(
    "FitCfg",
    "A planner fitted to its sensor (:class:`simlunar.study.lidar_planners.SensorFit`): at the "
    "reference planner's scan time, within an absolute time or energy budget (sensors side by "
    "side), or at most some dots per receiver pixel (docs/lidar.md).",
    (Part("fit", SensorFit, limits={"frames": {"le": 1024}}),),
)
FitCfg = FIT.model


class LidarPlannerOptsCfg(StrategyOptionsCfg):
    """A LIDAR planner label's options: its strategy and planner options, and optionally a
    fit to the sensor."""

    fit: FitCfg | None = Field(None, description="fit the plan to the sensor (docs/lidar.md)")


def _return_field(name: str):
    """A key of :class:`~simlunar.lidar.returns.ReturnOptions` (a length in m)."""
    f = next(f for f in dataclasses.fields(ReturnOptions) if f.name == name)
    m = f.metadata
    bounds = {k: m[k] for k in ("ge", "gt", "le", "lt") if m.get(k) is not None}
    return Field(f.default, description=f"{m['doc']} ({m['unit']})", **bounds)


class LidarOptionsCfg(_Model):
    """Options shared by the LIDARs and the block of each sensor."""

    instrument: Literal[tuple(INSTRUMENTS)] | None = Field(  # type: ignore[valid-type]
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
    bin_range_m: Metres = _return_field("bin_range_m")
    margin_m: Metres = _return_field("margin_m")
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
            # the instrument's hardware sets these (HARDWARE_SETS): a second value would be
            # silently ignored (compared with the defaults: a config written back keeps every key)
            for block, key, hw_key in _hardware_set_keys():
                if getattr(getattr(self, block), key) != getattr(_DEFAULTS[block], key):
                    raise ValueError(
                        f"{block}.{key}: set by the instrument's hardware (set hardware."
                        f"{hw_key} instead, or use the expert photon scales without an "
                        "instrument)"
                    )
        return self


#: the blocks' defaults (the hardware-set keys are compared with them)
_DEFAULTS = {name: block.default() for name, block in BLOCKS.items()}


def _hardware_set_keys() -> list[tuple[str, str, str]]:
    """(block, key, hardware key) of every key that an instrument's hardware sets, from
    :data:`~simlunar.lidar.scan.HARDWARE_SETS`."""
    out = []
    for hw_field, targets in HARDWARE_SETS.items():
        hw_key = HARDWARE.key_of(LidarHardware, hw_field)
        for name, block in BLOCKS.items():
            for cls, field_name in targets:
                key = block.key_of(cls, field_name)
                if key is not None and name != "hardware":
                    out.append((name, key, hw_key))
    return out


def instrument_hardware(o: LidarOptionsCfg) -> LidarHardware | None:
    """The instrument preset of a config with its hardware overrides (SI), or None without
    an instrument."""
    if o.instrument is None:
        return None
    return dataclasses.replace(
        INSTRUMENTS[o.instrument], **HARDWARE.library(o.hardware, "hardware")
    )


def receiver_wh(o: LidarOptionsCfg, block: str) -> tuple[int, int]:
    """The receiver array (width, height) of sensor block ``block`` (``flash`` or
    ``micromirror``): its ``receiver_px``, else the instrument's (with its hardware
    overrides), else the library's default."""
    wh = getattr(o, block).receiver_px
    if wh is not None:
        return tuple(wh)
    hw = instrument_hardware(o)
    key = BLOCKS[block].keys["receiver_px"]
    rows_cols = None if hw is None else hw.receiver_px
    if rows_cols is None:
        rows_cols = getattr(BLOCKS[block].parts[key.part].options(), key.field)
    return (rows_cols[1], rows_cols[0])
