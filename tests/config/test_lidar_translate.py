"""The LIDAR study's configuration in SI units: ns -> s, mrad -> rad, ms -> s, the receiver's
(width, height) -> (rows, cols), no dead time -> one detection per pulse; hazard options."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from simlunar.config import lidar_translate
from simlunar.config.lidar import HazardCfg
from simlunar.config.loading import load_experiment
from simlunar.config.studies import LidarStudyCfg
from simlunar.config.yamlio import parse_set
from simlunar.lidar.scan import SteeredBeamOptions
from simlunar.metrics.hazard import HazardOptions
from simlunar.sensors import FlashLidarOptions, MicromirrorOptions

EXPERIMENTS = Path(__file__).resolve().parents[2] / "experiments"
DESCENT = EXPERIMENTS / "lidar_descent_altimeter.yaml"


def test_descent_translates_to_si_options():
    s = load_experiment(DESCENT).study
    opts = lidar_translate.lidar_options(s, seed=7)
    so = opts.sensor_options
    assert isinstance(so, SteeredBeamOptions) and opts.sensor == "steered_beam"
    # the LOLA-class preset's receiver with the experiment's laser (10 uJ at 10 kHz)
    hw = so.hardware
    assert hw.pulse_energy_j == pytest.approx(10e-6) and hw.aperture_diameter_m == 0.14
    assert so.pulse.fwhm_s == pytest.approx(5e-9) and so.pulse.jitter_s == pytest.approx(5e-10)
    assert so.footprint.divergence_rad == pytest.approx(100e-6)
    assert so.steering.pulse_rate_hz == pytest.approx(1e4)
    assert so.steering.settle_s == pytest.approx(1e-3)
    # photons derived: E A eta / (h nu) per unit radiance of a 1 W/sr laser, by hand
    hnu = 6.62607015e-34 * 299_792_458.0 / 1064e-9
    det = so.photon_detector()
    assert det.signal_photons == pytest.approx(10e-6 * np.pi * 0.07**2 * 0.5 * 0.4 / hnu)
    assert so.steering.pulses_per_point == 4 and so.transient.seed == 7
    assert so.detector.regime == "linear_apd" and so.detector.apd.excess_noise > 3.9
    assert opts.densities[0] == pytest.approx(1 / 16) and len(opts.densities) == 5


def test_flash_and_micromirror_translate_receiver_width_height_to_rows_cols():
    cfg = load_experiment(
        DESCENT,
        parse_set(
            [
                "study.sensor=flash",
                "study.planner_opts={}",
                "study.planners=[wavelet, random]",
                "study.options.steered_beam={}",
                "study.options.flash={receiver_px: [32, 32], revisits: 2, zoom: 4}",
                "study.options.detector.dead_time_ns=null",
                "study.options.detector.apd=null",
            ]
        ),
    )
    so = lidar_translate.lidar_options(cfg.study).sensor_options
    assert isinstance(so, FlashLidarOptions) and so.receiver_px == (32, 32) and so.revisits == 2
    assert so.flash.detector.dead_time_s == float("inf")  # one detection per pulse
    cfg = load_experiment(
        DESCENT,
        parse_set(
            [
                "study.sensor=micromirror_flash",
                "study.options.steered_beam={}",
                "study.options.instrument=null",
                "study.options.hardware={}",
                "study.options.micromirror={receiver_px: [16, 16]}",
            ]
        ),
    )
    so = lidar_translate.lidar_options(cfg.study).sensor_options
    assert isinstance(so, MicromirrorOptions) and so.receiver_px == (16, 16)


def test_every_unit_of_a_hand_written_steered_beam_study():
    study = LidarStudyCfg(
        kind="lidar",
        planners=["grid", "wavelet"],
        densities=[0.25],
        trials=2,
        metrics=["mse"],
        planner_opts={"wavelet": {"placement": "lloyd"}},
        options={
            "pulse": {"fwhm_ns": 4, "jitter_ns": 0.5},
            "detector": {"dead_time_ns": 20, "expert_dark_count_rate_hz": 100},
            "ranging": {"method": "peak", "which": "first"},
            "transient": {"spp": 8, "max_depth": 3, "laser_intensity_w_sr": 2},
            "bin_range_m": "10 cm",
            "margin_m": 1,
            "steered_beam": {"divergence_mrad": 2, "settle_ms": 5, "max_accel_rad_s2": 10,
                             "order": "raster", "window_m": 4, "batch": 64},
        },
    )  # fmt: skip
    opts = lidar_translate.lidar_options(study, seed=3)
    assert opts.planners == ("grid", "wavelet") and opts.densities == (0.25,)
    assert opts.trials == 2 and opts.metrics == ("mse",) and opts.hazard is None
    assert opts.planner_opts["wavelet"]["placement"] == "lloyd"
    so = opts.sensor_options
    assert so.pulse.fwhm_s == pytest.approx(4e-9) and so.pulse.jitter_s == pytest.approx(5e-10)
    assert so.detector.dead_time_s == pytest.approx(2e-8)
    assert so.detector.dark_count_rate_hz == 100
    assert (so.ranging.method, so.ranging.which) == ("peak", "first")
    t = so.transient
    assert (t.spp, t.max_depth, t.seed, t.laser_intensity) == (8, 3, 3, 2.0)
    assert so.bin_range_m == pytest.approx(0.1) and so.margin_m == 1.0
    assert so.footprint.divergence_rad == pytest.approx(2e-3)
    assert so.steering.settle_s == pytest.approx(5e-3)
    assert so.steering.max_accel_rad_s2 == 10
    assert so.order.method == "raster" and so.window_m == 4 and so.batch == 64


def test_flash_receiver_width_height_becomes_rows_cols():
    study = LidarStudyCfg(kind="lidar", sensor="flash",
                          options={"flash": {"receiver_px": [40, 30], "zoom": 3}})  # fmt: skip
    so = lidar_translate.lidar_sensor_options(study)
    assert so.receiver_px == (30, 40) and so.zoom == 3


def test_hazard_options():
    assert lidar_translate.hazard_options(None) is None
    h = lidar_translate.hazard_options(HazardCfg(slope_deg="0.2 rad", relief_m="20 cm"))
    assert isinstance(h, HazardOptions)
    assert h.slope_deg == pytest.approx(11.459155902616464) and h.relief_m == pytest.approx(0.2)
    assert (h.window_px, h.baseline_px) == (15, 2)


def test_a_flash_and_a_micromirror_take_the_platform_s_motion():
    from simlunar.config.lidar_checks import check_lidar_study

    study = LidarStudyCfg(kind="lidar", sensor="flash",
                          options={"flash": {"receiver_px": [32, 32]},
                                   "motion": {"kind": "descent", "descent_rate_m_s": 2.0}})  # fmt: skip
    check_lidar_study(study)
    so = lidar_translate.lidar_sensor_options(study)
    assert so.motion.velocity_m_s == pytest.approx((0.0, 0.0, -2.0))
    mm = LidarStudyCfg(kind="lidar", sensor="micromirror_flash",
                       options={"motion": {"kind": "descent", "descent_rate_m_s": 3.0,
                                           "compensation": "start"}})  # fmt: skip
    check_lidar_study(mm)
    so = lidar_translate.lidar_sensor_options(mm)
    assert so.motion.velocity_m_s == pytest.approx((0.0, 0.0, -3.0))
    assert so.motion.navigation.compensation == "start"
    at_rest = LidarStudyCfg(kind="lidar", sensor="micromirror_flash")
    assert lidar_translate.lidar_sensor_options(at_rest).motion is None


def _flash_study(instrument, receiver=None, hardware=None):
    flash = {} if receiver is None else {"receiver_px": receiver}
    return LidarStudyCfg(kind="lidar", sensor="flash",
                         options={"instrument": instrument, "flash": flash,
                                  "hardware": hardware or {}})  # fmt: skip


def test_a_flash_takes_its_instrument_s_receiver_array():
    from simlunar.config.lidar import receiver_wh

    # the ALHAT-class preset is a 128 x 128 array; a YAML receiver_px wins; without an
    # instrument (or with a one-detector one) the library's 64 x 64
    assert lidar_translate.lidar_sensor_options(_flash_study("alhat_flash")).receiver_px == (
        128,
        128,
    )
    assert receiver_wh(_flash_study("alhat_flash").options, "flash") == (128, 128)
    got = lidar_translate.lidar_sensor_options(_flash_study("alhat_flash", [40, 30]))
    assert got.receiver_px == (30, 40)
    # a hardware override of the array, (width, height) as every receiver_px of the YAML
    o = _flash_study("alhat_flash", hardware={"receiver_px": [48, 32]})
    assert lidar_translate.lidar_sensor_options(o).receiver_px == (32, 48)
    assert receiver_wh(o.options, "flash") == (48, 32)
    assert lidar_translate.lidar_sensor_options(_flash_study(None)).receiver_px == (64, 64)
    assert lidar_translate.lidar_sensor_options(_flash_study("lola_beam")).receiver_px == (64, 64)


def test_hardware_keys_convert_from_their_declared_units():
    o = LidarStudyCfg(kind="lidar",
                      options={"instrument": "lola_beam",
                               "hardware": {"pulse_energy_uj": 10, "wavelength_nm": 1550,
                                            "aperture_diameter_mm": 100, "divergence_urad": 50,
                                            "field_urad": 200, "pulse_fwhm_ns": 3}}).options  # fmt: skip
    hw = lidar_translate.lidar_hardware(o, "steered_beam")
    assert hw.pulse_energy_j == 10 * 1e-6 and hw.wavelength_m == 1550 * 1e-9
    assert hw.aperture_diameter_m == 100 * 1e-3 and hw.divergence_rad == 50 * 1e-6
    assert hw.field_rad == 200 * 1e-6 and hw.pulse_fwhm_s == 3 * 1e-9
    assert hw.optics_efficiency == 0.5  # the preset's, not overridden
    # an override block writes back only what it sets
    assert o.hardware.model_dump() == {
        "pulse_energy_uj": 10.0, "wavelength_nm": 1550.0, "pulse_fwhm_ns": 3.0,
        "aperture_diameter_mm": 100.0, "divergence_urad": 50.0, "field_urad": 200.0,
    }  # fmt: skip


def test_the_instrument_names_are_the_presets():
    from simlunar.config.lidar import LidarOptionsCfg
    from simlunar.lidar.hardware import INSTRUMENTS

    ann = LidarOptionsCfg.model_fields["instrument"].annotation
    assert set(ann.__args__[0].__args__) == set(INSTRUMENTS)


def test_every_instrument_preset_translates_at_its_own_numbers():
    # a bound on the detector's photon scales once refused the LOLA-class preset's own
    # scale (~9e12 photons per unit rendered radiance at 0.54 mJ)
    from simlunar.lidar.hardware import INSTRUMENTS

    for name in INSTRUMENTS:
        for sensor in ("steered_beam", "flash", "micromirror_flash"):
            study = LidarStudyCfg(kind="lidar", sensor=sensor, options={"instrument": name})
            det = lidar_translate.lidar_sensor_options(study, seed=0)
            flash = getattr(det, "flash", det)
            assert flash.hardware is INSTRUMENTS[name] or flash.hardware == INSTRUMENTS[name]
            if sensor == "steered_beam":
                assert flash.photon_detector().signal_photons > 0
