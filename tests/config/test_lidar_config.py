"""The lidar study's configuration: the shipped experiments, SI translation, one-line errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from simlunar.config import lidar_translate
from simlunar.config.loading import load_experiment
from simlunar.config.yamlio import parse_set
from simlunar.errors import ConfigError
from simlunar.render.lidar_scan import SteeredBeamOptions
from simlunar.sensors import FlashLidarOptions, MicromirrorOptions

EXPERIMENTS = Path(__file__).resolve().parents[2] / "experiments"
DESCENT = EXPERIMENTS / "lidar_descent_altimeter.yaml"


@pytest.mark.parametrize(
    "name",
    [
        "lidar_descent_altimeter",
        "lidar_descent_micromirror",
        "lidar_hazard_flash",
        "lidar_rover_mast",
    ],
)
def test_the_shipped_lidar_experiments_validate(name):
    cfg = load_experiment(EXPERIMENTS / f"{name}.yaml")
    assert cfg.study.kind == "lidar"


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


@pytest.mark.parametrize(
    "sets, message",
    [
        (["study.sensor=sonar"], r"study\.sensor"),
        (["study.planners=[wavelet, psychic]"], r"study\.planners\[1\]: unknown strategy"),
        (["study.metrics=[mse, mse]"], r"study\.metrics"),
        (["study.trials=0"], r"study\.trials"),
        (["study.densities=[2]"], r"study\.densities"),
        (["study.options.pulse.fwhm_ns=-1"], r"study\.options\.pulse\.fwhm_ns"),
        (["study.options.steered_beam.order=spiral"], r"study\.options\.steered_beam\.order"),
        (["study.options.flash.revisits=2"], r"options\.flash: not an option of the steered_beam"),
        (["study.hazard={window_px: 4}"], r"study\.hazard\.window_px: .*odd"),
        (["study.options.detector.expert_signal_photons=5"], r"expert_signal_photons: .*instrument"),
        (["study.options.pulse.fwhm_ns=3"], r"pulse\.fwhm_ns: set by the instrument's hardware"),
        (["study.options.instrument=laser_pointer"], r"study\.options\.instrument"),
        (["study.options.detector.dead_time_ns=2"], r"apd: a linear-mode APD has no dead time"),
        (["study.planner_opts={grid: {uniform_mix: 0.5}}"], r"planner_opts\.grid\.uniform_mix"),
        (["render.camera={kind: orthographic_nadir}"], r"render\.camera: a lidar study needs"),
        (
            ["study.sensor=flash", "study.options.steered_beam={}",
             "study.options.flash={receiver_px: [32, 16]}"],
            r"receiver_px: \(32, 16\) must keep the camera's aspect",
        ),
    ],
)  # fmt: skip
def test_bad_values_are_one_line_errors(sets, message):
    with pytest.raises(ConfigError, match=message) as info:
        load_experiment(DESCENT, parse_set(sets))
    assert "\n" not in str(info.value)
