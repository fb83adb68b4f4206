"""The LIDAR sections of the schema: their defaults are the library's (through the SI
translation), unit strings converted, the hazard window odd, bounds with their reasons."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from simlunar.config.lidar import (
    DetectorCfg,
    FlashCfg,
    LidarOptionsCfg,
    MicromirrorCfg,
    PulseCfg,
    SteeredBeamCfg,
    TransientCfg,
)
from simlunar.config.lidar_translate import lidar_sensor_options
from simlunar.config.studies import LidarStudyCfg
from simlunar.lidar.flash import FlashOptions
from simlunar.lidar.scan import SteeredBeamOptions
from simlunar.sensors.lidar import FlashLidarOptions
from simlunar.sensors.micromirror import MicromirrorOptions


def test_steered_beam_defaults_are_the_librarys():
    got = lidar_sensor_options(LidarStudyCfg(kind="lidar"))
    want = SteeredBeamOptions()
    for name in ("pulse", "detector", "ranging", "footprint", "steering", "order", "transient",
                 "bin_range_m", "margin_m", "window_m", "batch"):  # fmt: skip
        assert getattr(got, name) == getattr(want, name), name


def test_flash_and_micromirror_defaults_are_the_librarys():
    flash = lidar_sensor_options(LidarStudyCfg(kind="lidar", sensor="flash"))
    want = FlashLidarOptions()
    assert (flash.receiver_px, flash.revisits, flash.zoom) == (
        want.receiver_px,
        want.revisits,
        want.zoom,
    )
    assert flash.flash.pulse_rate_hz == FlashOptions().pulse_rate_hz
    mm = lidar_sensor_options(LidarStudyCfg(kind="lidar", sensor="micromirror_flash"))
    assert mm.receiver_px == MicromirrorOptions().receiver_px


def test_lengths_take_units():
    o = LidarOptionsCfg(bin_range_m="5 cm", margin_m="1 km", steered_beam={"window_m": "800 cm"})
    assert o.bin_range_m == pytest.approx(0.05) and o.margin_m == 1000.0
    assert o.steered_beam.window_m == pytest.approx(8.0)


@pytest.mark.parametrize(
    ("model", "kw", "message"),
    [
        (PulseCfg, {"fwhm_ns": -1}, "greater than or equal to 0"),
        (PulseCfg, {"fwhm_ns": 2e4}, "less than or equal to 10000"),
        (PulseCfg, {"jitter_ns": -1}, "greater than or equal to 0"),
        (DetectorCfg, {"pulses": 0}, "greater than or equal to 1"),
        # an expert photon scale's sanity limit (the YAML's, not the library's)
        (DetectorCfg, {"expert_signal_photons": 2e12}, "less than or equal to 1000000000000"),
        (TransientCfg, {"max_depth": 1}, "greater than or equal to 2"),
        (SteeredBeamCfg, {"order": "spiral"}, "Input should be 'nn2opt', 'raster' or 'given'"),
        (SteeredBeamCfg, {"profile": "tophat"}, "Input should be 'gaussian' or 'uniform'"),
        (FlashCfg, {"zoom": 1}, "greater than or equal to 2"),
        (FlashCfg, {"receiver_px": (64, 0)}, "greater than or equal to 1"),
        (MicromirrorCfg, {"receiver_px": (8193, 64)}, "less than or equal to 8192"),
        (SteeredBeamCfg, {"pulse_rate_hz": 1e-4}, "greater than or equal to 0.001"),
        (FlashCfg, {"pulse_rate_hz": 2e9}, "less than or equal to 1000000000"),
        (MicromirrorCfg, {"pulse_rate_hz": 0}, "greater than or equal to 0.001"),
        (LidarOptionsCfg, {"bin_range_m": 0}, "greater than 0"),
    ],
)
def test_bounds(model, kw, message):
    with pytest.raises(ValidationError) as info:
        model(**kw)
    assert message in info.value.errors()[0]["msg"]
